//! How the expert starts one motion on one robot's lane: the motions that move no pose (grasp and
//! release at the gripper's values and settle time, a wait, holding until a panel shows a value)
//! and the pose motions (resolved to tool poses, solved by the IK method the robot model chooses,
//! routed around obstacles in free space, timed by TOPP under the model's limits). A robot whose
//! free-space motions go in joint space has only their end pose solved; a step that turns a round
//! part in the hand takes the grasp about its axis from which the arm can make the turn
//! (`with_room_to_turn`); a dial is turned a grip at a time and looked at again after each grip,
//! let go, turned back and gripped again until it rests in its notch. A new motion
//! kind is a `compiler::motion::Motion` variant and its arm here (or in `primitives::Lab` for
//! its poses).

use crate::route::{Route, route};
use crate::{ExpertPolicy, Lane, PlanFailure, Queued, planning};
use compiler::motion::{Motion, Target};
use policy::{Observation, PolicyError, StageEvent};
use primitives::alternatives::Scope;
use primitives::ik::{solutions, solve_with};
use primitives::topp::{Limits, Trajectory, plan_trajectory};
use primitives::{Kinematics, Lab, StepFrame};
use robots::RobotModel;
use runtime::clearance::Clearance;
use runtime::kinematics::ArmKinematics;

/// What a lane is doing.
pub(super) enum Active {
    Path {
        traj: Trajectory,
        t0: f64,
    },
    Hold {
        until: f64,
    },
    /// Closing the hand's actuated finger on a part of a held item until each joint (role, where
    /// it started, its goal) has reached its goal, or the deadline passes.
    Press {
        labware: String,
        joints: Vec<(String, f64, f64)>,
        deadline: f64,
    },
    /// Opening the hand's actuated finger evenly from `from` over `seconds` from `t0`.
    Ease {
        from: f64,
        t0: f64,
        seconds: f64,
    },
    /// Still until an instrument's run is done (or the deadline passes). A run that has not
    /// started [`RUN_START_GRACE_S`] after `since` never will (the arm is still): the step
    /// failed, named by `context`.
    Run {
        labware: String,
        deadline: f64,
        since: f64,
        context: String,
    },
    /// Still until a panel shows a value (or the deadline passes: the judge tells what came of it).
    Until {
        labware: String,
        param: String,
        value: String,
        deadline: f64,
    },
}

/// One robot as the expert drives it: its model, kinematics and collision check, and its targets.
pub(super) struct Arm {
    pub model: &'static RobotModel,
    pub kin: ArmKinematics,
    pub clearance: Clearance,
    pub target: Vec<f64>,
    pub gripper: f64,
    /// The arm's joints when the episode began (its drawn start pose): a seed for another IK
    /// branch where the one the arm is on leads nowhere.
    pub start: Vec<f64>,
}

