//! Helpers the integration tests share: compiling shipped protocols (as they are or edited),
//! running one episode with a policy, reading a predicate's value from its verdict, running the
//! `autobio` binary, scratch folders. Each test
//! file uses the ones it needs.
#![allow(dead_code)]

use std::path::PathBuf;
use std::process::{Command, Output};
use std::sync::Arc;

/// The value of the predicate written `text` in an episode's verdict.
pub(crate) fn predicate<'a>(
    r: &'a results::episode::EpisodeResult,
    text: &str,
) -> &'a results::verdict::PredicateValue {
    r.verdict
        .predicates()
        .iter()
        .find(|p| p.text == text)
        .unwrap_or_else(|| panic!("no `{text}` in {:#?}", r.verdict))
}

/// A protocol file compiled as it is.
pub(crate) fn compile(path: &str) -> compiler::Task {
    compile_edited(path, |s| s)
}

/// A protocol file compiled after editing its text.
pub(crate) fn compile_edited(path: &str, edit: impl FnOnce(String) -> String) -> compiler::Task {
    let source = edit(std::fs::read_to_string(path).unwrap());
    let (task, diags) = compiler::compile_source(&source, path);
    task.unwrap_or_else(|| panic!("{path}: {diags:#?}"))
}

/// The scene for episode `seed`, built.
pub(crate) fn scene(
    task: &compiler::Task,
    seed: u64,
) -> (compiler::SceneInstance, Arc<runtime::Scene>) {
    let instance = task.sample(seed);
    let scene = Arc::new(runtime::Scene::build(task, &instance).unwrap());
    (instance, scene)
}

/// One episode of `task` with the policy `make` builds for its scene.
pub(crate) fn run_with(
    task: &compiler::Task,
    seed: u64,
    opts: &scoring::episode::EpisodeOptions,
    make: impl FnOnce(
        &compiler::Task,
        &runtime::Scene,
        &compiler::SceneInstance,
    ) -> Box<dyn policy::Policy>,
) -> results::episode::EpisodeResult {
    let (instance, scene) = scene(task, seed);
    let mut policy = make(task, &scene, &instance);
    scoring::episode::run_episode(task, &scene, &instance, policy.as_mut(), opts).unwrap()
}

/// One episode with a policy by name (`expert`, `hold`), not recorded.
pub(crate) fn run(
    task: &compiler::Task,
    seed: u64,
    policy: &str,
) -> results::episode::EpisodeResult {
    run_with(
        task,
        seed,
        &scoring::episode::EpisodeOptions::default(),
        |t, s, i| scoring::policies::make(policy, t, s, i).unwrap(),
    )
}

/// Runs the `autobio` binary with `NO_COLOR` unset.
pub(crate) fn autobio(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_autobio"))
        .args(args)
        .env_remove("NO_COLOR")
        .output()
        .unwrap()
}

/// Runs the `autobio` binary with these environment variables set.
pub(crate) fn autobio_env(args: &[&str], vars: &[(&str, &str)]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_autobio"))
        .args(args)
        .envs(vars.iter().copied())
        .env_remove("NO_COLOR")
        .output()
        .unwrap()
}

/// Runs the `autobio` binary and kills it if it has not finished within `limit`: a run that
/// would hang fails the test with the time it took instead of blocking the suite.
pub(crate) fn autobio_within(args: &[&str], limit: std::time::Duration) -> Output {
    use std::io::Read;
    let mut child = Command::new(env!("CARGO_BIN_EXE_autobio"))
        .args(args)
        .env_remove("NO_COLOR")
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // Drained on threads, so a chatty run cannot block on a full pipe.
    let drain = |mut pipe: Box<dyn Read + Send>| {
        std::thread::spawn(move || {
            let mut bytes = Vec::new();
            pipe.read_to_end(&mut bytes).unwrap();
            bytes
        })
    };
    let out = drain(Box::new(child.stdout.take().unwrap()));
    let err = drain(Box::new(child.stderr.take().unwrap()));
    let start = std::time::Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        if start.elapsed() > limit {
            child.kill().unwrap();
            child.wait().unwrap();
            panic!(
                "`autobio {}` did not finish within {} s: {}",
                args.join(" "),
                limit.as_secs_f64(),
                text(&err.join().unwrap())
            );
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    };
    Output {
        status,
        stdout: out.join().unwrap(),
        stderr: err.join().unwrap(),
    }
}

/// Runs the `autobio` binary, which must succeed; its standard output.
pub(crate) fn autobio_ok(args: &[&str]) -> String {
    let out = autobio(args);
    assert!(
        out.status.success(),
        "autobio {args:?}: {}{}",
        text(&out.stdout),
        text(&out.stderr)
    );
    text(&out.stdout)
}

