//! The LeRobot dataset formats, written directly (no conversion script) and read back:
//! v2.1 (what openpi trains on: a parquet and one video per camera per episode, JSONL metadata)
//! and v3.0 (what `lerobot` 0.4+ reads: episodes sharing one parquet and one video per camera,
//! parquet metadata); the [`Capture`] that observes an episode's env (state, action and every
//! camera at the control rate), shards merged into one dataset, and the task table a reader
//! looks up.
//!
//! Each episode is staged in `.staging/` and moved into the dataset only when complete, its
//! metadata line appended last (fsynced), so an interrupted run leaves no half-written episode
//! and a resumed run continues it. It does not make episodes: the scripted expert's episodes are
//! generated into a dataset, and recordings exported, by the `demos` crate; so this crate (and
//! the Python wheel that reads task tables through it) links no planner (tests/no_simulator.rs).
//! Its tests are tests/datasets.rs and tests/merge.rs.

mod capture;
mod merge;
pub mod meta;
mod parquet;
pub mod stats;
mod video;
mod writer;

pub use capture::Capture;
pub use merge::{Merged, SHARD_FILE, ShardPlan, merge};
pub use video::Codec;
pub use writer::{CaptureSpec, DatasetWriter, FileSizes, Layout, Observations, Version};

use std::path::{Path, PathBuf};

#[derive(Debug, thiserror::Error)]
pub enum DatasetError {
    // The OS error is part of the message and not a `source`: a chain of causes prints it once.
    #[error("cannot {what} {path}: {why}")]
    Io {
        what: &'static str,
        path: PathBuf,
        why: std::io::Error,
    },
    #[error("ffmpeg failed on {path}: {why}")]
    Ffmpeg { path: PathBuf, why: String },
    #[error("cannot write the table {path}: {why}")]
    Parquet { path: PathBuf, why: String },
    #[error("{path}: {why}")]
    Existing { path: PathBuf, why: String },
    #[error("cannot export {path}: {why}")]
    Recording { path: PathBuf, why: String },
    #[error("episode {seed} of {task}: {why}")]
    Episode {
        task: String,
        seed: u64,
        why: String,
    },
}

impl DatasetError {
    pub fn io(what: &'static str, path: &Path, why: std::io::Error) -> DatasetError {
        DatasetError::Io {
            what,
            path: path.to_path_buf(),
            why,
        }
    }
}
