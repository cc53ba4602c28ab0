//! A misbehaving model server on loopback (tests/servers/openpi_server.py `--fault`, and the
//! vla-eval package's own error frames): each fault ends only the episode it happens in, with its
//! outcome class and reason; the episodes before and after it finish normally and every one is
//! in the journal. No fault stretches a reply past its timeout (pings, a reply trickled in
//! fragments, error frames for other requests), and a kept connection the server has closed
//! between episodes is replaced, not failed on. Every run is under a watchdog: a hang fails.

use crate::common;

use common::{Server, autobio, autobio_within, journal, scratch, text};
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;
use std::time::{Duration, Instant};

/// Longer than any run here takes (three episodes, faults at a 5 s timeout), far shorter than a
/// hang.
const WATCHDOG: Duration = Duration::from_secs(120);

const CLOSE: &str = "protocols/thermal_cycler/close_lid.toml";
const TASK: &str = "thermal_cycler.close_lid";

fn recordings() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let dir = scratch("fault-recordings");
        let out = autobio(&[
            "eval",
            "--protocol",
            CLOSE,
            "--episodes",
            "3",
            "--seed",
            "0",
            "--out",
            dir.to_str().unwrap(),
            "--record",
            "--image-every",
            "0",
        ]);
        assert!(out.status.success(), "{}", text(&out.stderr));
        dir
    })
}

/// pi0's layout with reset frames and a 5 s reply timeout: a thousand times a healthy reply on a
/// loaded 2-core machine, short enough for the faults that must reach it.
fn profile(dir: &Path) -> PathBuf {
    let text = std::fs::read_to_string("profiles/pi0.toml")
        .unwrap()
        .replace("reset_frame = false", "reset_frame = true")
        .replace("timeout_s = 30.0", "timeout_s = 5.0");
    let path = dir.join("profile.toml");
    std::fs::write(&path, text).unwrap();
    path
}

/// Three episodes against `url`; the journal and stderr.
fn run(url: &str, wire: &str, profile: &Path, dir: &Path) -> (Vec<Value>, String) {
    run_n(url, wire, profile, dir, "3")
}

/// `episodes` episodes against `url`; the journal and stderr.
fn run_n(
    url: &str,
    wire: &str,
    profile: &Path,
    dir: &Path,
    episodes: &str,
) -> (Vec<Value>, String) {
    let out = autobio_within(
        &[
            "eval",
            "--model",
            url,
            "--wire",
            wire,
            "--profile",
            profile.to_str().unwrap(),
            "--protocol",
            CLOSE,
            "--episodes",
            episodes,
            "--seed",
            "0",
            "--connect-attempts",
            "2",
            "--out",
            dir.to_str().unwrap(),
        ],
        WATCHDOG,
    );
    let stderr = text(&out.stderr);
    assert!(
        out.status.success(),
        "a fault must not end the run: {stderr}"
    );
    (journal(dir, TASK), stderr)
}

/// The server misbehaves in episode 1 only: episodes 0 and 2 succeed.
fn fault(mode: &str, outcome: &str, reason: &str) {
    fault_with(mode, &[], outcome, reason);
}

/// [`fault`], with more of the server's arguments.
fn fault_with(mode: &str, extra: &[&str], outcome: &str, reason: &str) {
    let dir = scratch(&format!("fault-{mode}{}", extra.join("")));
    let rec = recordings().to_str().unwrap().to_string();
    let mut args = vec![
        "--recordings",
        &rec,
        "--fault",
        mode,
        "--fault-episode",
        "1",
        "--fault-at",
        "2",
    ];
    args.extend(extra);
    let server = Server::start("openpi_server.py", &args);
    let (eps, stderr) = run(&server.url, "openpi", &profile(&dir), &dir);
    let got: Vec<(&str, u64)> = eps
        .iter()
        .map(|e| (e["outcome"].as_str().unwrap(), e["seed"].as_u64().unwrap()))
        .collect();
    assert_eq!(
        got,
        [("success", 0), (outcome, 1), ("success", 2)],
        "{mode}: {eps:#?}"
    );
    let error = eps[1]["error"].as_str().unwrap();
    assert!(error.contains(reason), "{mode}: {error}");
    assert_eq!(eps[1]["success"], false);
    assert!(
        stderr.contains(&format!("seed 1 (run 0): {outcome}: ")),
        "{mode}: {stderr}"
    );
}

