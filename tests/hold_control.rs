//! The no-motion control. A task a motionless robot passes (a lid that falls shut, a tube already
//! in place) is a broken task: every simulated task must score 0 under `hold`, each episode run
//! to its time limit with some measured check failing. The spread over every task and seeds 0-39
//! is CI's second step (`make hold-column`, tested to fail on a task hold passes in
//! tests/cli.rs); here, which tasks are simulated and one task's hold episode.
//! Also checks the policy factory: the report's policy field comes from the policy, and an unknown
//! name is refused with the known ones listed.

use crate::common;

use scoring::eval::{EvalOptions, evaluate};

#[test]
fn the_simulated_tasks_are_the_tables_and_a_motionless_robot_fails_one() {
    // Which shipped protocols run (their scene builds): the tasks docs/tasks.md lists and CI's
    // hold column (`make hold-column`) runs every one of under hold, on seeds 0-39, with the
    // checks below for each episode.
    let mut simulated = Vec::new();
    for path in common::shipped_protocols() {
        let name = path.display().to_string();
        let (task, diags) =
            compiler::compile_source(&std::fs::read_to_string(&path).unwrap(), &name);
        let task = task.unwrap_or_else(|| panic!("{name}: {diags:#?}"));
        if runtime::Scene::build(&task, &task.sample(0)).is_err() {
            continue;
        }
        if task.id == "thermal_cycler.close_lid" {
            hold_fails(&task, &name);
        }
        simulated.push(task.id);
    }
    simulated.sort();
    assert_eq!(
        simulated,
        [
            "centrifuge.insert_symmetric",
            "centrifuge.insert_symmetric_rotor_view",
            "centrifuge_5430.close_lid",
            "centrifuge_5430.open_lid",
            "centrifuge_5430.open_then_close",
            "centrifuge_5910.close_lid",
            "centrifuge_5910.close_lid_riser",
            "centrifuge_5910.open_lid",
            "centrifuge_5910.open_then_close",
            "centrifuge_mini.close_lid",
            "centrifuge_mini.open_lid",
            "centrifuge_mini.open_then_close",
            "lab.dilution",
            "lab.heat_shock",
            "lab.incubation_series",
            "lab.miniprep_spins",
            "lab.mix_by_inversion",
            "lab.pcr",
            "lab.pcr_run",
            "lab.pcr_setup",
            "lab.spin",
            "pipette.aspirate",
            "pipette.transfer",
            "thermal_cycler.close_lid",
            "thermal_cycler.close_then_open",
            "thermal_cycler.open_and_close",
            "thermal_cycler.open_lid",
            "thermal_cycler.open_then_close",
            "thermal_mixer.set_parameters",
            "thermal_mixer.set_parameters_legible",
            "tube.pick_up",
            "tube.recap",
            "tube.screw_cap",
            "tube.transfer",
            "tube.unscrew_cap",
            "two_arm.close_lid_and_transfer",
            "vortex_mixer.mix_tube",
            "workflows.bench_run",
            "workflows.centrifuge_run",
            "workflows.mixer_cycle",
            "workflows.mixer_run",
        ]
    );
}

/// `task` under `hold` on seed 0: no error, not won, score 0, some measured check failing (not
/// only checks that cannot be measured), run to its time limit (nothing ended it early).
fn hold_fails(task: &compiler::Task, name: &str) {
    let opts = EvalOptions {
        policy: scoring::policies::PolicySpec::Hold,
        episodes: 1,
        seed: 0,
        ..Default::default()
    };
    let report = evaluate(task, &opts, |_| {}).unwrap();
    assert_eq!(report.policy, "hold");
    let e = &report.episodes[0];
    assert!(e.error.is_none(), "{name}: {:?}", e.error);
    assert!(!e.success, "{name} passes with no motion: {:#?}", e.verdict);
    assert!(
        e.verdict
            .predicates()
            .iter()
            .any(|p| !p.value.is_nan() && !p.holds),
        "{name}: every measured check holds without motion: {:#?}",
        e.verdict
    );
    assert_eq!(e.verdict.score, 0.0, "{name}: {:#?}", e.verdict);
    assert!(
        (e.sim_time_s - task.stages[0].time_limit_s).abs() < 0.05,
        "{name}"
    );
}

#[test]
fn policies_are_made_by_name() {
    let path = "protocols/thermal_cycler/open_lid.toml";
    let (task, _) = compiler::compile_source(&std::fs::read_to_string(path).unwrap(), path);
    let task = task.unwrap();
    let instance = task.sample(0);
    let scene = runtime::Scene::build(&task, &instance).unwrap();
    for name in ["expert", "hold"] {
        let p = scoring::policies::make(name, &task, &scene, &instance).unwrap();
        assert_eq!(p.name(), name);
    }
    assert!(scoring::policies::known("replay:out/demo") && !scoring::policies::known("replay:"));
    // A replay needs its recording: its absence is that episode's policy error, named.
    let err = scoring::policies::make("replay:no/such/folder", &task, &scene, &instance)
        .err()
        .unwrap()
        .to_string();
    assert!(
        err.contains("replay of no/such/folder: cannot read the recording"),
        "{err}"
    );
    let err = scoring::policies::make("random", &task, &scene, &instance)
        .err()
        .unwrap()
        .to_string();
    assert!(
        err.contains("unknown policy `random`") && err.contains("expert, hold, replay:"),
        "{err}"
    );
}
