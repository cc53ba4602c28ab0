//! Evaluation runs: seeded episodes of one task with one policy (made per episode by name
//! through [`crate::policy::make`], or a model server through [`crate::remote`]), in one or more
//! runs, on one or more worker threads, or one shard of them. Each finished episode is appended
//! to the journal at once (so nothing finished is lost if the run dies); the run ends with a
//! versioned results JSON. `merge` joins shards' records into one.
//!
//! It does not simulate (the runtime does) and does not render reports (the leaderboard does).

mod merge;
pub mod record;
pub mod stats;

pub use merge::merge;
pub use record::{
    Conditions, GIT_COMMIT, Manifest, ModelRecord, journal_path, manifest_path, results_path,
    sha256_hex,
};
pub use stats::{
    AcrossRuns, Aggregate, EvalSummary, RunSummary, aggregate, mean_sem, summarise, wilson,
};

use crate::episode::{EpisodeOptions, EpisodeResult, run_episode};
use crate::policy::{self, PolicyError};
use crate::profile::{Layout, ProfileError};
use crate::remote::{Model, WireError};
use compiler::Task;
use record::RunRecord;
use serde::{Deserialize, Serialize};
use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, mpsc};
use std::time::{Duration, Instant};

/// 2: verdicts per stage with scores; `mean_score` in the summary. 3: each episode's `outcome`;
/// the summary's Wilson 95% interval and counts per outcome. 4: the `server_fault` outcome,
/// each episode's `run` and `policy_time_s`, per-run and across-run figures, the run's
/// `conditions`, version, git commit and (for models) `model`.
pub const RESULTS_SCHEMA_VERSION: u32 = 4;

/// Run r's seeds start at `seed + r * RUN_SEED_STRIDE`, so that a run can be extended with more
/// episodes without its seeds meeting the next run's.
pub const RUN_SEED_STRIDE: u64 = 1 << 20;

