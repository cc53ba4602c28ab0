//! The step-wise environment driven by hand, as a Python binding or a gym loop would drive it:
//! `reset(seed)`, then `observe` and `step(action)` with the scripted expert's actions, gives the
//! trajectory hash `autobio eval` reports for that seed (run as the real CLI), ends `terminated`
//! with the task's score as its reward, and refuses a step after the end. Under no motion the
//! episode is `truncated` at the time limit with reward 0.

use crate::common;

use policy::{Observation, Policy, Privileged};
use results::end::EpisodeEnd;
use runtime::{Env, EnvError, EnvOptions};
use std::process::Command;

/// One query of `policy` on the environment's state now (no images: the expert and hold need
/// none).
fn act(env: &Env, policy: &mut dyn Policy) -> Vec<Vec<f64>> {
    let seen = env.observe();
    let obs = Observation {
        time: seen.time,
        state: seen.state,
        stage: seen.stage,
        prompt: &seen.instruction,
        images: &[],
        previous: &[],
        environment_state: Vec::new(),
        privileged: Privileged {
            robots: seen.robots,
            labware: seen.labware,
            qpos: seen.qpos,
        },
    };
    policy.act(&obs).expect("the policy answers")
}

/// Steps `env` to its end with `policy`; the last transition.
fn run_to_end(env: &mut Env, policy: &mut dyn Policy) -> runtime::Transition {
    loop {
        for action in act(env, policy) {
            let t = env.step(&action).expect("a valid step");
            if t.done() {
                return t;
            }
            assert_eq!(t.reward, 0.0, "no reward before the end");
        }
    }
}

/// The trajectory hash `autobio eval` reports for `seed` of the protocol.
fn eval_hash(protocol: &str, seed: u64) -> String {
    let out = common::scratch(&format!("by-hand-eval-{seed}"));
    let status = Command::new(env!("CARGO_BIN_EXE_autobio"))
        .args(["eval", "--protocol", protocol, "--episodes", "1"])
        .args(["--seed", &seed.to_string(), "--out"])
        .arg(&out)
        .output()
        .expect("autobio runs");
    assert!(status.status.success(), "{status:?}");
    let task = common::compile(protocol);
    let text = std::fs::read_to_string(out.join(format!("{}.results.json", task.id))).unwrap();
    let results: serde_json::Value = serde_json::from_str(&text).unwrap();
    results["episodes"][0]["trajectory_hash"]
        .as_str()
        .unwrap()
        .to_string()
}

#[test]
fn stepping_by_hand_with_the_experts_actions_gives_evals_trajectory() {
    let protocol = "protocols/thermal_cycler/close_lid.toml";
    let task = common::compile(protocol);
    let seed = 3;
    let mut env = Env::make(&task, seed, EnvOptions::default()).unwrap();
    let mut expert = scoring::policies::make("expert", &task, env.scene(), env.instance()).unwrap();
    let end = run_to_end(&mut env, expert.as_mut());
    assert!(end.terminated && !end.truncated, "{end:?}");
    assert_eq!(end.reward, 1.0);
    assert_eq!(end.end, Some(EpisodeEnd::Success));
    assert_eq!(env.end(), Some(EpisodeEnd::Success));
    assert!(env.verdict().success);
    let by_hand = env.trajectory_hash();
    assert_eq!(by_hand, eval_hash(protocol, seed));
    assert!(matches!(env.step(&[0.0; 7]), Err(EnvError::Over)));

    // reset(seed) starts the same episode again: the same actions, the same trajectory.
    let first = env.reset(seed).unwrap();
    assert_eq!(first.time, 0.0);
    assert_eq!(env.control_steps(), 0);
    let mut expert = scoring::policies::make("expert", &task, env.scene(), env.instance()).unwrap();
    run_to_end(&mut env, expert.as_mut());
    assert_eq!(env.trajectory_hash(), by_hand);

    // Another seed is another episode.
    env.reset(seed + 1).unwrap();
    let mut expert = scoring::policies::make("expert", &task, env.scene(), env.instance()).unwrap();
    run_to_end(&mut env, expert.as_mut());
    assert_ne!(env.trajectory_hash(), by_hand);
}

#[test]
fn no_motion_is_truncated_at_the_time_limit_with_no_reward() {
    let task = common::compile("protocols/thermal_cycler/close_lid.toml");
    let mut env = Env::make(&task, 0, EnvOptions::default()).unwrap();
    let mut hold = scoring::policies::HoldPolicy;
    let end = run_to_end(&mut env, &mut hold);
    assert!(end.truncated && !end.terminated, "{end:?}");
    assert_eq!(end.reward, 0.0);
    assert_eq!(end.end, Some(EpisodeEnd::TimeLimit));
    let period = task.physics.timestep_s * task.physics.substeps as f64;
    assert!(
        end.time >= task.time_limit_s - 1e-6 && end.time < task.time_limit_s + period - 1e-6,
        "every control step up to the limit, and no more: {end:?}"
    );
}

#[test]
fn frames_are_drawn_at_the_tasks_camera_size_unless_overridden() {
    let task = common::compile("protocols/thermal_cycler/close_lid.toml");
    let mut env = Env::make(&task, 0, EnvOptions::default()).unwrap();
    let spec = &task.cameras[0];
    let frames = env.frames().unwrap().to_vec();
    assert_eq!(frames.len(), task.cameras.len());
    assert_eq!(
        [frames[0].width, frames[0].height],
        [spec.width as usize, spec.height as usize]
    );
    let mut small = Env::make(
        &task,
        0,
        EnvOptions {
            image_size: Some([64, 48]),
            ..Default::default()
        },
    )
    .unwrap();
    let f = &small.frames().unwrap()[0];
    assert_eq!([f.width, f.height, f.rgb.len()], [64, 48, 64 * 48 * 3]);
    // A bad action is refused with a typed error and ends the episode as the policy's error.
    assert_eq!(env.end(), None, "the episode runs");
    assert!(matches!(
        env.step(&[0.0; 3]),
        Err(EnvError::Step(runtime::StepError::BadAction { got: 3, .. }))
    ));
    assert_eq!(
        env.end(),
        Some(EpisodeEnd::PolicyError(
            "action has 3 values, the robots take 7".into()
        ))
    );
    assert!(matches!(env.step(&[0.0; 7]), Err(EnvError::Over)));
}

/// An unstable simulation (a timestep the arm's servos cannot take, as in
/// tests/episode_failures.rs) is no error of the caller's: its step is truncated, scores 0 and
/// carries the end with its reason, which the environment then reports.
#[test]
fn an_unstable_simulation_ends_the_step_truncated_with_its_reason() {
    let mut task = common::compile("protocols/thermal_cycler/close_lid.toml");
    task.physics.timestep_s = 0.05;
    task.physics.substeps = 1;
    let mut env = Env::make(&task, 0, EnvOptions::default()).unwrap();
    let mut expert = scoring::policies::make("expert", &task, env.scene(), env.instance()).unwrap();
    let end = run_to_end(&mut env, expert.as_mut());
    assert!(end.truncated && !end.terminated, "{end:?}");
    assert_eq!(end.reward, 0.0);
    let Some(EpisodeEnd::Unstable(why)) = &end.end else {
        panic!("not an unstable end: {end:?}");
    };
    assert!(why.starts_with("simulation became unstable at t="), "{why}");
    assert_eq!(env.end(), end.end);
    assert!(matches!(env.step(&[0.0; 7]), Err(EnvError::Over)));
}
