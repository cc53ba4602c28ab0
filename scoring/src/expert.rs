//! The scripted expert: each planned step goes to the robot its `with` names, expands into the
//! motions its primitive declares (`compiler::primitives`), and each motion is resolved against
//! live labware state when it starts (`primitives::resolve`), solved by IK for that robot and
//! followed along a TOPP-timed trajectory. Steps run one after another; the robots not moving hold.
//! Gripper values, settle times and speed limits come from each robot's model.

use crate::policy::{Observation, PlanFailure, Policy, PolicyError, StageEvent};
use crate::route::{Route, route};
use compiler::motion::{Motion, MotionStep};
use compiler::params::{Bindings, render};
use compiler::{SceneInstance, Task};
use primitives::topp::{Limits, Trajectory, plan_trajectory};
use primitives::{Kinematics, Lab, StepFrame, solve_ik};
use robots::{IkMethod, RobotModel};
use runtime::Scene;
use runtime::clearance::Clearance;
use runtime::kinematics::ArmKinematics;
use std::collections::{BTreeMap, VecDeque};

/// Pause after each path so the arm settles on its last waypoint (s).
const SETTLE_S: f64 = 0.2;

struct Queued {
    /// Index into the plan, and the stage the step belongs to.
    step: usize,
    stage: usize,
    motion: Motion,
}

/// One planned step, routed and expanded.
struct Step {
    robot: usize,
    /// The `on` item, rendered (what a `place` carries).
    on: Option<String>,
    label: String,
    motions: Vec<Motion>,
}

enum Active {
    Path {
        traj: Trajectory,
        t0: f64,
    },
    Hold {
        until: f64,
    },
    /// Still until a panel shows a value (or the deadline passes: the judge tells what came of it).
    Until {
        labware: String,
        param: String,
        value: String,
        deadline: f64,
    },
}

struct Arm {
    model: &'static RobotModel,
    kin: ArmKinematics,
    clearance: Clearance,
    target: Vec<f64>,
    gripper: f64,
}

pub struct ExpertPolicy {
    task: Task,
    params: Bindings,
    steps: Vec<Step>,
    arms: Vec<Arm>,
    started: bool,
    queue: VecDeque<Queued>,
    active: Option<Active>,
    frame: Option<(usize, StepFrame)>,
    /// Whether the current step has moved along a path yet (its grasp is then committed).
    step_moved: bool,
    control_dt: f64,
    events: Vec<StageEvent>,
    /// The episode's seed, and the free-space motions routed so far: each route's planner seed.
    seed: u64,
    routed: u64,
}

fn planning(context: String, failure: impl Into<PlanFailure>) -> PolicyError {
    PolicyError::Planning {
        context,
        failure: failure.into(),
    }
}

