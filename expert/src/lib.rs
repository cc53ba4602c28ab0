//! The scripted expert: each planned step goes to the robot its `with` names, expands into the
//! motions its primitive declares (`compiler::primitives`), and each motion is resolved against
//! live labware state when it starts (`primitives::Lab`), solved by the IK method the robot's
//! model chooses and followed along a TOPP-timed trajectory under the model's limits
//! ([`motion`]).
//!
//! One motion lane per robot ([`Lane`]): steps run in plan order, one group at a time, and a
//! group is a step with the steps after it marked `together` (on other robots), whose lanes move
//! in the same control steps. A group starts when the one before it has finished and the judge
//! has reached its stage. The robots with nothing to do hold their targets.
//!
//! The crate also holds the reach pass `autobio check` runs before any episode ([`reach`]) and
//! the routing of free-space paths around obstacles ([`route`], RRTConnect from `planner`). The
//! alternatives a step may take where its first choice is blocked are enumerated once, in
//! `primitives::alternatives`, and both the expert and the reach pass iterate them. It does not
//! run episodes or score them (`scoring` does). Its tests are the workspace's
//! (tests/expert_episodes.rs, tests/planning.rs, tests/reach.rs and every task's episodes).

mod motion;
pub mod reach;
pub mod route;

use compiler::motion::Motion;
use compiler::params::Bindings;
use compiler::primitives::Expanded;
use compiler::{SceneInstance, Task};
use motion::{Active, Arm};
use policy::{Observation, Policy, PolicyError, StageEvent};
use primitives::Kinematics;
use primitives::{Lab, StepFrame};
use runtime::Scene;
use runtime::clearance::Clearance;
use runtime::kinematics::ArmKinematics;
use std::collections::{BTreeMap, VecDeque};

/// Pause after each path so the arm settles on its last waypoint (s).
const SETTLE_S: f64 = 0.2;

/// How fast a press closes the hand's actuated finger: this share of its range per second (a
/// thumb's 0.68 rad in 6.7 s, about 0.1 rad/s: a pipette's plunger reaches its first stop in
/// about 3 s and the press stops within a control step of it).
const PRESS_RATE: f64 = 0.15;

/// A pressed joint has reached its goal when what is left of its way there is at most this share
/// of the way (a plunger 0.2 mm short of its first stop).
const PRESS_SHORT: f64 = 0.03;

/// How long after its step's last motion an instrument's run may take to start (s): the latch
/// catching a lid that settles shut, a key's press counted. Past it, with the arm still, the run
/// never will, and the expert gives the step up at once rather than wait out the task's time
/// limit (a failed spin would otherwise hold the arm still for minutes of simulated time).
const RUN_START_GRACE_S: f64 = 2.0;

struct Queued {
    /// Index into the plan, the group it runs in, and the stage it belongs to.
    step: usize,
    group: usize,
    stage: usize,
    motion: Motion,
    /// How many times the tool has been brought over the narrow opening this motion goes into
    /// (`motion::aim_over`): 0 before the first, and for every other motion.
    aims: u8,
}

/// One planned step, routed and expanded.
struct Step {
    /// The `on` item, rendered (what a `place` carries).
    on: Option<String>,
    label: String,
    motions: Vec<Motion>,
}

/// One robot's motions: what is queued for it, what it does now, and the frame of the step it is
/// in (how it holds what it carries).
#[derive(Default)]
struct Lane {
    queue: VecDeque<Queued>,
    active: Option<(usize, Active)>,
    frame: Option<(usize, StepFrame)>,
    /// Whether the current step has moved along a path yet (its grasp is then committed).
    step_moved: bool,
    /// Grips the current step has taken on a dial.
    dial_grips: usize,
}

impl Lane {
    /// The group of the motion running or next, if any.
    fn group(&self) -> Option<usize> {
        self.active
            .as_ref()
            .map(|(g, _)| *g)
            .or_else(|| self.queue.front().map(|q| q.group))
    }
}

