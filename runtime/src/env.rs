//! The step-wise environment: `reset(seed)` and `step(action)` over one task, in the paper's order
//! (observe, act, hold the action for the task's physics steps, poll the success checks), with
//! gymnasium's vocabulary: a step reports a reward, `terminated` (the task succeeded) and
//! `truncated` (a stage's or the task's time ran out).
//!
//! What watches an episode is an [`Observer`] handed to [`Env::step_with`]: the recorder, a
//! dataset capture, a policy's history frames. The trajectory hash is the environment's own
//! observer ([`results::episode::TrajectoryHash`], the one rule for "the same trajectory").
//! Cameras are one set, sized by [`EnvOptions::image_size`] or else by the task's own camera
//! spec, drawn at most once per control step whoever asks ([`Env::frames`]).
//!
//! Lab time is event-driven where nothing but instrument timers runs ([`crate::clock`]): a step
//! may jump the clock after its physics ([`Transition::skipped_s`]), so a 30-cycle profile costs a
//! few hundred control steps instead of a few hundred thousand.
//!
//! How an episode ended is the environment's to say where the end happens here
//! ([`Env::end`], [`Transition::end`]: the judge's success or time limit, an unstable simulation,
//! a refused action), as [`results::end::EpisodeEnd`], the one type every caller reads.
//!
//! It does not decide actions (policies do, in `scoring`) and does not write results; it reports
//! state, frames and the judge's verdict.

use crate::cameras::TaskCameras;
use crate::clock::IdleClock;
use crate::episode::{Episode, StepError};
use crate::render::RenderError;
use crate::scene::{Scene, SceneError};
use compiler::{SceneInstance, Task};
use labware::LabwareState;
use results::Image;
use results::end::EpisodeEnd;
use results::environment_state::EnvironmentState;
use results::episode::TrajectoryHash;
use results::recording::RecordError;
use results::verdict::{Judge, Verdict};
use std::sync::Arc;

/// How an environment draws its cameras.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EnvOptions {
    /// Every camera at this size (width, height); `None`: the task's own camera spec.
    pub image_size: Option<[usize; 2]>,
    /// Who draws the cameras (the rasteriser unless a photoreal pass asks for Blender).
    pub renderer: crate::cameras::Renderer,
}

