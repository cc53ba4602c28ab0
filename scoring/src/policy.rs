//! The policy interface: an observation in, a chunk of absolute actions out (openpi style).

use runtime::LabwareState;
use serde::{Deserialize, Serialize};

/// What a policy sees at one control step.
pub struct Observation<'a> {
    pub time: f64,
    /// Robot state: 6 arm joints (rad) then the gripper driver angle (rad).
    pub state: Vec<f64>,
    /// The stage now running (0 for single-stage tasks) and its instruction.
    pub stage: usize,
    pub prompt: &'a str,
    /// Privileged simulator state, used only by the scripted expert; never sent to models.
    pub privileged: Privileged,
}

pub struct Privileged {
    pub arm_q: Vec<f64>,
    pub ctrl: Vec<f64>,
    pub labware: Vec<LabwareState>,
}

/// A labelled moment of an episode (start of a motion, of a lab step).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StageEvent {
    pub time: f64,
    pub label: String,
}

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PolicyError {
    #[error("the expert cannot plan: {0}")]
    Planning(String),
}

pub trait Policy {
    fn name(&self) -> String;
    /// A chunk of actions (each: 6 joint targets then the gripper command), executed in order.
    fn act(&mut self, obs: &Observation) -> Result<Vec<Vec<f64>>, PolicyError>;
    /// Stage events produced since the last call.
    fn drain_events(&mut self) -> Vec<StageEvent> {
        Vec::new()
    }
}

/// The do-nothing baseline: holds the robot where it is (the lower bound on any leaderboard).
pub struct HoldPolicy;

impl Policy for HoldPolicy {
    fn name(&self) -> String {
        "hold".into()
    }

    fn act(&mut self, obs: &Observation) -> Result<Vec<Vec<f64>>, PolicyError> {
        Ok(vec![obs.privileged.ctrl.clone()])
    }
}
