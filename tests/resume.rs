//! The run record: a run writes its manifest before its first episode; a second run into the same
//! folder is refused unless it resumes; `--resume` continues only when the manifest's fingerprints
//! match, never reruns a finished episode, and survives the evaluating process being killed
//! (SIGKILL) mid-run with no finished episode lost or repeated.

use crate::common;

use common::{autobio, scratch, text};
use scoring::eval::EvalOptions;
use std::path::Path;
use std::time::{Duration, Instant};

const CLOSE: &str = "protocols/thermal_cycler/close_lid.toml";

fn opts(out: &Path, policy: &str, episodes: usize, resume: bool) -> EvalOptions {
    EvalOptions {
        policy: policy.parse().unwrap(),
        episodes,
        seed: 30,
        out: Some(out.to_path_buf()),
        record: false,
        image_every: 0,
        resume,
        ..Default::default()
    }
}

/// A result or summary with its measured times (wall clock, policy latency) removed: what a
/// resumed run must share with a run that was never interrupted.
fn timeless(mut v: serde_json::Value) -> serde_json::Value {
    match &mut v {
        serde_json::Value::Object(map) => {
            map.retain(|k, _| {
                !k.contains("wall") && !k.contains("policy_time") && !k.contains("latency")
            });
            for x in map.values_mut() {
                *x = timeless(x.take());
            }
        }
        serde_json::Value::Array(xs) => {
            for x in xs {
                *x = timeless(x.take());
            }
        }
        _ => {}
    }
    v
}

/// Seeds in the journal, in order.
/// The seeds of the journal's finished lines: a last line still being written (the run is
/// going on) is not one yet.
fn journal_seeds(dir: &Path) -> Vec<u64> {
    let text = std::fs::read_to_string(dir.join("thermal_cycler.close_lid.journal.jsonl"))
        .unwrap_or_default();
    text.split_inclusive('\n')
        .filter(|l| l.ends_with('\n'))
        .map(|l| {
            let v: serde_json::Value = serde_json::from_str(l).unwrap();
            v["seed"].as_u64().unwrap()
        })
        .collect()
}

#[test]
fn a_run_resumes_only_with_matching_fingerprints_and_never_reruns_an_episode() {
    let task = common::compile(CLOSE);
    let dir = scratch("resume");
    scoring::eval::evaluate(&task, &opts(&dir, "hold", 2, false), |_| {}).unwrap();
    let manifest: results::run::record::Manifest = serde_json::from_str(
        &std::fs::read_to_string(dir.join("thermal_cycler.close_lid.manifest.json")).unwrap(),
    )
    .unwrap();
    assert_eq!(
        (
            manifest.task_id.as_str(),
            manifest.policy.as_str(),
            manifest.seed
        ),
        ("thermal_cycler.close_lid", "hold", 30)
    );
    assert_eq!(
        (manifest.episodes, manifest.runs, manifest.shard),
        (2, 1, None)
    );
    // The commit is the checkout's, as git says (`-dirty` when the work tree has changes).
    let head = std::process::Command::new("git")
        .args(["rev-parse", "HEAD"])
        .output()
        .unwrap();
    let head = String::from_utf8(head.stdout).unwrap().trim().to_string();
    assert_eq!(
        manifest
            .git_commit
            .strip_suffix("-dirty")
            .unwrap_or(&manifest.git_commit),
        head
    );
    // The conditions are the protocol's and the robot's, as written there.
    let c = &manifest.conditions;
    assert_eq!(
        (
            c.control_hz,
            c.physics_steps_per_action,
            c.physics_timestep_s,
            c.time_limit_s
        ),
        (50.0, 10, 0.002, 31.5)
    );
    assert_eq!(c.state.len(), 7, "{:?}", c.state);
    assert_eq!(c.state[0], "arm/shoulder_pan_joint (rad)");
    assert_eq!(c.gripper, ["arm: open 0, closed 255"]);
    assert_eq!(manifest.task_sha256.len(), 64);
    assert!(manifest.protocol_sha256.is_some());

    // Into the same folder without --resume: refused, nothing run.
    let err = scoring::eval::evaluate(&task, &opts(&dir, "hold", 2, false), |_| {})
        .unwrap_err()
        .to_string();
    assert!(err.contains("continue it with --resume"), "{err}");
    // With another policy: the fingerprints differ.
    let err = scoring::eval::evaluate(&task, &opts(&dir, "expert", 4, true), |_| {})
        .unwrap_err()
        .to_string();
    assert!(err.contains("measured under another policy;"), "{err}");
    // With an edited protocol: the compiled task differs.
    let mut edited = task.clone();
    edited.time_limit_s += 1.0;
    let err = scoring::eval::evaluate(&edited, &opts(&dir, "hold", 4, true), |_| {})
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("measured under another compiled task"),
        "{err}"
    );
    assert_eq!(journal_seeds(&dir), [30, 31]);

    // Matching: only the episodes not yet run are run, and the report has them all.
    let mut ran = Vec::new();
    let report = scoring::eval::evaluate(&task, &opts(&dir, "hold", 4, true), |p| {
        ran.push(p.result.seed)
    })
    .unwrap();
    assert_eq!(ran, [32, 33]);
    assert_eq!(report.episodes.len(), 4);
    assert_eq!(journal_seeds(&dir), [30, 31, 32, 33]);
    // The resumed run is the run that was never interrupted, episode for episode (trajectory
    // hashes included) and in its summary, all but the measured times.
    let whole = scoring::eval::evaluate(
        &task,
        &opts(&scratch("resume-whole"), "hold", 4, false),
        |_| {},
    )
    .unwrap();
    let json = |x: serde_json::Result<serde_json::Value>| timeless(x.unwrap());
    assert_eq!(
        json(serde_json::to_value(&report.episodes)),
        json(serde_json::to_value(&whole.episodes))
    );
    assert_eq!(
        json(serde_json::to_value(&report.summary)),
        json(serde_json::to_value(&whole.summary))
    );
}