impl ExpertPolicy {
    /// Starts motion `q` on robot `r`'s lane: a new step's frame first (with an open hand where
    /// the step goes to grasp), then one function per motion family: a dial's grip
    /// ([`dial_grip`]), the motions that move no pose ([`in_place`]) and the pose motions
    /// ([`PathStart`]).
    pub(super) fn start(
        &mut self,
        r: usize,
        q: Queued,
        obs: &Observation,
    ) -> Result<Active, PolicyError> {
        let ExpertPolicy {
            task,
            params,
            steps,
            arms,
            lanes,
            events,
            seed,
            routed,
            ..
        } = self;
        let step = &steps[q.step];
        let context = format!("{}, {}", step.label, q.motion.label());
        let plan = |failure: PlanFailure| planning(context.clone(), failure);
        let lab = Lab::new(task, &obs.privileged.labware, params);
        let arm = &mut arms[r];
        let lane = &mut lanes[r];
        let tcp_now = arm.kin.tcp(&arm.target);
        if lane.frame.as_ref().map(|(s, _)| *s) != Some(q.step) {
            let base = task.robots[r].base.translation.vector.into();
            let frame = step_frame(arm, step, &lab, &tcp_now)
                .map_err(&plan)?
                .with_base(base);
            lane.frame = Some((q.step, frame));
            lane.step_moved = false;
            lane.dial_grips = 0;
            events.push(StageEvent {
                time: obs.time,
                label: step.label.clone(),
            });
            // A step that goes to grasp something needs an open hand: the step before may have
            // left the fingers closed (a button pressed with them as one finger).
            let g = arm.model.gripper;
            if arm.gripper != g.open && grasps_after_moving(&step.motions) {
                arm.gripper = g.open;
                events.push(StageEvent {
                    time: obs.time,
                    label: Motion::Release.label().to_string(),
                });
                lane.queue.push_front(q);
                return Ok(Active::Hold {
                    until: obs.time + g.settle_s,
                });
            }
        }
        events.push(StageEvent {
            time: obs.time,
            label: q.motion.label().to_string(),
        });
        if let Some(active) = dial_grip(arm, lane, &q, &lab, obs.time).map_err(&plan)? {
            return Ok(active);
        }
        let comply_at = &obs.privileged.robots[r].arm_q;
        if let Some(active) =
            in_place(arm, &q.motion, comply_at, &lab, obs.time, &context).map_err(&plan)?
        {
            return Ok(active);
        }
        let (q, look) = match aim_over(&q, &lab).map_err(&plan)? {
            None => (q, None),
            Some((over, aims)) => {
                let look = Queued {
                    motion: q.motion.clone(),
                    aims,
                    step: q.step,
                    group: q.group,
                    stage: q.stage,
                };
                (Queued { motion: over, ..q }, Some(look))
            }
        };
        let route_seed = || {
            let s = planner::mix(*seed, *routed);
            *routed += 1;
            s
        };
        let active = PathStart {
            arm,
            lane,
            lab: &lab,
            tcp_now,
            task,
            events,
            robot: r,
        }
        .start(q, obs, route_seed)
        .map_err(&plan)?;
        // Queued once the path is planned: that path (a straight Reach) looks ahead to nothing.
        if let Some(look) = look {
            lanes[r].queue.push_front(look);
        }
        Ok(active)
    }
}

/// How many times a tool is brought over a narrow opening at most: the first, and corrections.
const MAX_AIMS: u8 = 4;

/// How far over a narrow opening's mouth a tool is aimed before it goes in (m).
const OVER: f64 = 0.005;

/// A motion that brings a carried tool into a narrow opening (a pipette's tip into a PCR tube's
/// mouth, `labware::Opening`) first brings it [`OVER`] the mouth, looks once that path ends, and
/// brings it there again from where the arm then is while the tool misses the opening's aim; only
/// then does it go in, straight down. Each path is aimed from the tool's measured pose and the
/// arm's commanded one, so an arm that sags differently at a path's end than at its start ends
/// off by that difference (2.7-5 mm at a PCR tube in the block, from 12 cm above it, where the
/// bore is 5 mm across); corrected over the mouth, the tip never drags across the bore's wall.
/// The miss is the tool's distance from the point over the mouth (a tip too high or low counts
/// too: it then goes straight down, so that costs a try, not the aim).
///
/// `None`: make the motion as it is, once (every motion but one into a narrow opening, and that
/// one's way in once the tool is aimed). Else the motion that brings the tool (again) [`OVER`] the
/// opening instead, and how many times it will then have been made: the look that follows it.
fn aim_over(q: &Queued, lab: &Lab) -> Result<Option<(Motion, u8)>, PlanFailure> {
    let Motion::Reach {
        target:
            Target::Bring {
                carried,
                from,
                labware,
                to,
                above,
            },
    } = &q.motion
    else {
        return Ok(None);
    };
    if *above >= OVER {
        return Ok(None);
    }
    let over = Target::Bring {
        carried: carried.clone(),
        from: from.clone(),
        labware: labware.clone(),
        to: to.clone(),
        above: OVER,
    };
    let Some((miss, aim)) = primitives::bring_miss(&over, lab)? else {
        return Ok(None);
    };
    if q.aims > 0 && (miss <= aim || q.aims >= MAX_AIMS) {
        return Ok(None);
    }
    Ok(Some((Motion::Reach { target: over }, q.aims + 1)))
}

