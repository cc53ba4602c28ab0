//! `autobio eval --model` against real model servers on loopback (tests/servers, in the Python
//! environment `make setup` makes): one built on openpi-client's msgpack-numpy, one on the
//! vla-eval package, both answering with the scripted expert's recorded actions. They check the
//! observations they get, so a client that sends the wrong layout fails here.

use crate::common;

use common::{Server, autobio, journal, scratch, text};
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

const CLOSE: &str = "protocols/thermal_cycler/close_lid.toml";
const OPEN: &str = "protocols/thermal_cycler/open_lid.toml";
const CHAIN: &str = "protocols/thermal_cycler/close_then_open.toml";

/// The expert's recordings (3 seeds of each task), made once per test process.
fn recordings() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let dir = scratch("expert-recordings");
        let d = dir.to_str().unwrap();
        let out = autobio(&[
            "eval",
            "--protocol",
            CLOSE,
            "--protocol",
            OPEN,
            "--protocol",
            CHAIN,
            "--episodes",
            "3",
            "--seed",
            "0",
            "--out",
            d,
            "--record",
            "--image-every",
            "0",
        ]);
        assert!(out.status.success(), "{}", text(&out.stderr));
        dir
    })
}

/// The expert's journal line for `task` and `seed`.
fn expert(task: &str, seed: u64) -> Value {
    journal(recordings(), task)
        .into_iter()
        .find(|e| e["seed"] == seed)
        .unwrap()
}

/// pi0's layout with reset frames (the reference server learns the episode from them) and a
/// short timeout.
fn profile(dir: &Path, timeout_s: f64) -> String {
    let pi0 = std::fs::read_to_string("profiles/pi0.toml").unwrap();
    let text = pi0
        .replace("reset_frame = false", "reset_frame = true")
        .replace("timeout_s = 30.0", &format!("timeout_s = {timeout_s}"));
    assert_ne!(text, pi0);
    let path = dir.join("pi0-reset.toml");
    std::fs::write(&path, text).unwrap();
    path.to_str().unwrap().to_string()
}

fn eval_model(
    server: &Server,
    wire: &str,
    profile: &str,
    protocols: &[&str],
    episodes: u32,
    out: &Path,
) -> std::process::Output {
    let mut args = vec![
        "eval".to_string(),
        "--model".into(),
        server.url.clone(),
        "--wire".into(),
        wire.into(),
        "--profile".into(),
        profile.into(),
        "--episodes".into(),
        episodes.to_string(),
        "--seed".into(),
        "0".into(),
        "--out".into(),
        out.to_str().unwrap().into(),
    ];
    // Protocols, and any `--flag value` pairs among them passed through as they are.
    let mut raw = false;
    for p in protocols {
        if raw || p.starts_with("--") {
            args.push(p.to_string());
            raw = p.starts_with("--");
        } else {
            args.extend(["--protocol".to_string(), p.to_string()]);
        }
    }
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    autobio(&args)
}

fn manifest(dir: &Path, task: &str) -> Value {
    let text = std::fs::read_to_string(dir.join(format!("{task}.manifest.json"))).unwrap();
    serde_json::from_str(&text).unwrap()
}

