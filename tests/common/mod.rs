//! Helpers the integration tests share: compiling shipped protocols (as they are or edited),
//! running one episode with a policy, running the `autobio` binary, scratch folders. Each test
//! file uses the ones it needs.
#![allow(dead_code)]

use std::path::PathBuf;
use std::process::{Command, Output};
use std::sync::Arc;

/// A protocol file compiled as it is.
pub fn compile(path: &str) -> compiler::Task {
    compile_edited(path, |s| s)
}

/// A protocol file compiled after editing its text.
pub fn compile_edited(path: &str, edit: impl FnOnce(String) -> String) -> compiler::Task {
    let source = edit(std::fs::read_to_string(path).unwrap());
    let (task, diags) = compiler::compile_source(&source, path);
    task.unwrap_or_else(|| panic!("{path}: {diags:#?}"))
}

/// The scene for episode `seed`, built.
pub fn scene(task: &compiler::Task, seed: u64) -> (compiler::SceneInstance, Arc<runtime::Scene>) {
    let instance = task.sample(seed);
    let scene = Arc::new(runtime::Scene::build(task, &instance).unwrap());
    (instance, scene)
}

/// One episode of `task` with the policy `make` builds for its scene.
pub fn run_with(
    task: &compiler::Task,
    seed: u64,
    opts: &scoring::EpisodeOptions,
    make: impl FnOnce(
        &compiler::Task,
        &runtime::Scene,
        &compiler::SceneInstance,
    ) -> Box<dyn scoring::Policy>,
) -> scoring::EpisodeResult {
    let (instance, scene) = scene(task, seed);
    let mut policy = make(task, &scene, &instance);
    scoring::run_episode(task, &scene, &instance, policy.as_mut(), opts).unwrap()
}

/// One episode with a policy by name (`expert`, `hold`), not recorded.
pub fn run(task: &compiler::Task, seed: u64, policy: &str) -> scoring::EpisodeResult {
    run_with(
        task,
        seed,
        &scoring::EpisodeOptions::default(),
        |t, s, i| scoring::policies::make(policy, t, s, i).unwrap(),
    )
}

/// Runs the `autobio` binary with `NO_COLOR` unset.
pub fn autobio(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_autobio"))
        .args(args)
        .env_remove("NO_COLOR")
        .output()
        .unwrap()
}

pub fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// A fresh, empty folder under the system's temporary folder, unique to this test process.
pub fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("autobio-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The lines of a run's journal (`<out>/<task id>.journal.jsonl`), parsed; none if it is absent.
pub fn journal(dir: &std::path::Path, task_id: &str) -> Vec<serde_json::Value> {
    std::fs::read_to_string(dir.join(format!("{task_id}.journal.jsonl")))
        .unwrap_or_default()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

/// A reference model server (`tests/servers/<script>`) running on loopback in the servers'
/// Python environment; killed when dropped.
pub struct Server {
    child: std::process::Child,
    pub url: String,
}

impl Server {
    pub fn start(script: &str, args: &[&str]) -> Server {
        use std::io::BufRead;
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        let python = root.join(".deps/servers/bin/python");
        assert!(
            python.exists(),
            "{} is missing: run `make setup`",
            python.display()
        );
        let mut child = Command::new(python)
            .arg(root.join("tests/servers").join(script))
            .args(args)
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::inherit())
            .spawn()
            .unwrap();
        let mut line = String::new();
        std::io::BufReader::new(child.stdout.take().unwrap())
            .read_line(&mut line)
            .unwrap();
        let url = line
            .trim()
            .strip_prefix("listening on ")
            .unwrap_or_else(|| panic!("{script} did not start: {line:?}"))
            .to_string();
        Server { child, url }
    }
}

impl Drop for Server {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Standard deviation of an image's pixel values: a blank (one-colour) frame has none.
pub fn spread(rgb: &[u8]) -> f64 {
    let n = rgb.len() as f64;
    let mean = rgb.iter().map(|&v| f64::from(v)).sum::<f64>() / n;
    (rgb.iter()
        .map(|&v| (f64::from(v) - mean).powi(2))
        .sum::<f64>()
        / n)
        .sqrt()
}