/// A new step's frame: its motions resolved against the lab with the tool where it is, and for a
/// step that turns a round part in the hand, the grasp with room for the turn.
fn step_frame(
    arm: &mut Arm,
    step: &crate::Step,
    lab: &Lab,
    tcp_now: &labware::Pose,
) -> Result<StepFrame, PlanFailure> {
    let g = arm.model.gripper;
    let frame = StepFrame::new(
        &step.motions,
        lab,
        tcp_now,
        step.on.as_deref(),
        g.finger_reach,
        g.enclose,
    )?;
    Ok(with_room_to_turn(arm, frame, &step.motions, lab))
}

/// A dial's turn, where the dial is now decides: in its notch, nothing is left to do; short of it
/// with the hand open (let go after a grip), turn back and grip again; gripped, turn (the pose
/// motion that follows), at most `MAX_DIAL_GRIPS` times in one step. `None` for every other
/// motion, and for a gripped dial still to turn.
fn dial_grip(
    arm: &Arm,
    lane: &mut Lane,
    q: &Queued,
    lab: &Lab,
    time: f64,
) -> Result<Option<Active>, PlanFailure> {
    let Motion::TurnDial {
        labware,
        param,
        value,
        ..
    } = &q.motion
    else {
        return Ok(None);
    };
    let left = lab.dial_turn(labware, param, value)?;
    let now = Active::Hold { until: time };
    if left.abs() < DIAL_DONE {
        return Ok(Some(now));
    }
    if arm.gripper == arm.model.gripper.open {
        for motion in [q.motion.clone(), Motion::Grasp, Motion::TurnBack] {
            lane.queue.push_front(Queued {
                motion,
                step: q.step,
                group: q.group,
                stage: q.stage,
                aims: 0,
            });
        }
        return Ok(Some(now));
    }
    lane.dial_grips += 1;
    if lane.dial_grips > MAX_DIAL_GRIPS {
        return Err(primitives::PlanError::DialStuck {
            labware: labware.clone(),
            param: param.clone(),
            value: value.clone(),
            grips: MAX_DIAL_GRIPS,
        }
        .into());
    }
    Ok(None)
}

/// The motions that move no pose: the gripper closed or opened (then its settle time), a wait,
/// complying (the arm's targets where it is, `arm_q`), a held item's part pressed, the hand eased
/// open, holding until a panel shows a value. `None` for a pose motion.
fn in_place(
    arm: &mut Arm,
    motion: &Motion,
    arm_q: &[f64],
    lab: &Lab,
    time: f64,
    context: &str,
) -> Result<Option<Active>, PlanFailure> {
    let gripper = arm.model.gripper;
    Ok(Some(match motion {
        Motion::Grasp | Motion::Release => {
            arm.gripper = if matches!(motion, Motion::Grasp) {
                gripper.closed
            } else {
                gripper.open
            };
            Active::Hold {
                until: time + gripper.settle_s,
            }
        }
        Motion::Wait { seconds } => Active::Hold {
            until: time + seconds,
        },
        Motion::Comply => {
            arm.target = arm_q.to_vec();
            Active::Hold { until: time }
        }
        Motion::PressPart {
            labware,
            goals,
            timeout_s,
        } => {
            let (_, live) = lab.item(labware)?;
            let at = lab.at_goals(labware, goals)?;
            let joints = goals
                .iter()
                .map(|(role, _)| (role.clone(), live.joint(role), at.joint(role)))
                .collect();
            Active::Press {
                labware: labware.clone(),
                joints,
                deadline: time + timeout_s,
            }
        }
        Motion::EasePart { seconds } => Active::Ease {
            from: arm.gripper,
            t0: time,
            seconds: *seconds,
        },
        Motion::AwaitRun { labware, timeout_s } => Active::Run {
            labware: labware.clone(),
            deadline: time + timeout_s,
            since: time,
            context: context.to_string(),
        },
        Motion::HoldUntil {
            labware,
            param,
            value,
            timeout_s,
        } => Active::Until {
            labware: labware.clone(),
            param: param.clone(),
            value: value.clone(),
            deadline: time + timeout_s,
        },
        _ => return Ok(None),
    }))
}

