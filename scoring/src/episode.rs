//! The episode loop: reset, then observe -> act -> hold each action for one control period, until
//! success (checked after every control period) or the time limit. A policy failure or an unstable
//! simulation ends the episode as a failure with its reason; nothing already finished is lost.

use crate::policy::{Observation, Policy, Privileged, RobotPrivileged};
use crate::verdict::{Judge, Verdict};
use compiler::{SceneInstance, Task};
use runtime::Episode;
use runtime::record::Recorder;
use runtime::render::{Cameras, Image};
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

#[derive(Clone, Debug, Default)]
pub struct EpisodeOptions {
    /// Write an MCAP recording here.
    pub record: Option<PathBuf>,
    /// Render and record camera images every this many control steps (0 = no images).
    pub image_every: u32,
}

/// How an episode ended. Every class counts in a run's denominator.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Outcome {
    /// Every stage's checks held.
    Success,
    /// The time limit passed first.
    TimeLimit,
    /// The policy failed, sent no actions, or sent actions of the wrong shape, not finite or
    /// outside their actuators' ranges.
    PolicyError,
    /// The model server failed: refused or lost the connection, stayed silent past the
    /// timeout, reported an error, or sent frames that do not decode.
    ServerFault,
    /// The simulation became unstable.
    Unstable,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EpisodeResult {
    pub seed: u64,
    /// The run it belongs to (`--runs`; 0 otherwise).
    #[serde(default)]
    pub run: u32,
    pub success: bool,
    pub outcome: Outcome,
    pub verdict: Verdict,
    /// Why the episode ended early as a failure (policy error, unstable physics), if it did.
    pub error: Option<String>,
    pub sim_time_s: f64,
    pub control_steps: u64,
    pub wall_time_s: f64,
    /// Wall time spent inside the policy (a model's round trips included): the harness's own
    /// time is `wall_time_s` minus this.
    #[serde(default)]
    pub policy_time_s: f64,
    /// SHA-256 of every control step's qpos (little-endian f64): equal hashes, equal trajectories.
    pub trajectory_hash: String,
    pub recording: Option<String>,
}

/// The outcome class of a policy's failure.
pub fn outcome_of(e: &crate::PolicyError) -> Outcome {
    match e {
        crate::PolicyError::Server(_) => Outcome::ServerFault,
        _ => Outcome::PolicyError,
    }
}

/// The result of an episode whose policy could not be made (the expert cannot plan it, a replay
/// has no recording of its seed, the model server cannot be reached): judged on the initial
/// state, with its reason.
pub fn policy_failed(
    task: &Task,
    scene: &Arc<runtime::Scene>,
    instance: &SceneInstance,
    failure: &crate::PolicyError,
) -> EpisodeResult {
    let ep = Episode::new(scene.clone(), task, instance);
    let initial = ep.labware_state();
    let mut judge = Judge::new(task, &instance.params, &initial);
    judge.update(ep.time(), &initial);
    let mut verdict = judge.verdict();
    verdict.success = false;
    EpisodeResult {
        seed: instance.seed,
        run: 0,
        success: false,
        outcome: outcome_of(failure),
        verdict,
        error: Some(failure.to_string()),
        sim_time_s: 0.0,
        control_steps: 0,
        wall_time_s: 0.0,
        policy_time_s: 0.0,
        trajectory_hash: Sha256::new()
            .finalize()
            .iter()
            .map(|b| format!("{b:02x}"))
            .collect(),
        recording: None,
    }
}

/// Receives every control step of an episode (datasets): the observation's state before the
/// action, the action, and every task camera's frame at the sink's size.
pub trait StepSink {
    /// Render every camera at this size (width, height) each control step.
    fn image_size(&self) -> Option<[usize; 2]>;
    /// One control step; an error ends the episode as a failure.
    fn step(&mut self, state: &[f64], action: &[f64], images: &[Image]) -> Result<(), String>;
}

