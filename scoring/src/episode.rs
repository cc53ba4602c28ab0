//! The episode loop, on [`runtime::Env`]: observe, ask the policy for a chunk of actions, step
//! the environment with each until the episode ends (success, polled after every control step, or
//! the time limit). What watches the episode is an observer of the environment: the recording
//! ([`Recording`]), a dataset capture (any [`runtime::Observer`] the caller passes) and the
//! frames a policy wants from before its query ([`History`]). A policy failure or an unstable
//! simulation ends the episode as a failure with its reason; a recording or renderer fault ends
//! the loop with a typed [`EpisodeError`].

use compiler::{SceneInstance, Task};
use policy::{Observation, Policy, Privileged};
use results::Image;
use results::end::{Concluded, EpisodeEnd};
use results::episode::EpisodeResult;
use results::recording::{RecordError, Recorder};
use runtime::render::RenderError;
use runtime::{Env, EnvError, EnvOptions, ObserveError, Observer};
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

#[derive(Clone, Debug, Default)]
pub struct EpisodeOptions {
    /// Write an MCAP recording here.
    pub record: Option<PathBuf>,
    /// Render and record camera images every this many control steps (0 = no images).
    pub image_every: u32,
    /// Every camera at this size, unless the policy needs another (a model's profile: what it
    /// is sent wins); `None`: the task's camera spec.
    pub image_size: Option<[usize; 2]>,
    /// Who draws the cameras (the rasteriser unless a photoreal pass asks for Blender).
    pub renderer: runtime::cameras::Renderer,
}