#[test]
fn a_server_that_closes_mid_episode() {
    fault("close", "server_fault", "closed the connection");
}

#[test]
fn a_server_that_stalls_past_the_timeout() {
    fault("stall", "server_fault", "no reply within 5 s");
}

/// What a server logged with `--events` (one JSON object a line).
fn events(path: &Path) -> Vec<Value> {
    std::fs::read_to_string(path)
        .unwrap_or_default()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

#[test]
fn a_server_that_pings_while_it_stalls_does_not_stretch_the_timeout() {
    // A keepalive ping every 0.2 s: each ping is read (and answered) within the timeout.
    let log = scratch("fault-pings").join("events.jsonl");
    let log_arg = log.to_str().unwrap().to_string();
    fault_with(
        "stall",
        &["--ping-interval", "0.2", "--events", &log_arg],
        "server_fault",
        "no reply within 5 s",
    );
    // The pings were sent: many over the 5 s the stalled reply was waited for.
    let pings = events(&log).iter().filter(|e| e["event"] == "ping").count();
    assert!(pings >= 15, "{pings} pings sent");
}

#[test]
fn a_server_that_trickles_its_reply_does_not_stretch_the_timeout() {
    // The reply in 16-byte fragments 0.05 s apart takes seconds; a timeout per read would never
    // fire (and the episode would succeed), the one deadline per reply does.
    fault("trickle", "server_fault", "no reply within 5 s");
}

#[test]
fn a_server_that_answers_more_actions_than_the_chunk() {
    fault(
        "long",
        "policy_error",
        "a chunk of 51 actions; the profile allows at most 50",
    );
}

/// The server ends the kept connection after episode 0's last reply (`mode`: with a close frame,
/// or dropped with none): every episode succeeds, the later ones on a second connection.
fn stale_connection(mode: &str) {
    let dir = scratch(&format!("stale-{mode}"));
    let rec = recordings().to_str().unwrap().to_string();
    let log = dir.join("queries.jsonl");
    let server = Server::start(
        "openpi_server.py",
        &[
            "--recordings",
            &rec,
            "--fault",
            mode,
            "--fault-episode",
            "0",
            "--log",
            log.to_str().unwrap(),
        ],
    );
    let (eps, _) = run(&server.url, "openpi", &profile(&dir), &dir);
    assert_eq!(eps.len(), 3, "{eps:#?}");
    assert!(eps.iter().all(|e| e["outcome"] == "success"), "{eps:#?}");
    let connections: Vec<(u64, u64)> = std::fs::read_to_string(&log)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str::<Value>(l).unwrap())
        .map(|q| {
            (
                q["seed"].as_u64().unwrap(),
                q["connection"].as_u64().unwrap(),
            )
        })
        .collect::<std::collections::BTreeSet<_>>()
        .into_iter()
        .collect();
    assert_eq!(connections, [(0, 1), (1, 2), (2, 2)], "{mode}");
}

#[test]
fn a_kept_connection_the_server_closed_between_episodes_is_replaced() {
    stale_connection("close-after");
}

#[test]
fn a_kept_connection_the_server_dropped_between_episodes_is_replaced() {
    stale_connection("abort-after");
}

