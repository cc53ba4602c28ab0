//! The policies the harness knows by name, and the factory that makes one per episode: the
//! scripted expert (the `expert` crate), the no-motion control ([`HoldPolicy`]) and replays of a
//! recording's actions ([`ReplayPolicy`]). `--policy` parses into a [`PolicySpec`] once;
//! evaluation asks it to make the policy for each episode, so every policy takes the same path.
//! A model server is not made here: `--model` connects through [`crate::remote`].

use compiler::{SceneInstance, Task};
use policy::{Observation, Policy, PolicyError};
use runtime::Scene;

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

    fn never_moves(&self) -> bool {
        true
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
            results::run::recording_path(path, task, instance.seed)
        } else {
            path.to_path_buf()
        };
        let failed =
            |why: String| PolicyError::Failed(format!("replay of {}: {why}", file.display()));
        let rec = results::recording::read_recording(&file).map_err(|e| failed(e.to_string()))?;
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
                _ => Err(PolicyError::Unknown {
                    name: other.to_string(),
                    known: format!(
                        "{} (a model server is `--model ws://HOST:PORT`)",
                        POLICIES.join(", ")
                    ),
                }),
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
            PolicySpec::Expert => Box::new(expert::ExpertPolicy::new(task, scene, instance)?),
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
