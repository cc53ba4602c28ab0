//! A two-arm episode end to end: two UR5e arms on one bench, each doing its own step (one closes
//! and latches the thermal cycler, the other carries a tube between racks). Observations and
//! actions concatenate both arms (7 + 7), the expert routes each step to the arm its `with` names,
//! and the recording has one joint-state and one action channel per arm.

use expert::ExpertPolicy;
use scoring::episode::{EpisodeOptions, run_episode};
use std::sync::Arc;

#[test]
fn each_arm_does_its_own_step_and_both_are_recorded() {
    let path = "protocols/two_arm/close_lid_and_transfer.toml";
    let (task, diags) = compiler::compile_source(&std::fs::read_to_string(path).unwrap(), path);
    let task = task.unwrap_or_else(|| panic!("{diags:#?}"));
    let instance = task.sample(4);
    let scene = Arc::new(runtime::Scene::build(&task, &instance).unwrap());
    assert_eq!(scene.action_len(), 14);
    let ep = runtime::Episode::new(scene.clone(), &task, &instance);
    assert_eq!(ep.state().len(), 14);
    assert_eq!(ep.ctrl().len(), 14);
    let dir = std::env::temp_dir().join(format!("autobio-two-arms-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let rec_path = dir.join("two.mcap");
    let mut expert = ExpertPolicy::new(&task, &scene, &instance).unwrap();
    let r = run_episode(
        &task,
        &scene,
        &instance,
        &mut expert,
        &EpisodeOptions {
            record: Some(rec_path.clone()),
            image_every: 0,
            ..Default::default()
        },
    )
    .unwrap();
    assert!(r.success, "{:?} {:#?}", r.error, r.verdict);
    assert!(r.verdict.predicates().iter().all(|p| p.holds));

    // Each arm's recorded joints: the lid arm moves only during its step, the tube arm only after.
    let rec = results::recording::read_recording(&rec_path).unwrap();
    for arm in ["lidder", "mover"] {
        assert_eq!(
            rec.topics[&format!("/robot/{arm}/joint_state")],
            r.control_steps
        );
        assert_eq!(rec.topics[&format!("/robot/{arm}/action")], r.control_steps);
    }
    let buf = std::fs::read(&rec_path).unwrap();
    let mut stage_times = Vec::new();
    let mut moved: Vec<(String, f64)> = Vec::new();
    let mut last: std::collections::BTreeMap<String, Vec<f64>> = Default::default();
    for m in mcap::MessageStream::new(&buf).unwrap() {
        let m = m.unwrap();
        if m.channel.message_encoding != "json" {
            continue; // MuJoCo's state and camera frames are protobuf
        }
        let v: serde_json::Value = serde_json::from_slice(&m.data).unwrap();
        let t = m.log_time as f64 * 1e-9;
        if m.channel.topic == "/stage" {
            let label = v["label"].as_str().unwrap().to_string();
            if label.starts_with("step ") {
                stage_times.push((label, t));
            }
        } else if let Some(arm) = m.channel.topic.strip_suffix("/action") {
            let a: Vec<f64> = serde_json::from_value(v["action"].clone()).unwrap();
            assert_eq!(a.len(), 7);
            let arm = arm.trim_start_matches("/robot/").to_string();
            if last.get(&arm).is_some_and(|prev| prev != &a) {
                moved.push((arm.clone(), t));
            }
            last.insert(arm, a);
        }
    }
    let labels: Vec<&str> = stage_times.iter().map(|(l, _)| l.as_str()).collect();
    assert_eq!(
        labels,
        [
            "step 1: close_lid cycler with lidder",
            "step 2: pick tube with mover",
            "step 3: place tube with mover"
        ]
    );
    let handover = stage_times[1].1;
    let lidder_moves: Vec<f64> = moved
        .iter()
        .filter(|(a, _)| a == "lidder")
        .map(|m| m.1)
        .collect();
    let mover_moves: Vec<f64> = moved
        .iter()
        .filter(|(a, _)| a == "mover")
        .map(|m| m.1)
        .collect();
    assert!(!lidder_moves.is_empty() && !mover_moves.is_empty());
    assert!(
        lidder_moves.iter().all(|t| *t <= handover + 1e-9),
        "the lid arm moved after its step"
    );
    assert!(
        mover_moves.iter().all(|t| *t >= handover - 1e-9),
        "the tube arm moved during the lid step"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Both arms at once: with the tube's pick marked `together` with the lid's closing, the mover
/// starts at the first control step beside the lidder (one motion lane per robot), the episode
/// still succeeds, and it ends sooner than the same steps run one after another.
#[test]
fn steps_marked_together_move_both_arms_in_the_same_control_steps() {
    let path = "protocols/two_arm/close_lid_and_transfer.toml";
    let text = std::fs::read_to_string(path).unwrap();
    let together = text.replace(
        "do = \"pick\"\non = \"tube\"\nwith = \"mover\"",
        "do = \"pick\"\non = \"tube\"\nwith = \"mover\"\ntogether = true",
    );
    assert_ne!(together, text, "the edit applies");
    let compile = |t: &str| {
        let (task, diags) = compiler::compile_source(t, path);
        task.unwrap_or_else(|| panic!("{diags:#?}"))
    };
    let (sequential, parallel) = (compile(&text), compile(&together));
    assert!(parallel.stages[0].plan[1].together && !sequential.stages[0].plan[1].together);
    assert!(compiler::describe::describe(&parallel).contains("with mover, together with step 1"));
    assert!(!compiler::describe::describe(&sequential).contains("together"));
    let run = |task: &compiler::Task| {
        let instance = task.sample(4);
        let scene = Arc::new(runtime::Scene::build(task, &instance).unwrap());
        let mut expert = ExpertPolicy::new(task, &scene, &instance).unwrap();
        let mut starts = Vec::new();
        let mut env = runtime::Env::new(scene.clone(), task, &instance, Default::default());
        while !env.done() {
            let seen = env.observe();
            let obs = policy::Observation {
                time: seen.time,
                state: seen.state,
                stage: seen.stage,
                prompt: &seen.instruction,
                images: &[],
                previous: &[],
                environment_state: Vec::new(),
                privileged: policy::Privileged {
                    robots: seen.robots,
                    labware: seen.labware,
                    qpos: seen.qpos,
                },
            };
            let chunk = policy::Policy::act(&mut expert, &obs).unwrap();
            for e in policy::Policy::drain_events(&mut expert) {
                if e.label.starts_with("step ") {
                    starts.push((e.label, e.time));
                }
            }
            for a in chunk {
                if env.step(&a).unwrap().done() {
                    break;
                }
            }
        }
        (env.verdict().success, env.time(), starts)
    };
    let (ok_seq, t_seq, starts_seq) = run(&sequential);
    let (ok_par, t_par, starts_par) = run(&parallel);
    assert!(ok_seq && ok_par, "{starts_seq:?} {starts_par:?}");
    let started = |starts: &[(String, f64)], prefix: &str| {
        starts
            .iter()
            .find(|(l, _)| l.starts_with(prefix))
            .map(|(_, t)| *t)
            .unwrap()
    };
    assert_eq!(
        started(&starts_par, "step 2"),
        started(&starts_par, "step 1")
    );
    assert!(started(&starts_seq, "step 2") > 2.0, "{starts_seq:?}");
    assert!(
        t_par < t_seq - 2.0,
        "together {t_par} s, one after another {t_seq} s"
    );
}
