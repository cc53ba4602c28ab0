//! Evaluation runs: N seeded episodes of one task with one policy, made per episode by name through
//! [`crate::policy::make`]. Each finished episode is
//! appended to a JSONL journal immediately (so nothing finished is lost if the run dies), and the
//! run ends with a versioned results JSON.

use crate::episode::{EpisodeOptions, EpisodeResult, run_episode};
use crate::policy;
use compiler::Task;
use serde::{Deserialize, Serialize};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

/// 2: verdicts per stage with scores; `mean_score` in the summary.
pub const RESULTS_SCHEMA_VERSION: u32 = 2;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EvalSummary {
    pub episodes: usize,
    pub successes: usize,
    pub success_rate: f64,
    /// Standard error of the mean success rate.
    pub sem: f64,
    /// Mean episode score (binary or progress, averaged over stages).
    pub mean_score: f64,
    pub wall_time_s: f64,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EvalReport {
    pub schema_version: u32,
    pub task_id: String,
    pub protocol: String,
    pub policy: String,
    /// Episode i uses seed `seed + i`.
    pub seed: u64,
    pub summary: EvalSummary,
    pub episodes: Vec<EpisodeResult>,
}

pub struct EvalOptions {
    /// The policy's name (see [`crate::policy::POLICIES`]).
    pub policy: String,
    pub episodes: usize,
    pub seed: u64,
    /// Where to write recordings (`<task>_seed<seed>.mcap`), the journal and results.json.
    pub out: Option<PathBuf>,
    pub record: bool,
    pub image_every: u32,
}

pub fn summarise(episodes: &[EpisodeResult], wall: f64) -> EvalSummary {
    let n = episodes.len();
    let k = episodes.iter().filter(|e| e.success).count();
    let p = if n > 0 { k as f64 / n as f64 } else { 0.0 };
    let sem = if n > 1 {
        (p * (1.0 - p) / (n as f64 - 1.0)).sqrt()
    } else {
        0.0
    };
    EvalSummary {
        episodes: n,
        successes: k,
        success_rate: p,
        sem,
        mean_score: if n > 0 {
            episodes.iter().map(|e| e.verdict.score).sum::<f64>() / n as f64
        } else {
            0.0
        },
        wall_time_s: wall,
    }
}

/// Runs the named policy on `task`. `progress` is called after each episode.
pub fn evaluate(
    task: &Task,
    opts: &EvalOptions,
    mut progress: impl FnMut(&EpisodeResult),
) -> Result<EvalReport, String> {
    let start = Instant::now();
    if let Some(dir) = &opts.out {
        std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    }
    let journal_path = opts
        .out
        .as_ref()
        .map(|d| d.join(format!("{}.journal.jsonl", task.id)));
    let mut journal = match (&journal_path, &opts.out) {
        (Some(p), Some(dir)) => {
            let file = std::fs::OpenOptions::new()
                .create(true)
                .append(true)
                .open(p)
                .map_err(|e| format!("{}: {e}", p.display()))?;
            // The folder's entry for a new journal is on disk too, not only its lines.
            std::fs::File::open(dir)
                .and_then(|d| d.sync_all())
                .map_err(|e| format!("{}: {e}", dir.display()))?;
            Some(file)
        }
        _ => None,
    };
    let mut scene: Option<Arc<runtime::Scene>> = None;
    let mut results = Vec::new();
    let mut policy_name = opts.policy.clone();
    for i in 0..opts.episodes {
        let seed = opts.seed.wrapping_add(i as u64);
        let instance = task.sample(seed);
        if scene
            .as_ref()
            .is_none_or(|s| s.placements != instance.labware_placement)
        {
            scene = Some(Arc::new(
                runtime::Scene::build(task, &instance).map_err(|e| e.to_string())?,
            ));
        }
        let sc = scene.as_ref().expect("built above");
        let mut policy =
            policy::make(&opts.policy, task, sc, &instance).map_err(|e| e.to_string())?;
        policy_name = policy.name();
        let record = match (&opts.out, opts.record) {
            (Some(d), true) => Some(recording_path(d, task, seed)),
            _ => None,
        };
        let eo = EpisodeOptions {
            record,
            image_every: opts.image_every,
        };
        let r = run_episode(task, sc, &instance, policy.as_mut(), &eo)?;
        if let Some(j) = journal.as_mut() {
            let line = serde_json::to_string(&r).map_err(|e| e.to_string())?;
            // On disk before the next episode starts: a crash loses no finished episode.
            writeln!(j, "{line}")
                .and_then(|_| j.flush())
                .and_then(|_| j.sync_data())
                .map_err(|e| format!("journal: {e}"))?;
        }
        progress(&r);
        results.push(r);
    }
    let report = EvalReport {
        schema_version: RESULTS_SCHEMA_VERSION,
        task_id: task.id.clone(),
        protocol: task.source.clone(),
        policy: policy_name,
        seed: opts.seed,
        summary: summarise(&results, start.elapsed().as_secs_f64()),
        episodes: results,
    };
    if let Some(dir) = &opts.out {
        let p = dir.join(format!("{}.results.json", task.id));
        let text = serde_json::to_string_pretty(&report).map_err(|e| e.to_string())?;
        std::fs::write(&p, text).map_err(|e| format!("{}: {e}", p.display()))?;
    }
    Ok(report)
}

pub fn recording_path(dir: &Path, task: &Task, seed: u64) -> PathBuf {
    dir.join(format!("{}_seed{seed}.mcap", task.id))
}
