//! The cluster scripts under deploy/, run locally: `run-shard.sh` under a Slurm job array's
//! variables and under a Kubernetes Indexed Job's, a retried shard resuming instead of rerunning,
//! and `merge.sh` joining the shards into the summary one unsharded run gives. The Kubernetes
//! manifests are checked to be Indexed Jobs whose shard count agrees with the merge's.

mod common;

use common::{autobio, journal, scratch, text};
use serde_json::Value;
use std::path::Path;
use std::process::Command;

const ARGS: [&str; 8] = [
    "--protocol",
    "protocols/thermal_cycler/close_lid.toml",
    "--protocol",
    "protocols/thermal_cycler/open_lid.toml",
    "--episodes",
    "3",
    "--seed",
    "9",
];
const TASKS: [&str; 2] = ["thermal_cycler.close_lid", "thermal_cycler.open_lid"];

fn script(path: &str, args: &[&str], env: &[(&str, &str)]) -> std::process::Output {
    let out = Command::new(path)
        .args(args)
        .env_remove("SLURM_ARRAY_TASK_ID")
        .env_remove("JOB_COMPLETION_INDEX")
        .envs(env.iter().copied())
        .env("AUTOBIO", env!("CARGO_BIN_EXE_autobio"))
        .output()
        .unwrap();
    assert!(out.status.success(), "{path}: {}", text(&out.stderr));
    out
}

fn summary(dir: &Path, task: &str) -> Value {
    let text = std::fs::read_to_string(dir.join(format!("{task}.results.json"))).unwrap();
    let mut s: Value = serde_json::from_str::<Value>(&text).unwrap()["summary"].clone();
    s.as_object_mut().unwrap().remove("wall_time_s");
    s
}

#[test]
fn job_array_shards_resume_and_merge_into_one_run() {
    let root = scratch("deploy");
    let r = root.to_str().unwrap();
    let mut shard_args = vec![r, "--"];
    shard_args.extend(ARGS);
    // Slurm: an array 3-4 (index = ID - MIN).
    for id in ["3", "4"] {
        script(
            "deploy/run-shard.sh",
            &shard_args,
            &[
                ("SLURM_ARRAY_TASK_ID", id),
                ("SLURM_ARRAY_TASK_MIN", "3"),
                ("SLURM_ARRAY_TASK_COUNT", "2"),
            ],
        );
    }
    let shard1 = root.join("shard-1-of-2");
    let before = journal(&shard1, TASKS[0]);
    assert_eq!(before.len(), 1, "3 episodes over 2 shards: 2 and 1");
    // The same shard retried as a Kubernetes Indexed Job pod: it resumes and runs nothing again.
    let again = script(
        "deploy/run-shard.sh",
        &shard_args,
        &[("JOB_COMPLETION_INDEX", "1"), ("SHARDS", "2")],
    );
    assert_eq!(journal(&shard1, TASKS[0]), before);
    assert!(
        !text(&again.stderr).contains("(run 0)"),
        "{}",
        text(&again.stderr)
    );

    script("deploy/merge.sh", &[r, "2"], &[]);
    let whole = scratch("deploy-whole");
    let mut args = vec!["eval", "--out", whole.to_str().unwrap()];
    args.extend(ARGS);
    assert!(autobio(&args).status.success());
    for task in TASKS {
        assert_eq!(
            summary(&root.join("merged"), task),
            summary(&whole, task),
            "{task}"
        );
    }

    // Outside a job array the script says why it cannot run.
    let out = Command::new("deploy/run-shard.sh")
        .args(&shard_args)
        .env_remove("SLURM_ARRAY_TASK_ID")
        .env_remove("JOB_COMPLETION_INDEX")
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("no shard index"));
}

#[test]
fn kubernetes_manifests_are_indexed_jobs_that_agree_on_the_shard_count() {
    let python = Path::new(env!("CARGO_MANIFEST_DIR")).join(".deps/servers/bin/python");
    let read = |file: &str| -> Value {
        let out = Command::new(&python)
            .args([
                "-c",
                "import json, sys, yaml; print(json.dumps(yaml.safe_load(open(sys.argv[1]))))",
                file,
            ])
            .output()
            .unwrap();
        assert!(out.status.success(), "{file}: {}", text(&out.stderr));
        serde_json::from_slice(&out.stdout).unwrap()
    };
    let job = read("deploy/k8s/eval-indexed-job.yaml");
    let spec = &job["spec"];
    assert_eq!(job["kind"], "Job");
    assert_eq!(spec["completionMode"], "Indexed");
    let container = &spec["template"]["spec"]["containers"][0];
    assert_eq!(container["command"][0], "deploy/run-shard.sh");
    let shards = container["env"]
        .as_array()
        .unwrap()
        .iter()
        .find(|e| e["name"] == "SHARDS")
        .unwrap()["value"]
        .as_str()
        .unwrap()
        .parse::<u64>()
        .unwrap();
    assert_eq!(spec["completions"], shards);
    let merge = read("deploy/k8s/merge-job.yaml");
    let cmd = &merge["spec"]["template"]["spec"]["containers"][0]["command"];
    assert_eq!(cmd[0], "deploy/merge.sh");
    assert_eq!(cmd[2], shards.to_string());
    assert_eq!(
        merge["spec"]["template"]["spec"]["volumes"], spec["template"]["spec"]["volumes"],
        "the merge reads the volume the shards wrote"
    );
}