/// A pose motion started on one robot's lane: its tool poses solved to joint waypoints (with the
/// step's fallbacks), its end chosen so that the step's next straight motion can be made, routed
/// around obstacles in free space, and timed by TOPP.
struct PathStart<'a> {
    arm: &'a mut Arm,
    lane: &'a mut Lane,
    lab: &'a Lab<'a>,
    tcp_now: labware::Pose,
    task: &'a compiler::Task,
    events: &'a mut Vec<StageEvent>,
    robot: usize,
}

impl PathStart<'_> {
    fn start(
        self,
        q: Queued,
        obs: &Observation,
        route_seed: impl FnOnce() -> u64,
    ) -> Result<Active, PlanFailure> {
        let PathStart {
            arm,
            lane,
            lab,
            tcp_now,
            task,
            events,
            robot,
        } = self;
        let frame = &mut lane.frame.as_mut().expect("set when the step began").1;
        // The item may have turned in the fingers on the way: each seat motion aims with the
        // grasp as it is now.
        frame.regrip(lab, &tcp_now)?;
        let poses = frame.poses(&q.motion, lab, &tcp_now)?;
        // A robot that crosses free space in joint space goes straight to the IK solution
        // nearest where it is: solved along the tool's path instead, its wrist would follow the
        // path's orientations through a singularity onto the other branch (the ViperX's forearm
        // rolled half a turn, leaving its wrist no room for a cap's turn).
        let limits = arm.model.expert_limits;
        let direct = q.motion.through_free_space() && limits.joint_space_transits;
        let poses = path_ends(poses, direct);
        let free = FreeMotion {
            motion: &q.motion,
            lab,
            tcp_now,
            direct,
        };
        let waypoints = solve_with_fallbacks(arm, lane, q.step, &free, &poses)?;
        // A free-space motion's end decides the IK branch the step's next straight motion starts
        // from: where that motion cannot be solved from the end this path arrives at, the end is
        // taken on a branch from which it can.
        let next = lane
            .queue
            .front()
            .filter(|n| n.step == q.step && is_straight(&n.motion))
            .map(|n| n.motion.clone());
        // A seat-turned frame the free-space path below was planned with (not kept for the
        // step: the motions after it take the heading the item then has).
        let mut seat_frame: Option<StepFrame> = None;
        let waypoints = match &next {
            Some(next) if q.motion.through_free_space() => {
                let frame = &lane.frame.as_ref().expect("set when the step began").1;
                let end = poses.last().copied();
                match with_room_for_next(arm, frame, next, lab, waypoints.clone(), end) {
                    Some(w) => w,
                    // Before the step has moved, a round part may be taken from another side
                    // (the step keeps that grasp), or a round carried item brought over its
                    // seat at another heading (the motions after this one keep the heading the
                    // item then has).
                    None if !lane.step_moved => {
                        let turned = frame.alternatives(true).find_map(|alt| {
                            let w = free.path(arm, &alt.frame, Some(next))?;
                            Some((alt, w))
                        });
                        match turned {
                            Some((alt, w)) => {
                                match alt.scope {
                                    Scope::Step => lane.frame = Some((q.step, alt.frame)),
                                    Scope::Motion => seat_frame = Some(alt.frame),
                                }
                                w
                            }
                            None => waypoints,
                        }
                    }
                    None => waypoints,
                }
            }
            _ => waypoints,
        };
        // Home has no tool path: the arm goes to the model's home joints.
        let waypoints = match q.motion {
            Motion::Home => vec![arm.target.clone(), arm.model.home.to_vec()],
            _ => waypoints,
        };
        let first_path = !lane.step_moved;
        lane.step_moved = true;
        // A dial is looked at again once the hand has let go of it.
        if matches!(q.motion, Motion::TurnDial { .. }) {
            for motion in [q.motion.clone(), Motion::Release] {
                lane.queue.push_front(Queued {
                    motion,
                    step: q.step,
                    group: q.group,
                    stage: q.stage,
                    aims: 0,
                });
            }
        }
        // A turn is noted for the turn back that undoes it (on the frame the path was solved
        // with: the other grasp's, where that one was taken).
        if let Some((_, f)) = lane.frame.as_mut() {
            f.record_turn(&q.motion, lab, &tcp_now)?;
        }
        // TOPP's grid: 200 intervals, and for a planned route (~100 waypoints) 8 per waypoint.
        let mut grid = 200;
        let waypoints = if q.motion.through_free_space() {
            let frame = seat_frame
                .as_ref()
                .unwrap_or(&lane.frame.as_ref().expect("set when the step began").1);
            // What the hand carries moves with it: the item the step seats, else the liquid
            // tool it works with (a pipette held from the start).
            let carried = frame
                .carried()
                .map(str::to_string)
                .or_else(|| task.liquid_tool(&task.robots[robot].name, q.step))
                .and_then(|item| task.labware.iter().position(|l| l.name == item));
            arm.clearance.sync(&obs.privileged.qpos, carried);
            let routing = Routing {
                free: &free,
                next: next.as_ref(),
                seed: route_seed(),
                check_step: limits.check_step,
            };
            let (routed, kept) = routing.route(arm, frame, waypoints, first_path)?;
            if let Some(f) = kept {
                lane.frame = Some((q.step, f));
            }
            match routed {
                Route::Straight(path) => path,
                Route::Planned { path, hits, checks } => {
                    grid = grid.max(8 * path.len());
                    events.push(StageEvent {
                        time: obs.time,
                        label: format!("planned around {hits} ({checks} collision checks)"),
                    });
                    path
                }
            }
        } else {
            waypoints
        };
        let topp = Limits {
            vmax: limits.vmax,
            amax: limits.amax,
        };
        let traj = plan_trajectory(waypoints, &topp, grid);
        Ok(Active::Path { traj, t0: obs.time })
    }
}

