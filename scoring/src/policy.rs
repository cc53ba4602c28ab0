//! The policy interface (an observation in, a chunk of absolute actions out, openpi style) and the
//! policy factory: evaluation asks "make the policy named X for this episode", so the scripted
//! expert, the no-motion control and (later) replays and network models take the same path.

use compiler::{SceneInstance, Task};
use runtime::{LabwareState, Scene};
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
    /// Privileged simulator state, used only by the scripted expert and the controls; never sent
    /// to models.
    pub privileged: Privileged,
}

pub struct Privileged {
    /// Per robot, in task order: arm joint angles and current targets (its action layout).
    pub robots: Vec<RobotPrivileged>,
    pub labware: Vec<LabwareState>,
}

pub struct RobotPrivileged {
    pub arm_q: Vec<f64>,
    pub ctrl: Vec<f64>,
}

impl Privileged {
    /// Every robot's current targets, concatenated: the action that changes nothing.
    pub fn ctrl(&self) -> Vec<f64> {
        self.robots.iter().flat_map(|r| r.ctrl.clone()).collect()
    }
}

/// Why the expert cannot plan.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PlanFailure {
    #[error("no robot named `{0}`")]
    NoRobot(String),
    #[error("the expert has no motions for `{0}` yet")]
    NoMotions(String),
    #[error(transparent)]
    Resolve(#[from] primitives::PlanError),
    #[error(transparent)]
    Ik(#[from] primitives::IkError),
}

/// A labelled moment of an episode (start of a motion, of a lab step).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StageEvent {
    pub time: f64,
    pub label: String,
}

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PolicyError {
    /// The scripted expert cannot plan a step (`context` names the step and motion).
    #[error("the expert cannot plan {context}: {failure}")]
    Planning {
        context: String,
        failure: PlanFailure,
    },
    #[error("unknown policy `{0}`; known policies: {known}", known = POLICIES.join(", "))]
    Unknown(String),
    /// The policy could not produce actions (a model's own error, reported by it).
    #[error("the policy failed: {0}")]
    Failed(String),
}

pub trait Policy {
    fn name(&self) -> String;
    /// A chunk of actions (each: every robot's action, concatenated), executed in order.
    fn act(&mut self, obs: &Observation) -> Result<Vec<Vec<f64>>, PolicyError>;
    /// Stage events produced since the last call.
    fn drain_events(&mut self) -> Vec<StageEvent> {
        Vec::new()
    }
}

/// The no-motion control: holds every robot where its targets are. Every simulated task must
/// score 0 under it; a task a motionless robot passes is broken.
pub struct HoldPolicy;

impl Policy for HoldPolicy {
    fn name(&self) -> String {
        "hold".into()
    }

    fn act(&mut self, obs: &Observation) -> Result<Vec<Vec<f64>>, PolicyError> {
        Ok(vec![obs.privileged.ctrl()])
    }
}

/// The policies `make` knows by name.
pub const POLICIES: &[&str] = &["expert", "hold"];

/// Makes the policy named `name` for one episode.
pub fn make(
    name: &str,
    task: &Task,
    scene: &Scene,
    instance: &SceneInstance,
) -> Result<Box<dyn Policy>, PolicyError> {
    match name {
        "expert" => Ok(Box::new(crate::expert::ExpertPolicy::new(
            task, scene, instance,
        )?)),
        "hold" => Ok(Box::new(HoldPolicy)),
        other => Err(PolicyError::Unknown(other.to_string())),
    }
}
