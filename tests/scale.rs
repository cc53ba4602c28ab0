//! Runs at scale, as processes: `--workers` gives the same episodes as one worker; shards
//! (`--shard I/N`) joined by `autobio results merge` give the summary one unsharded run gives,
//! and a merge refuses missing, doubled or mismatched shards; `--runs K` reports each run and
//! their mean ± SEM; progress is a bar on a terminal and plain lines elsewhere.

use crate::common;

use common::{autobio, journal, scratch, text};
use serde_json::Value;
use std::path::Path;
use std::process::Command;

const CLOSE: &str = "protocols/thermal_cycler/close_lid.toml";
const TASK: &str = "thermal_cycler.close_lid";

fn eval(extra: &[&str], out: &Path) -> std::process::Output {
    let mut args = vec!["eval", "--protocol", CLOSE, "--out", out.to_str().unwrap()];
    if !extra.contains(&"--seed") {
        args.extend(["--seed", "5"]);
    }
    args.extend(extra);
    let o = autobio(&args);
    assert!(o.status.success(), "{}", text(&o.stderr));
    o
}

fn results(dir: &Path) -> Value {
    let text = std::fs::read_to_string(dir.join(format!("{TASK}.results.json"))).unwrap();
    serde_json::from_str(&text).unwrap()
}

/// An episode's line without its timings (which differ run to run).
fn untimed(mut e: Value) -> Value {
    for k in ["wall_time_s", "policy_time_s"] {
        e.as_object_mut().unwrap().remove(k);
    }
    e
}

#[test]
fn two_workers_run_the_same_episodes_as_one() {
    let (one, two) = (scratch("workers-1"), scratch("workers-2"));
    eval(&["--episodes", "4"], &one);
    eval(&["--episodes", "4", "--workers", "2"], &two);
    let a: Vec<Value> = results(&one)["episodes"]
        .as_array()
        .unwrap()
        .iter()
        .cloned()
        .map(untimed)
        .collect();
    let b: Vec<Value> = results(&two)["episodes"]
        .as_array()
        .unwrap()
        .iter()
        .cloned()
        .map(untimed)
        .collect();
    assert_eq!(a.len(), 4);
    assert_eq!(a, b, "the same seeds give the same episodes on any worker");
    assert_eq!(journal(&two, TASK).len(), 4);
}

#[test]
fn shards_merge_into_the_summary_of_one_run() {
    let whole = scratch("shard-whole");
    eval(&["--episodes", "3", "--runs", "2"], &whole);
    let parts: Vec<_> = (0..3).map(|i| scratch(&format!("shard-{i}"))).collect();
    for (i, dir) in parts.iter().enumerate() {
        eval(
            &[
                "--episodes",
                "3",
                "--runs",
                "2",
                "--shard",
                &format!("{i}/3"),
            ],
            dir,
        );
        assert_eq!(journal(dir, TASK).len(), 2, "6 episodes over 3 shards");
    }
    let merged = scratch("shard-merged").join("out");
    let p: Vec<&str> = parts.iter().map(|d| d.to_str().unwrap()).collect();
    let out = autobio(&[
        "results",
        "merge",
        p[0],
        p[1],
        p[2],
        "--out",
        merged.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(
        text(&out.stdout).contains("2 runs"),
        "{}",
        text(&out.stdout)
    );
    let (a, b) = (results(&whole), results(&merged));
    let summary = |r: &Value| {
        let mut s = r["summary"].clone();
        s.as_object_mut().unwrap().remove("wall_time_s");
        s
    };
    assert_eq!(summary(&a), summary(&b));
    let eps = |r: &Value| -> Vec<Value> {
        r["episodes"]
            .as_array()
            .unwrap()
            .iter()
            .cloned()
            .map(untimed)
            .collect()
    };
    assert_eq!(eps(&a), eps(&b));
    assert_eq!(b["shard"], Value::Null);
    assert_eq!(journal(&merged, TASK).len(), 6);

    // Refusals: a shard missing, a shard given twice, a shard of another run.
    let refused = |dirs: &[&str], want: &str| {
        let out_dir = scratch("shard-refused").join("out");
        let mut args = vec!["results", "merge"];
        args.extend(dirs);
        args.extend(["--out", out_dir.to_str().unwrap()]);
        let o = autobio(&args);
        assert_eq!(o.status.code(), Some(2), "{dirs:?}");
        let err = text(&o.stderr);
        assert!(err.contains(want), "{dirs:?}: {err}");
    };
    refused(&[p[0], p[1]], "shards 2/3 are missing");
    refused(&[p[0], p[1], p[1]], "shard 1/3 is in both");
    let other = scratch("shard-other-seed");
    eval(
        &[
            "--episodes",
            "3",
            "--runs",
            "2",
            "--shard",
            "2/3",
            "--seed",
            "6",
        ],
        &other,
    );
    refused(
        &[p[0], p[1], other.to_str().unwrap()],
        "measured under another seed",
    );
    refused(&[whole.to_str().unwrap()], "holds an unsharded run");
}

#[test]
fn runs_report_each_run_and_their_mean_and_sem() {
    let dir = scratch("runs");
    let out = eval(
        &["--episodes", "2", "--runs", "3", "--policy", "hold"],
        &dir,
    );
    let r = results(&dir);
    let runs = r["summary"]["runs"].as_array().unwrap();
    assert_eq!(runs.len(), 3);
    assert_eq!(r["summary"]["across_runs"]["runs"], 3);
    assert_eq!(r["summary"]["across_runs"]["success_rate_mean"], 0.0);
    let seeds: Vec<u64> = r["episodes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| e["seed"].as_u64().unwrap())
        .collect();
    let stride = 1u64 << 20;
    assert_eq!(
        seeds,
        [5, 6, 5 + stride, 6 + stride, 5 + 2 * stride, 6 + 2 * stride]
    );
    assert!(
        text(&out.stdout).contains("3 runs (0.0%, 0.0%, 0.0%)"),
        "{}",
        text(&out.stdout)
    );
}

#[test]
fn progress_is_a_bar_on_a_terminal_and_lines_elsewhere() {
    let dir = scratch("progress-plain");
    let out = eval(&["--episodes", "2", "--policy", "hold"], &dir);
    let err = text(&out.stderr);
    assert!(err.contains("1/2 seed 5 (run 0): time_limit"), "{err}");
    // A failed episode's line names the checks that did not hold.
    assert!(
        err.contains(
            "2/2 seed 6 (run 0): time_limit: `cycler.lid is closed` failed, `cycler.lid is locked` failed  running success 0.0%"
        ),
        "{err}"
    );
    assert!(!err.contains('\r'), "{err}");
    let tty_dir = scratch("progress-tty");
    let cmd = format!(
        "{} eval --protocol {CLOSE} --policy hold --episodes 2 --out {}",
        env!("CARGO_BIN_EXE_autobio"),
        tty_dir.display()
    );
    let o = Command::new("script")
        .args(["-qec", &cmd, "/dev/null"])
        .output()
        .unwrap();
    let tty = text(&o.stdout);
    assert!(tty.contains("2/2  success 0.0%  ETA 0:00"), "{tty}");
    assert!(tty.contains('\r') && tty.contains("[####"), "{tty}");
}
