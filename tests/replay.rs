//! Recordings replay to the verdict the live episode had, for a long-horizon chain (stage by
//! stage), under progress scoring (a partial score) and for a timed-out episode; a recording of
//! another schema version is refused by name; the camera images a recording carries show the
//! scene (not a blank frame) and change as the robot moves; re-simulating from the recorded state
//! (from the start or mid-episode) repeats every state and the trajectory hash, and a tampered
//! state is caught; redrawing the cameras from the recorded state gives the recorded frames byte
//! for byte; and mcap's own protobuf decoder reads the binary channels.

use crate::common;
use results::recording::{RecordError, Recorder, proto, read_recording};

use common::{compile, compile_edited, spread};
use results::verdict::Judge;
use scoring::episode::EpisodeOptions;
use std::path::PathBuf;

fn temp(name: &str) -> PathBuf {
    common::scratch(name).join(name)
}

/// Runs and records an episode; returns the live result and the replayed verdict.
fn record_and_replay(
    task: &compiler::Task,
    seed: u64,
    expert: bool,
    image_every: u32,
    name: &str,
) -> (
    results::episode::EpisodeResult,
    results::verdict::Verdict,
    PathBuf,
) {
    let path = temp(name);
    let opts = EpisodeOptions {
        record: Some(path.clone()),
        image_every,
        ..Default::default()
    };
    let policy = if expert { "expert" } else { "hold" };
    let live = common::run_with(task, seed, &opts, |t, s, i| {
        scoring::policies::make(policy, t, s, i).unwrap()
    });
    let rec = read_recording(&path).unwrap();
    let replayed: compiler::Task = serde_json::from_value(rec.task).unwrap();
    let params: compiler::params::Bindings =
        serde_json::from_value(rec.instance["params"].clone()).unwrap();
    let verdict = Judge::replay(&replayed, &params, &rec.labware_series);
    (live, verdict, path)
}

/// RGB frames of one camera channel, in time order.
fn frames(path: &PathBuf, topic: &str) -> Vec<Vec<u8>> {
    let bytes = std::fs::read(path).unwrap();
    mcap::MessageStream::new(&bytes)
        .unwrap()
        .map(|m| m.unwrap())
        .filter(|m| m.channel.topic == topic)
        .map(|m| {
            assert_eq!(m.channel.message_encoding, "protobuf");
            let png = proto::image_data(&m.data).expect("a CompressedImage");
            let img = results::Image::from_png("", png).unwrap();
            assert_eq!((img.width, img.height), (224, 224));
            img.rgb
        })
        .collect()
}

fn mean_abs_diff(a: &[u8], b: &[u8]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| f64::from(x.abs_diff(*y)))
        .sum::<f64>()
        / a.len() as f64
}

#[test]
fn a_chain_replays_stage_by_stage_and_its_images_show_the_motion() {
    let task = compile("protocols/thermal_cycler/close_then_open.toml");
    let (live, replayed, path) = record_and_replay(&task, 2, true, 10, "chain.mcap");
    assert!(live.success, "{:?}", live.error);
    assert_eq!(live.outcome, results::episode::Outcome::Success);
    assert_eq!(replayed, live.verdict);
    assert_eq!(replayed.stages.len(), 2);
    // Scored apart from success: both stages count.
    assert_eq!(replayed.score, 1.0, "both stages done");

    for topic in ["/camera/table_front", "/camera/arm/wrist"] {
        let f = frames(&path, topic);
        assert!(f.len() >= 10, "{topic}: {} frames", f.len());
        for (i, frame) in f.iter().enumerate() {
            assert_eq!(frame.len(), 224 * 224 * 3);
            assert!(
                spread(frame) > 10.0,
                "{topic} frame {i} is blank: {}",
                spread(frame)
            );
        }
        // The arm closes the lid and opens it again: the first and the middle frames differ.
        let change = mean_abs_diff(&f[0], &f[f.len() / 2]);
        assert!(change > 2.0, "{topic}: frames barely change ({change})");
    }
}

#[test]
fn a_progress_scored_episode_replays_to_its_partial_score() {
    let task = compile_edited("protocols/thermal_cycler/close_lid.toml", |s| {
        s.replace("time_limit = \"31.5 s\"", "time_limit = \"7 s\"")
            .replace(
                "all = [\"cycler.lid is closed\", \"cycler.lid is locked\"]",
                "all = [\"cycler.lid is closed\", \"cycler.lid is locked\"]\nscoring = \"progress\"",
            )
    });
    let (live, replayed, _) = record_and_replay(&task, 5, true, 0, "progress.mcap");
    assert!(!live.success);
    assert!(
        live.verdict.score > 0.0 && live.verdict.score < 1.0,
        "{:?}",
        live.verdict
    );
    assert_eq!(replayed, live.verdict);
}