pub struct ExpertPolicy {
    task: Task,
    params: Bindings,
    steps: Vec<Step>,
    arms: Vec<Arm>,
    lanes: Vec<Lane>,
    started: bool,
    control_dt: f64,
    events: Vec<StageEvent>,
    /// The episode's seed, and the free-space motions routed so far: each route's planner seed.
    seed: u64,
    routed: u64,
    /// Per item that runs, the runs it had started when the expert last finished waiting for
    /// one (or when the episode began): a wait for a run is over only once a newer one started.
    runs_awaited: BTreeMap<String, f64>,
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
        ik: primitives::ik::IkError,
    },
    /// An instrument's run did not start when its step had done what starts it (a key not
    /// counted as pressed, a lid not latched).
    #[error("`{labware}`'s run had not started {waited_s} s after its step")]
    RunNotStarted { labware: String, waited_s: f64 },
    /// A free-space motion's straight path collides and RRTConnect found no way around.
    #[error("the straight path hits {hits}, and {error}")]
    Blocked {
        hits: String,
        error: planner::PlanError,
    },
}

fn planning(context: String, failure: impl Into<PlanFailure>) -> PolicyError {
    PolicyError::Planning {
        context,
        failure: std::sync::Arc::new(failure.into()),
    }
}

impl ExpertPolicy {
    pub fn new(
        task: &Task,
        scene: &Scene,
        instance: &SceneInstance,
    ) -> Result<ExpertPolicy, PolicyError> {
        let mut lanes: Vec<Lane> = scene.robots.iter().map(|_| Lane::default()).collect();
        let mut steps = Vec::new();
        let mut group = 0;
        for (i, (stage, step)) in task.steps().enumerate() {
            // Steps are numbered from 1, as `describe` and the protocol's reader count them.
            let context = || format!("step {} `{}`", i + 1, step.primitive);
            let robot = task
                .robot_index(&step.robot)
                .ok_or_else(|| planning(context(), PlanFailure::NoRobot(step.robot.clone())))?;
            let Expanded { args, motions } = Expanded::of(task, i, step, &instance.params)
                .ok_or_else(|| {
                    planning(context(), PlanFailure::NoMotions(step.primitive.clone()))
                })?;
            if i > 0 && !step.together {
                group += 1;
            }
            lanes[robot]
                .queue
                .extend(motions.iter().map(|motion| Queued {
                    step: i,
                    group,
                    stage,
                    motion: motion.clone(),
                    aims: 0,
                }));
            steps.push(Step {
                on: args.get("on").cloned(),
                label: format!(
                    "step {}: {} {} with {}",
                    i + 1,
                    step.primitive,
                    args.get("on").map(String::as_str).unwrap_or(""),
                    step.robot
                ),
                motions,
            });
        }
        let arms = scene
            .robots
            .iter()
            .enumerate()
            .map(|(r, ids)| Arm {
                model: ids.model,
                kin: ArmKinematics::new(scene, r),
                clearance: Clearance::new(scene, r),
                target: instance.robot_q[r].clone(),
                gripper: ids.model.gripper.open,
                start: instance.robot_q[r].clone(),
            })
            .collect();
        Ok(ExpertPolicy {
            task: task.clone(),
            params: instance.params.clone(),
            steps,
            arms,
            lanes,
            started: false,
            control_dt: 1.0 / task.physics.control_hz(),
            events: Vec::new(),
            seed: instance.seed,
            routed: 0,
            runs_awaited: BTreeMap::new(),
        })
    }

    /// Every robot's targets, concatenated.
    fn action(&self) -> Vec<f64> {
        self.arms
            .iter()
            .flat_map(|a| a.target.iter().copied().chain([a.gripper]))
            .collect()
    }

    /// The group now running: the earliest group any lane still has.
    fn current_group(&self) -> Option<usize> {
        self.lanes.iter().filter_map(Lane::group).min()
    }

