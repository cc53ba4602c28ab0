//! The policy interface (an observation in, a chunk of absolute actions out, openpi style) and the
//! policy factory: evaluation asks "make the policy named X for this episode", so the scripted
//! expert, the no-motion control, replays of recorded actions and (later) network models take the
//! same path.

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
    /// Every task camera's current frame, in task order, at the size [`Policy::needs`] asks for
    /// (empty when it asks for none).
    pub images: &'a [runtime::render::Image],
    /// The same cameras `history_steps` control steps before this observation (the current
    /// frames at an episode's first query).
    pub previous: &'a [runtime::render::Image],
    /// Privileged simulator state, used only by the scripted expert and the controls; never sent
    /// to models.
    pub privileged: Privileged,
}

pub struct Privileged {
    /// Per robot, in task order: arm joint angles and current targets (its action layout).
    pub robots: Vec<RobotPrivileged>,
    pub labware: Vec<LabwareState>,
    /// MuJoCo's generalized positions: the scene the expert's collision checks start from.
    pub qpos: Vec<f64>,
}

/// One robot's arm joint angles and current targets.
pub use runtime::env::RobotState as RobotPrivileged;

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
    /// IK failed at one pose of a path (1-based, of `of` after the start).
    #[error("at pose {at} of {of}: {ik}")]
    IkAt {
        at: usize,
        of: usize,
        ik: primitives::IkError,
    },
    /// A free-space motion's straight path collides and RRTConnect found no way around.
    #[error("the straight path hits {hits}, and {error}")]
    Blocked {
        hits: String,
        error: planner::PlanError,
    },
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
    /// The model server failed: no connection, closed, silent, an error frame, garbage.
    #[error("model server fault: {0}")]
    Server(crate::remote::WireError),
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

/// Replays the actions a recording of this task and seed carries, control step by control step:
/// the same seed and the same actions give the same episode, byte for byte.
pub struct ReplayPolicy {
    /// Every robot's action per control step, concatenated in task order.
    actions: Vec<Vec<f64>>,
    next: usize,
}

impl ReplayPolicy {
    /// Reads the recording at `path` (a file, or a folder holding `<task id>_seed<seed>.mcap`)
    /// and checks that it is of this task and this episode's seed.
    pub fn new(
        path: &std::path::Path,
        task: &Task,
        instance: &SceneInstance,
    ) -> Result<Self, PolicyError> {
        let file = if path.is_dir() {
            crate::eval::recording_path(path, task, instance.seed)
        } else {
            path.to_path_buf()
        };
        let failed =
            |why: String| PolicyError::Failed(format!("replay of {}: {why}", file.display()));
        let rec = runtime::record::read_recording(&file).map_err(|e| failed(e.to_string()))?;
        let id = rec.task["id"].as_str().unwrap_or_default();
        if id != task.id {
            return Err(failed(format!("it records task `{id}`, not `{}`", task.id)));
        }
        let seed = rec.instance["seed"].as_u64();
        if seed != Some(instance.seed) {
            return Err(failed(format!(
                "it records seed {}, not the episode's seed {}",
                seed.map(|s| s.to_string()).unwrap_or_else(|| "none".into()),
                instance.seed
            )));
        }
        let per_robot: Vec<&Vec<Vec<f64>>> = task
            .robots
            .iter()
            .map(|r| {
                rec.actions
                    .get(&r.name)
                    .ok_or_else(|| failed(format!("it has no actions of robot `{}`", r.name)))
            })
            .collect::<Result<_, _>>()?;
        let steps = per_robot.iter().map(|a| a.len()).min().unwrap_or(0);
        let actions = (0..steps)
            .map(|k| {
                per_robot
                    .iter()
                    .flat_map(|a| a[k].iter().copied())
                    .collect()
            })
            .collect();
        Ok(ReplayPolicy { actions, next: 0 })
    }
}

impl Policy for ReplayPolicy {
    fn name(&self) -> String {
        "replay".into()
    }

    fn act(&mut self, _obs: &Observation) -> Result<Vec<Vec<f64>>, PolicyError> {
        if self.next >= self.actions.len() {
            return Err(PolicyError::Failed(format!(
                "the recording's {} actions are used up and the episode goes on",
                self.actions.len()
            )));
        }
        // The rest at once: the episode loop stops after any action that ends the episode.
        let chunk = self.actions[self.next..].to_vec();
        self.next = self.actions.len();
        Ok(chunk)
    }
}

/// The policies `make` knows by name (`replay:` takes a recording or a folder of them).
pub const POLICIES: &[&str] = &["expert", "hold", "replay:<recording or folder>"];

/// A policy named on the command line (`--policy`), parsed once.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum PolicySpec {
    /// The scripted expert.
    Expert,
    /// The no-motion control.
    Hold,
    /// The actions of a recording, or of `<task>_seed<seed>.mcap` in a folder, for the same seed.
    Replay(std::path::PathBuf),
}

impl std::str::FromStr for PolicySpec {
    type Err = PolicyError;
    fn from_str(name: &str) -> Result<PolicySpec, PolicyError> {
        match name {
            "expert" => Ok(PolicySpec::Expert),
            "hold" => Ok(PolicySpec::Hold),
            other => match other.strip_prefix("replay:") {
                Some(path) if !path.is_empty() => Ok(PolicySpec::Replay(path.into())),
                _ => Err(PolicyError::Unknown(other.to_string())),
            },
        }
    }
}

impl std::fmt::Display for PolicySpec {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            PolicySpec::Expert => f.write_str("expert"),
            PolicySpec::Hold => f.write_str("hold"),
            PolicySpec::Replay(p) => write!(f, "replay:{}", p.display()),
        }
    }
}

impl PolicySpec {
    /// Makes this policy for one episode.
    pub fn make(
        &self,
        task: &Task,
        scene: &Scene,
        instance: &SceneInstance,
    ) -> Result<Box<dyn Policy>, PolicyError> {
        Ok(match self {
            PolicySpec::Expert => {
                Box::new(crate::expert::ExpertPolicy::new(task, scene, instance)?)
            }
            PolicySpec::Hold => Box::new(HoldPolicy),
            PolicySpec::Replay(path) => Box::new(ReplayPolicy::new(path, task, instance)?),
        })
    }
}

/// Whether `make` knows the policy `name` (it may still fail for one episode, e.g. a replay
/// without a recording of that seed).
pub fn known(name: &str) -> bool {
    name.parse::<PolicySpec>().is_ok()
}

/// Makes the policy named `name` for one episode.
pub fn make(
    name: &str,
    task: &Task,
    scene: &Scene,
    instance: &SceneInstance,
) -> Result<Box<dyn Policy>, PolicyError> {
    name.parse::<PolicySpec>()?.make(task, scene, instance)
}
