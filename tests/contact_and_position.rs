//! The judge measures `<robot> touches <item>` from MuJoCo's contacts and `<item> near [x, y, z]`
//! from the item's live pose, on real episodes of the tube-transfer scene: the expert's grasp makes
//! the contact hold and a motionless robot never does; a tube left where it stands is near its own
//! position and not near a point 10 cm above it. Before, both predicates compiled but could never
//! hold, so a task using them could not be won.

use scoring::episode::{EpisodeOptions, run_episode};
use scoring::expert::ExpertPolicy;
use std::sync::Arc;

fn compile(success: &str, keep_place: bool) -> compiler::Task {
    let mut source = std::fs::read_to_string("protocols/tube/transfer.toml").unwrap();
    if !keep_place {
        // End holding the tube: the proof then agrees that the arm touches it.
        let place = source.find("[[steps]]\ndo = \"place\"").unwrap();
        let success_at = source.find("[success]").unwrap();
        source.replace_range(place..success_at, "");
    }
    let source = source.replace(
        "all = [\"tube in target.{row}{col}\"]",
        &format!("all = [{success:?}]"),
    );
    let (task, diags) = compiler::compile_source(&source, "inline.toml");
    task.unwrap_or_else(|| panic!("{diags:#?}"))
}

fn run(task: &compiler::Task, seed: u64, expert: bool) -> scoring::EpisodeResult {
    let instance = task.sample(seed);
    let scene = Arc::new(runtime::Scene::build(task, &instance).unwrap());
    let mut policy: Box<dyn scoring::Policy> = if expert {
        Box::new(ExpertPolicy::new(task, &scene, &instance).unwrap())
    } else {
        scoring::policy::make("hold", task, &scene, &instance).unwrap()
    };
    run_episode(
        task,
        &scene,
        &instance,
        policy.as_mut(),
        &EpisodeOptions::default(),
    )
    .unwrap()
}

#[test]
fn a_grasp_is_a_contact_and_no_motion_is_none() {
    let task = compile("arm touches tube", false);
    for seed in [3, 4] {
        let expert = run(&task, seed, true);
        assert!(expert.success, "{:?} {:#?}", expert.error, expert.verdict);
        let p = &expert.verdict.predicates()[0];
        assert!(p.holds && p.value == 1.0, "{p:?}");
        // The contact comes with the grasp, not at the start.
        assert!(expert.sim_time_s > 1.0, "{}", expert.sim_time_s);

        let hold = run(&task, seed, false);
        assert!(!hold.success, "a motionless arm touched the tube");
        let p = &hold.verdict.predicates()[0];
        assert!(!p.holds && p.value == 0.0, "{p:?}");
        assert!((hold.sim_time_s - task.time_limit_s).abs() < 0.05);
    }
}

#[test]
fn near_measures_the_distance_from_the_live_pose() {
    // Where the tube stands in episode 5 (its slot is drawn).
    let probe = compile("tube near [0, 0, 0] m", true);
    let instance = probe.sample(5);
    let scene = Arc::new(runtime::Scene::build(&probe, &instance).unwrap());
    let ep = runtime::Episode::new(scene, &probe, &instance);
    let tube = probe.labware_index("tube").unwrap();
    let at = ep.labware_state()[tube].pose.translation.vector;

    let here = compile(
        &format!("tube near [{:.4}, {:.4}, {:.4}] m", at.x, at.y, at.z),
        true,
    );
    let r = run(&here, 5, false);
    assert!(r.success, "{:#?}", r.verdict);
    let p = &r.verdict.predicates()[0];
    assert!(p.value < 1e-3, "{p:?}");

    let above = compile(
        &format!("tube near [{:.4}, {:.4}, {:.4}] m", at.x, at.y, at.z + 0.1),
        true,
    );
    let r = run(&above, 5, false);
    assert!(!r.success);
    let p = &r.verdict.predicates()[0];
    assert!(!p.holds && (p.value - 0.1).abs() < 2e-3, "{p:?}");
    assert_eq!(p.tolerance, 0.005, "the position tolerance's default");
}

#[test]
fn a_check_the_judge_cannot_measure_is_refused_before_running() {
    // A volume on a simulated tube compiles (the proof traces volumes), but the task scenes do not
    // simulate liquid: running it could never succeed, so the runtime refuses it with the reason.
    let source = std::fs::read_to_string("protocols/tube/transfer.toml")
        .unwrap()
        .replace(
            "all = [\"tube in target.{row}{col}\"]",
            "all = [\"tube in target.{row}{col}\", \"tube.volume = 0 µL\"]",
        );
    let (task, diags) = compiler::compile_source(&source, "inline.toml");
    let task = task.unwrap_or_else(|| panic!("{diags:#?}"));
    let err = match runtime::Scene::build(&task, &task.sample(0)) {
        Ok(_) => panic!("a task with an unmeasurable check was built"),
        Err(e) => e.to_string(),
    };
    assert!(
        err.contains("`tube.volume = 0 µL` cannot be measured"),
        "{err}"
    );
}
