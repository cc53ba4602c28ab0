//! Each subcommand as a separate process, with the exit codes README.md documents (0 did its job,
//! 1 what was checked failed, 2 could not run), and determinism across processes: the same seed
//! gives the same draws and the same trajectory hash in two separate runs of the binary.

use crate::common;

use common::{autobio, scratch, text};
use std::path::Path;

const CLOSE: &str = "protocols/thermal_cycler/close_lid.toml";

/// (seed, trajectory hash, success) per journal line.
fn journal(dir: &Path, task: &str) -> Vec<(u64, String, bool)> {
    common::journal(dir, task)
        .iter()
        .map(|v| {
            (
                v["seed"].as_u64().unwrap(),
                v["trajectory_hash"].as_str().unwrap().to_string(),
                v["success"].as_bool().unwrap(),
            )
        })
        .collect()
}

#[test]
fn the_same_seed_gives_the_same_episode_in_two_processes() {
    let (a, b) = (scratch("a"), scratch("b"));
    for dir in [&a, &b] {
        let out = autobio(&[
            "eval",
            "--protocol",
            CLOSE,
            "--episodes",
            "2",
            "--seed",
            "21",
            "--out",
            dir.to_str().unwrap(),
        ]);
        assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    }
    let (ja, jb) = (
        journal(&a, "thermal_cycler.close_lid"),
        journal(&b, "thermal_cycler.close_lid"),
    );
    assert_eq!(ja.len(), 2);
    assert_eq!(ja, jb, "two processes, same seeds, same trajectories");
    assert_ne!(ja[0].1, ja[1].1, "different seeds differ");
    assert!(ja.iter().all(|(_, _, ok)| *ok));
    // The draws a seed makes are the same in two processes too.
    let d1 = autobio(&["describe", "protocols/tube/transfer.toml", "--seed", "9"]);
    let d2 = autobio(&["describe", "protocols/tube/transfer.toml", "--seed", "9"]);
    assert_eq!(d1.status.code(), Some(0));
    assert_eq!(d1.stdout, d2.stdout);
    let _ = std::fs::remove_dir_all(&a);
    let _ = std::fs::remove_dir_all(&b);
}

#[test]
fn exit_codes_are_as_documented() {
    let dir = scratch("codes");
    let d = dir.to_str().unwrap();
    // 0: an evaluation that ran, also when every episode failed (the no-motion control).
    let out = autobio(&[
        "eval",
        "--protocol",
        CLOSE,
        "--policy",
        "hold",
        "--episodes",
        "1",
        "--seed",
        "3",
        "--out",
        d,
        "--record",
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    assert!(
        text(&out.stdout).contains("0.0% ±"),
        "{}",
        text(&out.stdout)
    );
    // 1: replaying that recording re-scores a failure (it ran to its time limit).
    let failed = dir.join("thermal_cycler.close_lid_seed3.mcap");
    let out = autobio(&["replay", failed.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1), "{}", text(&out.stderr));
    let stdout = text(&out.stdout);
    assert!(
        stdout.contains("re-scored: failure (score 0.000)"),
        "{stdout}"
    );
    // The run's own record of that episode (its journal line) says the same.
    let line = common::journal(&dir, "thermal_cycler.close_lid")
        .into_iter()
        .find(|e| e["seed"] == 3)
        .expect("seed 3 in the run's journal");
    assert_eq!(
        (&line["success"], &line["verdict"]["score"]),
        (
            &serde_json::Value::Bool(false),
            &serde_json::Value::from(0.0)
        ),
        "{line}"
    );

    // 0: demonstrations, and their replay re-scores a success.
    let demo = dir.join("demo");
    let out = autobio(&[
        "demo",
        "--protocol",
        CLOSE,
        "--episodes",
        "1",
        "--seed",
        "4",
        "--out",
        demo.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let rec = demo.join("thermal_cycler.close_lid_seed4.mcap");
    let out = autobio(&["replay", rec.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stdout));
    assert!(text(&out.stdout).contains("re-scored: success"));
    // Its actions, replayed in another process, give the same episode.
    let replayed = dir.join("replayed");
    let policy = format!("replay:{}", demo.display());
    let out = autobio(&[
        "eval",
        "--protocol",
        CLOSE,
        "--policy",
        &policy,
        "--episodes",
        "1",
        "--seed",
        "4",
        "--out",
        replayed.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    assert_eq!(
        journal(&replayed, "thermal_cycler.close_lid"),
        journal(&demo, "thermal_cycler.close_lid")
    );

    // 0: compile and describe; 2: the same given a protocol with errors.
    let out = autobio(&["compile", CLOSE]);
    assert_eq!(out.status.code(), Some(0));
    let task: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(task["id"], "thermal_cycler.close_lid");
    assert!(task["schema_version"].as_u64().is_some());
    let bad = "tests/corpus/faulty/unknown_level.toml";
    let never = dir.join("never");
    let never = never.to_str().unwrap();
    for args in [
        vec!["compile", bad],
        vec!["describe", bad],
        vec!["eval", "--protocol", bad, "--out", never],
        vec!["demo", "--protocol", bad, "--out", never],
    ] {
        let sub = args[0];
        let out = autobio(&args);
        assert_eq!(out.status.code(), Some(2), "{sub}");
        let err = text(&out.stderr);
        assert!(
            err.contains("error[E0021]") && err.contains("has errors"),
            "{err}"
        );
        assert!(out.stdout.is_empty());
        assert!(
            !Path::new(never).exists(),
            "{sub} wrote output for a faulty protocol"
        );
    }
    let out = autobio(&["describe", CLOSE, "--seed", "3"]);
    assert_eq!(out.status.code(), Some(0));
    assert!(text(&out.stdout).ends_with('\n'));

    // check: 1 on errors, 0 with warnings only.
    assert_eq!(autobio(&["check", bad]).status.code(), Some(1));
    let out = autobio(&[
        "check",
        "tests/corpus/warnings/weights_under_binary_scoring.toml",
    ]);
    assert_eq!(out.status.code(), Some(0));
    assert!(text(&out.stderr).contains("warning[W0005]"));

    // 2: what cannot run.
    let out = autobio(&["eval", "--protocol", CLOSE, "--policy", "telepathy"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("unknown policy `telepathy`"));
    let out = autobio(&["explain", "E9999"]);
    assert_eq!(out.status.code(), Some(2));
    let _ = std::fs::remove_dir_all(&dir);
}
