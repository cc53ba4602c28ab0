//! `autobio bench --only leaderboard`: verification's throughput (episodes re-enacted per second
//! with one worker and with two, on a real expert suite run of the first scene's task) and the
//! site's build time from 50 submissions x 16 tasks x 100 episodes (synthetic journals written
//! in the bundle format, packed by `leaderboard::bundle::submit`; target under 10 s).

use anyhow::{Context, Result};
use std::path::Path;
use std::time::Instant;

/// Both figures; `task` is the first scene's.
pub(crate) fn figures(task: &compiler::Task) -> Result<()> {
    let dir = std::env::temp_dir().join(format!("autobio-bench-lb-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir)?;
    let result = measure(task, &dir);
    let _ = std::fs::remove_dir_all(&dir);
    result
}

fn measure(task: &compiler::Task, dir: &Path) -> Result<()> {
    // A real suite run: 12 expert episodes of the task, recorded as a suite run records them.
    let episodes = 12;
    let suites = dir.join("suites");
    std::fs::create_dir_all(&suites)?;
    let source = std::fs::canonicalize(&task.source)
        .with_context(|| format!("the task's protocol {}", task.source))?;
    let suite_text = format!(
        "format = 1\n[suite]\nname = \"bench\"\nepisodes = {episodes}\nseed = 0\nruns = 1\ntasks = [{:?}]\n",
        source.display().to_string()
    );
    std::fs::write(suites.join("bench.toml"), &suite_text)?;
    let run = dir.join("run");
    std::fs::create_dir_all(&run)?;
    std::fs::write(run.join(results::suite::SUITE_FILE), &suite_text)?;
    let opts = scoring::eval::EvalOptions {
        episodes,
        out: Some(run.clone()),
        record: true,
        image_every: 0,
        ..Default::default()
    };
    // The run reads the protocol where the suite names it, as `eval --suite` does (a verifier
    // holds a manifest's path to the suite's entry).
    let mut task = task.clone();
    let named = source.display().to_string();
    for s in &mut task.stages {
        if s.source == task.source {
            s.source = named.clone();
        }
    }
    task.source = named;
    let report = scoring::eval::evaluate(&task, &opts, |_| {})?;
    let bundle = dir.join("bench.tar");
    leaderboard::bundle::submit(
        std::slice::from_ref(&run),
        &leaderboard::bundle::SubmitOptions {
            model_name: "bench".into(),
            training: None,
            out: bundle.clone(),
        },
    )?;
    let mut rates = Vec::new();
    for workers in [1, 2] {
        let work = dir.join(format!("verify-{workers}"));
        let unpacked = leaderboard::bundle::unpack(&bundle, &work, &Default::default())?;
        let opts = leaderboard::verify::VerifyOptions {
            suites: suites.clone(),
            workers,
        };
        let v = leaderboard::verify::verify(&unpacked, &opts, &crate::submissions::reenact);
        anyhow::ensure!(
            v.accepted(),
            "the bench's own bundle was refused: {:?}",
            v.failures
        );
        rates.push(v.reenacted as f64 / v.reenact_wall_s);
    }
    outln!(
        "verify   re-enacted     {:>10.2} episodes/s with 2 workers, {:.2} with 1: {:.2}x ({episodes} expert episodes of {})",
        rates[1],
        rates[0],
        rates[1] / rates[0],
        task.id
    );
    site_figure(dir, &report.episodes[0])
}

/// 50 synthetic submissions of 16 tasks x 100 episodes, packed, then the site built from them.
fn site_figure(dir: &Path, template: &results::episode::EpisodeResult) -> Result<()> {
    let (subs, tasks, episodes) = (50, 16, 100);
    let bundles = dir.join("bundles");
    std::fs::create_dir_all(&bundles)?;
    let manifest_template: serde_json::Value = serde_json::from_slice(&std::fs::read(
        std::fs::read_dir(dir.join("run"))?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .find(|p| p.to_string_lossy().ends_with(".manifest.json"))
            .context("the bench run's manifest")?,
    )?)?;
    let suite_text = format!(
        "format = 1\n[suite]\nname = \"synthetic\"\nepisodes = {episodes}\nseed = 0\nruns = 1\ntasks = [{}]\n",
        (0..tasks)
            .map(|t| format!("\"t{t}.toml\""))
            .collect::<Vec<_>>()
            .join(", ")
    );
    for s in 0..subs {
        let run = dir.join(format!("synthetic-{s}"));
        std::fs::create_dir_all(&run)?;
        std::fs::write(run.join(results::suite::SUITE_FILE), &suite_text)?;
        for t in 0..tasks {
            let id = format!("synthetic.task_{t:02}");
            let mut m = manifest_template.clone();
            m["task_id"] = id.clone().into();
            m["level"] = ["easy", "medium", "hard"][t % 3].into();
            std::fs::write(
                run.join(format!("{id}.manifest.json")),
                serde_json::to_vec(&m)?,
            )?;
            let mut journal = String::new();
            for seed in 0..episodes as u64 {
                let mut e = template.clone();
                e.seed = seed;
                // A deterministic spread of outcomes per submission and task.
                e.success = (seed * 7 + t as u64 * 3 + s as u64 * 11) % 100 < (s as u64 * 2 % 100);
                e.verdict.success = e.success;
                e.verdict.score = if e.success { 1.0 } else { 0.0 };
                journal.push_str(&serde_json::to_string(&e)?);
                journal.push('\n');
            }
            std::fs::write(run.join(format!("{id}.journal.jsonl")), journal)?;
        }
        leaderboard::bundle::submit(
            &[run],
            &leaderboard::bundle::SubmitOptions {
                model_name: format!("model {s:02}"),
                training: None,
                out: bundles.join(format!("model-{s:02}.tar")),
            },
        )?;
    }
    let t = Instant::now();
    let work = dir.join("site-work");
    let loaded = leaderboard::site::load(&bundles, &work)?;
    let files = leaderboard::site::build(&loaded, &dir.join("site"), None)?;
    let took = t.elapsed().as_secs_f64();
    outln!(
        "site     build          {took:>10.2} s for {subs} submissions x {tasks} tasks x {episodes} episodes ({} files; target under 10 s)",
        files.len()
    );
    Ok(())
}
