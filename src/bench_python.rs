//! `autobio bench --only python`: the Python package's cost per control step against the Rust
//! harness's on the same task and actions (the robots held at their targets), 224x224, every task
//! camera drawn each step: the Rust `runtime::Env` loop measured here, then the package's own
//! measurement (`python -m autobio.bench` in `.deps/python-env`, made by `make setup`): the
//! native core alone, the gymnasium environment (target: under 10% over Rust per step), and the
//! vector environment's steps/s with 1, 2 and 4 episodes on threads. Single-environment figures
//! are the best of three runs of 600 steps, to keep machine noise out of a few-percent ratio.

use anyhow::{Context, Result, bail};
use std::time::Instant;

const STEPS: usize = 600;
const SIZE: [usize; 2] = [224, 224];

pub(crate) fn figures(task: &compiler::Task) -> Result<()> {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let python = root.join(".deps/python-env/bin/python");
    if !python.exists() {
        outln!(
            "python   env            skipped: no {} (run `make setup`)",
            python.display()
        );
        return Ok(());
    }
    // A first, untimed pass warms the scene build and the renderer, as the Python side's does.
    // Each single-environment figure is the best of three runs (Python's too).
    rust_seconds(task, 20)?;
    let mut best = f64::INFINITY;
    for _ in 0..3 {
        best = best.min(rust_seconds(task, STEPS)?);
    }
    let rust = STEPS as f64 / best;
    let out = std::process::Command::new(&python)
        .args(["-m", "autobio.bench", "--task", &task.source])
        .args(["--steps", &STEPS.to_string()])
        .args(["--image-size", &format!("{}x{}", SIZE[0], SIZE[1])])
        .output()
        .context("running python -m autobio.bench")?;
    if !out.status.success() {
        bail!(
            "python -m autobio.bench failed: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    let lines: Vec<serde_json::Value> = String::from_utf8_lossy(&out.stdout)
        .lines()
        .filter_map(|l| serde_json::from_str(l).ok())
        .collect();
    let rate = |mode: &str, n: u64| {
        lines
            .iter()
            .find(|l| l["mode"] == mode && l["num_envs"] == n)
            .and_then(|l| l["steps_per_s"].as_f64())
            .with_context(|| format!("no `{mode}` figure for {n} from autobio.bench"))
    };
    let (core, gym) = (rate("core", 1)?, rate("gymnasium", 1)?);
    let overhead = |python: f64| (rust / python - 1.0) * 100.0;
    outln!(
        "python   env            {gym:>10.1} steps/s gymnasium, {core:.1} native core, {rust:.1} Rust Env: {:+.1}% per control step over Rust (core {:+.1}%; target under 10%; {} at {}x{}, {} cameras)",
        overhead(gym),
        overhead(core),
        task.id,
        SIZE[0],
        SIZE[1],
        task.cameras.len()
    );
    let one = rate("vector", 1)?;
    let vector: Vec<String> = [2u64, 4]
        .iter()
        .map(|&n| rate("vector", n).map(|r| format!("{r:.1} with {n} ({:.2}x)", r / one)))
        .collect::<Result<_>>()?;
    outln!(
        "python   vector         {one:>10.1} steps/s with 1 episode, {} (episodes on threads in Rust)",
        vector.join(", ")
    );
    Ok(())
}

/// Seconds for `steps` control steps of the Rust environment: every camera drawn, then the hold
/// action, a new seed when an episode ends.
fn rust_seconds(task: &compiler::Task, steps: usize) -> Result<f64> {
    let opts = runtime::EnvOptions {
        image_size: Some(SIZE),
        ..Default::default()
    };
    let mut env = runtime::Env::make(task, 0, opts)?;
    let mut seed = 0;
    let hold = |env: &runtime::Env| -> Vec<f64> {
        env.observe()
            .robots
            .iter()
            .flat_map(|r| r.ctrl.clone())
            .collect()
    };
    let mut action = hold(&env);
    let start = Instant::now();
    for _ in 0..steps {
        env.frames()?;
        if env.step(&action)?.done() {
            seed += 1;
            env.reset(seed)?;
            action = hold(&env);
        }
    }
    Ok(start.elapsed().as_secs_f64())
}
