//! Recordings replayed from their recorded state (`autobio replay`):
//! - [`resimulate`]: puts MuJoCo and the instruments into the state recorded at a control step,
//!   applies the recorded actions from there, and checks every following state bit for bit and
//!   the trajectory hash against the recording's;
//! - [`frames`]: sets each recorded state and draws the cameras at any size and level of detail,
//!   with no simulation (the frames an episode recorded come back byte for byte), for a new
//!   recording ([`render`]), PNG files, or a dataset (`demos::export`).
//!
//! - [`reenact`]: a verifier's replay, trusting nothing a recording states but its actions: the
//!   scene the seed draws for the caller's own task, the actions applied one control step each,
//!   the trajectory hash, verdict and end as the episode then comes out (`results::end`'s
//!   [`Reenacted`], the one type the verifier reads).
//!
//! Offline re-scoring from the labware series alone is [`results::verdict::Judge::replay`].

use compiler::{SceneInstance, Task};
use results::Image;
use results::end::EpisodeEnd;
pub use results::end::{ReenactOptions, Reenacted};
use results::episode::TrajectoryHash;
use results::recording::{RecordError, Recorder, RecordingSummary};
use results::verdict::{Judge, Verdict};
use runtime::cameras::TaskCameras;
use runtime::render::RenderError;
use runtime::{Episode, Scene};
use std::path::{Path, PathBuf};
use std::sync::Arc;