#[test]
fn a_killed_run_resumes_with_nothing_lost_or_repeated() {
    let dir = scratch("killed");
    let d = dir.to_str().unwrap();
    let args = [
        "eval",
        "--protocol",
        CLOSE,
        "--policy",
        "hold",
        "--episodes",
        "12",
        "--seed",
        "30",
        "--out",
        d,
    ];
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_autobio"))
        .args(args)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    // Killed as soon as the first episode is in the journal.
    let deadline = Instant::now() + Duration::from_secs(120);
    while journal_seeds(&dir).is_empty() {
        assert!(Instant::now() < deadline, "no episode finished in 120 s");
        std::thread::sleep(Duration::from_millis(5));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let before = journal_seeds(&dir);
    assert!(
        !before.is_empty() && before.len() < 12,
        "killed after {before:?}"
    );

    let mut resumed: Vec<&str> = args.to_vec();
    resumed.push("--resume");
    let out = autobio(&resumed);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let after = journal_seeds(&dir);
    assert_eq!(
        after,
        (30..42).collect::<Vec<u64>>(),
        "each seed once, in order"
    );
    assert_eq!(
        &after[..before.len()],
        &before[..],
        "finished lines kept as they were"
    );
    let read = |dir: &Path| -> serde_json::Value {
        serde_json::from_str(
            &std::fs::read_to_string(dir.join("thermal_cycler.close_lid.results.json")).unwrap(),
        )
        .unwrap()
    };
    let results = read(&dir);
    assert_eq!(results["summary"]["episodes"], 12);
    // The same run never killed: the same episodes (hashes included) and summary, but for the
    // measured times.
    let whole = scratch("killed-whole");
    let mut uninterrupted = args.to_vec();
    let w = whole.to_str().unwrap();
    *uninterrupted.last_mut().unwrap() = w;
    let out = autobio(&uninterrupted);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let whole = read(&whole);
    assert_eq!(
        timeless(results["episodes"].clone()),
        timeless(whole["episodes"].clone())
    );
    assert_eq!(
        timeless(results["summary"].clone()),
        timeless(whole["summary"].clone())
    );
}

#[test]
fn an_episode_whose_policy_cannot_be_made_fails_alone() {
    // Replays of a folder that has a recording of seed 30 only: seed 31's episode fails with the
    // reason, the run goes on, and both stay in the denominator.
    let task = common::compile(CLOSE);
    let recorded = scratch("recorded");
    let mut o = opts(&recorded, "expert", 1, false);
    o.record = true;
    scoring::eval::evaluate(&task, &o, |_| {}).unwrap();
    let policy = format!("replay:{}", recorded.display());
    let report =
        scoring::eval::evaluate(&task, &opts(&scratch("partial"), &policy, 2, false), |_| {})
            .unwrap();
    let [first, second] = &report.episodes[..] else {
        panic!("{report:#?}")
    };
    assert!(first.success);
    assert_eq!(second.outcome, results::episode::Outcome::PolicyError);
    let why = second.error.as_deref().unwrap();
    assert!(
        why.contains("seed31.mcap: cannot read the recording"),
        "{why}"
    );
    assert_eq!(report.summary.episodes, 2);
    assert_eq!(report.summary.success_rate, 0.5);
}

/// A journal whose last line a crash cut short resumes from the last whole line (the fragment is
/// dropped and its episode run again); a whole line that does not parse is not silently dropped:
/// resuming refuses, naming the line, and leaves the journal as it was.
#[test]
fn a_cut_short_journal_resumes_and_a_garbled_one_is_refused() {
    let dir = scratch("cut-journal");
    let journal = dir.join("thermal_cycler.close_lid.journal.jsonl");
    let task = common::compile(CLOSE);
    scoring::eval::evaluate(&task, &opts(&dir, "hold", 3, false), |_| {}).unwrap();
    let whole = std::fs::read_to_string(&journal).unwrap();
    let lines: Vec<&str> = whole.lines().collect();
    assert_eq!(lines.len(), 3);
    // Two whole lines and half of the third, as a crash mid-write leaves it.
    let cut = format!(
        "{}\n{}\n{}",
        lines[0],
        lines[1],
        &lines[2][..lines[2].len() / 2]
    );
    std::fs::write(&journal, &cut).unwrap();
    let report = scoring::eval::evaluate(&task, &opts(&dir, "hold", 3, true), |_| {}).unwrap();
    assert_eq!(report.episodes.len(), 3);
    assert_eq!(journal_seeds(&dir), [30, 31, 32]);
    let resumed = std::fs::read_to_string(&journal).unwrap();
    assert!(resumed.starts_with(&format!("{}\n{}\n", lines[0], lines[1])));
    assert_eq!(resumed.lines().count(), 3);
    assert!(resumed.ends_with('\n'));
    // The episode run again is the one the crash cut short, to its trajectory hash.
    let parse = |line: &str| timeless(serde_json::from_str(line).unwrap());
    assert_eq!(parse(resumed.lines().nth(2).unwrap()), parse(lines[2]));

    // A whole line that is not an episode result.
    let garbled = format!("{}\n{{\"not\": \"an episode\"}}\n", lines[0]);
    std::fs::write(&journal, &garbled).unwrap();
    let err = match scoring::eval::evaluate(&task, &opts(&dir, "hold", 3, true), |_| {}) {
        Ok(_) => panic!("a garbled journal was resumed"),
        Err(e) => e.to_string(),
    };
    assert!(err.contains("line 2 is not an episode result"), "{err}");
    assert_eq!(std::fs::read_to_string(&journal).unwrap(), garbled);
}

/// `autobio demo` killed in the middle of an episode's recording, then resumed: the finished
/// recordings are kept, the cut one never carried a recording's name (only `.partial`), and the
/// resumed run records it again; every recording then replays to its recorded success.
#[test]
fn a_demo_killed_mid_episode_resumes_with_whole_recordings() {
    let dir = scratch("killed-demo");
    let d = dir.to_str().unwrap();
    let args = [
        "demo",
        "--protocol",
        CLOSE,
        "--episodes",
        "3",
        "--seed",
        "0",
        "--out",
        d,
    ];
    let recording = |seed: u64| dir.join(format!("thermal_cycler.close_lid_seed{seed}.mcap"));
    let partial = dir.join("thermal_cycler.close_lid_seed1.mcap.partial");
    // Killed while seed 1 is being recorded: seed 0 finished, seed 1's partial file started. The
    // kill lands when the test sees that state; on a loaded machine seed 1 may finish first, and
    // the run is then started again (a fresh folder), up to five times.
    let mut killed_mid_episode = false;
    for _ in 0..5 {
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_autobio"))
            .args(args)
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::null())
            .spawn()
            .unwrap();
        let deadline = Instant::now() + Duration::from_secs(120);
        while journal_seeds(&dir).is_empty() || !partial.exists() {
            assert!(Instant::now() < deadline, "seed 1 did not start in 120 s");
            std::thread::sleep(Duration::from_millis(5));
        }
        child.kill().unwrap();
        child.wait().unwrap();
        if journal_seeds(&dir) == [0] && partial.exists() {
            killed_mid_episode = true;
            break;
        }
    }
    assert!(
        killed_mid_episode,
        "no kill landed inside seed 1 in five runs"
    );
    assert!(recording(0).exists());
    assert!(
        !recording(1).exists(),
        "a cut-short recording carries a recording's name"
    );
    let first = common::journal(&dir, "thermal_cycler.close_lid")[0].clone();

    // Without --resume: refused, and told how to continue.
    let out = autobio(&args);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        text(&out.stderr).contains("continue it with --resume"),
        "{}",
        text(&out.stderr)
    );
    let mut resumed: Vec<&str> = args.to_vec();
    resumed.push("--resume");
    let out = autobio(&resumed);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    assert_eq!(journal_seeds(&dir), [0, 1, 2], "each seed once, in order");
    assert_eq!(common::journal(&dir, "thermal_cycler.close_lid")[0], first);
    let partials: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "partial"))
        .collect();
    assert!(partials.is_empty(), "{partials:?}");
    for seed in 0..3 {
        let out = autobio(&["replay", recording(seed).to_str().unwrap()]);
        assert_eq!(
            out.status.code(),
            Some(0),
            "seed {seed}: {}",
            text(&out.stdout)
        );
        assert!(
            text(&out.stdout).contains("re-scored: success"),
            "seed {seed}: {}",
            text(&out.stdout)
        );
    }
}
