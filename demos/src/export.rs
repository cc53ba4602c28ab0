//! Recordings to a dataset (`autobio export REC... --format lerobot-v21|lerobot-v30`): each
//! recording's robot states and actions at every control step, and every camera redrawn from the
//! recorded MuJoCo state at the dataset's image size (no simulation, no expert). A recording of
//! an episode gives the rows and frames `autobio demo` writes for that episode, so exporting the
//! recordings of a run equals recording the run as a dataset (tested on the frames tables).
//! Recordings of failed episodes are not written (counted and reported). The environment state
//! (`--observation state|all`) is read from the recorded labware states before each action.

use crate::{Generated, Step};
use dataset::{Codec, DatasetError, DatasetWriter, Layout, Observations, Version};
use results::environment_state::EnvironmentState;
use scoring::replay::{FrameOptions, Recording, ReplayError};
use std::path::{Path, PathBuf};

pub struct ExportOptions {
    pub out: PathBuf,
    pub version: Version,
    pub codec: Codec,
    /// Camera images' size (width, height).
    pub image_size: [usize; 2],
    pub resume: bool,
    /// Where v3.0's shared files roll over.
    pub file_sizes: dataset::FileSizes,
    /// What the frames observe: cameras, the environment state, or both.
    pub observations: Observations,
    /// Who draws the frames from the recorded states.
    pub renderer: runtime::cameras::Renderer,
}

/// The `.mcap` files named, a folder standing for the recordings in it (sorted by name).
fn recordings(paths: &[PathBuf]) -> Result<Vec<PathBuf>, DatasetError> {
    let mut out = Vec::new();
    for p in paths {
        if p.is_dir() {
            let mut found: Vec<PathBuf> = std::fs::read_dir(p)
                .map_err(|e| DatasetError::io("list", p, e))?
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|f| f.extension().is_some_and(|x| x == "mcap"))
                .collect();
            found.sort();
            out.extend(found);
        } else {
            out.push(p.clone());
        }
    }
    Ok(out)
}

fn unreadable(path: &Path, e: ReplayError) -> DatasetError {
    DatasetError::Recording {
        path: path.to_path_buf(),
        why: e.to_string(),
    }
}

/// Writes the recordings (files, or folders of them) into one dataset; `progress` hears each.
pub fn export(
    paths: &[PathBuf],
    opts: &ExportOptions,
    mut progress: impl FnMut(Step<'_>),
) -> Result<Generated, DatasetError> {
    let files = recordings(paths)?;
    let mut recs = Vec::new();
    for f in &files {
        recs.push(Recording::open(f).map_err(|e| unreadable(f, e))?);
    }
    let mut tasks: Vec<compiler::Task> = Vec::new();
    for r in &recs {
        if !tasks.iter().any(|t| t.id == r.task.id) {
            tasks.push(r.task.clone());
        }
    }
    let mut writer = DatasetWriter::open(
        &opts.out,
        opts.version,
        opts.codec,
        Layout::of(&tasks, &opts.out, opts.observations)?,
        opts.image_size,
        opts.resume,
    )?;
    writer.set_file_sizes(opts.file_sizes);
    if opts.observations.cameras() {
        writer.check_renderer(&opts.renderer)?;
    }
    let mut out = Generated {
        resumed: writer.episodes(),
        ..Default::default()
    };
    let spec = writer.capture_spec();
    let total = recs.len();
    for (done, rec) in recs.iter().enumerate() {
        let done = done + 1;
        let (id, seed) = (rec.task.id.clone(), rec.instance.seed);
        if writer.has(&id, seed) {
            continue;
        }
        let success = rec
            .summary
            .verdict
            .as_ref()
            .and_then(|v| v["verdict"]["success"].as_bool())
            == Some(true);
        if !success {
            let why = "the recorded episode did not succeed".to_string();
            progress(Step {
                task: &id,
                seed,
                result: Err(&why),
                done,
                total,
            });
            out.failed.push((id, seed, why));
            continue;
        }
        let actions = rec.actions().map_err(|e| unreadable(&rec.path, e))?;
        let states: Vec<Vec<f64>> = (0..rec.steps())
            .map(|k| {
                rec.task
                    .robots
                    .iter()
                    .flat_map(|r| {
                        rec.summary
                            .robot_states
                            .get(&r.name)
                            .and_then(|s| s.get(k))
                            .cloned()
                            .unwrap_or_default()
                    })
                    .collect()
            })
            .collect();
        let mut capture = spec.capture(&id, seed)?;
        if opts.observations.cameras() {
            capture.set_renderer(&opts.renderer);
        }
        let environment: Vec<Vec<f64>> = if capture.wants_environment_state() {
            let layout = EnvironmentState::of(&rec.task);
            (0..rec.steps())
                .map(|k| {
                    let labware = rec
                        .summary
                        .labware_series
                        .get(k)
                        .map_or(&[][..], |(_, l)| l.as_slice());
                    layout.values(&rec.task, labware, &rec.instance.params)
                })
                .collect()
        } else {
            vec![Vec::new(); rec.steps()]
        };
        let drawn = if opts.observations.cameras() {
            let frames = FrameOptions {
                size: Some(opts.image_size),
                detail: None,
                every: Some(1),
                renderer: opts.renderer,
            };
            scoring::replay::frames(rec, &frames, |k, _, images| {
                capture
                    .push(&states[k], &environment[k], &actions[k], &images)
                    .map_err(|e| ReplayError::Consumer(e.into()))
            })
        } else {
            (0..rec.steps()).try_for_each(|k| {
                capture
                    .push(&states[k], &environment[k], &actions[k], &[])
                    .map_err(|e| ReplayError::Consumer(e.into()))
            })
        };
        if let Err(e) = drawn {
            capture.discard();
            return Err(unreadable(&rec.path, e));
        }
        capture.set_perturbation(rec.instance.perturbation.as_ref());
        let n = writer.commit(capture, &rec.instance.instruction, None)?;
        out.frames += n;
        progress(Step {
            task: &id,
            seed,
            result: Ok(n),
            done,
            total,
        });
    }
    out.written = writer.finish()?;
    Ok(out)
}