#[test]
fn a_timed_out_episode_replays_to_its_failure() {
    let mut task = compile("protocols/tube/transfer.toml");
    task.time_limit_s = 1.0;
    task.stages[0].time_limit_s = 1.0;
    let (live, replayed, _) = record_and_replay(&task, 8, false, 0, "timeout.mcap");
    assert!(!live.success && live.error.is_none());
    assert_eq!(live.outcome, results::episode::Outcome::TimeLimit);
    assert!((live.sim_time_s - 1.0).abs() < 0.05);
    assert_eq!(replayed, live.verdict);
}

#[test]
fn a_recording_of_another_schema_version_is_refused() {
    let path = temp("old.mcap");
    let mut r = Recorder::create(&path).unwrap();
    r.write(
        "/task",
        "autobio.Task",
        0.0,
        &serde_json::json!({"schema_version": 1, "task": {}, "instance": {}}),
    )
    .unwrap();
    r.finish().unwrap();
    let Err(err) = read_recording(&path) else {
        panic!("a version-1 recording was read")
    };
    assert!(matches!(err, RecordError::Version { found: 1 }), "{err:?}");
    assert!(err.to_string().contains("schema version 1"), "{err}");
}

#[test]
fn replaying_recorded_actions_reproduces_the_episode_byte_for_byte() {
    let task = compile("protocols/thermal_cycler/close_lid.toml");
    let (live, _, path) = record_and_replay(&task, 7, true, 0, "actions.mcap");
    assert!(live.success);
    let policy = format!("replay:{}", path.display());
    let again = common::run(&task, 7, &policy);
    assert!(again.success, "{:?}", again.error);
    assert_eq!(again.trajectory_hash, live.trajectory_hash);
    assert_eq!(again.control_steps, live.control_steps);
    assert_eq!(again.verdict, live.verdict);
    // Another seed's episode is not this recording's.
    let (instance, scene) = common::scene(&task, 8);
    let err = match scoring::policies::make(&policy, &task, &scene, &instance) {
        Ok(_) => panic!("a seed-7 recording replayed for seed 8"),
        Err(e) => e.to_string(),
    };
    assert!(
        err.contains("it records seed 7, not the episode's seed 8"),
        "{err}"
    );
    // A folder of recordings: the one named for the task and seed is used.
    let dir = path.parent().unwrap();
    std::fs::copy(&path, dir.join("thermal_cycler.close_lid_seed7.mcap")).unwrap();
    let from_folder = common::run(&task, 7, &format!("replay:{}", dir.display()));
    assert_eq!(from_folder.trajectory_hash, live.trajectory_hash);
}

/// The `autobio replay` binary on a recording: status, stdout.
fn replay(args: &[&str]) -> (i32, String) {
    let mut all = vec!["replay"];
    all.extend_from_slice(args);
    let out = common::autobio(&all);
    let text = format!("{}{}", common::text(&out.stdout), common::text(&out.stderr));
    (out.status.code().unwrap_or(-1), text)
}

/// A copy of `path` with one recorded MuJoCo state changed (the first qpos value at `step`).
fn tampered(path: &std::path::Path, step: usize, name: &str) -> PathBuf {
    let out = temp(name);
    let mut w = Recorder::create(&out).unwrap();
    let mut k = 0;
    results::recording::for_each_message(path, |m| {
        if m.channel.topic != "/physics/state" {
            return w.pass(m);
        }
        let (spec, mut state) = proto::state_values(&m.data).unwrap();
        if k == step {
            state[1] += 1e-9;
        }
        k += 1;
        let mut changed = m.clone();
        changed.data = std::borrow::Cow::Owned(proto::physics_state(m.log_time, spec, &state));
        w.pass(&changed)
    })
    .unwrap();
    w.finish().unwrap();
    out
}

