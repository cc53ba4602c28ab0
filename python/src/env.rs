//! `autobio._core.Env`: one task's episodes, stepped from Python over `runtime::Env`. It hands
//! Python plain values (lists, bytes of RGB pixels, JSON text); the gymnasium layer
//! (`autobio/env.py`) shapes them into spaces and arrays. Nothing here decides actions or judges:
//! the reward, `terminated` and `truncated` are the runtime's, as `autobio eval` reads them.
//!
//! A simulation that becomes unstable ends the episode as `autobio eval` ends it (a failure with a
//! reason, scoring 0); an action of the wrong length, not finite or outside its
//! range is the caller's mistake and raises `ValueError` before anything moves (the episode goes
//! on).

use crate::tasks;
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyBytes;
use results::environment_state::EnvironmentState;
use runtime::{EnvError, EnvOptions};

/// What one step did: reward, terminated, truncated, and why the episode ended early, if it did.
pub(crate) type Outcome = (f64, bool, bool, Option<String>);

/// One step in Python's terms: an action the runtime would refuse raises before anything moves
/// (the episode goes on); an unstable simulation ends the episode with its reason, failed and
/// scoring 0, as `autobio eval` scores an episode that ends in an error.
pub(crate) fn step(env: &mut runtime::Env, action: &[f64]) -> Result<Outcome, EnvFailure> {
    runtime::check_action(&env.episode().action_bounds(), action)
        .map_err(|e| EnvFailure::Action(e.to_string()))?;
    match env.step(action) {
        // The runtime's end, as `autobio eval` reads it (an unstable simulation: truncated,
        // scoring 0, with its reason).
        Ok(t) => {
            let why = t.end.as_ref().and_then(|e| e.error()).map(str::to_string);
            Ok((t.reward, t.terminated, t.truncated, why))
        }
        Err(EnvError::Step(e)) => Err(EnvFailure::Action(e.to_string())),
        Err(e) => Err(EnvFailure::Other(e.to_string())),
    }
}

/// Why a step raised.
#[derive(Debug)]
pub enum EnvFailure {
    Action(String),
    Other(String),
}

impl From<EnvFailure> for PyErr {
    fn from(e: EnvFailure) -> PyErr {
        match e {
            EnvFailure::Action(m) => PyValueError::new_err(m),
            EnvFailure::Other(m) => PyRuntimeError::new_err(m),
        }
    }
}

pub(crate) fn options(image_size: Option<(usize, usize)>) -> EnvOptions {
    EnvOptions {
        image_size: image_size.map(|(w, h)| [w, h]),
        ..Default::default()
    }
}

pub(crate) fn runtime_err(e: impl std::fmt::Display) -> PyErr {
    PyRuntimeError::new_err(e.to_string())
}

/// One task's episodes, stepped by hand: `reset(seed)`, then `step(action)` until the episode
/// is over. Seeds are `autobio eval`'s: the same seed and actions give the same episode and
/// trajectory hash.
#[pyclass(unsendable, module = "autobio._core")]
pub struct Env {
    env: runtime::Env,
    seed: u64,
    layout: EnvironmentState,
}

#[pymethods]
impl Env {
    /// `task`: a shipped task id (`autobio.tasks()`) or a protocol or chain file.
    /// `image_size`: (width, height) for every camera; default the task's camera spec.
    #[new]
    #[pyo3(signature = (task, seed = 0, image_size = None))]
    fn new(task: &str, seed: u64, image_size: Option<(usize, usize)>) -> PyResult<Self> {
        let task = tasks::load(task).map_err(crate::load_err)?;
        let env = runtime::Env::make(&task, seed, options(image_size)).map_err(runtime_err)?;
        let layout = EnvironmentState::of(&task);
        Ok(Env { env, seed, layout })
    }

    /// Starts the episode `seed` draws.
    fn reset(&mut self, seed: u64) -> PyResult<()> {
        self.env.reset(seed).map_err(runtime_err)?;
        self.seed = seed;
        Ok(())
    }

    /// One control step: (reward, terminated, truncated, error). `error` is why the simulation
    /// ended the episode (unstable), else None.
    fn step(&mut self, action: Vec<f64>) -> PyResult<Outcome> {
        Ok(step(&mut self.env, &action)?)
    }

    /// Every robot's state, concatenated in task order (`state_names`).
    fn state(&self) -> Vec<f64> {
        self.env.episode().state()
    }

    /// The task's environment state now (`environment_state_names`): the poses, joints, panel
    /// values and volumes its success checks read, then the drawn parameters. Privileged.
    fn environment_state(&self) -> Vec<f64> {
        self.env.environment_state(&self.layout)
    }

    #[getter]
    fn environment_state_names(&self) -> Vec<String> {
        self.layout.names().to_vec()
    }