/// `autobio eval --suite SUITE --out OUT` with `extra` arguments, which must succeed.
pub(crate) fn eval_suite(suite: &std::path::Path, out: &std::path::Path, extra: &[&str]) -> String {
    let mut args = vec![
        "eval",
        "--suite",
        suite.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend(extra);
    autobio_ok(&args)
}

/// `autobio leaderboard submit RUN --model-name MODEL --out BUNDLE` with `extra` arguments,
/// which must succeed.
pub(crate) fn submit(
    run: &std::path::Path,
    model: &str,
    bundle: &std::path::Path,
    extra: &[&str],
) -> String {
    let mut args = vec![
        "leaderboard",
        "submit",
        run.to_str().unwrap(),
        "--model-name",
        model,
        "--out",
        bundle.to_str().unwrap(),
    ];
    args.extend(extra);
    autobio_ok(&args)
}

pub(crate) fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// A fresh, empty folder under the system's temporary folder, unique to this call (tests run
/// in parallel in one process: two that ask for the same name get two folders).
pub(crate) fn scratch(name: &str) -> PathBuf {
    static CALLS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let n = CALLS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let dir = std::env::temp_dir().join(format!("autobio-test-{}-{n}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The lines of a run's journal (`<out>/<task id>.journal.jsonl`), parsed; none if it is absent.
pub(crate) fn journal(dir: &std::path::Path, task_id: &str) -> Vec<serde_json::Value> {
    std::fs::read_to_string(dir.join(format!("{task_id}.journal.jsonl")))
        .unwrap_or_default()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

/// How long a reference model server may take to come up (Python and numpy importing on a
/// loaded 2-core machine take a few seconds).
pub(crate) const SERVER_START_DEADLINE: std::time::Duration = std::time::Duration::from_secs(60);

/// A reference model server (`tests/servers/<script>`) running on loopback in the servers'
/// Python environment; killed when dropped.
pub(crate) struct Server {
    child: std::process::Child,
    pub url: String,
}

impl Server {
    pub(crate) fn start(script: &str, args: &[&str]) -> Server {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        let mut cmd = Command::new(python());
        cmd.arg(root.join("tests/servers").join(script)).args(args);
        Server::spawn(cmd, script, SERVER_START_DEADLINE).unwrap_or_else(|e| panic!("{e}"))
    }

    /// Starts `cmd` and waits at most `deadline` for its first line, `listening on <url>`; a
    /// server that says nothing by then is killed and reported.
    pub(crate) fn spawn(
        mut cmd: Command,
        name: &str,
        deadline: std::time::Duration,
    ) -> Result<Server, String> {
        use std::io::BufRead;
        let mut child = cmd
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::inherit())
            .spawn()
            .map_err(|e| format!("{name}: cannot start: {e}"))?;
        let stdout = child.stdout.take().unwrap();
        let (tx, rx) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            let mut line = String::new();
            let read = std::io::BufReader::new(stdout).read_line(&mut line);
            let _ = tx.send(read.map(|_| line));
        });
        let line = match rx.recv_timeout(deadline) {
            Ok(Ok(line)) => line,
            Ok(Err(e)) => {
                let _ = child.kill();
                return Err(format!("{name}: cannot read its first line: {e}"));
            }
            Err(_) => {
                let _ = child.kill();
                let _ = child.wait();
                return Err(format!(
                    "{name} did not say where it listens within {:.1} s",
                    deadline.as_secs_f64()
                ));
            }
        };
        match line.trim().strip_prefix("listening on ") {
            Some(url) => Ok(Server {
                child,
                url: url.to_string(),
            }),
            None => {
                let _ = child.kill();
                let _ = child.wait();
                Err(format!("{name} did not start: {line:?}"))
            }
        }
    }
}

/// The lab languages' Python (autoprotocol-python, Opentrons' analyzer; `make setup` makes it).
pub(crate) fn lab_python() -> std::path::PathBuf {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let python = root.join(".deps/lab-languages/bin/python");
    assert!(
        python.exists(),
        "{} is missing: run `make setup`",
        python.display()
    );
    python
}

/// The servers' Python (`make setup` makes it).
pub(crate) fn python() -> std::path::PathBuf {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let python = root.join(".deps/servers/bin/python");
    assert!(
        python.exists(),
        "{} is missing: run `make setup`",
        python.display()
    );
    python
}

impl Drop for Server {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Standard deviation of an image's pixel values: a blank (one-colour) frame has none.
pub(crate) fn spread(rgb: &[u8]) -> f64 {
    let n = rgb.len() as f64;
    let mean = rgb.iter().map(|&v| f64::from(v)).sum::<f64>() / n;
    (rgb.iter()
        .map(|&v| (f64::from(v) - mean).powi(2))
        .sum::<f64>()
        / n)
        .sqrt()
}

/// Every shipped protocol and chain file (`protocols/<kind>/<name>.toml`), sorted; scene files,
/// which protocols share and which are no tasks, left out.
pub(crate) fn shipped_protocols() -> Vec<PathBuf> {
    let mut out = Vec::new();
    for dir in std::fs::read_dir("protocols").unwrap() {
        for f in std::fs::read_dir(dir.unwrap().path()).unwrap() {
            let f = f.unwrap().path();
            let scene = std::fs::read_to_string(&f).is_ok_and(|t| compiler::is_scene_file(&t));
            if f.extension().is_some_and(|e| e == "toml") && !scene {
                out.push(f);
            }
        }
    }
    out.sort();
    out
}

/// A protocol the expert cannot run: two arms, a tube from a drawn slot, and a hand-over it has no
/// motions for yet (every episode ends in a policy error naming step 2).
pub(crate) const HAND_OVER: &str = r#"format = 1
[protocol]
id = "tube.hand_over"
level = "medium"
instruction = "hand the tube over"
time_limit = "20 s"
[robots.first]
model = "ur5e_2f85"
base = { pos_m = [0.0, 0.4, 0.824] }
[robots.second]
model = "ur5e_2f85"
base = { pos_m = [0.0, -0.4, 0.824], yaw_deg = 90 }
[labware.rack]
kind = "tube_rack"
pose = { pos_m = [0.0, 0.0, 0.854] }
[labware.tube]
kind = "tube_50ml"
at = "rack.{slot}"
[params.slot]
slot = "rack"
[[steps]]
do = "pick"
on = "tube"
with = "first"
[[steps]]
do = "hand_over"
on = "tube"
to = "second"
with = "first"
[success]
all = ["second touches tube", "tube lifted 5 cm"]
"#;