impl ExpertPolicy {
    pub fn new(
        task: &Task,
        scene: &Scene,
        instance: &SceneInstance,
    ) -> Result<ExpertPolicy, PolicyError> {
        let mut queue = VecDeque::new();
        let mut steps = Vec::new();
        for (i, (stage, step)) in task.steps().enumerate() {
            let context = || format!("step {i} `{}`", step.primitive);
            let robot = task
                .robot_index(&step.robot)
                .ok_or_else(|| planning(context(), PlanFailure::NoRobot(step.robot.clone())))?;
            let expand = compiler::primitives::primitive(&step.primitive)
                .and_then(|p| p.motions)
                .ok_or_else(|| {
                    planning(context(), PlanFailure::NoMotions(step.primitive.clone()))
                })?;
            let args: BTreeMap<String, String> = step
                .args
                .iter()
                .map(|(k, v)| {
                    let v = render(v, &instance.params).unwrap_or_else(|_| v.clone());
                    (k.clone(), v)
                })
                .collect();
            let kind = args
                .get("on")
                .and_then(|on| task.labware.iter().find(|l| &l.name == on))
                .and_then(|l| labware::kind(&l.kind));
            let motions = expand(&MotionStep { args: &args, kind });
            queue.extend(motions.iter().map(|motion| Queued {
                step: i,
                stage,
                motion: motion.clone(),
            }));
            steps.push(Step {
                robot,
                on: args.get("on").cloned(),
                label: format!(
                    "step {i}: {} {} with {}",
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
            })
            .collect();
        Ok(ExpertPolicy {
            task: task.clone(),
            params: instance.params.clone(),
            steps,
            arms,
            started: false,
            queue,
            active: None,
            frame: None,
            step_moved: false,
            control_dt: 1.0 / task.physics.control_hz(),
            events: Vec::new(),
            seed: instance.seed,
            routed: 0,
        })
    }

    fn start(&mut self, q: Queued, obs: &Observation) -> Result<Active, PolicyError> {
        let step = &self.steps[q.step];
        let context = format!("{}, {}", step.label, q.motion.label());
        let lab = Lab::new(&self.task, &obs.privileged.labware, &self.params);
        let arm = &mut self.arms[step.robot];
        let tcp_now = arm.kin.tcp(&arm.target);
        if self.frame.as_ref().map(|(s, _)| *s) != Some(q.step) {
            let reach = arm.model.gripper.finger_reach;
            let frame = StepFrame::new(&step.motions, &lab, &tcp_now, step.on.as_deref(), reach)
                .map_err(|e| planning(context.clone(), e))?;
            self.frame = Some((q.step, frame));
            self.step_moved = false;
            self.events.push(StageEvent {
                time: obs.time,
                label: step.label.clone(),
            });
        }
        self.events.push(StageEvent {
            time: obs.time,
            label: q.motion.label().to_string(),
        });
        let gripper = arm.model.gripper;
        match q.motion {
            Motion::Grasp | Motion::Release => {
                arm.gripper = if matches!(q.motion, Motion::Grasp) {
                    gripper.closed
                } else {
                    gripper.open
                };
                return Ok(Active::Hold {
                    until: obs.time + gripper.settle_s,
                });
            }
            Motion::Wait { seconds } => {
                return Ok(Active::Hold {
                    until: obs.time + seconds,
                });
            }
            Motion::HoldUntil {
                labware,
                param,
                value,
                timeout_s,
            } => {
                return Ok(Active::Until {
                    labware,
                    param,
                    value,
                    deadline: obs.time + timeout_s,
                });
            }
            _ => {}
        }
        let frame = &mut self.frame.as_mut().expect("set above").1;
        // The item may have turned in the fingers on the way: each seat motion aims with the
        // grasp as it is now.
        frame
            .regrip(&lab, &tcp_now)
            .map_err(|e| planning(context.clone(), e))?;
        let frame = &*frame;
        let poses = frame
            .poses(&q.motion, &lab, &tcp_now)
            .map_err(|e| planning(context.clone(), e))?;
        // Before the step's first path, the other symmetric grasp is a second try.
        let waypoints = match solve_path(arm, &poses) {
            Ok(w) => w,
            Err(first) => {
                let other = (!self.step_moved)
                    .then(|| frame.other_grasp())
                    .flatten()
                    .ok_or_else(|| planning(context.clone(), first.clone()))?;
                let poses = other
                    .poses(&q.motion, &lab, &tcp_now)
                    .map_err(|e| planning(context.clone(), e))?;
                let w = solve_path(arm, &poses).map_err(|_| planning(context.clone(), first))?;
                self.frame = Some((q.step, other));
                w
            }
        };
        self.step_moved = true;
        // TOPP's grid: 200 intervals, and for a planned route (~100 waypoints) 8 per waypoint.
        let mut grid = 200;
        let waypoints = if q.motion.through_free_space() {
            let frame = &self.frame.as_ref().expect("set above").1;
            let carried = frame
                .carried()
                .and_then(|item| self.task.labware.iter().position(|l| l.name == item));
            arm.clearance.sync(&obs.privileged.qpos, carried);
            let seed = planner::mix(self.seed, self.routed);
            self.routed += 1;
            let limits = arm.kin.limits();
            match route(&mut arm.clearance, &limits, waypoints, seed)
                .map_err(|e| planning(context.clone(), e))?
            {
                Route::Straight(path) => path,
                Route::Planned { path, hits, checks } => {
                    grid = grid.max(8 * path.len());
                    self.events.push(StageEvent {
                        time: obs.time,
                        label: format!("planned around {hits} ({checks} collision checks)"),
                    });
                    path
                }
            }
        } else {
            waypoints
        };
        let limits = Limits {
            vmax: arm.model.expert_limits.vmax,
            amax: arm.model.expert_limits.amax,
        };
        let traj = plan_trajectory(waypoints, &limits, grid);
        Ok(Active::Path { traj, t0: obs.time })
    }

    /// Every robot's targets, concatenated.
    fn action(&self) -> Vec<f64> {
        self.arms
            .iter()
            .flat_map(|a| a.target.iter().copied().chain([a.gripper]))
            .collect()
    }

    /// The robot the current step moves.
    fn moving(&self) -> Option<usize> {
        self.frame.as_ref().map(|(s, _)| self.steps[*s].robot)
    }
}

/// Joint waypoints through `poses` (the first is where the arm's target is), each solved by IK
/// from the last.
fn solve_path(arm: &mut Arm, poses: &[labware::Pose]) -> Result<Vec<Vec<f64>>, PlanFailure> {
    let mut waypoints = vec![arm.target.clone()];
    let mut seed = arm.target.clone();
    let of = poses.len().saturating_sub(1);
    for (i, pose) in poses.iter().enumerate().skip(1) {
        let qn = match arm.model.ik {
            IkMethod::Qp => solve_ik(&mut arm.kin, pose, &seed, &Default::default())
                .map_err(|ik| PlanFailure::IkAt { at: i, of, ik })?,
        };
        waypoints.push(qn.clone());
        seed = qn;
    }
    Ok(waypoints)
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
                Some(Active::Until {
                    labware,
                    param,
                    value,
                    deadline,
                }) => {
                    let lab = Lab::new(&self.task, &obs.privileged.labware, &self.params);
                    let shows = lab
                        .panel(labware, param, value)
                        .is_some_and(|(shown, target)| (shown - target).abs() < 1e-9);
                    if shows || obs.time >= *deadline {
                        self.active = None;
                        continue;
                    }
                    return Ok(vec![self.action()]);
                }
                Some(Active::Path { traj, t0 }) => {
                    let t = next_t - t0;
                    let robot = self.moving().expect("a path belongs to a step");
                    if t > traj.duration() + SETTLE_S {
                        self.arms[robot].target = traj.end();
                        self.active = None;
                        continue;
                    }
                    self.arms[robot].target = traj.sample(t);
                    return Ok(vec![self.action()]);
                }
            }
        }
    }

    fn drain_events(&mut self) -> Vec<StageEvent> {
        std::mem::take(&mut self.events)
    }
}