#[derive(Debug, thiserror::Error)]
pub enum EvalError {
    #[error("cannot {what} {path}: {source}")]
    Io {
        what: &'static str,
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path} is not what autobio wrote: {why}")]
    Format { path: PathBuf, why: String },
    #[error("cannot resume the run in {dir}: {why}")]
    Resume { dir: PathBuf, why: String },
    #[error(
        "{dir} already has a run of {task} (its journal {journal}); continue it with --resume, or use another --out",
        dir = dir.display(),
        journal = journal.display()
    )]
    Exists {
        dir: PathBuf,
        task: String,
        journal: PathBuf,
    },
    #[error(transparent)]
    Profile(#[from] ProfileError),
    #[error(transparent)]
    Wire(#[from] WireError),
    #[error(transparent)]
    Policy(#[from] PolicyError),
    #[error("cannot build the scene of {task} for seed {seed}: {why}")]
    Scene {
        task: String,
        seed: u64,
        why: String,
    },
    #[error("episode {seed} of {task} could not be run: {why}")]
    Episode {
        task: String,
        seed: u64,
        why: String,
    },
    #[error("cannot merge: {0}")]
    Merge(String),
    #[error("bad shard `{0}`: expected I/N with 0 <= I < N, e.g. 0/4")]
    Shard(String),
    #[error("{0} episodes per run is more than a run's {RUN_SEED_STRIDE} seeds; use --runs")]
    TooManyEpisodes(usize),
}

impl EvalError {
    pub(crate) fn io(what: &'static str, path: &Path, source: std::io::Error) -> EvalError {
        EvalError::Io {
            what,
            path: path.to_path_buf(),
            source,
        }
    }
}

/// One share of a run's episodes: those whose position in the run's plan is `index` modulo
/// `count`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Shard {
    pub index: u32,
    pub count: u32,
}

impl Shard {
    /// Whether the plan's episode at `position` is this shard's.
    pub fn takes(&self, position: usize) -> bool {
        position as u64 % u64::from(self.count) == u64::from(self.index)
    }
}

impl std::str::FromStr for Shard {
    type Err = EvalError;
    fn from_str(s: &str) -> Result<Shard, EvalError> {
        let bad = || EvalError::Shard(s.to_string());
        let (i, n) = s.split_once('/').ok_or_else(bad)?;
        let (index, count): (u32, u32) = (
            i.trim().parse().map_err(|_| bad())?,
            n.trim().parse().map_err(|_| bad())?,
        );
        if count == 0 || index >= count {
            return Err(bad());
        }
        Ok(Shard { index, count })
    }
}

impl std::fmt::Display for Shard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

/// A model server to evaluate: where, what it speaks, and its profile.
#[derive(Clone, Debug)]
pub struct ModelSpec {
    pub url: String,
    pub wire: crate::remote::Wire,
    pub profile: crate::profile::LoadedProfile,
    /// Connection attempts per episode and the first retry's wait (doubled per retry).
    pub attempts: u32,
    pub backoff_s: f64,
}

impl ModelSpec {
    fn connect(&self) -> Result<Model, WireError> {
        let mut m = Model::new(&self.url, self.wire, self.profile.clone())?;
        m.set_retries(self.attempts, Duration::from_secs_f64(self.backoff_s));
        Ok(m)
    }
}

pub struct EvalOptions {
    /// The policy's name (see [`crate::policy::POLICIES`]); ignored when `model` is given.
    pub policy: String,
    /// Episodes per run.
    pub episodes: usize,
    pub seed: u64,
    /// Where to write recordings (`<task>_seed<seed>.mcap`), the run record and results.
    pub out: Option<PathBuf>,
    pub record: bool,
    pub image_every: u32,
    /// Continue the run whose journal is in `out`: only when its manifest's fingerprints match,
    /// and never rerunning a finished episode.
    pub resume: bool,
    pub model: Option<ModelSpec>,
    /// Runs (1 unless `--runs`): statistics per run and mean ± SEM across them.
    pub runs: u32,
    /// Worker threads running episodes at once (each with its own scene, renderer and model
    /// connection).
    pub workers: usize,
    pub shard: Option<Shard>,
}

impl Default for EvalOptions {
    fn default() -> EvalOptions {
        EvalOptions {
            policy: "expert".into(),
            episodes: 1,
            seed: 0,
            out: None,
            record: false,
            image_every: 0,
            resume: false,
            model: None,
            runs: 1,
            workers: 1,
            shard: None,
        }
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EvalReport {
    pub schema_version: u32,
    pub task_id: String,
    /// The task's difficulty level (`easy`, `medium`, `hard`).
    pub level: String,
    pub protocol: String,
    pub policy: String,
    /// Run r's episode i uses seed `seed + r * 2^20 + i`.
    pub seed: u64,
    pub summary: EvalSummary,
    pub conditions: Conditions,
    pub model: Option<ModelRecord>,
    pub autobio_version: String,
    pub git_commit: String,
    /// The shard this report covers, if it is one.
    #[serde(default)]
    pub shard: Option<Shard>,
    /// In plan order (run, then seed).
    pub episodes: Vec<EpisodeResult>,
}

/// The episodes of a run, in order: (run, seed) for each run's episodes, then only those of
/// `shard`, if given (every N-th from I, so that each shard gets a share of every run).
pub fn plan(seed: u64, episodes: usize, runs: u32, shard: Option<Shard>) -> Vec<(u32, u64)> {
    (0..runs)
        .flat_map(|r| {
            (0..episodes as u64).map(move |i| {
                (
                    r,
                    seed.wrapping_add(r as u64 * RUN_SEED_STRIDE)
                        .wrapping_add(i),
                )
            })
        })
        .enumerate()
        .filter(|(k, _)| shard.is_none_or(|s| s.takes(*k)))
        .map(|(_, p)| p)
        .collect()
}

/// Where a run stands after each finished episode.
pub struct Progress<'a> {
    pub result: &'a EpisodeResult,
    /// Episodes finished, those of a resumed run included, and planned.
    pub done: usize,
    pub total: usize,
    pub successes: usize,
    /// Episodes a resumed run found finished.
    pub resumed: usize,
    pub elapsed_s: f64,
}

/// Runs one task's episodes; `progress` is called after each finished episode.
pub fn evaluate(
    task: &Task,
    opts: &EvalOptions,
    mut progress: impl FnMut(&Progress),
) -> Result<EvalReport, EvalError> {
    let start = Instant::now();
    // A model: one connection per worker; the first greets the server before the manifest is
    // written, so that the manifest holds what the server said about itself.
    let mut first_model = None;
    let layout = match &opts.model {
        Some(spec) => {
            let layout = spec.profile.profile.resolve(task)?;
            let mut m = spec.connect()?;
            // An unreachable server is not fatal: each episode then fails as a server fault.
            m.open().ok();
            first_model = Some(m);
            Some(layout)
        }
        None => None,
    };
    let model_record = first_model.as_ref().map(|m| ModelRecord {
        url: m.url().to_string(),
        wire: m.wire,
        profile_origin: m.profile.origin.clone(),
        profile_sha256: m.profile.sha256(),
        profile: m.profile.profile.clone(),
        metadata: m.metadata.clone(),
    });
    let here = Manifest {
        results_schema_version: RESULTS_SCHEMA_VERSION,
        autobio_version: env!("CARGO_PKG_VERSION").to_string(),
        git_commit: GIT_COMMIT.to_string(),
        task_id: task.id.clone(),
        level: task.level.clone(),
        protocol: task.source.clone(),
        task_sha256: sha256_hex(&serde_json::to_vec(task).unwrap_or_default()),
        protocol_sha256: std::fs::read(&task.source).ok().map(|b| sha256_hex(&b)),
        protocol_files: record::protocol_files(task),
        policy: match &opts.model {
            Some(_) => "model".to_string(),
            None => opts.policy.clone(),
        },
        seed: opts.seed,
        episodes: opts.episodes,
        runs: opts.runs.max(1),
        shard: opts.shard,
        conditions: Conditions::of(task),
        model: model_record.clone(),
    };
    if opts.episodes as u64 > RUN_SEED_STRIDE {
        return Err(EvalError::TooManyEpisodes(opts.episodes));
    }
    if opts.model.is_none() && !policy::known(&opts.policy) {
        return Err(PolicyError::Unknown(opts.policy.clone()).into());
    }
    let (mut record, finished) = match &opts.out {
        Some(dir) => {
            let (r, f) = RunRecord::open(dir, &here, opts.resume)?;
            (Some(r), f)
        }
        None => (None, Vec::new()),
    };
    let planned = plan(opts.seed, opts.episodes, here.runs, opts.shard);
    let position: HashMap<u64, usize> = planned
        .iter()
        .enumerate()
        .map(|(k, (_, seed))| (*seed, k))
        .collect();
    // A finished episode is never run again: its journal line stands.
    let done: HashSet<u64> = finished.iter().map(|f| f.seed).collect();
    let todo: Vec<(u32, u64)> = planned
        .iter()
        .filter(|(_, seed)| !done.contains(seed))
        .copied()
        .collect();
    let mut results: Vec<EpisodeResult> = finished
        .into_iter()
        .filter(|f| position.contains_key(&f.seed))
        .collect();
    let resumed = results.len();
    let mut successes = results.iter().filter(|r| r.success).count();

    let workers = opts.workers.clamp(1, todo.len().max(1));
    let next = AtomicUsize::new(0);
    let stop = AtomicBool::new(false);
    let mut failure = None;
    std::thread::scope(|s| {
        let (tx, rx) = mpsc::channel();
        for w in 0..workers {
            let tx = tx.clone();
            let (todo, next, stop, layout) = (&todo, &next, &stop, &layout);
            let model = if w == 0 { first_model.take() } else { None };
            s.spawn(move || {
                let mut worker = Worker {
                    task,
                    opts,
                    layout: layout.clone(),
                    model,
                    scene: None,
                };
                while !stop.load(Ordering::Relaxed) {
                    let k = next.fetch_add(1, Ordering::Relaxed);
                    let Some(&(run, seed)) = todo.get(k) else {
                        break;
                    };
                    if tx.send(worker.episode(run, seed)).is_err() {
                        break;
                    }
                }
            });
        }
        drop(tx);
        for r in rx {
            let step = r.and_then(|r| {
                if let Some(rec) = record.as_mut() {
                    rec.append(&r)?;
                }
                Ok(r)
            });
            match step {
                Ok(r) => {
                    successes += r.success as usize;
                    results.push(r);
                    progress(&Progress {
                        result: results.last().expect("just pushed"),
                        done: results.len(),
                        total: planned.len(),
                        successes,
                        resumed,
                        elapsed_s: start.elapsed().as_secs_f64(),
                    });
                }
                Err(e) => {
                    // Finished episodes are on disk; the others stop at their next episode.
                    stop.store(true, Ordering::Relaxed);
                    failure.get_or_insert(e);
                }
            }
        }
    });
    if let Some(e) = failure {
        return Err(e);
    }
    results.sort_by_key(|r| position.get(&r.seed).copied());
    let policy_name = match &opts.model {
        Some(m) => format!("model {} ({}, {})", m.url, m.wire, m.profile.profile.name),
        None => opts.policy.clone(),
    };
    let report = EvalReport {
        schema_version: RESULTS_SCHEMA_VERSION,
        task_id: task.id.clone(),
        level: task.level.clone(),
        protocol: task.source.clone(),
        policy: policy_name,
        seed: opts.seed,
        summary: summarise(&results, start.elapsed().as_secs_f64()),
        conditions: here.conditions.clone(),
        model: model_record,
        autobio_version: here.autobio_version.clone(),
        git_commit: here.git_commit.clone(),
        shard: opts.shard,
        episodes: results,
    };
    if let Some(dir) = &opts.out {
        record::write_json(&results_path(dir, &task.id), &report)?;
    }
    Ok(report)
}

/// One worker thread's state: its scene (rebuilt when a seed places labware elsewhere) and its
/// own model connection.
struct Worker<'t> {
    task: &'t Task,
    opts: &'t EvalOptions,
    layout: Option<Layout>,
    model: Option<Model>,
    scene: Option<Arc<runtime::Scene>>,
}

impl Worker<'_> {
    fn episode(&mut self, run: u32, seed: u64) -> Result<EpisodeResult, EvalError> {
        let (task, opts) = (self.task, self.opts);
        let instance = task.sample(seed);
        let scene =
            &runtime::Scene::reuse_or_build(&mut self.scene, task, &instance).map_err(|e| {
                EvalError::Scene {
                    task: task.id.clone(),
                    seed,
                    why: e.to_string(),
                }
            })?;
        let eo = EpisodeOptions {
            record: match (&opts.out, opts.record) {
                (Some(d), true) => Some(recording_path(d, task, seed)),
                _ => None,
            },
            image_every: opts.image_every,
        };
        // A policy that cannot be made for this episode fails this episode, not the run.
        let made = match (&opts.model, &self.layout) {
            (Some(spec), Some(layout)) => {
                if self.model.is_none() {
                    self.model = Some(spec.connect()?);
                }
                let info = crate::remote::EpisodeInfo {
                    task_id: &task.id,
                    seed,
                    instruction: &instance.instruction,
                };
                let m = self.model.as_mut().expect("connected above");
                crate::remote::ModelPolicy::start(m, layout.clone(), &info)
                    .map(|p| Box::new(p) as Box<dyn policy::Policy>)
            }
            _ => policy::make(&opts.policy, task, scene, &instance),
        };
        let mut r =
            match made {
                Ok(mut policy) => run_episode(task, scene, &instance, policy.as_mut(), &eo)
                    .map_err(|why| EvalError::Episode {
                        task: task.id.clone(),
                        seed,
                        why,
                    })?,
                Err(e @ PolicyError::Unknown(_)) => return Err(e.into()),
                Err(e) => crate::episode::policy_failed(task, scene, &instance, &e),
            };
        r.run = run;
        Ok(r)
    }
}

pub fn recording_path(dir: &Path, task: &Task, seed: u64) -> PathBuf {
    dir.join(format!("{}_seed{seed}.mcap", task.id))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_split_the_plan_without_overlap_or_gaps() {
        let all = plan(7, 5, 3, None);
        assert_eq!(all.len(), 15);
        assert_eq!(all[0], (0, 7));
        assert_eq!(all[5], (1, 7 + RUN_SEED_STRIDE));
        let mut joined: Vec<(u32, u64)> = (0..4)
            .flat_map(|i| plan(7, 5, 3, Some(Shard { index: i, count: 4 })))
            .collect();
        joined.sort();
        let mut want = all.clone();
        want.sort();
        assert_eq!(joined, want);
        for bad in ["4/4", "1", "a/2", "0/0", "-1/3"] {
            assert!(bad.parse::<Shard>().is_err(), "{bad}");
        }
        assert_eq!(
            "2/5".parse::<Shard>().unwrap(),
            Shard { index: 2, count: 5 }
        );
    }
}
