//! The cluster scripts under deploy/, run locally: `run-shard.sh` under a Slurm job array's
//! variables and under a Kubernetes Indexed Job's, a retried shard resuming instead of rerunning,
//! and `merge.sh` joining the shards into the summary one unsharded run gives. The Kubernetes
//! manifests are checked to be Indexed Jobs whose shard count agrees with the merge's.

use crate::common;

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

#[test]
fn a_job_array_verifies_one_bundle_per_task_and_records_each() {
    // Two bundles of a 1-episode suite (the expert's, and one with a flipped journal line), each
    // verified by its own array task under Slurm's and Kubernetes' variables; each record says
    // how its bundle stands, and a refused bundle is a finished task.
    let root = scratch("deploy-verify");
    let suites = root.join("suites");
    std::fs::create_dir_all(&suites).unwrap();
    let protocol =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("protocols/thermal_cycler/close_lid.toml");
    std::fs::write(
        suites.join("one.toml"),
        format!(
            "format = 1\n[suite]\nname = \"one\"\nepisodes = 1\nseed = 0\nruns = 1\ntasks = [{:?}]\n",
            protocol.display().to_string()
        ),
    )
    .unwrap();
    let run = root.join("run");
    common::eval_suite(&suites.join("one.toml"), &run, &[]);
    let bundles = root.join("bundles");
    std::fs::create_dir_all(&bundles).unwrap();
    let submit = |name: &str| {
        common::submit(&run, name, &bundles.join(format!("{name}.tar")), &[]);
    };
    submit("a-honest");
    // The second bundle claims the episode failed.
    let journal = run.join("thermal_cycler.close_lid.journal.jsonl");
    let line = std::fs::read_to_string(&journal).unwrap();
    std::fs::write(
        &journal,
        line.replace("\"success\":true", "\"success\":false"),
    )
    .unwrap();
    submit("b-flipped");
    let s = suites.to_str().unwrap();
    let b = bundles.to_str().unwrap();
    script(
        "deploy/verify-bundle.sh",
        &[b, "--suites", s],
        &[
            ("SLURM_ARRAY_TASK_ID", "7"),
            ("SLURM_ARRAY_TASK_MIN", "7"),
            ("SLURM_CPUS_PER_TASK", "1"),
        ],
    );
    script(
        "deploy/verify-bundle.sh",
        &[b, "--suites", s],
        &[("JOB_COMPLETION_INDEX", "1")],
    );
    let record = |name: &str| -> Value {
        serde_json::from_str(
            &std::fs::read_to_string(bundles.join(format!("{name}.tar.verification.json")))
                .unwrap(),
        )
        .unwrap()
    };
    assert_eq!(record("a-honest")["passed"], true);
    let flipped = record("b-flipped");
    assert_eq!(flipped["passed"], false);
    assert!(
        flipped["reasons"][0]
            .as_str()
            .unwrap()
            .ends_with("success: false (derived true)"),
        "{flipped}"
    );
    // An index past the bundles is an error, not a silent success.
    let out = Command::new("deploy/verify-bundle.sh")
        .args([b])
        .env_remove("SLURM_ARRAY_TASK_ID")
        .env("JOB_COMPLETION_INDEX", "2")
        .env("AUTOBIO", env!("CARGO_BIN_EXE_autobio"))
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(
        text(&out.stderr).contains("holds 2 bundles"),
        "{}",
        text(&out.stderr)
    );
}
