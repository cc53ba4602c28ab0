//! Demonstrations: the scripted expert's episodes generated into a LeRobot dataset
//! (`autobio demo --format`, `autobio dataset`), and recordings exported into one
//! (`autobio export`). The dataset format itself (writer, capture, merge) is the `dataset` crate;
//! this crate adds what makes episodes (the expert through `scoring`'s episode loop) and what
//! redraws recorded ones (`scoring::replay`), so a dataset reader need not link the planner.
//! Its tests are tests/datasets.rs, tests/merge.rs and tests/resume.rs.

mod export;

pub use export::{ExportOptions, export};

use dataset::{
    Capture, CaptureSpec, Codec, DatasetError, DatasetWriter, FileSizes, Layout, Observations,
    Version,
};
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, mpsc};

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
    /// Episodes recorded at once, each thread with its own scene and renderer.
    pub workers: usize,
    /// Record only this shard's share of the plan: every `count`-th episode from `index`.
    pub shard: Option<results::run::Shard>,
    /// Where v3.0's shared files roll over.
    pub file_sizes: FileSizes,
    /// What the frames observe: cameras, the environment state, or both.
    pub observations: Observations,
    /// Who draws the frames: the rasteriser, or Blender for a photoreal dataset (the episodes
    /// are the same either way: drawing never touches the simulation).
    pub renderer: runtime::cameras::Renderer,
}

/// One episode handled, for progress reports.
pub struct Step<'a> {
    pub task: &'a str,
    pub seed: u64,
    /// Its frames, or why it was not written.
    pub result: Result<usize, &'a str>,
    /// Episodes handled so far in this run, of `total`.
    pub done: usize,
    pub total: usize,
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

