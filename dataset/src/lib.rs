//! Demonstration datasets in LeRobot's formats, written directly (no conversion script):
//! v2.1 (what openpi trains on: a parquet and one video per camera per episode, JSONL metadata)
//! and v3.0 (what `lerobot` 0.4+ reads: episodes sharing one parquet and one video per camera,
//! parquet metadata). Episodes come from the scripted expert through the episode loop's step
//! sink: state, action and every camera at the control rate; failed episodes are not written.
//!
//! Each episode is staged in `.staging/` and moved into the dataset only when complete, its
//! metadata line appended last (fsynced), so an interrupted run leaves no half-written episode
//! and `--resume` continues it. It does not record MCAP (the runtime does) or score anything.

mod capture;
mod parquet;
pub mod stats;
mod video;
mod writer;

pub use capture::Capture;
pub use video::Codec;
pub use writer::{DatasetWriter, Version};

use std::path::{Path, PathBuf};

#[derive(Debug, thiserror::Error)]
pub enum DatasetError {
    #[error("cannot {what} {path}: {source}")]
    Io {
        what: &'static str,
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("ffmpeg failed on {path}: {why}")]
    Ffmpeg { path: PathBuf, why: String },
    #[error("cannot write the table {path}: {why}")]
    Parquet { path: PathBuf, why: String },
    #[error("{path}: {why}")]
    Existing { path: PathBuf, why: String },
    #[error("episode {seed} of {task}: {why}")]
    Episode {
        task: String,
        seed: u64,
        why: String,
    },
}

impl DatasetError {
    pub(crate) fn io(what: &'static str, path: &Path, source: std::io::Error) -> DatasetError {
        DatasetError::Io {
            what,
            path: path.to_path_buf(),
            source,
        }
    }
}

/// What `generate` is asked for.
pub struct GenerateOptions {
    pub episodes: usize,
    pub seed: u64,
    pub out: PathBuf,
    pub version: Version,
    pub codec: Codec,
    pub resume: bool,
    /// Camera images' size (width, height).
    pub image_size: [usize; 2],
}

/// What a generation run did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Generated {
    /// Episodes in the dataset (this run's and, resumed, those before).
    pub written: usize,
    /// Episodes a resumed dataset already had.
    pub resumed: usize,
    /// Expert episodes that failed and were not written.
    pub failed: Vec<(String, u64, String)>,
    pub frames: usize,
}

/// Records `opts.episodes` seeded expert episodes of each task into one dataset; `progress`
/// hears each episode (task id, seed, whether it was written).
pub fn generate(
    tasks: &[compiler::Task],
    opts: &GenerateOptions,
    mut progress: impl FnMut(&str, u64, Result<usize, &str>),
) -> Result<Generated, DatasetError> {
    let mut writer = DatasetWriter::open(
        &opts.out,
        opts.version,
        opts.codec,
        tasks,
        opts.image_size,
        opts.resume,
    )?;
    let mut out = Generated {
        resumed: writer.episodes(),
        ..Default::default()
    };
    for task in tasks {
        let mut scene: Option<std::sync::Arc<runtime::Scene>> = None;
        for i in 0..opts.episodes {
            let seed = opts.seed.wrapping_add(i as u64);
            if writer.has(&task.id, seed) {
                continue;
            }
            let instance = task.sample(seed);
            if scene
                .as_ref()
                .is_none_or(|s| s.placements != instance.labware_placement)
            {
                let built =
                    runtime::Scene::build(task, &instance).map_err(|e| DatasetError::Episode {
                        task: task.id.clone(),
                        seed,
                        why: e.to_string(),
                    })?;
                scene = Some(std::sync::Arc::new(built));
            }
            let scene = scene.as_ref().expect("built above");
            let episode_err = |why: String| DatasetError::Episode {
                task: task.id.clone(),
                seed,
                why,
            };
            let mut capture = writer.capture(task, seed)?;
            let result = match scoring::policy::make("expert", task, scene, &instance) {
                Ok(mut policy) => scoring::episode::run_episode_with(
                    task,
                    scene,
                    &instance,
                    policy.as_mut(),
                    &Default::default(),
                    Some(&mut capture),
                )
                .map_err(episode_err)?,
                Err(e) => scoring::episode::policy_failed(task, scene, &instance, &e),
            };
            if result.success {
                let frames = writer.commit(capture, &instance.instruction)?;
                out.frames += frames;
                progress(&task.id, seed, Ok(frames));
            } else {
                let why = result
                    .error
                    .clone()
                    .unwrap_or_else(|| format!("{:?}", result.outcome));
                capture.discard();
                progress(&task.id, seed, Err(&why));
                out.failed.push((task.id.clone(), seed, why));
            }
        }
    }
    out.written = writer.finish()?;
    Ok(out)
}