/// Why the environment could not go on.
#[derive(Debug, thiserror::Error)]
pub enum EnvError {
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// The action was refused; the episode is over ([`Env::end`]: a policy error). An unstable
    /// simulation is no error of the caller's: its step ends the episode ([`Transition::end`]).
    #[error(transparent)]
    Step(#[from] StepError),
    #[error(transparent)]
    Render(#[from] RenderError),
    #[error(transparent)]
    Observe(#[from] ObserveError),
    #[error("the episode is over (success or time limit); reset the environment to start another")]
    Over,
}

/// Why an observer failed.
#[derive(Debug, thiserror::Error)]
pub enum ObserveError {
    #[error(transparent)]
    Render(#[from] RenderError),
    /// A recording could not be written (a full disk is `RecordError::Write`).
    #[error(transparent)]
    Record(#[from] RecordError),
    /// The observer's own failure (a dataset capture's video encoder).
    #[error("{0}")]
    Own(Box<dyn std::error::Error + Send + Sync>),
}

/// Watches an episode step by step. Observers see the state an action acts on and the state it
/// left; they cannot change the episode (the `&mut` is for [`Env::frames`]' cache).
pub trait Observer {
    /// Before the action of a control step is applied.
    fn before_step(&mut self, _env: &mut Env, _action: &[f64]) -> Result<(), ObserveError> {
        Ok(())
    }
    /// After the action was held for the task's physics steps and the checks were polled.
    fn after_step(&mut self, _env: &Env) -> Result<(), ObserveError> {
        Ok(())
    }
}

impl Observer for TrajectoryHash {
    fn after_step(&mut self, env: &Env) -> Result<(), ObserveError> {
        self.step(env.episode.data.qpos());
        Ok(())
    }
}

/// One robot's privileged state: what the scripted expert and the controls read.
#[derive(Clone, Debug, PartialEq)]
pub struct RobotState {
    /// Arm joint angles (rad).
    pub arm_q: Vec<f64>,
    /// Current targets, in the robot's action layout.
    pub ctrl: Vec<f64>,
}

/// What the environment shows at a control step, images aside ([`Env::frames`]).
#[derive(Clone, Debug)]
pub struct Observation {
    pub time: f64,
    /// Every robot's state, concatenated in task order (the robot models' layouts).
    pub state: Vec<f64>,
    /// The stage now running and its instruction (the task's, with the drawn parameters).
    pub stage: usize,
    pub instruction: String,
    /// Privileged simulator state, for the scripted expert and the controls; never for models.
    pub robots: Vec<RobotState>,
    pub labware: Vec<LabwareState>,
    /// MuJoCo's generalized positions.
    pub qpos: Vec<f64>,
}

/// What one step did: gymnasium's `(reward, terminated, truncated)`, the time it reached, and how
/// the episode ended if it ended here.
#[derive(Clone, Debug, PartialEq)]
pub struct Transition {
    /// The task's score when the episode ends at this step; 0 before.
    pub reward: f64,
    /// Every stage's checks held.
    pub terminated: bool,
    /// A stage's or the task's time limit passed first.
    pub truncated: bool,
    pub time: f64,
    pub control_steps: u64,
    /// Seconds of lab time the step jumped over after its physics (only instrument timers ran);
    /// 0 for an ordinary step.
    pub skipped_s: f64,
    /// How the episode ended, where it ended at this step.
    pub end: Option<EpisodeEnd>,
}

impl Transition {
    pub fn done(&self) -> bool {
        self.terminated || self.truncated
    }
}

/// One task's episodes, stepped by hand or by the episode loop.
pub struct Env {
    task: Task,
    opts: EnvOptions,
    instance: SceneInstance,
    episode: Episode,
    judge: Judge,
    hash: TrajectoryHash,
    /// The judge said the episode is over (success, or a stage's time ran out).
    over: bool,
    /// The episode ended by an error of its own: an unstable simulation or a refused action.
    failed: Option<EpisodeEnd>,
    /// Made on the first frame asked for; the control step its last frames show.
    cameras: Option<TaskCameras>,
    frames: Option<(u64, Vec<Image>)>,
    /// How long the robots have been idle (the clock's jumps).
    clock: IdleClock,
    /// What the last step jumped over (s).
    skipped_s: f64,
}

impl Env {
    /// An environment for `task` at the episode `seed` draws (its scene built for it).
    pub fn make(task: &Task, seed: u64, opts: EnvOptions) -> Result<Env, EnvError> {
        let instance = task.sample(seed);
        let scene = Arc::new(Scene::build(task, &instance)?);
        Ok(Env::new(scene, task, &instance, opts))
    }

    /// An environment at the start of `instance`'s episode, on a scene built for it.
    pub fn new(scene: Arc<Scene>, task: &Task, instance: &SceneInstance, opts: EnvOptions) -> Env {
        let episode = Episode::new(scene, task, instance);
        let initial = episode.labware_state();
        let mut judge = Judge::new(task, &instance.params, &initial);
        let over = judge.update(episode.time(), &initial);
        Env {
            task: task.clone(),
            opts,
            instance: instance.clone(),
            episode,
            judge,
            hash: TrajectoryHash::new(),
            over,
            failed: None,
            cameras: None,
            frames: None,
            clock: IdleClock::default(),
            skipped_s: 0.0,
        }
    }

    /// Seconds the last step jumped over (0: an ordinary step).
    pub fn skipped_s(&self) -> f64 {
        self.skipped_s
    }

    /// The policy never moves (the hold control): an idle scene at rest may then jump to its
    /// deadline with no instrument running ([`IdleClock::never_moves`]).
    pub fn set_never_moves(&mut self, never: bool) {
        self.clock.never_moves = never;
    }

    /// When the stage now running, or the task, runs out of time, whichever is first (s).
    pub fn deadline(&self) -> f64 {
        self.judge
            .deadline()
            .unwrap_or(f64::INFINITY)
            .min(self.task.time_limit_s)
    }

    /// Starts the episode `seed` draws, on the same scene when its labware stands where it did.
    pub fn reset(&mut self, seed: u64) -> Result<Observation, EnvError> {
        let instance = self.task.sample(seed);
        let mut slot = Some(self.episode.scene.clone());
        let scene = Scene::reuse_or_build(&mut slot, &self.task, &instance)?;
        let same = Arc::ptr_eq(&scene, &self.episode.scene);
        let cameras = self.cameras.take().filter(|_| same);
        let task = self.task.clone();
        *self = Env::new(scene, &task, &instance, self.opts);
        self.cameras = cameras;
        if let Some(c) = self.cameras.as_mut() {
            c.set_look(&self.episode.scene, self.instance.perturbation.as_ref())?;
        }
        Ok(self.observe())
    }

    /// The MuJoCo episode, to read (robot and labware state, MuJoCo's state); stepping it goes
    /// through [`Env::step`] only, so the hash, the judge and the frames always see every step.
    pub fn episode(&self) -> &Episode {
        &self.episode
    }

    pub fn task(&self) -> &Task {
        &self.task
    }

    pub fn instance(&self) -> &SceneInstance {
        &self.instance
    }

    pub fn scene(&self) -> &Arc<Scene> {
        &self.episode.scene
    }

    pub fn time(&self) -> f64 {
        self.episode.time()
    }

    /// Control steps taken since the reset.
    pub fn control_steps(&self) -> u64 {
        self.hash.steps()
    }

    /// The stage now running.
    pub fn stage(&self) -> usize {
        self.judge.stage()
    }

    /// The episode is over: success, a stage's time ran out, or the task's time limit passed.
    pub fn done(&self) -> bool {
        self.over || self.failed.is_some() || self.time() >= self.task.time_limit_s
    }

    /// How the episode ended (`None` while it runs): an unstable simulation or a refused action
    /// where one ended it, else the judge's success or time limit.
    pub fn end(&self) -> Option<EpisodeEnd> {
        if let Some(failed) = &self.failed {
            return Some(failed.clone());
        }
        self.done()
            .then(|| EpisodeEnd::judged(&self.judge.verdict()))
    }

    /// The judge's verdict so far.
    pub fn verdict(&self) -> Verdict {
        self.judge.verdict()
    }

    /// The trajectory hash of the steps so far ([`TrajectoryHash`]).
    pub fn trajectory_hash(&self) -> String {
        self.hash.hex()
    }

    /// The instruction of the stage now running.
    pub fn instruction(&self) -> &str {
        self.instance
            .stage_instructions
            .get(self.stage())
            .map(String::as_str)
            .unwrap_or(&self.instance.instruction)
    }

    /// The task's environment state now, in `layout` (made once per task with
    /// [`EnvironmentState::of`]): the privileged observation a state-based policy reads.
    pub fn environment_state(&self, layout: &EnvironmentState) -> Vec<f64> {
        layout.values(
            &self.task,
            &self.episode.labware_state(),
            &self.instance.params,
        )
    }

    /// The state now, images aside.
    pub fn observe(&self) -> Observation {
        let ep = &self.episode;
        Observation {
            time: ep.time(),
            state: ep.state(),
            stage: self.stage(),
            instruction: self.instruction().to_string(),
            robots: (0..ep.scene.robots.len())
                .map(|r| RobotState {
                    arm_q: ep.arm_q(r),
                    ctrl: ep.robot_ctrl(r),
                })
                .collect(),
            labware: ep.labware_state(),
            qpos: ep.qpos(),
        }
    }

    /// The size every camera is drawn at.
    pub fn image_size(&self) -> [usize; 2] {
        self.opts.image_size.unwrap_or_else(|| {
            self.task
                .cameras
                .first()
                .map_or([224, 224], |c| [c.width as usize, c.height as usize])
        })
    }

    /// Every task camera's frame of the state now, in task order, under the episode's drawn
    /// perturbation (its look, then its sensor noise); drawn once per control step however many
    /// ask.
    pub fn frames(&mut self) -> Result<&[Image], RenderError> {
        let step = self.control_steps();
        if self.frames.as_ref().is_none_or(|(k, _)| *k != step) {
            let names: Vec<String> = self.task.cameras.iter().map(|c| c.name.clone()).collect();
            self.make_cameras()?;
            let cams = self.cameras.as_mut().expect("made above");
            let mut images = cams.render(&self.episode.data, self.episode.logic(), &names)?;
            let drawn = self.instance.perturbation.as_ref();
            crate::perturb::degrade_frames(&mut images, drawn, self.instance.seed, step);
            self.frames = Some((step, images));
        }
        Ok(&self.frames.as_ref().expect("drawn above").1)
    }

    /// Makes the cameras on first use, with the episode's look.
    fn make_cameras(&mut self) -> Result<(), RenderError> {
        if self.cameras.is_none() {
            let [w, h] = self.image_size();
            let mut cams = TaskCameras::new(&self.episode.scene, w, h, self.opts.renderer, None)?;
            cams.set_look(&self.episode.scene, self.instance.perturbation.as_ref())?;
            self.cameras = Some(cams);
        }
        Ok(())
    }

    /// The state now from a free camera (`view`), at the environment's image size; not one of the
    /// task's cameras, and not cached.
    pub fn view(&mut self, view: &crate::render::View) -> Result<Image, RenderError> {
        self.make_cameras()?;
        let cams = self.cameras.as_mut().expect("made above");
        cams.render_view(&self.episode.data, self.episode.logic(), view)
    }

    /// One control step with no observer but the trajectory hash.
    pub fn step(&mut self, action: &[f64]) -> Result<Transition, EnvError> {
        self.step_with(action, &mut [])
    }

    /// One control step: the observers see the state before the action, the action is held for
    /// the task's physics steps, the checks are polled, and the observers see the result. A
    /// refused action ends the episode with [`EnvError::Step`]; an unstable simulation ends it
    /// with a truncated step whose [`Transition::end`] says why (observers do not see it).
    pub fn step_with(
        &mut self,
        action: &[f64],
        observers: &mut [&mut dyn Observer],
    ) -> Result<Transition, EnvError> {
        if self.done() {
            return Err(EnvError::Over);
        }
        for o in observers.iter_mut() {
            o.before_step(self, action)?;
        }
        if let Err(e) = self
            .episode
            .apply(action)
            .and_then(|_| self.episode.control_step())
        {
            self.skipped_s = 0.0;
            if let StepError::Unstable { .. } = e {
                let end = EpisodeEnd::Unstable(e.to_string());
                self.failed = Some(end.clone());
                return Ok(Transition {
                    reward: 0.0,
                    terminated: false,
                    truncated: true,
                    time: self.time(),
                    control_steps: self.control_steps(),
                    skipped_s: 0.0,
                    end: Some(end),
                });
            }
            self.failed = Some(EpisodeEnd::PolicyError(e.to_string()));
            return Err(e.into());
        }
        self.clock.note(action, &self.episode);
        self.over = self
            .judge
            .update(self.time(), &self.episode.labware_state());
        self.skipped_s = 0.0;
        if let Some(to) = (!self.over)
            .then(|| self.clock.jump_to(&self.episode, self.deadline()))
            .flatten()
        {
            self.skipped_s = to - self.time();
            self.episode.skip_to(to);
            self.over = self
                .judge
                .update(self.time(), &self.episode.labware_state());
        }
        let mut hash = std::mem::take(&mut self.hash);
        hash.after_step(self)?;
        self.hash = hash;
        for o in observers.iter_mut() {
            o.after_step(self)?;
        }
        let done = self.done();
        let verdict = done.then(|| self.judge.verdict());
        let success = verdict.as_ref().is_some_and(|v| v.success);
        Ok(Transition {
            reward: verdict.as_ref().map_or(0.0, |v| v.score),
            terminated: success,
            truncated: done && !success,
            time: self.time(),
            control_steps: self.control_steps(),
            skipped_s: self.skipped_s,
            end: verdict.as_ref().map(EpisodeEnd::judged),
        })
    }
}
