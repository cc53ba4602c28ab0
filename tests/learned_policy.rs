//! The loop closed with a learned policy, end to end with the real parts: a 5-episode state
//! dataset from `autobio demo --observation state`, a tiny ACT trained on it by LeRobot's own
//! `lerobot-train`, the checkpoint served by `python -m autobio.serve` over openpi's websocket,
//! two episodes of `autobio eval --suite suites/learned-smoke.toml --model` against it, the run
//! packed and verified (every episode re-enacted), the site labelling it a state model; and the
//! same checkpoint run in process by LeRobot's own `lerobot-eval` on autobio's gym env; and
//! `python -m autobio.diagnose` on the dataset and the checkpoint, including a misaligned replay
//! that its alignment check must catch.

use crate::common::{Server, autobio_ok, journal, scratch, submit};
use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// LeRobot's Python (`make setup` makes it, with the autobio wheel).
fn lerobot_python() -> PathBuf {
    let python = root().join(".deps/lerobot-env/bin/python");
    assert!(
        python.exists(),
        "{} is missing: run `make setup`",
        python.display()
    );
    python
}

fn run_python(args: &[&str], what: &str) -> String {
    let out = Command::new(lerobot_python())
        .args(args)
        .env("HF_HUB_OFFLINE", "1")
        // One thread per torch process: the tiny model gains nothing from two, and the tests
        // beside it need the other core (two-thread torch beside them oversubscribes it).
        .env("OMP_NUM_THREADS", "1")
        .output()
        .unwrap();
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(out.status.success(), "{what} failed:\n{text}");
    text
}

/// A tiny ACT on the state dataset in `data`: a few hundred steps, a checkpoint at the end.
fn train(data: &Path, out: &Path) -> PathBuf {
    run_python(
        &[
            "-m",
            "lerobot.scripts.lerobot_train",
            "--dataset.repo_id=autobio/test",
            &format!("--dataset.root={}", data.display()),
            "--policy.type=act",
            "--policy.device=cpu",
            "--policy.push_to_hub=false",
            "--policy.dim_model=32",
            "--policy.n_heads=2",
            "--policy.dim_feedforward=64",
            "--policy.n_encoder_layers=1",
            "--policy.n_decoder_layers=1",
            "--policy.chunk_size=10",
            "--policy.n_action_steps=10",
            "--policy.use_vae=false",
            "--policy.optimizer_lr=1e-3",
            r#"--policy.normalization_mapping={"VISUAL": "MEAN_STD", "STATE": "MEAN_STD", "ENV": "MEAN_STD", "ACTION": "MEAN_STD"}"#,
            &format!("--output_dir={}", out.display()),
            "--steps=300",
            "--batch_size=8",
            "--save_freq=300",
            "--eval_freq=0",
            "--log_freq=100",
            "--num_workers=0",
            "--wandb.enable=false",
        ],
        "lerobot-train",
    );
    let ckpt = out.join("checkpoints/last/pretrained_model");
    assert!(ckpt.join("model.safetensors").is_file(), "no checkpoint");
    ckpt
}

#[test]
fn a_trained_lerobot_policy_is_served_evaluated_and_verified() {
    let dir = scratch("learned");
    let data = dir.join("data");
    autobio_ok(&[
        "demo",
        "--protocol",
        "protocols/thermal_cycler/close_lid.toml",
        "--episodes",
        "5",
        "--format",
        "lerobot-v30",
        "--observation",
        "state",
        "--out",
        data.to_str().unwrap(),
    ]);
    let info: serde_json::Value =
        serde_json::from_slice(&std::fs::read(data.join("meta/info.json")).unwrap()).unwrap();
    let features = info["features"].as_object().unwrap();
    assert!(
        features.contains_key("observation.environment_state")
            && !features.keys().any(|k| k.starts_with("observation.images")),
        "a state dataset has the environment state and no camera: {:?}",
        features.keys()
    );
    let ckpt = train(&data, &dir.join("train"));

    let mut cmd = Command::new(lerobot_python());
    cmd.args(["-m", "autobio.serve", "--policy"])
        .arg(&ckpt)
        .args(["--port", "0"])
        .env("HF_HUB_OFFLINE", "1")
        .env("OMP_NUM_THREADS", "1");
    let server = Server::spawn(cmd, "autobio.serve", std::time::Duration::from_secs(120))
        .unwrap_or_else(|e| panic!("{e}"));
    let run = dir.join("run");
    crate::common::eval_suite(
        &root().join("suites/learned-smoke.toml"),
        &run,
        &[
            "--model",
            &server.url,
            "--wire",
            "openpi",
            "--profile",
            "lerobot-state",
        ],
    );
    drop(server);
    let lines = journal(&run, "thermal_cycler.close_lid");
    assert_eq!(lines.len(), 2, "{lines:?}");
    for l in &lines {
        // The policy drove the episode to its end: a verdict, not a fault of the wire or the
        // policy's actions.
        let outcome = l["outcome"].as_str().unwrap();
        assert!(
            ["success", "time_limit"].contains(&outcome),
            "episode ended as {outcome}: {l}"
        );
        assert!(l["control_steps"].as_u64().unwrap() > 10, "{l}");
    }
    let manifest: serde_json::Value = serde_json::from_slice(
        &std::fs::read(run.join("thermal_cycler.close_lid.manifest.json")).unwrap(),
    )
    .unwrap();
    let model = &manifest["model"];
    assert_eq!(
        model["profile"]["environment_state_key"],
        "observation.environment_state"
    );
    assert_eq!(model["metadata"]["observation_mode"], "state", "{model}");
    assert_eq!(model["metadata"]["policies"]["*"]["policy_type"], "act");

    let bundle = dir.join("act.tar");
    submit(
        &run,
        "tiny ACT (state)",
        &bundle,
        &["--training", "5 demos, 300 steps"],
    );
    let verified = autobio_ok(&["leaderboard", "verify", bundle.to_str().unwrap()]);
    assert!(verified.contains("accepted"), "{verified}");
    let bundles = dir.join("bundles");
    std::fs::create_dir_all(&bundles).unwrap();
    std::fs::rename(&bundle, bundles.join("act.tar")).unwrap();
    let site = dir.join("site");
    autobio_ok(&[
        "leaderboard",
        "build",
        bundles.to_str().unwrap(),
        "--out",
        site.to_str().unwrap(),
    ]);
    let md = std::fs::read_to_string(site.join("ranking.md")).unwrap();
    assert!(
        md.contains("state observation")
            && md.contains("| tiny ACT (state) | 5 demos, 300 steps | state |"),
        "the site labels the model a state model:\n{md}"
    );

    diagnose(&dir, &data, &ckpt);

    // LeRobot's own evaluation loop, pointed at autobio's gym env through its env plugin.
    let evald = dir.join("lerobot-eval");
    run_python(
        &[
            "-m",
            "lerobot.scripts.lerobot_eval",
            "--env.discover_packages_path=autobio.lerobot",
            "--env.type=autobio",
            "--env.task=thermal_cycler.close_lid",
            "--env.obs_type=environment_state_agent_pos",
            // Its videos of the episode are drawn at this size: small, to keep the test quick.
            "--env.image_size=64",
            &format!("--policy.path={}", ckpt.display()),
            "--policy.device=cpu",
            "--eval.n_episodes=1",
            "--eval.batch_size=1",
            "--seed=1000",
            &format!("--output_dir={}", evald.display()),
        ],
        "lerobot-eval",
    );
    let info: serde_json::Value =
        serde_json::from_slice(&std::fs::read(evald.join("eval_info.json")).unwrap()).unwrap();
    let overall = &info["overall"];
    assert_eq!(overall["n_episodes"], 1, "{info}");
    assert!(overall["pc_success"].is_number(), "{info}");
}