/// Joint waypoints through a motion's tool `poses`, trying in order: the poses as resolved, the
/// motion's own fallback paths, before the step's first path the other symmetric grasp (the step
/// then keeps it), and last, for a free-space motion whose line the arm cannot follow (through a
/// singularity, past a joint's range midway), a path in joint space.
fn solve_with_fallbacks(
    arm: &mut Arm,
    lane: &mut Lane,
    step: usize,
    free: &FreeMotion,
    poses: &[labware::Pose],
) -> Result<Vec<Vec<f64>>, PlanFailure> {
    let first = match solve_path(arm, poses) {
        Ok(w) => return Ok(w),
        Err(first) => first,
    };
    let frame = &lane.frame.as_ref().expect("set when the step began").1;
    let fallback = frame
        .fallback_poses(free.motion, free.lab, &free.tcp_now)
        .unwrap_or_default()
        .iter()
        .find_map(|p| solve_path(arm, p).ok());
    if let Some(w) = fallback {
        return Ok(w);
    }
    let other = (!lane.step_moved)
        .then(|| frame.other_grasp())
        .flatten()
        .and_then(|other| {
            let poses = path_ends(
                other.poses(free.motion, free.lab, &free.tcp_now).ok()?,
                free.direct,
            );
            solve_path(arm, &poses).ok().map(|w| (other, w))
        });
    if let Some((other, w)) = other {
        lane.frame = Some((step, other));
        return Ok(w);
    }
    free.motion
        .through_free_space()
        .then(|| in_joint_space(arm, poses))
        .flatten()
        .ok_or(first)
}

/// The motion being planned and what its poses are resolved with.
struct FreeMotion<'a> {
    motion: &'a Motion,
    lab: &'a Lab<'a>,
    tcp_now: labware::Pose,
    /// Whether the robot crosses free space in joint space (only a path's ends are solved).
    direct: bool,
}

