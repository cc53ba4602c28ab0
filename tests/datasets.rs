//! `autobio demo --format lerobot-v21|lerobot-v30`: datasets checked by readers that are not
//! ours (tests/datasets/check_lerobot.py: pyarrow for parquet and metadata, ffprobe for every
//! frame's time), byte-identical parquet for the same seeds, no failed episode written, and an
//! interrupted run resumed.

use crate::common;

use common::{autobio, scratch, text};
use serde_json::Value;
use std::path::Path;
use std::process::Command;

const CLOSE: &str = "protocols/thermal_cycler/close_lid.toml";

fn demo(
    format: &str,
    episodes: &str,
    seed: &str,
    out: &Path,
    extra: &[&str],
) -> std::process::Output {
    let mut args = vec![
        "demo",
        "--protocol",
        CLOSE,
        "--format",
        format,
        "--episodes",
        episodes,
        "--seed",
        seed,
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend(extra);
    autobio(&args)
}

fn check(dir: &Path, version: &str) -> Value {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let out = Command::new(root.join(".deps/servers/bin/python"))
        .arg(root.join("tests/datasets/check_lerobot.py"))
        .arg(dir)
        .arg(version)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}: {}",
        dir.display(),
        text(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

#[test]
fn v21_datasets_are_lerobots_layout_and_byte_identical_per_seed() {
    // One worker and two: the same seeds give the same files, byte for byte, at the same
    // episode indices.
    let (a, b) = (scratch("v21-a").join("ds"), scratch("v21-b").join("ds"));
    for (dir, workers) in [(&a, "1"), (&b, "2")] {
        let out = demo("lerobot-v21", "2", "3", dir, &["--workers", workers]);
        assert!(out.status.success(), "{}", text(&out.stderr));
    }
    let summary = check(&a, "v2.1");
    assert_eq!(summary["episodes"], 2);
    let video = &summary["videos"]["observation.images.table_front"];
    assert_eq!(video["codec_name"], "av1");
    assert_eq!(video["avg_frame_rate"], "50/1");
    assert_eq!(
        (video["width"].as_u64(), video["height"].as_u64()),
        (Some(224), Some(224))
    );
    check(&b, "v2.1");
    for i in 0..2 {
        let parquet = format!("data/chunk-000/episode_{i:06}.parquet");
        assert_eq!(
            std::fs::read(a.join(&parquet)).unwrap(),
            std::fs::read(b.join(&parquet)).unwrap(),
            "{parquet}: the same seed must give the same parquet, byte for byte"
        );
    }
    assert_eq!(
        std::fs::read(a.join("meta/episodes.jsonl")).unwrap(),
        std::fs::read(b.join("meta/episodes.jsonl")).unwrap()
    );
    // Into the same folder again without --resume: refused, nothing touched.
    let again = demo("lerobot-v21", "1", "3", &a, &[]);
    assert_eq!(again.status.code(), Some(2));
    assert!(
        text(&again.stderr).contains("--resume"),
        "{}",
        text(&again.stderr)
    );
}

#[test]
fn v30_datasets_share_files_and_resume() {
    let dir = scratch("v30").join("ds");
    let out = demo("lerobot-v30", "1", "0", &dir, &["--codec", "h264"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    // Resumed with one more episode: the first is kept, the second added, the shared files
    // rebuilt.
    let out = demo(
        "lerobot-v30",
        "2",
        "0",
        &dir,
        &["--codec", "h264", "--resume"],
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(
        text(&out.stdout).contains("1 written"),
        "{}",
        text(&out.stdout)
    );
    // Resumed with another codec: refused (the videos are joined by stream copy).
    let other = demo("lerobot-v30", "3", "0", &dir, &["--resume"]);
    assert_eq!(other.status.code(), Some(2));
    assert!(
        text(&other.stderr).contains("h264 videos, not 224x224 av1"),
        "{}",
        text(&other.stderr)
    );
    let summary = check(&dir, "v3.0");
    assert_eq!(summary["episodes"], 2);
    assert_eq!(
        summary["videos"]["observation.images.table_front"]["codec_name"],
        "h264"
    );
    assert!(!dir.join(".staging").exists());
}

#[test]
fn a_failed_expert_episode_is_not_written() {
    // An edited protocol whose time limit is too short for the expert: every episode fails and
    // none is written, and the run says so.
    let dir = scratch("failed");
    let text_ = std::fs::read_to_string(CLOSE).unwrap();
    let short = text_.replacen("time_limit = \"31.5 s\"", "time_limit = \"0.5 s\"", 1);
    assert_ne!(short, text_);
    let path = dir.join("short.toml");
    std::fs::write(&path, short).unwrap();
    let out = autobio(&[
        "demo",
        "--protocol",
        path.to_str().unwrap(),
        "--format",
        "lerobot-v21",
        "--episodes",
        "1",
        "--out",
        dir.join("ds").to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let stdout = text(&out.stdout);
    assert!(
        stdout.contains("0 written") && stdout.contains("1 left out"),
        "{stdout}"
    );
    let info: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("ds/meta/info.json")).unwrap())
            .unwrap();
    assert_eq!(info["total_episodes"], 0);
    assert!(!dir.join("ds/data").exists());
}

/// A process's standard output; it must have succeeded.
fn ok(out: std::process::Output) -> String {
    assert!(
        out.status.success(),
        "{}{}",
        text(&out.stdout),
        text(&out.stderr)
    );
    text(&out.stdout)
}

/// Seeds 0 and 1 of the thermal cycler's close recorded as MCAP (states and actions, no images).
fn record_two_episodes(out: &Path) {
    crate::common::autobio_ok(&[
        "eval",
        "--protocol",
        CLOSE,
        "--episodes",
        "2",
        "--seed",
        "0",
        "--record",
        "--image-every",
        "0",
        "--out",
        out.to_str().unwrap(),
    ]);
}

fn same_file(a: &Path, b: &Path) {
    let (x, y) = (std::fs::read(a).unwrap(), std::fs::read(b).unwrap());
    assert!(x == y, "{} and {} differ", a.display(), b.display());
}

#[test]
fn recordings_export_and_shards_merge_into_the_dataset_one_run_writes() {
    let dir = scratch("export-merge");
    let d = |n: &str| dir.join(n);
    let s = |p: &Path| p.to_str().unwrap().to_string();
    // The reference: one run of two episodes.
    ok(demo(
        "lerobot-v30",
        "2",
        "0",
        &d("ds"),
        &["--codec", "h264"],
    ));

    // The same two episodes recorded as MCAP (no images), then exported: the cameras are
    // redrawn from the recorded states, so the tables and statistics are the run's.
    record_two_episodes(&d("rec"));
    let out = ok(autobio(&[
        "export",
        &s(&d("rec")),
        "--format",
        "lerobot-v30",
        "--codec",
        "h264",
        "--out",
        &s(&d("ex")),
    ]));
    assert!(
        out.contains("2 episodes in the dataset, 2 exported, 0 left out"),
        "{out}"
    );
    for f in [
        "data/chunk-000/file-000.parquet",
        "meta/stats.json",
        "meta/tasks.parquet",
    ] {
        same_file(&d("ds").join(f), &d("ex").join(f));
    }
    assert_eq!(check(&d("ex"), "v3.0")["episodes"], 2);

    // Files roll over at the sizes asked (LeRobot's `*_files_size_in_mb`): with limits below
    // one episode's size, each episode gets its own data and video files, which the checker
    // follows through the episodes table.
    ok(autobio(&[
        "export",
        &s(&d("rec")),
        "--format",
        "lerobot-v30",
        "--codec",
        "h264",
        "--data-file-mb",
        "0.001",
        "--video-file-mb",
        "0.001",
        "--out",
        &s(&d("rolled")),
    ]));
    // Relative paths, from another working directory (ffmpeg resolves a concat list's names
    // against the list's folder).
    let out = Command::new(env!("CARGO_BIN_EXE_autobio"))
        .current_dir(&dir)
        .args([
            "export",
            "rec",
            "--format",
            "lerobot-v30",
            "--codec",
            "h264",
            "--out",
            "relative",
        ])
        .output()
        .unwrap();
    ok(out);
    same_file(
        &d("ex/data/chunk-000/file-000.parquet"),
        &d("relative/data/chunk-000/file-000.parquet"),
    );
    let rolled = check(&d("rolled"), "v3.0");
    assert_eq!(rolled["data_files"], 2, "{rolled}");
    for key in [
        "observation.images.table_front",
        "observation.images.arm_wrist",
    ] {
        assert_eq!(rolled["video_files"][key], 2, "{rolled}");
    }
    assert!(d("rolled/data/chunk-000/file-001.parquet").exists());
    let info: Value =
        serde_json::from_str(&std::fs::read_to_string(d("rolled/meta/info.json")).unwrap())
            .unwrap();
    assert_eq!(info["data_files_size_in_mb"], 0.001);
    assert_eq!(check(&d("ds"), "v3.0")["data_files"], 1);

    // Two shards of the same plan, merged in either order: the run's tables and statistics.
    for i in ["0/2", "1/2"] {
        let shard = d(&format!("shard{}", &i[..1]));
        ok(demo(
            "lerobot-v30",
            "2",
            "0",
            &shard,
            &["--codec", "h264", "--shard", i],
        ));
    }
    let out = ok(autobio(&[
        "dataset",
        "merge",
        &s(&d("shard1")),
        &s(&d("shard0")),
        "--out",
        &s(&d("merged")),
    ]));
    let frames = check(&d("ds"), "v3.0")["frames"].clone();
    assert!(
        out.contains(&format!(
            "2 episodes, {frames} frames, merged from 2 shards"
        )),
        "{out} ({frames} frames)"
    );
    for f in [
        "data/chunk-000/file-000.parquet",
        "meta/stats.json",
        "meta/tasks.parquet",
        "meta/episodes/chunk-000/file-000.parquet",
        "meta/info.json",
    ] {
        same_file(&d("ds").join(f), &d("merged").join(f));
    }
    assert_eq!(check(&d("merged"), "v3.0")["episodes"], 2);

    // Refusals: a missing shard, a shard twice, a dataset that is no shard, and a shard
    // resumed without its --shard.
    let refused = |args: &[&str], why: &str| {
        let out = autobio(args);
        assert_eq!(out.status.code(), Some(2), "{}", text(&out.stdout));
        assert!(text(&out.stderr).contains(why), "{}", text(&out.stderr));
    };
    refused(
        &["dataset", "merge", &s(&d("shard0")), "--out", &s(&d("m2"))],
        "shard 1/2 is missing; merge needs all 2",
    );
    refused(
        &[
            "dataset",
            "merge",
            &s(&d("shard0")),
            &s(&d("shard0")),
            "--out",
            &s(&d("m3")),
        ],
        "is shard 0/2 again",
    );
    refused(
        &["dataset", "merge", &s(&d("ds")), "--out", &s(&d("m4"))],
        "is not a shard",
    );
    let out = demo(
        "lerobot-v30",
        "2",
        "0",
        &d("shard0"),
        &["--codec", "h264", "--resume"],
    );
    assert_eq!(out.status.code(), Some(2));
    assert!(
        text(&out.stderr).contains("is a shard's dataset"),
        "{}",
        text(&out.stderr)
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn state_datasets_carry_the_environment_state_and_export_the_same() {
    // `--observation state`: the task's environment state and the robot state, no camera. The
    // layout's names are the task's, not the seed's; an export of the same episodes recorded as
    // MCAP writes the same table and statistics.
    let dir = scratch("state-dataset");
    let d = |n: &str| dir.join(n);
    let s = |p: &Path| p.to_str().unwrap().to_string();
    ok(demo(
        "lerobot-v30",
        "2",
        "0",
        &d("ds"),
        &["--observation", "state"],
    ));
    let summary = check(&d("ds"), "v3.0");
    assert_eq!(summary["videos"], serde_json::json!({}), "{summary}");
    let info: Value =
        serde_json::from_str(&std::fs::read_to_string(d("ds").join("meta/info.json")).unwrap())
            .unwrap();
    let env = &info["features"]["observation.environment_state"];
    let names: Vec<&str> = env["names"]
        .as_array()
        .unwrap()
        .iter()
        .map(|n| n.as_str().unwrap())
        .collect();
    assert_eq!(summary["environment_state"], names.len());
    // The thermal cycler's pose and its lid and lever joints (what the check reads) are in it.
    for want in ["cycler.x", "cycler.qw", "cycler.lid", "cycler.lever"] {
        assert!(
            names.iter().any(|n| n.starts_with(want)),
            "{want} not in {names:?}"
        );
    }
    assert!(
        !dir.join("ds/videos").exists(),
        "a state dataset draws no camera"
    );

    // Another seed: the same names in the same order.
    ok(demo(
        "lerobot-v30",
        "1",
        "7",
        &d("other"),
        &["--observation", "state"],
    ));
    let other: Value =
        serde_json::from_str(&std::fs::read_to_string(d("other").join("meta/info.json")).unwrap())
            .unwrap();
    assert_eq!(
        other["features"]["observation.environment_state"]["names"],
        env["names"]
    );

    record_two_episodes(&d("rec"));
    ok(autobio(&[
        "export",
        &s(&d("rec")),
        "--format",
        "lerobot-v30",
        "--observation",
        "state",
        "--out",
        &s(&d("ex")),
    ]));
    for f in [
        "data/chunk-000/file-000.parquet",
        "meta/stats.json",
        "meta/info.json",
    ] {
        same_file(&d("ds").join(f), &d("ex").join(f));
    }
}