/// Runs one episode of `task` with the scene instance for `seed`.
pub fn run_episode(
    task: &Task,
    scene: &Arc<runtime::Scene>,
    instance: &SceneInstance,
    policy: &mut dyn Policy,
    opts: &EpisodeOptions,
) -> Result<EpisodeResult, String> {
    run_episode_with(task, scene, instance, policy, opts, None)
}

/// [`run_episode`], also feeding every control step to `sink`.
pub fn run_episode_with(
    task: &Task,
    scene: &Arc<runtime::Scene>,
    instance: &SceneInstance,
    policy: &mut dyn Policy,
    opts: &EpisodeOptions,
    mut sink: Option<&mut dyn StepSink>,
) -> Result<EpisodeResult, String> {
    let start = Instant::now();
    let mut ep = Episode::new(scene.clone(), task, instance);
    let mut rec = match &opts.record {
        Some(p) => {
            let mut r = Recorder::create(p).map_err(|e| format!("{}: {e}", p.display()))?;
            let tj = serde_json::to_value(task).map_err(|e| e.to_string())?;
            let ij = serde_json::to_value(instance).map_err(|e| e.to_string())?;
            r.task(&tj, &ij).map_err(|e| e.to_string())?;
            Some(r)
        }
        None => None,
    };
    let mut cameras = if rec.is_some() && opts.image_every > 0 {
        Some(Cameras::new(scene, 224, 224)?)
    } else {
        None
    };
    let cam_names: Vec<String> = task.cameras.iter().map(|c| c.name.clone()).collect();
    let needs = policy.needs();
    let mut eyes = match needs.image_size {
        Some([w, h]) => Some(Cameras::new(scene, w, h)?),
        None => None,
    };
    let mut previous: Option<Vec<runtime::render::Image>> = None;
    let mut sink_eyes = match sink.as_ref().and_then(|s| s.image_size()) {
        Some([w, h]) => Some(Cameras::new(scene, w, h)?),
        None => None,
    };
    let mut policy_time = 0.0;
    let mut hasher = Sha256::new();
    let mut steps = 0u64;
    let mut error = None;
    let mut outcome = None;
    let initial = ep.labware_state();
    let mut judge = Judge::new(task, &instance.params, &initial);
    let robots = ep.scene.robots.clone();
    let mut over = judge.update(ep.time(), &initial);
    'episode: while !over && ep.time() < task.time_limit_s {
        let stage = judge.stage();
        let images = match eyes.as_mut() {
            Some(c) => c.render(&ep.data, ep.logic(), &cam_names)?,
            None => Vec::new(),
        };
        let before = previous.take().unwrap_or_else(|| images.clone());
        let obs = Observation {
            images: &images,
            previous: &before,
            time: ep.time(),
            state: ep.state(),
            stage,
            prompt: instance
                .stage_instructions
                .get(stage)
                .map(String::as_str)
                .unwrap_or(&instance.instruction),
            privileged: Privileged {
                robots: (0..robots.len())
                    .map(|r| RobotPrivileged {
                        arm_q: ep.arm_q(r),
                        ctrl: ep.robot_ctrl(r),
                    })
                    .collect(),
                labware: ep.labware_state(),
                qpos: ep.qpos(),
            },
        };
        let asked = Instant::now();
        let answer = policy.act(&obs);
        policy_time += asked.elapsed().as_secs_f64();
        let chunk = match answer {
            Ok(c) if !c.is_empty() => c,
            Ok(_) => {
                error = Some("policy returned an empty action chunk".into());
                outcome = Some(Outcome::PolicyError);
                break;
            }
            Err(e) => {
                error = Some(e.to_string());
                outcome = Some(outcome_of(&e));
                break;
            }
        };
        // The frames `history_steps` control steps before the next query.
        let history_at = (needs.history_steps > 0)
            .then(|| chunk.len().checked_sub(needs.history_steps as usize))
            .flatten();
        if history_at.is_none() && needs.history_steps > 0 {
            previous = Some(images.clone());
        }
        if let Some(r) = rec.as_mut() {
            for ev in policy.drain_events() {
                r.stage(ev.time, &ev.label).map_err(|e| e.to_string())?;
            }
        }
        for (k, action) in chunk.into_iter().enumerate() {
            if history_at == Some(k)
                && let Some(c) = eyes.as_mut()
            {
                previous = Some(c.render(&ep.data, ep.logic(), &cam_names)?);
            }
            let t = ep.time();
            if let Some(s) = sink.as_mut() {
                let frames = match sink_eyes.as_mut() {
                    Some(c) => c.render(&ep.data, ep.logic(), &cam_names)?,
                    None => Vec::new(),
                };
                if let Err(e) = s.step(&ep.state(), &action, &frames) {
                    error = Some(format!("the step sink failed: {e}"));
                    outcome = Some(Outcome::PolicyError);
                    break 'episode;
                }
            }
            if let Some(r) = rec.as_mut() {
                let mut rest = action.as_slice();
                for (k, ids) in robots.iter().enumerate() {
                    let (mine, others) = rest.split_at(ids.model.action_len().min(rest.len()));
                    rest = others;
                    r.joint_state(t, &ids.name, &ep.robot_state(k), &ep.robot_ctrl(k))
                        .map_err(|e| e.to_string())?;
                    r.action(t, &ids.name, mine).map_err(|e| e.to_string())?;
                }
                r.labware(t, &ep.labware_state())
                    .map_err(|e| e.to_string())?;
                r.physics(t, &ep.physics_state())
                    .map_err(|e| e.to_string())?;
                if let Some(c) = cameras.as_mut()
                    && steps.is_multiple_of(opts.image_every as u64)
                {
                    for img in c.render(&ep.data, ep.logic(), &cam_names)? {
                        r.image(t, &img).map_err(|e| e.to_string())?;
                    }
                }
            }
            if let Err(e) = ep.apply(&action).and_then(|_| ep.control_step()) {
                outcome = Some(match e {
                    runtime::StepError::Unstable { .. } => Outcome::Unstable,
                    runtime::StepError::BadAction { .. }
                    | runtime::StepError::NonFinite { .. }
                    | runtime::StepError::OutOfRange { .. } => Outcome::PolicyError,
                });
                error = Some(e.to_string());
                break 'episode;
            }
            steps += 1;
            for v in ep.data.qpos() {
                hasher.update(v.to_le_bytes());
            }
            over = judge.update(ep.time(), &ep.labware_state());
            if over || ep.time() >= task.time_limit_s {
                break;
            }
        }
    }
    let mut verdict = judge.verdict();
    if error.is_some() {
        verdict.success = false;
    }
    policy.end_episode(verdict.success, steps);
    let trajectory_hash: String = hasher
        .finalize()
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect();
    if let Some(mut r) = rec {
        let t = ep.time();
        r.labware(t, &ep.labware_state())
            .map_err(|e| e.to_string())?;
        r.physics(t, &ep.physics_state())
            .map_err(|e| e.to_string())?;
        r.write(
            "/verdict",
            "autobio.Verdict",
            t,
            &serde_json::json!({
                "verdict": verdict, "error": error,
                "trajectory_hash": trajectory_hash, "control_steps": steps,
            }),
        )
        .map_err(|e| e.to_string())?;
        r.finish().map_err(|e| e.to_string())?;
    }
    let outcome = outcome.unwrap_or(if verdict.success {
        Outcome::Success
    } else {
        Outcome::TimeLimit
    });
    Ok(EpisodeResult {
        seed: instance.seed,
        run: 0,
        success: verdict.success,
        outcome,
        verdict,
        error,
        sim_time_s: ep.time(),
        control_steps: steps,
        wall_time_s: start.elapsed().as_secs_f64(),
        policy_time_s: policy_time,
        trajectory_hash,
        recording: opts.record.as_ref().map(|p| p.display().to_string()),
    })
}