#[test]
fn a_vla_eval_reply_for_an_earlier_request_fails_only_its_episode() {
    // Seed 1's third observation is answered twice: the copy carries that observation's seq and
    // arrives as the "reply" to the fourth. It is refused as stale, and the next episode runs on
    // a fresh connection.
    let dir = scratch("fault-vla-eval-stale");
    let rec = recordings().to_str().unwrap().to_string();
    let server = Server::start(
        "vla_eval_server.py",
        &["--recordings", &rec, "--duplicate-seed", "1"],
    );
    let text = std::fs::read_to_string("profiles/pi0.toml").unwrap();
    let path = dir.join("pi0.toml");
    std::fs::write(&path, text.replace("timeout_s = 30.0", "timeout_s = 10.0")).unwrap();
    let (eps, _) = run(&server.url, "vla-eval", &path, &dir);
    let got: Vec<&str> = eps.iter().map(|e| e["outcome"].as_str().unwrap()).collect();
    assert_eq!(got, ["success", "server_fault", "success"], "{eps:#?}");
    let error = eps[1]["error"].as_str().unwrap();
    assert!(
        error.contains("carries seq") && error.contains("replies must echo their request's seq"),
        "{error}"
    );
}

#[test]
fn error_frames_for_other_requests_do_not_stretch_a_vla_eval_timeout() {
    // The server sends an `error` frame for another seq every 0.5 s and never answers: the
    // episode fails at its 5 s timeout, not after the server's minute of noise.
    let dir = scratch("fault-vla-eval-noise");
    let log = dir.join("events.jsonl");
    let server = Server::start(
        "vla_eval_noise_server.py",
        &["--events", log.to_str().unwrap()],
    );
    let start = Instant::now();
    let (eps, _) = run_n(&server.url, "vla-eval", &profile(&dir), &dir, "1");
    let took = start.elapsed();
    assert_eq!(eps.len(), 1);
    assert_eq!(eps[0]["outcome"], "server_fault", "{eps:#?}");
    let error = eps[0]["error"].as_str().unwrap();
    assert!(error.contains("no reply within 5 s"), "{error}");
    assert!(took < Duration::from_secs(30), "took {took:?}");
    // The noise was made: error frames within the 5 s the reply was waited for.
    let noise: Vec<f64> = events(&log)
        .iter()
        .filter(|e| e["event"] == "error_frame")
        .map(|e| e["after_s"].as_f64().unwrap())
        .collect();
    assert!(noise.iter().filter(|&&t| t < 5.0).count() >= 6, "{noise:?}");
}

#[test]
fn a_server_that_answers_the_wrong_shape() {
    fault(
        "shape",
        "policy_error",
        "actions of 8 values; this task's actions have 7",
    );
}

#[test]
fn a_server_that_answers_nan() {
    fault("nan", "policy_error", "not a finite number");
}

#[test]
fn a_server_that_answers_out_of_range_targets() {
    fault(
        "range",
        "policy_error",
        "(100) is outside its actuator's range",
    );
}

#[test]
fn a_server_that_reports_an_error_frame() {
    fault(
        "error",
        "server_fault",
        "the model ran out of memory (a fault on request)",
    );
}

#[test]
fn a_server_that_sends_garbage() {
    fault("garbage", "server_fault", "not msgpack");
}

#[test]
fn a_server_that_refuses_connections() {
    let dir = scratch("fault-refused");
    // A port that was just free: bound, then let go.
    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    let (eps, _) = run(
        &format!("ws://127.0.0.1:{port}"),
        "openpi",
        &profile(&dir),
        &dir,
    );
    assert_eq!(eps.len(), 3);
    for e in &eps {
        assert_eq!(e["outcome"], "server_fault", "{e}");
        let error = e["error"].as_str().unwrap();
        assert!(
            error.contains("cannot connect") && error.contains("after 2 attempts"),
            "{error}"
        );
    }
    let results: Value = serde_json::from_str(
        &std::fs::read_to_string(dir.join(format!("{TASK}.results.json"))).unwrap(),
    )
    .unwrap();
    assert_eq!(
        results["summary"]["episodes"], 3,
        "faults stay in the denominator"
    );
    assert_eq!(results["summary"]["outcomes"]["server_fault"], 3);
    assert_eq!(results["summary"]["success_rate"], 0.0);
}