    /// Every task camera's frame of the state now (`camera_names` order), as RGB bytes, row-major,
    /// top row first.
    fn frames<'py>(&mut self, py: Python<'py>) -> PyResult<Vec<Bound<'py, PyBytes>>> {
        let frames = self.env.frames().map_err(runtime_err)?;
        Ok(frames.iter().map(|f| PyBytes::new(py, &f.rgb)).collect())
    }

    /// The judge's verdict so far, as JSON (`success`, `score`, per-stage predicates).
    fn verdict_json(&self) -> PyResult<String> {
        serde_json::to_string(&self.env.verdict()).map_err(runtime_err)
    }

    /// The action that holds every robot at its current targets: `autobio eval --policy hold`'s
    /// no-motion control, in the action layout.
    fn hold_action(&self) -> Vec<f64> {
        let ep = self.env.episode();
        (0..ep.scene.robots.len())
            .flat_map(|r| ep.robot_ctrl(r))
            .collect()
    }

    /// (is_success, score): the judge's verdict so far, without its per-predicate detail.
    fn outcome(&self) -> (bool, f64) {
        let v = self.env.verdict();
        (v.success, v.score)
    }

    /// Every item's live state, as JSON.
    fn labware_json(&self) -> PyResult<String> {
        serde_json::to_string(&self.env.episode().labware_state()).map_err(runtime_err)
    }

    /// The compiled task, as `autobio compile` writes it.
    fn task_json(&self) -> PyResult<String> {
        serde_json::to_string(self.env.task()).map_err(runtime_err)
    }

    #[getter]
    fn id(&self) -> String {
        self.env.task().id.clone()
    }
    #[getter]
    fn level(&self) -> String {
        self.env.task().level.clone()
    }
    #[getter]
    fn seed(&self) -> u64 {
        self.seed
    }
    /// The running stage's instruction, with the seed's parameters filled in.
    #[getter]
    fn instruction(&self) -> String {
        self.env.instruction().to_string()
    }
    /// The whole task's instruction (a chain's, over all its stages).
    #[getter]
    fn task_instruction(&self) -> String {
        self.env.instance().instruction.clone()
    }
    #[getter]
    fn stage(&self) -> usize {
        self.env.stage()
    }
    /// The parameters the seed drew (name to value, as written in the protocol).
    #[getter]
    fn params(&self) -> std::collections::BTreeMap<String, String> {
        self.env.instance().params.clone()
    }
    #[getter]
    fn time(&self) -> f64 {
        self.env.time()
    }
    #[getter]
    fn control_steps(&self) -> u64 {
        self.env.control_steps()
    }
    /// Seconds per control step (the action is held for the task's physics substeps).
    #[getter]
    fn control_dt(&self) -> f64 {
        control_dt(self.env.task())
    }
    #[getter]
    fn time_limit_s(&self) -> f64 {
        self.env.task().time_limit_s
    }
    /// The most control steps an episode can take before its time limit ends it.
    #[getter]
    fn max_steps(&self) -> u64 {
        max_steps(self.env.task())
    }
    #[getter]
    fn done(&self) -> bool {
        self.env.done()
    }
    #[getter]
    fn trajectory_hash(&self) -> String {
        self.env.trajectory_hash()
    }
    #[getter]
    fn camera_names(&self) -> Vec<String> {
        self.env
            .task()
            .cameras
            .iter()
            .map(|c| c.name.clone())
            .collect()
    }
    /// (width, height) of every camera frame.
    #[getter]
    fn image_size(&self) -> (usize, usize) {
        let [w, h] = self.env.image_size();
        (w, h)
    }
    #[getter]
    fn state_names(&self) -> Vec<String> {
        layout(self.env.task(), |m| m.state_names())
    }
    #[getter]
    fn action_names(&self) -> Vec<String> {
        layout(self.env.task(), |m| m.action_names())
    }
    /// Each action component's lower bound (the actuators' ranges; -inf where unbounded).
    #[getter]
    fn action_low(&self) -> Vec<f64> {
        self.env
            .episode()
            .action_bounds()
            .iter()
            .map(|b| b.0)
            .collect()
    }
    #[getter]
    fn action_high(&self) -> Vec<f64> {
        self.env
            .episode()
            .action_bounds()
            .iter()
            .map(|b| b.1)
            .collect()
    }
}

pub(crate) fn control_dt(task: &compiler::Task) -> f64 {
    task.physics.timestep_s * f64::from(task.physics.substeps)
}

/// An upper bound on an episode's control steps: the time limit over the control period, and one
/// more for the clock's rounding (the runtime ends the episode at its own time, never later).
pub(crate) fn max_steps(task: &compiler::Task) -> u64 {
    (task.time_limit_s / control_dt(task)).ceil() as u64 + 1
}

/// A layout over the task's robots, each name prefixed with its robot's name (`arm/...`), as the
/// datasets name their features.
pub(crate) fn layout(
    task: &compiler::Task,
    names: fn(&robots::RobotModel) -> Vec<String>,
) -> Vec<String> {
    task.robots
        .iter()
        .flat_map(|r| {
            robots::model(&r.model)
                .map(names)
                .unwrap_or_default()
                .into_iter()
                .map(move |n| format!("{}/{n}", r.name))
        })
        .collect()
}
