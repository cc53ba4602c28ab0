//! Evaluation runs: seeded episodes of one task with one policy (made per episode by name
//! through [`crate::policies::PolicySpec::make`], or a model server through [`crate::remote`]), in one or more
//! runs, on one or more worker threads, or one shard of them. Each finished episode is appended
//! to the journal at once (so nothing finished is lost if the run dies); the run ends with a
//! versioned results JSON. `merge` joins shards' records into one.
//!
//! It does not simulate (the runtime does) and does not render reports (the leaderboard does).

use results::run::record::{
    self, Conditions, GIT_COMMIT, Manifest, ModelRecord, results_path, sha256_hex,
};
use results::run::stats::summarise;
use results::run::{
    EvalReport, RESULTS_SCHEMA_VERSION, RUN_SEED_STRIDE, RunError, Shard, plan, recording_path,
};

use crate::episode::{EpisodeError, EpisodeOptions, run_episode};
use crate::policies;
use crate::remote::Model;
use compiler::Task;
use policy::PolicyError;
use policy::WireError;
use record::RunRecord;
use results::episode::EpisodeResult;
use results::profile::{Layout, ProfileError};
use std::collections::{HashMap, HashSet};
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, mpsc};
use std::time::{Duration, Instant};

/// Why an evaluation run stopped (a failed episode does not stop it: it is a result).
#[derive(Debug, thiserror::Error)]
pub enum EvalError {
    #[error(transparent)]
    Run(#[from] RunError),
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
        why: runtime::SceneError,
    },
    #[error("episode {seed} of {task} could not be run: {why}")]
    Episode {
        task: String,
        seed: u64,
        why: EpisodeError,
    },
}

/// A model server to evaluate: where, what it speaks, and its profile.
#[derive(Clone, Debug)]
pub struct ModelSpec {
    pub url: String,
    pub wire: results::run::record::Wire,
    pub profile: results::profile::LoadedProfile,
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
    /// The policy (see [`crate::policies::POLICIES`]); ignored when `model` is given.
    pub policy: policies::PolicySpec,
    /// Episodes per run.
    pub episodes: usize,
    pub seed: u64,
    /// Where to write recordings (`<task>_seed<seed>.mcap`), the run record and results.
    pub out: Option<PathBuf>,
    pub record: bool,
    pub image_every: u32,
    /// Every camera at this size (`--size`); a model's profile's size wins over it; `None`: the
    /// task's own camera spec.
    pub image_size: Option<[usize; 2]>,
    /// Who draws the cameras: the rasteriser, or Blender for recordings with photoreal frames
    /// (`demo --renderer blender`).
    pub renderer: runtime::cameras::Renderer,
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
    /// The checkpoint the model server serves, one per training seed: only its run is
    /// evaluated.
    pub checkpoint: Option<results::run::Checkpoint>,
}

impl Default for EvalOptions {
    fn default() -> EvalOptions {
        EvalOptions {
            policy: policies::PolicySpec::Expert,
            episodes: 1,
            seed: 0,
            out: None,
            record: false,
            image_every: 0,
            image_size: None,
            renderer: Default::default(),
            resume: false,
            model: None,
            runs: 1,
            workers: 1,
            shard: None,
            checkpoint: None,
        }
    }
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

/// Runs one task's episodes; `progress` is called after each finished episode. Long on purpose:
/// the plan, the workers and the in-order commit of finished episodes share one scope of
/// threads and channels, which reads as one piece.
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
        profile_sha256: sha256_hex(m.profile.text.as_bytes()),
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
        task_content_sha256: Some(record::task_content_sha256(task)),
        protocol_files: record::protocol_files(task),
        imported_from: task.imported_from.clone(),
        policy: match &opts.model {
            Some(_) => "model".to_string(),
            None => opts.policy.to_string(),
        },
        seed: opts.seed,
        episodes: opts.episodes,
        runs: opts.runs.max(1),
        shard: opts.shard,
        checkpoint: opts.checkpoint.clone(),
        conditions: Conditions::of(task),
        model: model_record.clone(),
    };
    if opts.episodes as u64 > RUN_SEED_STRIDE {
        return Err(RunError::TooManyEpisodes(opts.episodes).into());
    }
    let (mut record, finished) = match &opts.out {
        Some(dir) => {
            let (r, f) = RunRecord::open(dir, &here, opts.resume)?;
            (Some(r), f)
        }
        None => (None, Vec::new()),
    };
    let mut planned = plan(opts.seed, opts.episodes, here.runs, opts.shard);
    if let Some(c) = &opts.checkpoint {
        if c.run >= here.runs {
            return Err(RunError::CheckpointRun {
                run: c.run,
                runs: here.runs,
            }
            .into());
        }
        planned.retain(|(run, _)| *run == c.run);
    }
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
        None => opts.policy.to_string(),
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
                    why: e,
                }
            })?;
        let eo = EpisodeOptions {
            record: match (&opts.out, opts.record) {
                (Some(d), true) => Some(recording_path(d, task, seed)),
                _ => None,
            },
            image_every: opts.image_every,
            image_size: opts.image_size,
            renderer: opts.renderer,
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
            _ => opts.policy.make(task, scene, &instance),
        };
        let mut r =
            match made {
                Ok(mut policy) => run_episode(task, scene, &instance, policy.as_mut(), &eo)
                    .map_err(|why| EvalError::Episode {
                        task: task.id.clone(),
                        seed,
                        why,
                    })?,
                Err(e @ PolicyError::Unknown { .. }) => return Err(e.into()),
                Err(e) => crate::episode::policy_failed(task, scene, &instance, &e, eo.record)
                    .map_err(|why| EvalError::Episode {
                        task: task.id.clone(),
                        seed,
                        why,
                    })?,
            };
        r.run = run;
        Ok(r)
    }
}
