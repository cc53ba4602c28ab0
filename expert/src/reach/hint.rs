//! The base hint of E0036 and W0010: the nearest base (on rings in the plane, then raised) from
//! which every target checked for a robot, in every sampled layout, solves with room to spare and
//! the arm comes in clear of the scene. It does not decide what is reported (`diagnostics`).

use super::*;

/// Rings searched for a base hint: every `HINT_STEP` metres out to `HINT_RADIUS`, in
/// `HINT_DIRECTIONS` directions each.
pub(super) const HINT_STEP: f64 = 0.025;
pub(super) const HINT_RADIUS: f64 = 0.8;
pub(super) const HINT_DIRECTIONS: usize = 16;
/// How much farther out than each target (m, in the plane, away from the base) the hinted base
/// must still reach.
pub(super) const HINT_MARGIN: f64 = 0.1;
/// How far back along a grasp's axis the hinted base's arm must come in clear of the scene (m),
/// and how many reached bases at each height are stood up and checked so before the search
/// gives that height up.
pub(super) const HINT_APPROACH: f64 = 0.07;
pub(super) const HINT_CLEAR_TRIES: usize = 120;
/// Where no base at the robot's height serves (a target high above it, reached only with a
/// joint past its range), raised bases are searched too: `HINT_RISE` metres at a time, up to
/// `HINT_RISES` times (a riser under the robot, as `protocols/centrifuge_5910/riser.toml`).
pub(super) const HINT_RISE: f64 = 0.05;
pub(super) const HINT_RISES: usize = 10;

/// The nearest base (m) for the robot, now at `base`, from which every one of its `aims` solves
/// (one grasp of each, from its home, then its path) with `HINT_MARGIN` to spare (the grasp
/// moved that much farther out from the base solves too) and which `clear` accepts, searched
/// ring by ring in the plane at the base's height, then on rings around each raised height in
/// turn; `None` within the search. The margin is the expert's room around a grasp: the approach
/// before it, the lift after it.
fn base_shift(
    aims: &[&Aim],
    model: &robots::RobotModel,
    kin: &mut ArmKinematics,
    base: [f64; 3],
    mut clear: impl FnMut([f64; 3]) -> bool,
) -> Option<[f64; 3]> {
    // Reached bases stood up and checked, per height: the raised search gets its own budget.
    let mut tried: BTreeMap<u64, usize> = BTreeMap::new();
    let home = model.home.to_vec();
    let rings = (HINT_RADIUS / HINT_STEP).round() as usize;
    let around = |rise: f64, first: usize| {
        (first..=rings).flat_map(move |k| {
            let directions = if k == 0 { 1 } else { HINT_DIRECTIONS };
            (0..directions).map(move |j| {
                let a = std::f64::consts::TAU * j as f64 / HINT_DIRECTIONS as f64;
                let r = k as f64 * HINT_STEP;
                [r * a.cos(), r * a.sin(), rise]
            })
        })
    };
    let level = around(0.0, 1);
    let raised = (1..=HINT_RISES).flat_map(|k| around(k as f64 * HINT_RISE, 0));
    level
        .chain(raised)
        .find(|d| {
            let height = tried.entry(d[2].to_bits()).or_default();
            if *height >= HINT_CLEAR_TRIES {
                return false;
            }
            // The base moved by d reaches what the base where it is reaches moved by -d.
            let back = labware::frame::translation([-d[0], -d[1], -d[2]]);
            let reached = aims.iter().all(|aim| {
                aim.grasps.iter().any(|(pose, path)| {
                    let near = back * pose;
                    let p = near.translation.vector;
                    let out = nalgebra::Vector2::new(p.x - base[0], p.y - base[1]);
                    let out = out.try_normalize(1e-9).unwrap_or_default() * HINT_MARGIN;
                    let far = labware::frame::translation([out.x, out.y, 0.0]) * near;
                    if solve_with(model.ik, kin, &far, &home).is_err() {
                        return false;
                    }
                    let Ok(mut q) = solve_with(model.ik, kin, &near, &home) else {
                        return false;
                    };
                    // And the path it then follows, each pose from the last.
                    path.iter().all(|at| {
                        solve_with(model.ik, kin, &(back * at), &q)
                            .map(|next| q = next)
                            .is_ok()
                    })
                })
            });
            // Reached: then stood there for real, clear of the scene on the way in.
            reached && {
                *tried.entry(d[2].to_bits()).or_default() += 1;
                clear([base[0] + d[0], base[1] + d[1], base[2] + d[2]])
            }
        })
        .map(|d| [base[0] + d[0], base[1] + d[1], base[2] + d[2]])
}

/// Whether `robot` stood at `base` (the task otherwise as it is) has an IK solution clear of
/// the scene for every aim's approach (`HINT_APPROACH` back along the grasp's axis, where the
/// expert comes in from): a base the arm reaches from can still put its upper arm through an
/// instrument.
fn clear_from(
    task: &Task,
    instance: &compiler::SceneInstance,
    robot: usize,
    base: [f64; 3],
    aims: &[&Aim],
) -> bool {
    let mut moved = task.clone();
    moved.robots[robot].base.translation.vector = nalgebra::Vector3::new(base[0], base[1], base[2]);
    let Ok(scene) = Scene::build(&moved, instance) else {
        return false;
    };
    let scene = Arc::new(scene);
    let episode = Episode::new(scene.clone(), &moved, instance);
    let mut kin = ArmKinematics::new(&scene, robot);
    let mut clearance = Clearance::new(&scene, robot);
    clearance.sync(&episode.qpos(), None);
    // Stood inside something (an instrument, the other robot), the arm touches it at its start.
    if clearance.touching_at_sync() > 0 {
        return false;
    }
    let model = scene.robots[robot].model;
    let starts = [instance.robot_q[robot].clone(), model.home.to_vec()];
    aims.iter().filter(|aim| aim.as_started).all(|aim| {
        aim.grasps.iter().any(|(grasp, _)| {
            let approach = labware::frame::translated_local(grasp, [0.0, 0.0, -HINT_APPROACH]);
            starts.iter().any(|seed| {
                solve_with(model.ik, &mut kin, &approach, seed)
                    .is_ok_and(|q| clearance.may_end_at(&q))
            })
        })
    })
}

/// The nearest base for `robot` from which its targets in every sampled layout solve (as
/// [`base_shift`] searches) and its arm comes in clear in each: the hint of E0036 and of W0010.
pub(super) fn base_for_every_layout(task: &Task, robot: usize) -> Option<[f64; 3]> {
    let mut layouts: Vec<Layout> = (0..SAMPLED_LAYOUTS)
        .filter_map(|seed| Layout::of(task, seed))
        .collect();
    let mut kin = layouts.first_mut()?.kins.swap_remove(robot);
    let model = layouts[0].scene.robots[robot].model;

    let all: Vec<&Aim> = layouts.iter().flat_map(|l| aims_of(l, robot)).collect();
    let base = task.robots[robot].base.translation.vector;
    let base = [base.x, base.y, base.z];
    base_shift(&all, model, &mut kin, base, |at| {
        layouts
            .iter()
            .all(|l| clear_from(task, &l.instance, robot, at, &aims_of(l, robot)))
    })
}

/// `robot`'s aims in `layout`.
fn aims_of(layout: &Layout, robot: usize) -> Vec<&Aim> {
    layout.aims.iter().filter(|a| a.robot == robot).collect()
}