/// `python -m autobio.diagnose`: the dataset re-enacts exactly from its seeds with its own
/// actions (and, shifted by one frame, does not: the check can fail); the checkpoint's open-loop
/// error on a held-out episode beats always answering the mean; one closed-loop rollout reports
/// where it went.
fn diagnose(dir: &Path, data: &Path, ckpt: &Path) {
    let held = dir.join("held-out");
    autobio_ok(&[
        "demo",
        "--protocol",
        "protocols/thermal_cycler/close_lid.toml",
        "--episodes",
        "1",
        "--seed",
        "5000",
        "--format",
        "lerobot-v30",
        "--observation",
        "state",
        "--out",
        held.to_str().unwrap(),
    ]);
    let report = |extra: &[&str], name: &str| -> serde_json::Value {
        let json = dir.join(name);
        let mut args = vec![
            "-m",
            "autobio.diagnose",
            "--dataset",
            data.to_str().unwrap(),
            "--episodes",
            "2",
            "--json",
            json.to_str().unwrap(),
        ];
        args.extend(extra);
        run_python(&args, "autobio.diagnose");
        serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap()
    };
    let r = report(
        &[
            "--policy",
            ckpt.to_str().unwrap(),
            "--held-out",
            held.to_str().unwrap(),
            "--rollouts",
            "1",
        ],
        "diagnosis.json",
    );
    let aligned = r["alignment"].as_array().unwrap();
    assert_eq!(aligned.len(), 2, "{r}");
    for a in aligned {
        assert!(
            a["first_divergent_frame"].is_null() && a["success"] == true,
            "the dataset's own actions re-enact its episodes: {a}"
        );
        assert!(a["max_gap"].as_f64().unwrap() < 1e-3, "{a}");
        assert_eq!(a["aligned"], true, "action[t] follows frame t: {a}");
    }
    let open = &r["open_loop"];
    assert!(open["frames"].as_u64().unwrap() > 100, "{open}");
    assert!(
        open["error_std"].as_f64().unwrap() < open["mean_action_error_std"].as_f64().unwrap(),
        "the trained policy predicts held-out actions better than their mean: {open}"
    );
    let rollouts = r["drift"]["rollouts"].as_array().unwrap();
    assert_eq!(rollouts.len(), 1, "{r}");
    assert_eq!(rollouts[0]["seed"], 1000);
    assert!(rollouts[0]["steps"].as_u64().unwrap() > 10, "{r}");
    let phase = rollouts[0]["furthest_phase"].as_f64().unwrap();
    assert!((0.0..=1.0).contains(&phase), "{r}");

    // Actions one frame late: the re-enactment leaves the recorded states, and the unshifted
    // actions (its neighbour) track them longer.
    let shifted = report(&["--shift", "1"], "shifted.json");
    for a in shifted["alignment"].as_array().unwrap() {
        assert!(
            !a["first_divergent_frame"].is_null() && a["aligned"] == false,
            "a one-frame shift must be caught: {a}"
        );
        assert!(
            a["frames_tracked"]["-1"].as_u64() > a["frames_tracked"]["0"].as_u64(),
            "{a}"
        );
    }
}