impl FreeMotion<'_> {
    /// Joint waypoints for the motion planned with frame `f` (one of a step's alternatives): its
    /// path solved pose by pose, else in joint space, ending where the step's `next` straight
    /// motion (if any) solves from. `None` where it has none.
    fn path(&self, arm: &mut Arm, f: &StepFrame, next: Option<&Motion>) -> Option<Vec<Vec<f64>>> {
        let poses = path_ends(
            f.poses(self.motion, self.lab, &self.tcp_now).ok()?,
            self.direct,
        );
        let w = solve_path(arm, &poses)
            .ok()
            .or_else(|| in_joint_space(arm, &poses))?;
        match next {
            Some(n) => with_room_for_next(arm, f, n, self.lab, w, poses.last().copied()),
            None => Some(w),
        }
    }
}

/// A free-space motion's waypoints routed around obstacles.
struct Routing<'a> {
    free: &'a FreeMotion<'a>,
    next: Option<&'a Motion>,
    seed: u64,
    check_step: f64,
}

impl Routing<'_> {
    /// The route of `waypoints` planned with `frame`; where it is blocked for good, a route to
    /// another solution of its end, then the step's alternatives (a round item over its seat at
    /// another heading, and on the step's `first_path` a round part taken from another side),
    /// each routed likewise. With the route, the alternative grasp the step keeps, if one was
    /// taken.
    fn route(
        &self,
        arm: &mut Arm,
        frame: &StepFrame,
        waypoints: Vec<Vec<f64>>,
        first_path: bool,
    ) -> Result<(Route, Option<StepFrame>), PlanFailure> {
        let joint_limits = arm.kin.limits();
        let end = waypoints.last().map(|q| arm.kin.tcp(q));
        let blocked = match route(
            &mut arm.clearance,
            &joint_limits,
            self.check_step,
            waypoints,
            self.seed,
        ) {
            Ok(routed) => return Ok((routed, None)),
            Err(blocked) => blocked,
        };
        // Home is the model's home joints, not another pose of its tool.
        if matches!(self.free.motion, Motion::Home) {
            return Err(blocked);
        }
        if let Some(routed) = self.to_other_end(arm, frame, end) {
            return Ok((routed, None));
        }
        frame
            .alternatives(first_path)
            .find_map(|alt| {
                let w = self.free.path(arm, &alt.frame, self.next)?;
                let end = w.last().map(|q| arm.kin.tcp(q));
                let routed = route(
                    &mut arm.clearance,
                    &joint_limits,
                    self.check_step,
                    w,
                    self.seed,
                )
                .ok()
                .or_else(|| self.to_other_end(arm, &alt.frame, end))?;
                let kept = (alt.scope == Scope::Step).then_some(alt.frame);
                Some((routed, kept))
            })
            .ok_or(blocked)
    }

    fn to_other_end(
        &self,
        arm: &mut Arm,
        frame: &StepFrame,
        end: Option<labware::Pose>,
    ) -> Option<Route> {
        route_to_other_end(
            arm,
            frame,
            self.next,
            self.free.lab,
            end,
            self.check_step,
            self.seed,
        )
    }
}

/// What is left of a dial's turn (rad) that counts as none: the detent holds it in its notch.
const DIAL_DONE: f64 = 0.1;

/// Grips a step may take to turn a dial: more is a hand slipping on it, which turning on would
/// not mend.
const MAX_DIAL_GRIPS: usize = 8;

/// Largest joint change (rad) between two of a turn's poses (0.1 rad apart) that still follows
/// one IK branch; more is a jump to another, which the arm would make in a straight joint line
/// that tears the part from the thread instead of turning it.
const TURN_STEP_JOINT: f64 = 0.5;

