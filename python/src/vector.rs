//! `autobio._core.VecEnv`: N episodes of one task stepped together, each on its own thread in
//! Rust (the GIL released while they run), for gymnasium's vector API (`autobio/vector.py`).
//!
//! Each worker thread makes and owns its environment (a MuJoCo episode and its EGL cameras stay
//! on the thread that made them) and answers one command at a time. Per slot, a batch either
//! resets (autoreset, or a first reset) or steps; replies come back in slot order. Episodes are
//! the single environment's: the same seed and actions give the same trajectory hash. Every action
//! of a batch is checked against the actuators' ranges before any slot moves, so a refused one
//! raises `ValueError` naming its slot and no episode has advanced.

use crate::env::{EnvFailure, Outcome, options, runtime_err, step};
use crate::tasks;
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};
use std::sync::Mutex;
use std::sync::mpsc::{Receiver, Sender, channel};
use std::thread::JoinHandle;

enum Command {
    Reset(u64),
    Step(Vec<f64>),
}

/// One slot's answer: the step's outcome (a reset's is all zero), then the observation.
struct Reply {
    outcome: Result<Outcome, EnvFailure>,
    state: Vec<f64>,
    environment_state: Vec<f64>,
    frames: Vec<Vec<u8>>,
    instruction: String,
    stage: usize,
    success: bool,
    score: f64,
    hash: String,
    control_steps: u64,
    seed: u64,
    /// The action components' ranges (the same for every seed of a task).
    bounds: Vec<(f64, f64)>,
}