#[test]
fn openpi_server_reaches_the_experts_success_and_trajectories() {
    let rec = recordings().to_str().unwrap().to_string();
    let dir = scratch("openpi-e2e");
    let log = dir.join("queries.jsonl");
    let server = Server::start(
        "openpi_server.py",
        &["--recordings", &rec, "--log", log.to_str().unwrap()],
    );
    let out = eval_model(
        &server,
        "openpi",
        &profile(&dir, 30.0),
        &[CLOSE, OPEN, CHAIN],
        3,
        &dir,
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    for task in [
        "thermal_cycler.close_lid",
        "thermal_cycler.open_lid",
        "thermal_cycler.close_then_open",
    ] {
        let eps = journal(&dir, task);
        assert_eq!(eps.len(), 3, "{task}");
        for e in &eps {
            let seed = e["seed"].as_u64().unwrap();
            let x = expert(task, seed);
            assert_eq!(e["outcome"], "success", "{task} seed {seed}: {e}");
            // float64 actions over msgpack-numpy: the very same episode as the expert's.
            assert_eq!(
                e["trajectory_hash"], x["trajectory_hash"],
                "{task} seed {seed}"
            );
            assert_eq!(e["control_steps"], x["control_steps"], "{task} seed {seed}");
        }
        let m = manifest(&dir, task);
        assert_eq!(m["policy"], "model");
        assert_eq!(m["model"]["wire"], "openpi");
        assert_eq!(
            m["model"]["metadata"]["server"], "autobio reference openpi expert",
            "the metadata frame is kept: {m}"
        );
        assert_eq!(m["model"]["profile"]["chunk"], 50);
        assert_eq!(m["conditions"]["control_hz"], 50.0);
        assert_eq!(m["conditions"]["physics_steps_per_action"], 10);
        let commit = m["git_commit"].as_str().unwrap();
        assert!(
            commit.len() >= 40 && commit[..40].chars().all(|c| c.is_ascii_hexdigit()),
            "{m}"
        );
        assert_eq!(m["model"]["profile_sha256"].as_str().unwrap().len(), 64);
    }
    // The chain's instruction switches to the second stage's once the first stage's checks pass.
    let queries: Vec<Value> = std::fs::read_to_string(&log)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    let chain: Vec<&Value> = queries
        .iter()
        .filter(|q| q["task"] == "thermal_cycler.close_then_open" && q["seed"] == 0)
        .collect();
    let prompts: Vec<&str> = chain
        .iter()
        .map(|q| q["prompt"].as_str().unwrap())
        .collect();
    assert!(
        queries.iter().all(|q| !q["keys"]
            .as_array()
            .unwrap()
            .iter()
            .any(|k| k.as_str().unwrap().contains("environment_state"))),
        "a profile without `environment_state_key` sends no environment state"
    );
    let first = prompts[0];
    let switched = prompts
        .iter()
        .position(|p| *p != first)
        .expect("the prompt never switched");
    assert!(
        prompts[switched..].iter().all(|p| *p == prompts[switched]),
        "the prompt went back: {prompts:?}"
    );
}

#[test]
fn openpi_server_without_a_metadata_frame_autobios_variant() {
    let rec = recordings().to_str().unwrap().to_string();
    let dir = scratch("openpi-no-metadata");
    let server = Server::start("openpi_server.py", &["--recordings", &rec, "--no-metadata"]);
    // Two workers, two connections to the server at once: the same episodes as the expert's.
    let out = eval_model(
        &server,
        "openpi",
        &profile(&dir, 30.0),
        &[CLOSE, "--workers", "2"],
        2,
        &dir,
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    let eps = journal(&dir, "thermal_cycler.close_lid");
    assert_eq!(eps.len(), 2);
    for e in &eps {
        let x = expert("thermal_cycler.close_lid", e["seed"].as_u64().unwrap());
        assert_eq!(e["outcome"], "success", "{e}");
        assert_eq!(e["trajectory_hash"], x["trajectory_hash"]);
    }
    assert_eq!(
        manifest(&dir, "thermal_cycler.close_lid")["model"]["metadata"],
        Value::Null
    );
}

#[test]
fn vla_eval_server_reaches_the_experts_success() {
    let rec = recordings().to_str().unwrap().to_string();
    let dir = scratch("vla-eval-e2e");
    let server = Server::start("vla_eval_server.py", &["--recordings", &rec]);
    // vla-eval sends an observation (two rendered cameras) every control step: one episode of
    // each keeps this test short.
    let out = eval_model(&server, "vla-eval", "pi0", &[CLOSE, CHAIN], 1, &dir);
    assert!(out.status.success(), "{}", text(&out.stderr));
    for task in ["thermal_cycler.close_lid", "thermal_cycler.close_then_open"] {
        let eps = journal(&dir, task);
        assert_eq!(eps.len(), 1);
        for e in &eps {
            // vla-eval's server casts actions to float32: not the same bits, the same outcome.
            assert_eq!(e["outcome"], "success", "{task}: {e}");
            let x = expert(task, e["seed"].as_u64().unwrap());
            let (a, b) = (
                e["control_steps"].as_i64().unwrap(),
                x["control_steps"].as_i64().unwrap(),
            );
            assert!(
                (a - b).abs() <= 5,
                "{task}: {a} control steps against the expert's {b}"
            );
        }
        let m = manifest(&dir, task);
        assert_eq!(m["model"]["wire"], "vla-eval");
        assert_eq!(
            m["model"]["metadata"]["model_server"], "ExpertServer",
            "{m}"
        );
        assert_eq!(m["model"]["metadata"]["protocol_version"], 1);
    }
}

#[test]
fn rdt_profile_sends_the_unified_state_and_a_real_earlier_frame() {
    let rec = recordings().to_str().unwrap().to_string();
    let dir = scratch("rdt");
    let log = dir.join("queries.jsonl");
    let server = Server::start(
        "openpi_server.py",
        &[
            "--recordings",
            &rec,
            "--layout",
            "rdt",
            "--chunk",
            "64",
            "--execute",
            "64",
            "--log",
            log.to_str().unwrap(),
        ],
    );
    let rdt = std::fs::read_to_string("profiles/rdt.toml")
        .unwrap()
        .replace("reset_frame = false", "reset_frame = true");
    let path = dir.join("rdt-reset.toml");
    std::fs::write(&path, rdt).unwrap();
    let out = eval_model(&server, "openpi", path.to_str().unwrap(), &[CLOSE], 2, &dir);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let eps = journal(&dir, "thermal_cycler.close_lid");
    assert_eq!(eps.len(), 2, "{eps:#?}");
    for e in eps {
        let x = expert("thermal_cycler.close_lid", e["seed"].as_u64().unwrap());
        assert_eq!(e["outcome"], "success", "{e}");
        assert_eq!(e["trajectory_hash"], x["trajectory_hash"]);
    }
    let queries: Vec<Value> = std::fs::read_to_string(&log)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    let first: Vec<&Value> = queries.iter().filter(|q| q["query"] == 0).collect();
    assert!(
        !first.is_empty(),
        "the server logged no episode's first query"
    );
    assert!(
        first.iter().all(|q| q["history_differs"] == false),
        "an episode's first query repeats its current frame"
    );
    assert!(
        queries.iter().any(|q| q["history_differs"] == true),
        "the earlier frame must be a real earlier frame while the arm moves: {queries:?}"
    );
}

/// The privileged environment state goes out only when the profile names its key: then every
/// query carries the task's whole layout (`autobio describe` lists it), the expert's episode is
/// unchanged, and the manifest's profile records the key.
#[test]
fn the_environment_state_is_sent_when_the_profile_asks_for_it() {
    let rec = recordings().to_str().unwrap().to_string();
    let dir = scratch("openpi-environment-state");
    let log = dir.join("queries.jsonl");
    let server = Server::start(
        "openpi_server.py",
        &["--recordings", &rec, "--log", log.to_str().unwrap()],
    );
    let base = std::fs::read_to_string(profile(&dir, 30.0)).unwrap();
    let path = dir.join("pi0-state.toml");
    std::fs::write(
        &path,
        base.replace(
            "prompt_key = \"prompt\"",
            "prompt_key = \"prompt\"\nenvironment_state_key = \"observation.environment_state\"",
        ),
    )
    .unwrap();
    let out = eval_model(&server, "openpi", path.to_str().unwrap(), &[CLOSE], 1, &dir);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let e = &journal(&dir, "thermal_cycler.close_lid")[0];
    assert_eq!(e["outcome"], "success", "{e}");
    assert_eq!(
        e["trajectory_hash"],
        expert("thermal_cycler.close_lid", 0)["trajectory_hash"]
    );
    assert_eq!(
        manifest(&dir, "thermal_cycler.close_lid")["model"]["profile"]["environment_state_key"],
        "observation.environment_state"
    );
    let sheet = text(&autobio(&["describe", CLOSE]).stdout);
    let line = sheet
        .lines()
        .find(|l| l.starts_with("environment state ("))
        .unwrap_or_else(|| panic!("describe lists no environment state:\n{sheet}"));
    let n: usize = line["environment state (".len()..]
        .split(' ')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    let queries: Vec<Value> = std::fs::read_to_string(&log)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert!(queries.len() > 1);
    let states: Vec<&Vec<Value>> = queries
        .iter()
        .map(|q| {
            q["environment_state"]
                .as_array()
                .expect("no environment state sent")
        })
        .collect();
    assert!(states.iter().all(|s| s.len() == n), "{n} values expected");
    assert_ne!(
        states.first(),
        states.last(),
        "the lid moves, so the environment state changes over the episode"
    );
}

/// A server that never says where it listens fails the test at the deadline, not by hanging it.
#[test]
fn a_server_that_never_comes_up_fails_within_its_deadline() {
    let mut cmd = std::process::Command::new(common::python());
    cmd.args(["-c", "import time; time.sleep(60)"]);
    let started = std::time::Instant::now();
    let err = match Server::spawn(cmd, "silent", std::time::Duration::from_millis(500)) {
        Ok(_) => panic!("a silent server came up"),
        Err(e) => e,
    };
    assert!(
        err.contains("did not say where it listens within 0.5 s"),
        "{err}"
    );
    assert!(started.elapsed() < std::time::Duration::from_secs(10));
    // And one that says something else is reported with what it said.
    let mut cmd = std::process::Command::new(common::python());
    cmd.args(["-c", "print('hello')"]);
    let err = match Server::spawn(cmd, "chatty", std::time::Duration::from_secs(30)) {
        Ok(_) => panic!("a server that never listened came up"),
        Err(e) => e,
    };
    assert!(err.contains("chatty did not start: \"hello\\n\""), "{err}");
}
