//! End-to-end episodes on real MuJoCo: the scripted expert succeeds on both thermal-cycler
//! protocols, the same seed reproduces the same trajectory bit for bit, an episode that leaves the
//! lid open fails, and a recording re-scores offline to the same verdict.

use expert::ExpertPolicy;
use results::verdict::Judge;
use scoring::episode::{EpisodeOptions, run_episode};
use scoring::policies::HoldPolicy;
use std::path::Path;
use std::sync::Arc;

fn task(name: &str) -> compiler::Task {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("protocols/thermal_cycler")
        .join(name);
    let source = std::fs::read_to_string(&path).unwrap();
    let (task, diags) = compiler::compile_source(&source, name);
    task.unwrap_or_else(|| panic!("{name}: {diags:?}"))
}

fn expert_episode(
    task: &compiler::Task,
    seed: u64,
    opts: &EpisodeOptions,
) -> results::episode::EpisodeResult {
    let instance = task.sample(seed);
    let scene = Arc::new(runtime::Scene::build(task, &instance).unwrap());
    let mut expert = ExpertPolicy::new(task, &scene, &instance).unwrap();
    run_episode(task, &scene, &instance, &mut expert, opts).unwrap()
}

#[test]
fn expert_succeeds_on_three_seeded_episodes() {
    for (name, seed) in [
        ("close_lid.toml", 11),
        ("open_lid.toml", 12),
        ("close_lid.toml", 13),
    ] {
        let t = task(name);
        let r = expert_episode(&t, seed, &EpisodeOptions::default());
        assert!(
            r.success,
            "{name} seed {seed}: {:?} {:?}",
            r.error, r.verdict
        );
        assert!(r.sim_time_s < t.time_limit_s);
    }
}

#[test]
fn same_seed_same_trajectory() {
    let t = task("open_lid.toml");
    let a = expert_episode(&t, 5, &EpisodeOptions::default());
    let b = expert_episode(&t, 5, &EpisodeOptions::default());
    assert_eq!(a.trajectory_hash, b.trajectory_hash);
    assert_eq!(a.control_steps, b.control_steps);
    let c = expert_episode(&t, 6, &EpisodeOptions::default());
    assert_ne!(
        a.trajectory_hash, c.trajectory_hash,
        "different seeds start the arm elsewhere"
    );
}

#[test]
fn an_episode_that_leaves_the_lid_open_fails() {
    let mut t = task("close_lid.toml");
    t.time_limit_s = 2.0;
    let instance = t.sample(1);
    let scene = Arc::new(runtime::Scene::build(&t, &instance).unwrap());
    let r = run_episode(
        &t,
        &scene,
        &instance,
        &mut HoldPolicy,
        &EpisodeOptions::default(),
    )
    .unwrap();
    assert!(!r.success);
    assert!(r.error.is_none(), "{:?}", r.error);
    let closed = &r.verdict.predicates()[0];
    assert!(
        !closed.holds && closed.value.abs() < 0.05,
        "the lid stays open: {closed:?}"
    );
    assert!((r.sim_time_s - 2.0).abs() < 0.05);
}

#[test]
fn recording_rescores_offline_to_the_same_verdict() {
    let t = task("close_lid.toml");
    let dir = std::env::temp_dir().join(format!("autobio-test-rec-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("ep.mcap");
    let r = expert_episode(
        &t,
        3,
        &EpisodeOptions {
            record: Some(path.clone()),
            image_every: 25,
            ..Default::default()
        },
    );
    assert!(r.success);
    let rec = results::recording::read_recording(&path).unwrap();
    assert_eq!(rec.topics["/task"], 1);
    assert_eq!(rec.topics["/robot/arm/joint_state"], r.control_steps);
    assert_eq!(rec.topics["/robot/arm/action"], r.control_steps);
    assert!(rec.topics["/camera/table_front"] >= r.control_steps / 25);
    assert!(rec.topics["/camera/arm/wrist"] >= 1);
    let replayed: compiler::Task = serde_json::from_value(rec.task).unwrap();
    assert_eq!(replayed, t);
    let params: compiler::params::Bindings =
        serde_json::from_value(rec.instance["params"].clone()).unwrap();
    assert_eq!(
        Judge::replay(&replayed, &params, &rec.labware_series),
        r.verdict
    );
    // The CLI agrees, without simulating.
    let replay = stdout_of(
        std::process::Command::new(env!("CARGO_BIN_EXE_autobio"))
            .arg("replay")
            .arg(&path),
    );
    assert!(replay.contains("re-scored: success"));
    // Foxglove's own reader (the `mcap` Python package that `make setup` installs) agrees on the
    // channels, their schemas and every message count.
    let script = r#"
import sys, collections
from mcap.reader import make_reader
with open(sys.argv[1], "rb") as f:
    r = make_reader(f)
    s = r.get_summary()
    counts = collections.Counter(c.topic for _, c, _ in r.iter_messages())
    for c in s.channels.values():
        print(c.topic, s.schemas[c.schema_id].name, counts[c.topic])
    print("total", s.statistics.message_count)
"#;
    let deps = Path::new(env!("CARGO_MANIFEST_DIR")).join(".deps/python");
    let listing = stdout_of(
        std::process::Command::new("python3")
            .args(["-c", script])
            .arg(&path)
            .env("PYTHONPATH", &deps),
    );
    for (topic, n) in &rec.topics {
        let line = listing
            .lines()
            .find(|l| l.starts_with(&format!("{topic} ")))
            .unwrap_or_else(|| panic!("{topic} missing from {listing}"));
        assert!(line.ends_with(&format!(" {n}")), "{line} vs {n}");
    }
    assert!(listing.contains("/camera/table_front foxglove.CompressedImage"));
    assert!(listing.contains(&format!("total {}", rec.messages)));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Runs a command, asserts it succeeded, and returns its standard output.
fn stdout_of(cmd: &mut std::process::Command) -> String {
    let out = cmd.output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}