#[derive(Debug, thiserror::Error)]
pub enum ReplayError {
    #[error(transparent)]
    Record(#[from] RecordError),
    #[error("the recording's {0} does not match this autobio's schema: {1}")]
    Schema(&'static str, serde_json::Error),
    #[error(transparent)]
    Scene(#[from] runtime::SceneError),
    #[error(transparent)]
    Restore(#[from] runtime::RestoreError),
    #[error(
        "the recording has no MuJoCo state (`/physics/state`); it was made before recordings carried it"
    )]
    NoState,
    #[error("the recording has {steps} control steps; step {asked} is not one of them")]
    NoStep { asked: usize, steps: usize },
    #[error("the recording's robot `{0}` has {1} actions for {2} control steps")]
    Actions(String, usize, usize),
    #[error("the simulation failed at control step {step}: {error}")]
    Step {
        step: usize,
        error: runtime::StepError,
    },
    #[error(transparent)]
    Render(#[from] RenderError),
    #[error("a recorded frame of `{camera}` does not decode: {why}")]
    Frame { camera: String, why: std::io::Error },
    /// What a caller drawing frames for its own use failed at (a dataset's video encoder).
    #[error("{0}")]
    Consumer(Box<dyn std::error::Error + Send + Sync>),
    // The OS error is part of the message and not a `source`: a chain of causes prints it once.
    #[error("cannot write {path}: {why}")]
    Write { path: PathBuf, why: std::io::Error },
}

/// A recording with its task and scene instance decoded.
pub struct Recording {
    pub path: PathBuf,
    pub summary: RecordingSummary,
    pub task: Task,
    pub instance: SceneInstance,
}

impl Recording {
    pub fn open(path: &Path) -> Result<Recording, ReplayError> {
        let summary = results::recording::read_recording(path)?;
        let task = serde_json::from_value(summary.task.clone())
            .map_err(|e| ReplayError::Schema("task", e))?;
        let instance = serde_json::from_value(summary.instance.clone())
            .map_err(|e| ReplayError::Schema("scene instance", e))?;
        Ok(Recording {
            path: path.to_path_buf(),
            summary,
            task,
            instance,
        })
    }

    /// Control steps recorded (states before each action; the last state follows them).
    pub fn steps(&self) -> usize {
        self.summary.physics.len().saturating_sub(1)
    }

    /// The trajectory hash the episode reported, if the recording has one.
    pub fn recorded_hash(&self) -> Option<&str> {
        self.summary.verdict.as_ref()?["trajectory_hash"].as_str()
    }

    /// The action applied at each control step (every robot's part, in task order).
    pub fn actions(&self) -> Result<Vec<Vec<f64>>, ReplayError> {
        let steps = self.steps();
        let mut out = vec![Vec::new(); steps];
        for r in &self.task.robots {
            let mine = self.summary.actions.get(&r.name).map_or(&[][..], |a| a);
            if mine.len() < steps {
                return Err(ReplayError::Actions(r.name.clone(), mine.len(), steps));
            }
            for (k, a) in out.iter_mut().enumerate() {
                a.extend_from_slice(&mine[k]);
            }
        }
        Ok(out)
    }

    /// A scene for the recording and an episode restored to control step `k`.
    fn episode_at(&self, scene: &Arc<Scene>, k: usize) -> Result<Episode, ReplayError> {
        let mut ep = Episode::new(scene.clone(), &self.task, &self.instance);
        self.restore(&mut ep, k)?;
        Ok(ep)
    }

    fn restore(&self, ep: &mut Episode, k: usize) -> Result<(), ReplayError> {
        let (_, state) = self.summary.physics.get(k).ok_or(ReplayError::NoStep {
            asked: k,
            steps: self.steps(),
        })?;
        let logic = self
            .summary
            .labware_series
            .get(k)
            .map(|(_, items)| items.iter().map(|i| i.logic.clone()).collect())
            .unwrap_or_default();
        ep.restore(state, logic)?;
        Ok(())
    }

    fn scene(&self) -> Result<Arc<Scene>, ReplayError> {
        if self.summary.physics.is_empty() {
            return Err(ReplayError::NoState);
        }
        Ok(Arc::new(Scene::build(&self.task, &self.instance)?))
    }
}

/// What a re-simulation found.
#[derive(Clone, Debug)]
pub struct Resimulation {
    pub from_step: usize,
    pub steps: usize,
    /// The [`TrajectoryHash`] over the recorded states up to `from_step` and the re-simulated ones
    /// after.
    pub hash: String,
    pub recorded_hash: Option<String>,
    /// The first control step whose re-simulated state differs from the recorded one.
    pub first_divergence: Option<usize>,
    /// The verdict re-judged on the re-simulated states.
    pub verdict: Verdict,
}

impl Resimulation {
    /// Every state equal and the hash the recorded one.
    pub fn reproduced(&self) -> bool {
        self.first_divergence.is_none() && self.recorded_hash.as_deref() == Some(self.hash.as_str())
    }
}

/// Re-simulates the recording from control step `from_step` (see the module doc).
pub fn resimulate(rec: &Recording, from_step: usize) -> Result<Resimulation, ReplayError> {
    let scene = rec.scene()?;
    let steps = rec.steps();
    if from_step > steps {
        return Err(ReplayError::NoStep {
            asked: from_step,
            steps,
        });
    }
    let actions = rec.actions()?;
    let mut ep = rec.episode_at(&scene, from_step)?;
    let nq = scene.model.ffi().nq as usize;
    let qpos = |state: &[f64]| state[1..1 + nq].to_vec();
    let mut hash = TrajectoryHash::new();
    for (_, state) in &rec.summary.physics[1..=from_step] {
        hash.step(&qpos(state));
    }
    let series = &rec.summary.labware_series;
    let first = series.first().map(|(_, s)| s.clone()).unwrap_or_default();
    let mut judge = Judge::new(&rec.task, &rec.instance.params, &first);
    for (t, s) in &series[..=from_step.min(series.len().saturating_sub(1))] {
        judge.update(*t, s);
    }
    let mut first_divergence = None;
    for (k, action) in actions.iter().enumerate().skip(from_step) {
        ep.apply(action)
            .and_then(|_| ep.control_step())
            .map_err(|error| ReplayError::Step { step: k, error })?;
        // A step that jumped the clock (`runtime::clock`) recorded the time it jumped to.
        let recorded_time = rec.summary.physics[k + 1].1[0];
        if recorded_time > ep.time() + 0.5 * ep.control_period() {
            ep.skip_to(recorded_time);
        }
        hash.step(ep.data.qpos());
        let now = ep.physics_state();
        let recorded = &rec.summary.physics[k + 1].1;
        let same = now.len() == recorded.len()
            && now
                .iter()
                .zip(recorded)
                .all(|(a, b)| a.to_bits() == b.to_bits());
        if !same && first_divergence.is_none() {
            first_divergence = Some(k + 1);
        }
        judge.update(ep.time(), &ep.labware_state());
    }
    Ok(Resimulation {
        from_step,
        steps,
        hash: hash.hex(),
        recorded_hash: rec.recorded_hash().map(str::to_string),
        first_divergence,
        verdict: judge.verdict(),
    })
}

/// Re-enacts an episode of `task` (the verifier's own, not a recording's) from the scene `seed`
/// draws and `actions` (one per control step, every robot's part in task order). Trusts
/// nothing recorded but the actions (and, for an episode that ended by a policy's or server's
/// error, that error's text).
pub fn reenact(
    task: &Task,
    seed: u64,
    actions: &[Vec<f64>],
    opts: &ReenactOptions,
) -> Result<Reenacted, crate::episode::EpisodeError> {
    use crate::episode::{EpisodeError, Recording};
    let instance = task.sample(seed);
    let scene = Arc::new(
        Scene::build(task, &instance)
            .map_err(runtime::EnvError::from)
            .map_err(EpisodeError::Env)?,
    );
    let env_opts = runtime::EnvOptions {
        image_size: opts.image_size,
        ..Default::default()
    };
    let mut env = runtime::Env::new(scene, task, &instance, env_opts);
    let mut recording = match &opts.record {
        Some(p) => Some(Recording::create(
            p.clone(),
            task,
            &instance,
            opts.image_every,
        )?),
        None => None,
    };
    let mut used = 0;
    for a in actions {
        if env.done() {
            break;
        }
        used += 1;
        let mut observers: Vec<&mut dyn runtime::Observer> = Vec::new();
        if let Some(r) = recording.as_mut() {
            observers.push(r);
        }
        match env.step_with(a, &mut observers) {
            // A refused action ended the episode: the environment's end says why.
            Ok(_) | Err(runtime::EnvError::Step(_)) => {}
            Err(e) => return Err(EpisodeError::Env(e)),
        }
    }
    // The environment's error first (a refused action, an unstable simulation), then the error
    // the claim names, then the judge's end; none where the actions ran out first.
    let end = env
        .end()
        .filter(|e| e.error().is_some())
        .or_else(|| opts.claimed.clone())
        .or_else(|| env.end());
    let concluded = end
        .clone()
        .unwrap_or_else(|| EpisodeEnd::judged(&env.verdict()))
        .conclude(env.verdict());
    if let Some(r) = recording {
        r.finish(&env, concluded.error.as_deref(), &concluded.verdict)?;
    }
    Ok(Reenacted {
        hash: env.trajectory_hash(),
        end,
        verdict: concluded.verdict,
        time_s: env.time(),
        control_steps: env.control_steps(),
        unused_actions: actions.len() - used,
    })
}

/// How to draw a recording's frames.
#[derive(Clone, Debug, Default)]
pub struct FrameOptions {
    /// Width and height; `None`: the recorded frames' size, else 224x224.
    pub size: Option<[usize; 2]>,
    /// `None`: by size (`runtime::render::detail_for`).
    pub detail: Option<robots::Detail>,
    /// Every this many control steps; `None`: the recorded frames' cadence, else every step.
    pub every: Option<usize>,
    /// Who draws: the rasteriser, or Blender for photoreal frames.
    pub renderer: runtime::cameras::Renderer,
}

impl Recording {
    /// The recorded frames' size, from the first frame's PNG header.
    pub fn recorded_size(&self) -> Option<[usize; 2]> {
        let (_, png) = self.summary.images.values().next()?.first()?;
        let img = Image::from_png("", png).ok()?;
        Some([img.width, img.height])
    }

    /// The recorded frames' cadence in control steps.
    pub fn recorded_every(&self) -> Option<usize> {
        let frames = self.summary.images.values().next()?;
        let period = self.task.physics.timestep_s * self.task.physics.substeps as f64;
        match frames.as_slice() {
            [(a, _), (b, _), ..] => Some((((b - a) / period).round() as usize).max(1)),
            [_] => Some(self.steps().max(1)),
            [] => None,
        }
    }
}

/// Draws every camera from the recorded state at each chosen control step (no simulation) and
/// hands each step's frames to `each` with the step's index and time.
pub fn frames(
    rec: &Recording,
    opts: &FrameOptions,
    mut each: impl FnMut(usize, f64, Vec<Image>) -> Result<(), ReplayError>,
) -> Result<(), ReplayError> {
    let scene = rec.scene()?;
    let [w, h] = opts
        .size
        .or_else(|| rec.recorded_size())
        .unwrap_or([224, 224]);
    let detail = opts
        .detail
        .unwrap_or_else(|| runtime::render::detail_for(w, h));
    let every = opts
        .every
        .or_else(|| rec.recorded_every())
        .unwrap_or(1)
        .max(1);
    let mut cams = TaskCameras::new(&scene, w, h, opts.renderer, Some(detail))?;
    // The episode's perturbation, as its environment showed it.
    let drawn = rec.instance.perturbation.as_ref();
    cams.set_look(&scene, drawn)?;
    let names: Vec<String> = rec.task.cameras.iter().map(|c| c.name.clone()).collect();
    let mut ep = Episode::new(scene.clone(), &rec.task, &rec.instance);
    // The last state follows the last action; an episode records frames only before actions.
    for k in (0..rec.steps()).step_by(every) {
        rec.restore(&mut ep, k)?;
        let mut images = cams.render(&ep.data, ep.logic(), &names)?;
        runtime::perturb::degrade_frames(&mut images, drawn, rec.instance.seed, k as u64);
        each(k, rec.summary.physics[k].0, images)?;
    }
    Ok(())
}

/// What [`render`] wrote.
#[derive(Clone, Debug, PartialEq)]
pub struct Rendered {
    pub frames: usize,
    pub size: [usize; 2],
    pub out: PathBuf,
    pub png_dir: Option<PathBuf>,
}

/// Writes a copy of the recording whose camera channels are redrawn with `opts` (and, with
/// `png_dir`, every frame as `<camera>_<step>.png` there, a `/` in a camera's name as `_`);
/// `progress` hears each drawn control step and the recording's steps.
pub fn render(
    rec: &Recording,
    opts: &FrameOptions,
    out: &Path,
    png_dir: Option<&Path>,
    mut progress: impl FnMut(usize, usize),
) -> Result<Rendered, ReplayError> {
    let write_err = |path: &Path| {
        let path = path.to_path_buf();
        move |why| ReplayError::Write { path, why }
    };
    if let Some(d) = png_dir {
        std::fs::create_dir_all(d).map_err(write_err(d))?;
    }
    let mut w = Recorder::create(out)?;
    results::recording::for_each_message(&rec.path, |m| {
        if m.channel.topic.starts_with("/camera/") {
            Ok(())
        } else {
            w.pass(m)
        }
    })?;
    let mut count = 0;
    let mut size = [0, 0];
    let steps = rec.steps();
    frames(rec, opts, |k, t, images| {
        progress(k, steps);
        for img in images {
            size = [img.width, img.height];
            if let Some(d) = png_dir {
                let p = d.join(format!("{}_{k:05}.png", img.camera.replace('/', "_")));
                let png = img.to_png().map_err(write_err(&p))?;
                std::fs::write(&p, png).map_err(write_err(&p))?;
            }
            w.image(t, &img)?;
            count += 1;
        }
        Ok(())
    })?;
    w.finish()?;
    Ok(Rendered {
        frames: count,
        size,
        out: out.to_path_buf(),
        png_dir: png_dir.map(Path::to_path_buf),
    })
}

/// The recorded frames of one camera decoded (time, image).
pub fn recorded_frames(rec: &Recording, camera: &str) -> Result<Vec<(f64, Image)>, ReplayError> {
    rec.summary
        .images
        .get(camera)
        .map_or(&[][..], |f| f)
        .iter()
        .map(|(t, png)| {
            Image::from_png(camera, png)
                .map(|i| (*t, i))
                .map_err(|why| ReplayError::Frame {
                    camera: camera.to_string(),
                    why,
                })
        })
        .collect()
}