    /// Moves lane `r` on as far as it can this control step: ends finished motions and starts
    /// the next of the current group while the judge's stage allows. Whether anything changed.
    fn advance(&mut self, r: usize, obs: &Observation) -> Result<bool, PolicyError> {
        let next_t = obs.time + self.control_dt;
        let mut changed = false;
        loop {
            let group = self.current_group();
            let lane = &mut self.lanes[r];
            match &lane.active {
                // A later stage's steps wait until the judge has moved on to that stage.
                None => match lane.queue.front() {
                    Some(q) if Some(q.group) == group && q.stage <= obs.stage => {
                        let q = lane.queue.pop_front().expect("front exists");
                        let g = q.group;
                        let active = self.start(r, q, obs)?;
                        self.lanes[r].active = Some((g, active));
                        changed = true;
                    }
                    _ => return Ok(changed),
                },
                Some((_, active)) => {
                    let done = match active {
                        Active::Hold { until } => obs.time + 1e-9 >= *until,
                        Active::Press {
                            labware,
                            joints,
                            deadline,
                        } => {
                            let lab = Lab::new(&self.task, &obs.privileged.labware, &self.params);
                            let reached = lab.item(labware).is_ok_and(|(_, live)| {
                                joints.iter().all(|(role, start, goal)| {
                                    let left = (goal - live.joint(role)) * (goal - start).signum();
                                    left <= PRESS_SHORT * (goal - start).abs()
                                })
                            });
                            if reached || obs.time >= *deadline {
                                true
                            } else {
                                let arm = &mut self.arms[r];
                                let g = arm.model.gripper;
                                let step = PRESS_RATE * (g.closed - g.open) * self.control_dt;
                                arm.gripper = g.clamp(arm.gripper + step);
                                false
                            }
                        }
                        Active::Ease { from, t0, seconds } => {
                            let t = ((next_t - t0) / seconds).clamp(0.0, 1.0);
                            let arm = &mut self.arms[r];
                            arm.gripper = from + (arm.model.gripper.open - from) * t;
                            t >= 1.0
                        }
                        Active::Run {
                            labware,
                            deadline,
                            since,
                            context,
                        } => {
                            let lab = Lab::new(&self.task, &obs.privileged.labware, &self.params);
                            let started = lab.runs_started(labware);
                            let awaited = self.runs_awaited.get(labware).copied().unwrap_or(0.0);
                            if started <= awaited {
                                if obs.time >= since + RUN_START_GRACE_S {
                                    return Err(planning(
                                        context.clone(),
                                        PlanFailure::RunNotStarted {
                                            labware: labware.clone(),
                                            waited_s: RUN_START_GRACE_S,
                                        },
                                    ));
                                }
                                false
                            } else if lab.run_done(labware) || obs.time >= *deadline {
                                self.runs_awaited.insert(labware.clone(), started);
                                true
                            } else {
                                false
                            }
                        }
                        Active::Until {
                            labware,
                            param,
                            value,
                            deadline,
                        } => {
                            let lab = Lab::new(&self.task, &obs.privileged.labware, &self.params);
                            let shows = lab
                                .panel(labware, param, value)
                                .is_some_and(|(shown, target)| (shown - target).abs() < 1e-9);
                            shows || obs.time >= *deadline
                        }
                        Active::Path { traj, t0 } => {
                            let t = next_t - t0;
                            if t > traj.duration() + SETTLE_S {
                                self.arms[r].target = traj.end();
                                true
                            } else {
                                // A spline through waypoints at a joint's limit can overshoot it
                                // between them: the command stays inside the limits (each joint's
                                // range narrowed to its servo's command range, `ArmKinematics`).
                                let limits = self.arms[r].kin.limits();
                                self.arms[r].target = traj
                                    .sample(t)
                                    .iter()
                                    .zip(limits)
                                    .map(|(q, (lo, hi))| q.clamp(lo, hi))
                                    .collect();
                                false
                            }
                        }
                    };
                    if !done {
                        return Ok(changed);
                    }
                    self.lanes[r].active = None;
                    changed = true;
                }
            }
        }
    }
}

impl Policy for ExpertPolicy {
    fn name(&self) -> String {
        "expert".into()
    }

    fn act(&mut self, obs: &Observation) -> Result<Vec<Vec<f64>>, PolicyError> {
        if !self.started {
            for (arm, live) in self.arms.iter_mut().zip(&obs.privileged.robots) {
                arm.target = live.arm_q.clone();
                arm.gripper = live.ctrl.last().copied().unwrap_or(arm.model.gripper.open);
            }
            self.started = true;
            let lab = Lab::new(&self.task, &obs.privileged.labware, &self.params);
            for item in &obs.privileged.labware {
                let runs = lab.runs_started(&item.name);
                self.runs_awaited.insert(item.name.clone(), runs);
            }
        }
        // Until no lane moves on: a lane that finishes its group's last motion lets the next
        // group start in this same control step, whichever robot it is on.
        loop {
            let mut changed = false;
            for r in 0..self.lanes.len() {
                changed |= self.advance(r, obs)?;
            }
            if !changed {
                return Ok(vec![self.action()]);
            }
        }
    }

    fn drain_events(&mut self) -> Vec<StageEvent> {
        std::mem::take(&mut self.events)
    }
}
