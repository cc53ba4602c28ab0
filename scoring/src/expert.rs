//! The scripted expert: expands the task's plan into motions, resolves each against live labware
//! state when it starts, solves IK for its waypoints and follows the TOPP-timed trajectory.

use crate::policy::{Observation, Policy, PolicyError, StageEvent};
use compiler::{LabwareParams, PlannedStep, SceneInstance, Task};
use labware::Pose;
use primitives::topp::{Limits, Trajectory, plan_trajectory};
use primitives::{GripContext, Kinematics, Motion, expand, solve_ik};
use runtime::Scene;
use runtime::kinematics::ArmKinematics;
use std::collections::VecDeque;

/// Joint velocity and acceleration limits of the expert (as the upstream thermal-cycler expert).
pub const EXPERT_LIMITS: Limits = Limits {
    vmax: 1.5,
    amax: 1.0,
};
const SETTLE_S: f64 = 0.2;

struct Queued {
    /// Index into the flattened plan, and the stage the step belongs to.
    step: usize,
    stage: usize,
    motion: Motion,
}

enum Active {
    Path { traj: Trajectory, t0: f64 },
    Hold { until: f64 },
}

pub struct ExpertPolicy {
    task: Task,
    /// Every stage's steps in order, with the labware each acts on.
    plan: Vec<(PlannedStep, usize)>,
    placements: Vec<Pose>,
    kin: ArmKinematics,
    queue: VecDeque<Queued>,
    active: Option<Active>,
    context: Option<(usize, GripContext)>,
    target: Option<Vec<f64>>,
    gripper: f64,
    control_dt: f64,
    events: Vec<StageEvent>,
}

impl ExpertPolicy {
    pub fn new(
        task: &Task,
        scene: &Scene,
        instance: &SceneInstance,
    ) -> Result<ExpertPolicy, PolicyError> {
        let mut queue = VecDeque::new();
        let mut plan = Vec::new();
        for (i, (stage, step)) in task.steps().enumerate() {
            let no_expert = || {
                PolicyError::Planning(format!(
                    "the expert has no motions for `{}` on this labware yet",
                    step.primitive
                ))
            };
            let li = step
                .labware
                .as_deref()
                .and_then(|l| task.labware_index(l))
                .ok_or_else(no_expert)?;
            let LabwareParams::ThermalCycler(p) = &task.labware[li].params else {
                return Err(no_expert());
            };
            let motions = expand(&step.primitive, p).ok_or_else(no_expert)?;
            queue.extend(motions.into_iter().map(|motion| Queued {
                step: i,
                stage,
                motion,
            }));
            plan.push((step.clone(), li));
        }
        Ok(ExpertPolicy {
            task: task.clone(),
            plan,
            placements: instance.labware_placement.clone(),
            kin: ArmKinematics::new(scene, 0),
            queue,
            active: None,
            context: None,
            target: None,
            gripper: 0.0,
            control_dt: 1.0 / task.physics.control_hz(),
            events: Vec::new(),
        })
    }

    fn start(&mut self, q: Queued, obs: &Observation) -> Result<Active, PolicyError> {
        let (step, li) = &self.plan[q.step];
        let li = *li;
        let live = &obs.privileged.labware[li];
        let live = (live.joints["lid"], live.joints["lever"]);
        let target = self.target.clone().expect("set before start");
        let tcp_now = self.kin.tcp(&target);
        if self.context.as_ref().map(|(s, _)| *s) != Some(q.step) {
            let LabwareParams::ThermalCycler(p) = &self.task.labware[li].params else {
                return Err(PolicyError::Planning("checked in new".into()));
            };
            let (lid, lever) = match q.motion {
                Motion::Approach { lid, lever, .. } => (lid, lever),
                _ => live,
            };
            self.context = Some((
                q.step,
                GripContext::new(p.clone(), self.placements[li], lid, lever, &tcp_now),
            ));
            self.events.push(StageEvent {
                time: obs.time,
                label: format!(
                    "step {}: {} {}",
                    q.step,
                    step.primitive,
                    step.labware.as_deref().unwrap_or("")
                ),
            });
        }
        self.events.push(StageEvent {
            time: obs.time,
            label: q.motion.label().to_string(),
        });
        let cx = &self.context.as_ref().expect("set above").1;
        if let Motion::Gripper { ctrl, duration_s } = q.motion {
            self.gripper = ctrl;
            return Ok(Active::Hold {
                until: obs.time + duration_s,
            });
        }
        let poses = cx.poses(&q.motion, &tcp_now, live);
        let mut waypoints = vec![target.clone()];
        let mut seed = target;
        for pose in poses.iter().skip(1) {
            let qn = solve_ik(&mut self.kin, pose, &seed, &Default::default())
                .map_err(|e| PolicyError::Planning(format!("{}: {e}", q.motion.label())))?;
            waypoints.push(qn.clone());
            seed = qn;
        }
        let traj = plan_trajectory(waypoints, &EXPERT_LIMITS, 200);
        Ok(Active::Path { traj, t0: obs.time })
    }

    fn action(&self) -> Vec<f64> {
        let mut a = self.target.clone().expect("set in act");
        a.push(self.gripper);
        a
    }
}

impl Policy for ExpertPolicy {
    fn name(&self) -> String {
        "expert".into()
    }

    fn act(&mut self, obs: &Observation) -> Result<Vec<Vec<f64>>, PolicyError> {
        if self.target.is_none() {
            self.target = Some(obs.privileged.arm_q.clone());
            self.gripper = obs.privileged.ctrl.last().copied().unwrap_or(0.0);
        }
        let next_t = obs.time + self.control_dt;
        loop {
            match &self.active {
                // A later stage's steps wait until the judge has moved on to that stage.
                None => match self.queue.front() {
                    Some(q) if q.stage <= obs.stage => {
                        let q = self.queue.pop_front().expect("front exists");
                        self.active = Some(self.start(q, obs)?);
                    }
                    _ => return Ok(vec![self.action()]),
                },
                Some(Active::Hold { until }) => {
                    if obs.time + 1e-9 >= *until {
                        self.active = None;
                        continue;
                    }
                    return Ok(vec![self.action()]);
                }
                Some(Active::Path { traj, t0 }) => {
                    let t = next_t - t0;
                    if t > traj.duration() + SETTLE_S {
                        self.target = Some(traj.end());
                        self.active = None;
                        continue;
                    }
                    self.target = Some(traj.sample(t));
                    return Ok(vec![self.action()]);
                }
            }
        }
    }

    fn drain_events(&mut self) -> Vec<StageEvent> {
        std::mem::take(&mut self.events)
    }
}