/// Why an episode could not be run to its end (an episode that fails is a result, not this).
#[derive(Debug, thiserror::Error)]
pub enum EpisodeError {
    #[error("the recording {path}: {source}")]
    Record {
        path: PathBuf,
        #[source]
        source: RecordError,
    },
    #[error(transparent)]
    Render(#[from] RenderError),
    #[error(transparent)]
    Env(EnvError),
    #[error("cannot describe the task for its recording: {0}")]
    Describe(#[from] serde_json::Error),
}

/// How a policy's failure ends its episode: a model server's fault, or the policy's error.
pub fn end_of(e: &policy::PolicyError) -> EpisodeEnd {
    match e {
        policy::PolicyError::Server(_) => EpisodeEnd::ServerFault(e.to_string()),
        _ => EpisodeEnd::PolicyError(e.to_string()),
    }
}

/// The result of an episode whose policy could not be made (the expert cannot plan it, a replay
/// has no recording of its seed, the model server cannot be reached): judged on the initial
/// state, a failure that scores 0 (`Verdict::ended_by_error`), with its reason. With `record`, the
/// episode is recorded like any other (its start, no actions, the verdict), so that a run's every
/// episode has its recording and a leaderboard can re-enact it.
pub fn policy_failed(
    task: &Task,
    scene: &Arc<runtime::Scene>,
    instance: &SceneInstance,
    failure: &policy::PolicyError,
    record: Option<PathBuf>,
) -> Result<EpisodeResult, EpisodeError> {
    let env = Env::new(scene.clone(), task, instance, EnvOptions::default());
    let ended = end_of(failure).conclude(env.verdict());
    if let Some(path) = &record {
        Recording::create(path.clone(), task, instance, 0)?.finish(
            &env,
            ended.error.as_deref(),
            &ended.verdict,
        )?;
    }
    Ok(EpisodeResult {
        seed: instance.seed,
        run: 0,
        success: ended.verdict.success,
        outcome: ended.outcome,
        verdict: ended.verdict,
        error: ended.error,
        sim_time_s: 0.0,
        control_steps: 0,
        wall_time_s: 0.0,
        policy_time_s: 0.0,
        trajectory_hash: results::episode::TrajectoryHash::new().hex(),
        recording: record.map(|p| p.display().to_string()),
    })
}

/// An episode's MCAP recording, as an observer: before each action every robot's state and
/// action, the labware, MuJoCo's state and (every `image_every` steps) the cameras.
pub struct Recording {
    path: PathBuf,
    writer: Recorder,
    image_every: u64,
}

impl Recording {
    pub fn create(
        path: PathBuf,
        task: &Task,
        instance: &SceneInstance,
        image_every: u32,
    ) -> Result<Recording, EpisodeError> {
        let failed = |source| EpisodeError::Record {
            path: path.clone(),
            source,
        };
        let mut writer = Recorder::create(&path).map_err(failed)?;
        let (tj, ij) = (serde_json::to_value(task)?, serde_json::to_value(instance)?);
        writer.task(&tj, &ij).map_err(failed)?;
        Ok(Recording {
            path,
            writer,
            image_every: u64::from(image_every),
        })
    }

    fn failed(&self, source: RecordError) -> EpisodeError {
        EpisodeError::Record {
            path: self.path.clone(),
            source,
        }
    }

    /// A labelled moment (a motion's or a lab step's start).
    pub fn stage(&mut self, t: f64, label: &str) -> Result<(), EpisodeError> {
        self.writer.stage(t, label).map_err(|e| self.failed(e))
    }

    /// The state after the last step, the verdict, and the file closed.
    pub fn finish(
        mut self,
        env: &Env,
        error: Option<&str>,
        verdict: &results::verdict::Verdict,
    ) -> Result<(), EpisodeError> {
        let t = env.time();
        let ep = env.episode();
        let end = serde_json::json!({
            "verdict": verdict, "error": error,
            "trajectory_hash": env.trajectory_hash(), "control_steps": env.control_steps(),
        });
        let written = self
            .writer
            .labware(t, &ep.labware_state())
            .and_then(|_| self.writer.physics(t, &ep.physics_state()))
            .and_then(|_| self.writer.write("/verdict", "autobio.Verdict", t, &end));
        written.map_err(|e| self.failed(e))?;
        let path = self.path;
        self.writer
            .finish()
            .map_err(|source| EpisodeError::Record { path, source })
    }
}

impl Observer for Recording {
    fn before_step(&mut self, env: &mut Env, action: &[f64]) -> Result<(), ObserveError> {
        let t = env.time();
        let ep = env.episode();
        let mut rest = action;
        for (k, ids) in ep.scene.robots.iter().enumerate() {
            let (mine, others) = rest.split_at(ids.model.action_len().min(rest.len()));
            rest = others;
            self.writer
                .joint_state(t, &ids.name, &ep.robot_state(k), &ep.robot_ctrl(k))?;
            self.writer.action(t, &ids.name, mine)?;
        }
        self.writer.labware(t, &ep.labware_state())?;
        self.writer.physics(t, &ep.physics_state())?;
        if self.image_every > 0 && env.control_steps().is_multiple_of(self.image_every) {
            for img in env.frames()? {
                self.writer.image(t, img)?;
            }
        }
        Ok(())
    }

    /// A step that jumped the clock says so on `/stage`, at the time it jumped to.
    fn after_step(&mut self, env: &Env) -> Result<(), ObserveError> {
        let skipped = env.skipped_s();
        if skipped > 0.0 {
            self.writer.stage(
                env.time(),
                &format!("clock jumped {skipped:.3} s: only instrument timers ran"),
            )?;
        }
        Ok(())
    }
}

/// The frames a policy asks for from `history_steps` control steps before its next query
/// ([`policy::Needs::history_steps`]): taken at that step of the chunk, or, for a chunk
/// no longer than the history, the frames of the query itself.
pub struct History {
    steps: usize,
    /// The step of the current chunk to take them at, and the chunk's next step.
    at: Option<usize>,
    k: usize,
    frames: Option<Vec<Image>>,
}

impl History {
    pub fn new(steps: u32) -> History {
        History {
            steps: steps as usize,
            at: None,
            k: 0,
            frames: None,
        }
    }

    /// The frames for the query now (`current` at the first query).
    fn take(&mut self, current: &[Image]) -> Vec<Image> {
        self.frames.take().unwrap_or_else(|| current.to_vec())
    }

    /// A chunk of `len` actions starts, answered to a query with `current` frames.
    fn chunk(&mut self, len: usize, current: &[Image]) {
        self.k = 0;
        self.at = (self.steps > 0)
            .then(|| len.checked_sub(self.steps))
            .flatten();
        if self.at.is_none() && self.steps > 0 {
            self.frames = Some(current.to_vec());
        }
    }
}

impl Observer for History {
    fn before_step(&mut self, env: &mut Env, _action: &[f64]) -> Result<(), ObserveError> {
        if self.at == Some(self.k) {
            self.frames = Some(env.frames()?.to_vec());
        }
        self.k += 1;
        Ok(())
    }
}

/// Runs one episode of `task` with the scene instance for `seed`.
pub fn run_episode(
    task: &Task,
    scene: &Arc<runtime::Scene>,
    instance: &SceneInstance,
    policy: &mut dyn Policy,
    opts: &EpisodeOptions,
) -> Result<EpisodeResult, EpisodeError> {
    run_episode_with(task, scene, instance, policy, opts, None)
}

/// [`run_episode`], with one more observer of every control step (a dataset capture). An
/// observer's own failure ([`ObserveError::Own`]) fails the episode with its reason.
pub fn run_episode_with(
    task: &Task,
    scene: &Arc<runtime::Scene>,
    instance: &SceneInstance,
    policy: &mut dyn Policy,
    opts: &EpisodeOptions,
    mut extra: Option<&mut dyn Observer>,
) -> Result<EpisodeResult, EpisodeError> {
    let start = Instant::now();
    let needs = policy.needs();
    let image_size = needs.image_size.or(opts.image_size);
    let env_opts = EnvOptions {
        image_size,
        renderer: opts.renderer,
    };
    let mut env = Env::new(scene.clone(), task, instance, env_opts);
    env.set_never_moves(policy.never_moves());
    let mut recording = match &opts.record {
        Some(p) => Some(Recording::create(
            p.clone(),
            task,
            instance,
            opts.image_every,
        )?),
        None => None,
    };
    let mut history = History::new(needs.history_steps);
    let layout = needs
        .environment_state
        .then(|| results::environment_state::EnvironmentState::of(task));
    let mut policy_time = 0.0;
    // How the policy's side ended the episode, where it did (the environment says the rest).
    let mut failure: Option<EpisodeEnd> = None;
    'episode: while !env.done() {
        let images = match needs.image_size {
            Some(_) => env.frames()?.to_vec(),
            None => Vec::new(),
        };
        let previous = history.take(&images);
        let seen = env.observe();
        let obs = Observation {
            images: &images,
            previous: &previous,
            environment_state: layout
                .as_ref()
                .map(|l| env.environment_state(l))
                .unwrap_or_default(),
            time: seen.time,
            state: seen.state,
            stage: seen.stage,
            prompt: &seen.instruction,
            privileged: Privileged {
                robots: seen.robots,
                labware: seen.labware,
                qpos: seen.qpos,
            },
        };
        let asked = Instant::now();
        let answer = policy.act(&obs);
        policy_time += asked.elapsed().as_secs_f64();
        let chunk = match answer {
            Ok(c) if !c.is_empty() => c,
            Ok(_) => {
                failure = Some(EpisodeEnd::PolicyError(
                    "policy returned an empty action chunk".into(),
                ));
                break;
            }
            Err(e) => {
                failure = Some(end_of(&e));
                break;
            }
        };
        history.chunk(chunk.len(), &images);
        if let Some(r) = recording.as_mut() {
            for ev in policy.drain_events() {
                r.stage(ev.time, &ev.label)?;
            }
        }
        for action in chunk {
            let mut observers: Vec<&mut dyn Observer> = Vec::with_capacity(3);
            if let Some(o) = extra.as_deref_mut() {
                observers.push(o);
            }
            if let Some(r) = recording.as_mut() {
                observers.push(r);
            }
            if needs.image_size.is_some() {
                observers.push(&mut history);
            }
            match env.step_with(&action, &mut observers) {
                Ok(t) if t.done() => break 'episode,
                Ok(_) => {}
                // A refused action: the environment's end says so.
                Err(EnvError::Step(_)) => break 'episode,
                Err(EnvError::Observe(ObserveError::Own(e))) => {
                    failure = Some(EpisodeEnd::PolicyError(format!(
                        "the step sink failed: {e}"
                    )));
                    break 'episode;
                }
                Err(EnvError::Observe(ObserveError::Render(e)) | EnvError::Render(e)) => {
                    return Err(e.into());
                }
                Err(EnvError::Observe(ObserveError::Record(source))) => {
                    return Err(EpisodeError::Record {
                        path: opts.record.clone().unwrap_or_default(),
                        source,
                    });
                }
                Err(e) => return Err(EpisodeError::Env(e)),
            }
        }
    }
    // The environment's own end first (an unstable simulation, a refused action), else the
    // policy's, else the judge's.
    let end = env
        .end()
        .filter(|e| e.error().is_some())
        .or(failure)
        .or_else(|| env.end())
        .unwrap_or_else(|| EpisodeEnd::judged(&env.verdict()));
    let Concluded {
        outcome,
        error,
        verdict,
    } = end.conclude(env.verdict());
    let steps = env.control_steps();
    policy.end_episode(verdict.success, steps);
    if let Some(r) = recording {
        r.finish(&env, error.as_deref(), &verdict)?;
    }
    Ok(EpisodeResult {
        seed: instance.seed,
        run: 0,
        success: verdict.success,
        outcome,
        verdict,
        error,
        sim_time_s: env.time(),
        control_steps: steps,
        wall_time_s: start.elapsed().as_secs_f64(),
        policy_time_s: policy_time,
        trajectory_hash: env.trajectory_hash(),
        recording: opts.record.as_ref().map(|p| p.display().to_string()),
    })
}