/// Why a slot has no reply; raised as `RuntimeError` with this message.
#[derive(Debug, thiserror::Error)]
enum WorkerError {
    /// Making or resetting the environment failed.
    #[error(transparent)]
    Env(#[from] runtime::EnvError),
    #[error(transparent)]
    Render(#[from] runtime::render::RenderError),
    #[error("reset the vector environment before stepping it")]
    NotReset,
    #[error("an environment thread has stopped")]
    Stopped,
}

impl From<WorkerError> for PyErr {
    fn from(e: WorkerError) -> PyErr {
        PyRuntimeError::new_err(e.to_string())
    }
}

struct Worker {
    commands: Sender<Command>,
    replies: Mutex<Receiver<Result<Reply, WorkerError>>>,
    thread: Option<JoinHandle<()>>,
}

/// What a worker's thread runs: make the environment on the first reset, then obey.
fn serve(
    task: compiler::Task,
    opts: runtime::EnvOptions,
    images: bool,
    commands: Receiver<Command>,
    replies: Sender<Result<Reply, WorkerError>>,
) {
    let mut env: Option<runtime::Env> = None;
    let mut seed = 0;
    let layout = results::environment_state::EnvironmentState::of(&task);
    for command in commands {
        let result = (|| {
            let step = match command {
                Command::Reset(s) => {
                    seed = s;
                    match env.as_mut() {
                        Some(e) => e.reset(s).map(|_| ()),
                        None => runtime::Env::make(&task, s, opts).map(|e| env = Some(e)),
                    }?;
                    Ok((0.0, false, false, None))
                }
                Command::Step(action) => match env.as_mut() {
                    Some(e) => step(e, &action),
                    None => return Err(WorkerError::NotReset),
                },
            };
            let e = env.as_mut().expect("made by the first reset");
            let frames = if images {
                e.frames()?.iter().map(|f| f.rgb.clone()).collect()
            } else {
                Vec::new()
            };
            let verdict = e.verdict();
            Ok(Reply {
                outcome: step,
                state: e.episode().state(),
                environment_state: e.environment_state(&layout),
                frames,
                instruction: e.instruction().to_string(),
                stage: e.stage(),
                success: verdict.success,
                score: verdict.score,
                hash: e.trajectory_hash(),
                control_steps: e.control_steps(),
                seed,
                bounds: e.episode().action_bounds(),
            })
        })();
        if replies.send(result).is_err() {
            break;
        }
    }
}

/// N episodes of one task on N threads.
#[pyclass(module = "autobio._core")]
pub struct VecEnv {
    workers: Vec<Worker>,
    /// The action ranges, once a reset reported them: every action is checked against them
    /// before any slot moves.
    bounds: Option<Vec<(f64, f64)>>,
}

#[pymethods]
impl VecEnv {
    /// `task`: a shipped task id or a protocol file; `images`: draw the cameras every step.
    #[new]
    #[pyo3(signature = (task, num_envs, image_size = None, images = true))]
    fn new(
        task: &str,
        num_envs: usize,
        image_size: Option<(usize, usize)>,
        images: bool,
    ) -> PyResult<Self> {
        if num_envs == 0 {
            return Err(PyValueError::new_err("num_envs must be at least 1"));
        }
        let task = tasks::load(task).map_err(crate::load_err)?;
        let opts = options(image_size);
        let workers = (0..num_envs)
            .map(|k| {
                let (commands, inbox) = channel();
                let (outbox, replies) = channel();
                let task = task.clone();
                let thread = std::thread::Builder::new()
                    .name(format!("autobio-env-{k}"))
                    .spawn(move || serve(task, opts, images, inbox, outbox))
                    .map_err(runtime_err)?;
                Ok(Worker {
                    commands,
                    replies: Mutex::new(replies),
                    thread: Some(thread),
                })
            })
            .collect::<PyResult<Vec<_>>>()?;
        Ok(VecEnv {
            workers,
            bounds: None,
        })
    }

    #[getter]
    fn num_envs(&self) -> usize {
        self.workers.len()
    }

    /// One batch: slot k resets to `resets[k]` when that is a seed, else steps with
    /// `actions[k]`. Every slot runs at once; the replies come back in slot order, each a dict:
    /// `reward`, `terminated`, `truncated`, `error`, `state`, `environment_state`, `frames`, `instruction`, `stage`,
    /// `is_success`, `score`, `trajectory_hash`, `control_steps`, `seed`.
    fn batch<'py>(
        &mut self,
        py: Python<'py>,
        actions: Vec<Vec<f64>>,
        resets: Vec<Option<u64>>,
    ) -> PyResult<Vec<Bound<'py, PyDict>>> {
        let n = self.workers.len();
        if resets.len() != n || (actions.len() != n && !actions.is_empty()) {
            return Err(PyValueError::new_err(format!(
                "a batch needs {n} actions and {n} reset seeds, got {} and {}",
                actions.len(),
                resets.len()
            )));
        }
        for (k, (action, reset)) in actions.iter().zip(&resets).enumerate() {
            if reset.is_some() {
                continue;
            }
            let Some(bounds) = &self.bounds else {
                return Err(PyRuntimeError::new_err(
                    "reset the vector environment before stepping it",
                ));
            };
            runtime::check_action(bounds, action)
                .map_err(|e| PyValueError::new_err(format!("environment {k}: {e}")))?;
        }
        let workers = &self.workers;
        let replies = py.detach(move || {
            // Every worker that took a command is answered before anything is returned, so a
            // failure never leaves a reply queued for the next batch.
            let mut actions = actions.into_iter();
            let sent: Vec<bool> = workers
                .iter()
                .zip(resets)
                .map(|(w, reset)| {
                    let action = actions.next().unwrap_or_default();
                    let command = match reset {
                        Some(seed) => Command::Reset(seed),
                        None => Command::Step(action),
                    };
                    w.commands.send(command).is_ok()
                })
                .collect();
            let replies: Vec<Result<Reply, WorkerError>> = workers
                .iter()
                .zip(&sent)
                .map(|(w, &sent)| {
                    if !sent {
                        return Err(WorkerError::Stopped);
                    }
                    w.replies
                        .lock()
                        .map_err(|_| WorkerError::Stopped)?
                        .recv()
                        .map_err(|_| WorkerError::Stopped)?
                })
                .collect();
            replies
                .into_iter()
                .collect::<Result<Vec<Reply>, WorkerError>>()
        });
        let replies = replies?;
        if self.bounds.is_none() {
            self.bounds = replies.first().map(|r| r.bounds.clone());
        }
        replies
            .into_iter()
            .map(|r| {
                let (reward, terminated, truncated, error) = r.outcome?;
                let d = PyDict::new(py);
                d.set_item("reward", reward)?;
                d.set_item("terminated", terminated)?;
                d.set_item("truncated", truncated)?;
                d.set_item("error", error)?;
                d.set_item("state", r.state)?;
                d.set_item("environment_state", r.environment_state)?;
                let frames: Vec<Bound<'py, PyBytes>> =
                    r.frames.iter().map(|f| PyBytes::new(py, f)).collect();
                d.set_item("frames", frames)?;
                d.set_item("instruction", r.instruction)?;
                d.set_item("stage", r.stage)?;
                d.set_item("is_success", r.success)?;
                d.set_item("score", r.score)?;
                d.set_item("trajectory_hash", r.hash)?;
                d.set_item("control_steps", r.control_steps)?;
                d.set_item("seed", r.seed)?;
                Ok(d)
            })
            .collect()
    }

    /// Stops every thread (also when the object is dropped).
    fn close(&mut self) {
        for w in &mut self.workers {
            let (dead, _) = channel();
            w.commands = dead;
            if let Some(t) = w.thread.take() {
                let _ = t.join();
            }
        }
    }
}

impl Drop for VecEnv {
    fn drop(&mut self) {
        self.close();
    }
}