#[test]
fn a_vla_eval_server_error_frame_keeps_the_connection() {
    // One camera where vla-eval's server wants two: its `predict` raises, the package answers an
    // `error` frame, and every episode fails with the server's own words, on one connection.
    let dir = scratch("fault-vla-eval");
    let rec = recordings().to_str().unwrap().to_string();
    let log = dir.join("starts.jsonl");
    let server = Server::start(
        "vla_eval_server.py",
        &["--recordings", &rec, "--log", log.to_str().unwrap()],
    );
    let text = std::fs::read_to_string("profiles/pi0.toml").unwrap();
    let one_camera = &text[..text
        .find("[[image]]\nkey = \"observation/wrist_image\"")
        .unwrap()];
    let path = dir.join("one-camera.toml");
    std::fs::write(&path, one_camera).unwrap();
    let (eps, _) = run(&server.url, "vla-eval", &path, &dir);
    assert_eq!(eps.len(), 3);
    for e in &eps {
        assert_eq!(e["outcome"], "server_fault", "{e}");
        let error = e["error"].as_str().unwrap();
        assert!(
            error.contains("observation_failed") && error.contains("1 images"),
            "{error}"
        );
    }
    let sessions: std::collections::BTreeSet<String> = std::fs::read_to_string(&log)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str::<Value>(l).unwrap()["session"].to_string())
        .collect();
    assert_eq!(
        sessions.len(),
        1,
        "an error frame must not cost the connection"
    );
}

#[test]
fn a_vla_eval_server_that_cannot_start_an_episode() {
    // vla-eval answers a failed `on_episode_start` with an `error` frame for that frame's seq:
    // the episode fails with it, and the next one is not handed the failed one's stale reply.
    let dir = scratch("fault-vla-eval-start");
    let rec = recordings().to_str().unwrap().to_string();
    let server = Server::start(
        "vla_eval_server.py",
        &["--recordings", &rec, "--fail-start-seed", "0"],
    );
    let text = std::fs::read_to_string("profiles/pi0.toml").unwrap();
    let path = dir.join("pi0.toml");
    std::fs::write(&path, text.replace("timeout_s = 30.0", "timeout_s = 10.0")).unwrap();
    let (eps, _) = run_n(&server.url, "vla-eval", &path, &dir, "2");
    let got: Vec<&str> = eps.iter().map(|e| e["outcome"].as_str().unwrap()).collect();
    assert_eq!(got, ["server_fault", "success"], "{eps:#?}");
    let error = eps[0]["error"].as_str().unwrap();
    assert!(
        error.contains("episode_start_failed") && error.contains("no checkpoint for seed 0"),
        "{error}"
    );
}

#[test]
fn a_server_whose_metadata_frame_comes_late() {
    // The metadata frame arrives after the client stopped waiting for it: it is recognised as
    // metadata (no `actions`), not taken for the first reply.
    let dir = scratch("fault-late-metadata");
    let rec = recordings().to_str().unwrap().to_string();
    let log = dir.join("events.jsonl");
    let server = Server::start(
        "openpi_server.py",
        &[
            "--recordings",
            &rec,
            "--metadata-delay",
            "1.0",
            "--events",
            log.to_str().unwrap(),
        ],
    );
    let (eps, _) = run(&server.url, "openpi", &profile(&dir), &dir);
    assert_eq!(eps.len(), 3, "{eps:#?}");
    assert!(eps.iter().all(|e| e["outcome"] == "success"), "{eps:#?}");
    // It was late: sent a second after the connection opened, past the client's wait, which
    // therefore recorded no metadata in the run's manifest.
    let sent: Vec<f64> = events(&log)
        .iter()
        .filter(|e| e["event"] == "metadata")
        .map(|e| e["after_s"].as_f64().unwrap())
        .collect();
    assert!(
        !sent.is_empty() && sent.iter().all(|&t| t >= 1.0),
        "{sent:?}"
    );
    let manifest: Value = serde_json::from_str(
        &std::fs::read_to_string(dir.join("thermal_cycler.close_lid.manifest.json")).unwrap(),
    )
    .unwrap();
    assert_eq!(manifest["model"]["metadata"], Value::Null, "{manifest}");
}
