//! Evaluation runs as records: the results JSON ([`EvalReport`]), the run record in an `--out`
//! folder ([`record`]: manifest, journal), the plan of a run's seeds and its shards, statistics
//! ([`stats`]) and joining shards ([`merge`]).
//!
//! It runs no episode (`scoring::eval::evaluate` does) and renders no report (the leaderboard does).

mod merge;
pub mod record;
pub mod stats;

pub use merge::merge;
// Second paths the leaderboard and `src/submissions.rs` (owned elsewhere) still use; `record::`
// and `stats::` are canonical.

use record::{Conditions, ModelRecord};
use stats::EvalSummary;

use crate::episode::EpisodeResult;
use compiler::Task;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// 2: verdicts per stage with scores; `mean_score` in the summary. 3: each episode's `outcome`;
/// the summary's Wilson 95% interval and counts per outcome. 4: the `server_fault` outcome,
/// each episode's `run` and `policy_time_s`, per-run and across-run figures, the run's
/// `conditions`, version, git commit and (for models) `model`.
pub const RESULTS_SCHEMA_VERSION: u32 = 4;

/// Run r's seeds start at `seed + r * RUN_SEED_STRIDE`, so that a run can be extended with more
/// episodes without its seeds meeting the next run's.
pub const RUN_SEED_STRIDE: u64 = 1 << 20;

/// What can go wrong with a run record: reading or writing it, resuming or merging it.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
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
    #[error("cannot merge: {0}")]
    Merge(String),
    #[error("bad shard `{0}`: expected I/N with 0 <= I < N, e.g. 0/4")]
    Shard(String),
    #[error("{0} episodes per run is more than a run's {RUN_SEED_STRIDE} seeds; use --runs")]
    TooManyEpisodes(usize),
    #[error("training seed {run} has no run to evaluate: the run has {runs} (training seeds 0 to {})", runs - 1)]
    CheckpointRun { run: u32, runs: u32 },
}

impl RunError {
    pub fn io(what: &'static str, path: &Path, source: std::io::Error) -> RunError {
        RunError::Io {
            what,
            path: path.to_path_buf(),
            source,
        }
    }
}

/// The trained checkpoint a suite run's model server serves, one of several trained alike on
/// different training seeds (the paper's ± is the SEM over three such). Training seed `run`'s
/// checkpoint is evaluated on the suite's run `run` only, so that one folder per training seed
/// together covers every planned episode once, as the runs of one model do.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Checkpoint {
    /// The training seed's index (0-based): the suite run it is evaluated on.
    pub run: u32,
    /// The submitter's name for the checkpoint (a path, a hub revision, a hash).
    pub name: String,
}

impl std::fmt::Display for Checkpoint {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "training seed {}: {}", self.run, self.name)
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
    type Err = RunError;
    fn from_str(s: &str) -> Result<Shard, RunError> {
        let bad = || RunError::Shard(s.to_string());
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

/// Where a run keeps the recording of one episode.
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