/// Records `opts.episodes` seeded expert episodes of each task into one dataset, on
/// `opts.workers` threads; `progress` hears each episode. Episodes are committed in plan order (task, then seed) whatever thread finishes
/// first, so a dataset's episode indices do not depend on the number of workers.
pub fn generate(
    tasks: &[compiler::Task],
    opts: &GenerateOptions,
    mut progress: impl FnMut(Step<'_>),
) -> Result<Generated, DatasetError> {
    let mut writer = DatasetWriter::open(
        &opts.out,
        opts.version,
        opts.codec,
        Layout::of(tasks, &opts.out, opts.observations)?,
        opts.image_size,
        opts.resume,
    )?;
    writer.set_file_sizes(opts.file_sizes);
    if opts.observations.cameras() {
        writer.check_renderer(&opts.renderer)?;
    }
    if let Some(shard) = opts.shard {
        let asked = dataset::ShardPlan {
            shard,
            tasks: tasks.iter().map(|t| t.id.clone()).collect(),
            episodes: opts.episodes,
            seed: opts.seed,
        };
        asked.write_new(&opts.out)?;
    } else if opts.out.join(dataset::SHARD_FILE).exists() {
        return Err(DatasetError::Existing {
            path: opts.out.clone(),
            why: "is a shard's dataset; resume it with its --shard, or merge it with autobio dataset merge".into(),
        });
    }
    let mut out = Generated {
        resumed: writer.episodes(),
        ..Default::default()
    };
    // The whole plan (task, then seed), numbered; a shard keeps its share, a resumed run what
    // the dataset lacks.
    let plan: Vec<(usize, usize, u64)> = tasks
        .iter()
        .enumerate()
        .flat_map(|(t, _)| (0..opts.episodes as u64).map(move |i| (t, opts.seed.wrapping_add(i))))
        .enumerate()
        .filter(|(k, _)| opts.shard.is_none_or(|s| s.takes(*k)))
        .filter(|(_, (t, seed))| !writer.has(&tasks[*t].id, *seed))
        .map(|(k, (t, seed))| (k, t, seed))
        .collect();
    let spec = writer.capture_spec();
    // A dataset without cameras draws nothing, whoever would have drawn.
    let renderer = if opts.observations.cameras() {
        opts.renderer
    } else {
        Default::default()
    };
    let next = AtomicUsize::new(0);
    let stop = AtomicBool::new(false);
    let mut failure = None;
    std::thread::scope(|s| {
        let (tx, rx) = mpsc::channel();
        for _ in 0..opts.workers.clamp(1, plan.len().max(1)) {
            let (tx, plan, next, stop, spec) = (tx.clone(), &plan, &next, &stop, &spec);
            s.spawn(move || {
                let mut scenes: Vec<Option<Arc<runtime::Scene>>> = vec![None; tasks.len()];
                while !stop.load(Ordering::Relaxed) {
                    let k = next.fetch_add(1, Ordering::Relaxed);
                    let Some(&(_, t, seed)) = plan.get(k) else {
                        break;
                    };
                    let r = record(&tasks[t], seed, spec, renderer, &mut scenes[t]);
                    if tx.send((k, r)).is_err() {
                        break;
                    }
                }
            });
        }
        drop(tx);
        // Finished episodes wait here until every earlier one is committed.
        let mut waiting: BTreeMap<usize, Result<Recorded, DatasetError>> = BTreeMap::new();
        let mut due = 0;
        for (k, r) in rx {
            waiting.insert(k, r);
            while let Some(r) = waiting.remove(&due) {
                let (position, t, seed) = plan[due];
                due += 1;
                let id = &tasks[t].id;
                let step = r.and_then(|rec| match rec.ending {
                    Ending::Success { instruction } => {
                        let frames = writer.commit(rec.capture, &instruction, Some(position))?;
                        out.frames += frames;
                        progress(Step {
                            task: id,
                            seed,
                            result: Ok(frames),
                            done: due,
                            total: plan.len(),
                        });
                        Ok(())
                    }
                    Ending::Failure { why } => {
                        rec.capture.discard();
                        progress(Step {
                            task: id,
                            seed,
                            result: Err(&why),
                            done: due,
                            total: plan.len(),
                        });
                        out.failed.push((id.clone(), seed, why));
                        Ok(())
                    }
                });
                if let Err(e) = step {
                    stop.store(true, Ordering::Relaxed);
                    failure.get_or_insert(e);
                }
            }
        }
    });
    if let Some(e) = failure {
        return Err(e);
    }
    out.written = writer.finish()?;
    Ok(out)
}

/// One expert episode, captured, and how it ended.
struct Recorded {
    capture: Capture,
    ending: Ending,
}

/// How a captured expert episode ended: whether it is committed or discarded.
enum Ending {
    /// It succeeded: committed under this instruction.
    Success { instruction: String },
    /// It failed (the episode's error, else its outcome): discarded, and listed with this reason.
    Failure { why: String },
}

fn record(
    task: &compiler::Task,
    seed: u64,
    spec: &CaptureSpec,
    renderer: runtime::cameras::Renderer,
    scene: &mut Option<Arc<runtime::Scene>>,
) -> Result<Recorded, DatasetError> {
    let episode_err = |why: String| DatasetError::Episode {
        task: task.id.clone(),
        seed,
        why,
    };
    let instance = task.sample(seed);
    let scene = &runtime::Scene::reuse_or_build(scene, task, &instance)
        .map_err(|e| episode_err(e.to_string()))?;
    let mut capture = spec.capture(&task.id, seed)?;
    capture.set_renderer(&renderer);
    let opts = scoring::episode::EpisodeOptions {
        image_size: Some(capture.image_size()),
        renderer,
        ..Default::default()
    };
    let result = match scoring::policies::make("expert", task, scene, &instance) {
        Ok(mut policy) => scoring::episode::run_episode_with(
            task,
            scene,
            &instance,
            policy.as_mut(),
            &opts,
            Some(&mut capture),
        )
        .map_err(|e| episode_err(e.to_string()))?,
        Err(e) => scoring::episode::policy_failed(task, scene, &instance, &e, None)
            .map_err(|e| episode_err(e.to_string()))?,
    };
    let ending = if result.success {
        Ending::Success {
            instruction: instance.instruction.clone(),
        }
    } else {
        Ending::Failure {
            why: result
                .error
                .clone()
                .unwrap_or_else(|| format!("{:?}", result.outcome)),
        }
    };
    Ok(Recorded { capture, ending })
}
