//! The policy interface: an observation in, a chunk of absolute actions out (openpi style), what
//! a policy needs rendered, and how it fails (a model server's faults as [`WireError`]).
//!
//! It holds no policy: the scripted expert is the `expert` crate, the no-motion control, replays
//! and models over the network are `scoring`'s, and `scoring::policies` makes one by name. Its
//! types are exercised through those crates' tests (tests/episode_failures.rs,
//! tests/model_servers.rs).

use labware::LabwareState;
use runtime::RobotState;
use serde::{Deserialize, Serialize};

/// What a policy sees at one control step.
pub struct Observation<'a> {
    pub time: f64,
    /// Every robot's state, concatenated in task order (each: arm joints (rad), then the gripper
    /// driver angle (rad); layouts from the robot models).
    pub state: Vec<f64>,
    /// The stage now running (0 for single-stage tasks) and its instruction.
    pub stage: usize,
    pub prompt: &'a str,
    /// Every task camera's current frame, in task order, at the size [`Policy::needs`] asks for
    /// (empty when it asks for none).
    pub images: &'a [results::Image],
    /// The same cameras `history_steps` control steps before this observation (the current
    /// frames at an episode's first query).
    pub previous: &'a [results::Image],
    /// The task's environment state (`results::environment_state`), when [`Needs`] asks for
    /// it; empty otherwise. Privileged: a model that reads it is a state-based model.
    pub environment_state: Vec<f64>,
    /// Privileged simulator state, used only by the scripted expert and the controls; never sent
    /// to models.
    pub privileged: Privileged,
}

pub struct Privileged {
    /// Per robot, in task order: arm joint angles and current targets (its action layout).
    pub robots: Vec<RobotState>,
    pub labware: Vec<LabwareState>,
    /// MuJoCo's generalized positions: the scene the expert's collision checks start from.
    pub qpos: Vec<f64>,
}

impl Privileged {
    /// Every robot's current targets, concatenated: the action that changes nothing.
    pub fn ctrl(&self) -> Vec<f64> {
        self.robots.iter().flat_map(|r| r.ctrl.clone()).collect()
    }
}

/// A labelled moment of an episode (start of a motion, of a lab step).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StageEvent {
    pub time: f64,
    pub label: String,
}

#[derive(Debug, Clone, thiserror::Error)]
pub enum PolicyError {
    /// The scripted expert cannot plan a step (`context` names the step and motion; the
    /// expert's own failure type, `expert::PlanFailure`, is the source).
    #[error("the expert cannot plan {context}: {failure}")]
    Planning {
        context: String,
        failure: std::sync::Arc<dyn std::error::Error + Send + Sync>,
    },
    /// A name the factory does not know, with the names it does.
    #[error("unknown policy `{name}`; known policies: {known}")]
    Unknown { name: String, known: String },
    /// The policy could not produce actions (a model's own error, reported by it).
    #[error("the policy failed: {0}")]
    Failed(String),
    /// The model server failed: no connection, closed, silent, an error frame, garbage.
    #[error("model server fault: {0}")]
    Server(WireError),
    /// The model answered, but not with actions this task can run.
    #[error("the model's actions are unusable: {0}")]
    BadActions(String),
}

/// What a policy needs the episode loop to render for it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Needs {
    /// Render every task camera at this size (width, height) before each query.
    pub image_size: Option<[usize; 2]>,
    /// Also keep the frames from this many control steps before each query.
    pub history_steps: u32,
    /// Also read the task's environment state before each query ([`Observation::environment_state`]).
    pub environment_state: bool,
}

pub trait Policy {
    fn name(&self) -> String;
    /// A chunk of actions (each: every robot's action, concatenated), executed in order.
    fn act(&mut self, obs: &Observation) -> Result<Vec<Vec<f64>>, PolicyError>;
    /// What the episode loop must render for this policy.
    fn needs(&self) -> Needs {
        Needs::default()
    }
    /// The episode ended (after the verdict): `success` and the control steps run.
    fn end_episode(&mut self, _success: bool, _steps: u64) {}
    /// Stage events produced since the last call.
    fn drain_events(&mut self) -> Vec<StageEvent> {
        Vec::new()
    }
    /// The policy never moves a robot (the hold control): the environment may then jump an idle
    /// scene at rest to its deadline (`runtime::clock`).
    fn never_moves(&self) -> bool {
        false
    }
}

/// How a model server failed us. Each ends the episode it happens in with its reason.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum WireError {
    #[error("bad model address `{url}`: {why}")]
    Address { url: String, why: String },
    #[error("cannot connect to {url} after {attempts} attempts over {waited_s:.1} s: {last}")]
    Connect {
        url: String,
        attempts: u32,
        waited_s: f64,
        last: String,
    },
    #[error("the server closed the connection{0}")]
    Closed(String),
    #[error("no reply within {0} s")]
    Timeout(f64),
    #[error("the server reported an error: {0}")]
    ErrorFrame(String),
    #[error("the reply is malformed: {0}")]
    Malformed(String),
}