/// For a step that turns a round part in the hand (`Motion::Turn`, `Motion::TurnDial`), the grasp about the part's
/// axis nearest the step's own from which the arm makes the step's first turn within its joint
/// limits and on one IK branch: the closest grasp can leave a wrist joint a few degrees short of
/// the turn, and the arm then tears the part off its thread. Any other step, or a step for which
/// no grasp has the room, keeps its frame.
fn with_room_to_turn(arm: &mut Arm, frame: StepFrame, motions: &[Motion], lab: &Lab) -> StepFrame {
    let Some((angle, centre)) = motions.iter().find_map(|m| match m {
        Motion::Turn { angle, .. } => Some((*angle, 0.0)),
        // From the dial's live angle (the tool's pose plays no part), each grip taken half a
        // grip back so that the hand sweeps evenly either side of where it came in.
        Motion::TurnDial { .. } => frame
            .turn_angle(m, lab, &labware::Pose::identity())
            .ok()
            .map(|a| (a, -a / 2.0)),
        _ => None,
    }) else {
        return frame;
    };
    let turn = Motion::Turn {
        angle,
        thread: None,
        stop: None,
    };
    let limits = arm.kin.limits();
    let within = |q: &[f64]| {
        q.iter()
            .zip(&limits)
            .all(|(v, (lo, hi))| *v >= *lo && *v <= *hi)
    };
    let mut fits = |f: &StepFrame| -> Option<()> {
        // `None` where the grasp or a pose of the turn has no solution that keeps to one branch.
        let grasp = f.first_pose(motions, lab).ok()??;
        let mut q = solve_with(arm.model.ik, &mut arm.kin, &grasp, &arm.target).ok()?;
        for pose in f.poses(&turn, lab, &grasp).ok()?.iter().skip(1) {
            let next = solve_with(arm.model.ik, &mut arm.kin, pose, &q).ok()?;
            let jump = next
                .iter()
                .zip(&q)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            if !within(&next) || jump > TURN_STEP_JOINT {
                return None;
            }
            q = next;
        }
        Some(())
    };
    let chosen = frame.turn_grasps(centre).find(|f| fits(f).is_some());
    chosen.unwrap_or(frame)
}

/// A free-space motion's tool poses as the arm follows them: where the robot crosses free space
/// in joint space (`direct`), only the first and the last.
fn path_ends(poses: Vec<labware::Pose>, direct: bool) -> Vec<labware::Pose> {
    match (poses.first(), poses.last()) {
        (Some(a), Some(b)) if direct && poses.len() > 2 => vec![*a, *b],
        _ => poses,
    }
}

/// Whether a step moves the hand to something before its first grasp or release, and that first
/// one is a grasp (a pick's way down to the item): such a step must start with the hand open. A
/// step whose first motion is the grasp (a button pressed with the fingers closed as one finger)
/// closes the hand where it is.
fn grasps_after_moving(motions: &[Motion]) -> bool {
    let first = motions
        .iter()
        .position(|m| matches!(m, Motion::Grasp | Motion::Release));
    matches!(first, Some(i) if i > 0 && matches!(motions[i], Motion::Grasp))
}

/// Motions that go in a straight line from where the tool is to a target (down to a grasp, in to
/// a button): solved pose by pose from the joints they start at, so those joints decide whether
/// they can be made.
fn is_straight(motion: &Motion) -> bool {
    matches!(
        motion,
        Motion::Reach { .. } | Motion::Enclose { .. } | Motion::Press { .. }
    )
}

/// Whether `next` (a straight motion) can be solved pose by pose with the arm at `q`.
/// Its own fallback paths count, as they will when it runs (a round part reached at the turn
/// nearest the tool).
fn solves_next(arm: &mut Arm, frame: &StepFrame, next: &Motion, lab: &Lab, q: &[f64]) -> bool {
    let tcp = arm.kin.tcp(q);
    let own = frame.poses(next, lab, &tcp).into_iter();
    let fallbacks = frame.fallback_poses(next, lab, &tcp).unwrap_or_default();
    own.chain(fallbacks)
        .any(|poses| solve_path_from(arm, q, &poses).is_ok())
}

/// The IK solutions of a free-space path's `end` pose: every branch the robot model's method
/// finds, seeded from where the arm is, its home pose and the episode's start pose, nearest the
/// arm first (the goal region; where the path's own end is among them, trying it again costs a
/// check).
fn other_ends(arm: &mut Arm, end: &labware::Pose) -> Vec<Vec<f64>> {
    let seeds = [
        arm.target.clone(),
        arm.model.home.to_vec(),
        arm.start.clone(),
    ];
    solutions(arm.model.ik, &mut arm.kin, end, &seeds)
}

