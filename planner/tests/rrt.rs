//! RRTConnect through the real OMPL shim on a joint space with a wall that has one window.

use planner::{PlanError, Problem, plan, segment_is_clear, shortcut};

/// Six joints in ±3; a wall at |q0| < 0.3 that is open only where q1 is near 2 and q2 near -2.
fn valid(q: &[f64]) -> bool {
    q[0].abs() >= 0.3 || ((q[1] - 2.0).abs() < 0.4 && (q[2] + 2.0).abs() < 0.4)
}

fn problem(seed: u64) -> Problem {
    Problem {
        bounds: vec![(-3.0, 3.0); 6],
        start: vec![-2.5; 6],
        goal: vec![2.5; 6],
        step: 0.02,
        range: 0.0,
        max_checks: 200_000,
        seed,
    }
}

fn clear_path(path: &[Vec<f64>]) -> bool {
    path.windows(2)
        .all(|w| segment_is_clear(&w[0], &w[1], 0.02, &mut |q: &[f64]| valid(q)))
}

#[test]
fn rrt_connect_goes_through_the_window_and_shortcutting_keeps_it_clear() {
    let p = problem(7);
    // The straight motion goes through the wall.
    assert!(!segment_is_clear(
        &p.start,
        &p.goal,
        0.02,
        &mut |q: &[f64]| valid(q)
    ));
    let path = plan(&p, valid).unwrap();
    assert_eq!(path.first(), Some(&p.start));
    assert_eq!(path.last(), Some(&p.goal));
    assert!(clear_path(&path));
    // Where it crosses q0 = 0, it is in the window.
    let crossing = path
        .windows(2)
        .find(|w| w[0][0] < 0.0 && w[1][0] >= 0.0)
        .map(|w| planner::lerp(&w[0], &w[1], -w[0][0] / (w[1][0] - w[0][0])))
        .expect("the path crosses the wall's plane");
    assert!(
        (crossing[1] - 2.0).abs() < 0.4 && (crossing[2] + 2.0).abs() < 0.4,
        "{crossing:?}"
    );
    let short = shortcut(&path, 100, 0.02, 7, valid);
    assert!(clear_path(&short));
    let len = |p: &[Vec<f64>]| {
        p.windows(2)
            .map(|w| planner::distance(&w[0], &w[1]))
            .sum::<f64>()
    };
    assert!(len(&short) <= len(&path) + 1e-9);
    assert_eq!(short.first(), Some(&p.start));
    assert_eq!(short.last(), Some(&p.goal));
}

#[test]
fn the_same_seed_plans_the_same_path_and_another_seed_another() {
    let a = plan(&problem(3), valid).unwrap();
    // Another plan in between: no process-wide generator state may leak into the next call.
    let other = plan(&problem(4), valid).unwrap();
    let b = plan(&problem(3), valid).unwrap();
    assert_eq!(a, b);
    assert_ne!(a, other);
    // Seeds that differ only above the low 32 bits plan apart too.
    assert_ne!(a, plan(&problem(3 + (1 << 32)), valid).unwrap());
    assert_eq!(
        shortcut(&a, 50, 0.02, 9, valid),
        shortcut(&b, 50, 0.02, 9, valid)
    );
}

#[test]
fn invalid_ends_and_a_closed_wall_are_typed_errors() {
    let mut p = problem(1);
    p.start[0] = 0.0;
    p.start[1] = 0.0;
    assert_eq!(plan(&p, valid), Err(PlanError::StartInvalid));
    let mut p = problem(1);
    p.goal[0] = 0.1;
    p.goal[1] = 0.0;
    assert_eq!(plan(&p, valid), Err(PlanError::GoalInvalid));
    let mut p = problem(1);
    p.max_checks = 5_000;
    assert_eq!(
        plan(&p, |q: &[f64]| q[0].abs() >= 0.3),
        Err(PlanError::NoPath(5_000))
    );
    let mut p = problem(1);
    p.goal[0] = 3.5;
    assert!(matches!(plan(&p, valid), Err(PlanError::Malformed(_))));
    let mut p = problem(1);
    p.step = 100.0;
    assert!(matches!(plan(&p, valid), Err(PlanError::Malformed(_))));
    // A panicking check is "not valid", not an unwind into C++.
    assert_eq!(
        plan(&problem(1), |_: &[f64]| -> bool { panic!("checker bug") }),
        Err(PlanError::StartInvalid)
    );
}