#[test]
fn a_recording_resimulates_from_its_state_and_redraws_its_frames_exactly() {
    let task = compile("protocols/thermal_cycler/close_lid.toml");
    let (live, _, path) = record_and_replay(&task, 3, true, 25, "exact.mcap");
    assert!(live.success, "{:?}", live.error);
    let p = path.to_str().unwrap();

    // From the first recorded state and from one mid-episode (instrument logic restored too).
    for from in ["0", "240"] {
        let (code, out) = replay(&[p, "--simulate", "--from-step", from]);
        assert_eq!(code, 0, "{out}");
        assert!(
            out.contains(&format!("  trajectory hash  {}", live.trajectory_hash)),
            "{out}"
        );
        assert!(
            out.contains("every state equal to the recorded one, bit for bit"),
            "{out}"
        );
        assert!(out.contains("reproduced (re-judged: success"), "{out}");
    }
    // A state changed by 1e-9 rad is caught at its step, and the command fails.
    let bad = tampered(&path, 300, "tampered.mcap");
    let (code, out) = replay(&[bad.to_str().unwrap(), "--simulate"]);
    assert_eq!(code, 1, "{out}");
    assert!(
        out.contains("the state first differs at control step 300"),
        "{out}"
    );
    assert!(out.contains("NOT reproduced"), "{out}");
    let (code, out) = replay(&[p, "--simulate", "--from-step", "100000"]);
    assert_eq!(code, 2, "{out}");
    assert!(out.contains("step 100000 is not one of them"), "{out}");

    // Redrawn from the recorded state at the recorded size and cadence: the same frames.
    let again = temp("exact.render.mcap");
    let (code, out) = replay(&[p, "--render", "--out", again.to_str().unwrap()]);
    assert_eq!(code, 0, "{out}");
    for topic in ["/camera/table_front", "/camera/arm/wrist"] {
        let (a, b) = (frames(&path, topic), frames(&again, topic));
        assert!(a.len() >= 10, "{topic}: {} frames", a.len());
        assert_eq!(a.len(), b.len(), "{topic}");
        for (i, (x, y)) in a.iter().zip(&b).enumerate() {
            assert!(x == y, "{topic} frame {i} differs: {}", mean_abs_diff(x, y));
        }
    }
    // Every other message is carried over.
    let (orig, redrawn) = (
        read_recording(&path).unwrap(),
        read_recording(&again).unwrap(),
    );
    assert_eq!(orig.topics, redrawn.topics);
    assert_eq!(orig.physics, redrawn.physics);

    // Another size, every 100 steps, with PNG files.
    let big = temp("exact.big.mcap");
    let pngs = temp("pngs");
    let (code, out) = replay(&[
        p,
        "--render",
        "--size",
        "320x240",
        "--every",
        "100",
        "--out",
        big.to_str().unwrap(),
        "--png",
        pngs.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{out}");
    let steps = live.control_steps as usize;
    let expected = steps.div_ceil(100);
    assert!(
        out.contains(&format!("rendered: {} frames at 320x240", 2 * expected)),
        "{out}"
    );
    let first = std::fs::read(pngs.join("arm_wrist_00000.png")).unwrap();
    let img = results::Image::from_png("wrist", &first).unwrap();
    assert_eq!((img.width, img.height), (320, 240));
    assert!(spread(&img.rgb) > 10.0);
    let (code, out) = replay(&[p, "--render", "--size", "7x7"]);
    assert_eq!(code, 2, "{out}");
    assert!(
        out.contains("`7` is not a side between 16 and 4096 pixels"),
        "{out}"
    );

    // mcap's protobuf decoder (what Foxglove's tooling uses) reads the binary channels.
    let python = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(".deps/servers/bin/python");
    let out = std::process::Command::new(python)
        .arg("tests/recordings/check_recording.py")
        .arg(&path)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", common::text(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    for cam in ["/camera/table_front", "/camera/arm/wrist"] {
        let c = &v["cameras"][cam];
        assert_eq!(c["format"], "png", "{v}");
        assert_eq!(c["sizes"], serde_json::json!([[224, 224]]), "{v}");
        assert_eq!(c["count"].as_u64(), Some(orig.topics[cam]), "{v}");
        assert_eq!(v["topics"][cam]["schema"], "foxglove.CompressedImage");
    }
    assert_eq!(v["state"]["spec"], proto::STATE_SPEC, "{v}");
    assert_eq!(v["state"]["count"].as_u64(), Some(steps as u64 + 1), "{v}");
    assert_eq!(
        v["state"]["lengths"],
        serde_json::json!([orig.physics[0].1.len()])
    );
}