/// A free-space path's `waypoints` ending where the step's `next` straight motion can be solved
/// from. The path as solved ends on the branch the arm is on; where `next` cannot be made from
/// there (an elbow up over a rack beside the arm's own base, after opening a lid far from it),
/// the nearest other solution of the path's `end` from which `next` solves is taken, the arm
/// going there in joint space (routed around obstacles like any free-space path). `None` where
/// no end serves.
fn with_room_for_next(
    arm: &mut Arm,
    frame: &StepFrame,
    next: &Motion,
    lab: &Lab,
    waypoints: Vec<Vec<f64>>,
    end: Option<labware::Pose>,
) -> Option<Vec<Vec<f64>>> {
    let last = waypoints.last().cloned()?;
    if solves_next(arm, frame, next, lab, &last) {
        return Some(waypoints);
    }
    other_ends(arm, &end?)
        .into_iter()
        .find(|q| solves_next(arm, frame, next, lab, q))
        .map(|q| vec![arm.target.clone(), q])
}

/// A route to another solution of a free-space path's `end` where the one its waypoints arrive
/// at is blocked for good (the forearm in an instrument's housing): the nearest solution clear
/// of the scene from which the step's `next` straight motion (if any) solves and to which a
/// route is found.
#[allow(clippy::too_many_arguments)]
fn route_to_other_end(
    arm: &mut Arm,
    frame: &StepFrame,
    next: Option<&Motion>,
    lab: &Lab,
    end: Option<labware::Pose>,
    check_step: f64,
    seed: u64,
) -> Option<Route> {
    let joint_limits = arm.kin.limits();
    for q in other_ends(arm, &end?) {
        if !arm.clearance.may_end_at(&q)
            || next.is_some_and(|n| !solves_next(arm, frame, n, lab, &q))
        {
            continue;
        }
        let path = vec![arm.target.clone(), q];
        if let Ok(r) = route(&mut arm.clearance, &joint_limits, check_step, path, seed) {
            return Some(r);
        }
    }
    None
}

/// A joint-space path to the last of `poses`: from where the arm is to the end pose solved from
/// there, else from the home pose, else from the episode's start pose (routed around obstacles
/// like any free-space path). `None` where the end has no solution.
fn in_joint_space(arm: &mut Arm, poses: &[labware::Pose]) -> Option<Vec<Vec<f64>>> {
    let end = poses.last()?;
    [
        arm.target.clone(),
        arm.model.home.to_vec(),
        arm.start.clone(),
    ]
    .iter()
    .find_map(|seed| solve_with(arm.model.ik, &mut arm.kin, end, seed).ok())
    .map(|q| vec![arm.target.clone(), q])
}

/// Joint waypoints through `poses` (the first is where the arm's target is), each solved by the
/// robot model's IK method from the last.
fn solve_path(arm: &mut Arm, poses: &[labware::Pose]) -> Result<Vec<Vec<f64>>, PlanFailure> {
    let from = arm.target.clone();
    solve_path_from(arm, &from, poses)
}

/// As [`solve_path`], with the arm at `from` (the first of `poses` is its tool pose there).
fn solve_path_from(
    arm: &mut Arm,
    from: &[f64],
    poses: &[labware::Pose],
) -> Result<Vec<Vec<f64>>, PlanFailure> {
    let mut waypoints = vec![from.to_vec()];
    let mut seed = from.to_vec();
    let of = poses.len().saturating_sub(1);
    for (i, pose) in poses.iter().enumerate().skip(1) {
        let qn = solve_with(arm.model.ik, &mut arm.kin, pose, &seed)
            .map_err(|ik| PlanFailure::IkAt { at: i, of, ik })?;
        waypoints.push(qn.clone());
        seed = qn;
    }
    Ok(waypoints)
}
