//! Reach before any episode (`autobio check`): whether each step's robot can bring its tool to
//! the step's first target (the grasp, press or dial frame the expert aims at) and to the point
//! it comes in from (the approach's standoff back along the target's axis), then along the path
//! it follows holding a part (a lid's handle over its whole arc, each pose solved from the last
//! as the expert solves it, from where earlier steps left the lid; a lift after the grasp), and to the
//! seat (and above it) where it places an item it picked, with the item as the pick grasped it,
//! in the layout the task's first seed draws. Targets come from the labware models as the expert
//! resolves them (`primitives::StepFrame`) and are solved by the robot model's IK from the
//! robot's start pose and from its home, in either of a symmetric target's grasps. A target none
//! of these solve is E0036 at the step's `with` (one per step), saying why: past a joint's range
//! (the pose solves with the ranges widened: which joint, the angle it would need, its range), or
//! out of reach (how close the best solve came); with a hint: the nearest base position (the
//! same heading) from which every target this pass checks for that robot, in every sampled
//! layout, solves with 10 cm to spare, found by moving the targets instead of the base (a base
//! shift is the targets' opposite shift to the arm) on rings around it at its height, then, where
//! none serves (a wrist past its range over a high shelf), on rings around raised heights (a
//! riser); each found base is stood up for real in each layout's rebuilt scene, where the arm
//! must not start inside anything and must come in to each target that stands as the scene
//! starts clear of it. A hinted base is reached and clear; the expert may still fail there for
//! other reasons (a key pressed from another angle): the hint is where to start.
//!
//! [`margins`] gives each step's reach margin for `autobio describe`: how far its targets could
//! move away from the robot and still be reached.
//!
//! A held tool brought onto a round opening (`aspirate`, `dispense`: a pipette's tip over a
//! tube's mouth and under its surface) is solved as the tool sits in the hand at the start, at
//! the headings about the opening's axis the expert tries (twelve, 30 degrees apart); onto an
//! opening that is not round, or a container another robot holds (the two-arm aspirate's
//! lifted tube), it is not checked. It does not check hand-overs or a seat for an item
//! another robot picked, the free-space
//! paths between targets (the expert routes those, `crate::route`), the straight lines between
//! checked poses, or a chain's later stages, and it skips a step acting on an item an earlier
//! step put elsewhere (its target is not where it starts). A task whose scene cannot be built is
//! left to the runtime's refusal. The next seven seeds' layouts are checked too: a step reached in
//! seed 0's but not in some of them is W0010 (the task checks; some of its episodes will fail at
//! planning), with the same hint where a base serves every layout.

use compiler::motion::{Motion, MotionStep, Target};
use compiler::params::render;
use compiler::{Checked, Task};
use dsl::ast::Document;
use dsl::{Code, Diagnostic};
use labware::{LabwareState, Pose};
use primitives::resolve::first_target;
use primitives::{Lab, StepFrame, solve_with};
use runtime::clearance::Clearance;
use runtime::kinematics::ArmKinematics;
use runtime::{Episode, Scene};
use std::collections::{BTreeMap, BTreeSet};
use std::sync::Arc;

/// One step's target that no start solves.
#[derive(Clone, Debug, PartialEq)]
pub struct Unreachable {
    /// The step's index in the plan (from 0).
    pub step: usize,
    /// The robot the step names.
    pub robot: String,
    /// What the step aims at, e.g. "`tube`'s `grasp`".
    pub target: String,
    /// The target's position (m, world frame).
    pub at: [f64; 3],
    /// How close the best solve came (m, rad), where the IK says.
    pub short_by: Option<(f64, f64)>,
    /// Where the target is in reach but only past a joint's range: which, and how far.
    pub limit: Option<JointLimit>,
    /// A base position (m) from which every checked target of the robot solves, if one was found.
    pub base_hint: Option<[f64; 3]>,
    /// The robot's base now (m).
    pub base: [f64; 3],
}

/// Rings searched for a base hint: every `HINT_STEP` metres out to `HINT_RADIUS`, in
/// `HINT_DIRECTIONS` directions each.
const HINT_STEP: f64 = 0.025;
const HINT_RADIUS: f64 = 0.8;
const HINT_DIRECTIONS: usize = 16;
/// How much farther out than each target (m, in the plane, away from the base) the hinted base
/// must still reach.
const HINT_MARGIN: f64 = 0.1;
/// How far back along a grasp's axis the hinted base's arm must come in clear of the scene (m),
/// and how many reached bases at each height are stood up and checked so before the search
/// gives that height up.
const HINT_APPROACH: f64 = 0.07;
const HINT_CLEAR_TRIES: usize = 120;
/// Where no base at the robot's height serves (a target high above it, reached only with a
/// joint past its range), raised bases are searched too: `HINT_RISE` metres at a time, up to
/// `HINT_RISES` times (a riser under the robot, as `protocols/centrifuge_5910/riser.toml`).
const HINT_RISE: f64 = 0.05;
const HINT_RISES: usize = 10;

/// A checked target of one robot: the step it belongs to and the tool poses that reach it (its
/// grasps).
struct Aim {
    step: usize,
    robot: usize,
    target: String,
    /// The tool poses that take the target (its symmetric grasps, the first the expert's
    /// choice), each with the path the tool then follows holding a part (a lid's handle along
    /// its arc), each pose solved from the last; the path is empty for a step that follows
    /// nothing.
    grasps: Vec<(Pose, Vec<Pose>)>,
    /// Whether the scene as it starts is the scene at this target (no earlier step has moved a
    /// lid, nothing is carried), so that a hinted base's clear approach can be checked in it.
    as_started: bool,
}

/// Every step of `task` (a single stage) whose first target its robot cannot reach in seed 0's
/// layout; empty when all are reached, or when the pass does not apply (a chain, a scene the
/// runtime cannot build).
pub fn unreachable(task: &Task) -> Vec<Unreachable> {
    misses(task, 0, true)
}

/// Whether every step of `task` is reached in each sampled layout (what [`check`] would say
/// nothing about), without searching for a base hint where one is not: synthesis's test.
pub fn reached_everywhere(task: &Task) -> bool {
    misses(task, 0, false).is_empty() && beyond_seed_0(task, &BTreeSet::new()).is_empty()
}

/// Layouts the pass samples: seed 0's (E0036) and the next ones (W0010).
pub const SAMPLED_LAYOUTS: u64 = 8;

/// For each step its robot reaches in seed 0's layout but not in some of the next
/// `SAMPLED_LAYOUTS - 1` seeds' (other slots drawn, labware placed elsewhere in its
/// randomisation), those seeds, in order; steps missed in seed 0 are E0036's, not listed.
pub fn partly_unreachable(task: &Task) -> BTreeMap<usize, Vec<u64>> {
    let first: BTreeSet<usize> = misses(task, 0, false).iter().map(|u| u.step).collect();
    beyond_seed_0(task, &first)
}

/// The steps not in `first` (those missed in seed 0's layout) that the next seeds miss.
fn beyond_seed_0(task: &Task, first: &BTreeSet<usize>) -> BTreeMap<usize, Vec<u64>> {
    let mut out: BTreeMap<usize, Vec<u64>> = BTreeMap::new();
    for seed in 1..SAMPLED_LAYOUTS {
        for u in misses(task, seed, false) {
            if !first.contains(&u.step) {
                out.entry(u.step).or_default().push(seed);
            }
        }
    }
    out
}

/// One step's reach margin (`autobio describe`): how far its targets could all move away from
/// its robot, in the plane, and still be reached as the pass reaches them, in seed 0's layout.
#[derive(Clone, Debug, PartialEq)]
pub struct Margin {
    /// Index into the plan (0-based).
    pub step: usize,
    pub robot: String,
    /// Metres, in `MARGIN_STEP`s up to `MARGIN_MAX` (a margin of `MARGIN_MAX` is "at least");
    /// `None` where a target is out of reach as it stands (E0036).
    pub margin: Option<f64>,
}

/// The margin search: targets moved out in steps of this (m), up to this.
pub const MARGIN_STEP: f64 = 0.01;
pub const MARGIN_MAX: f64 = 0.3;

/// Every checked step's reach margin, in plan order: each of its targets (its grasp and the path
/// it then follows) moved away from the robot's base along the line from the base, until one no
/// longer solves from the robot's start pose, its home or its last solution. Empty where the pass
/// does not apply (a chain, a scene the runtime cannot build).
pub fn margins(task: &Task) -> Vec<Margin> {
    let Some(mut layout) = Layout::of(task, 0) else {
        return Vec::new();
    };
    let mut out: Vec<Margin> = Vec::new();
    let mut last: Vec<Option<Vec<f64>>> = vec![None; layout.scene.robots.len()];
    let steps: BTreeSet<usize> = layout.aims.iter().map(|a| a.step).collect();
    for step in steps {
        let aims: Vec<&Aim> = layout.aims.iter().filter(|a| a.step == step).collect();
        let robot = aims[0].robot;
        let model = layout.scene.robots[robot].model;
        let base = task.robots[robot].base.translation.vector;
        let mut starts = vec![layout.instance.robot_q[robot].clone(), model.home.to_vec()];
        starts.extend(last[robot].clone());
        let kin = &mut layout.kins[robot];
        let reached_at = |d: f64, kin: &mut ArmKinematics| -> Option<Vec<f64>> {
            let mut q = None;
            for aim in &aims {
                let moved = aim.moved_out([base.x, base.y], d);
                q = Some(reach(model, kin, &moved, &starts).ok()?);
            }
            q
        };
        let Some(q) = reached_at(0.0, kin) else {
            out.push(Margin {
                step,
                robot: task.robots[robot].name.clone(),
                margin: None,
            });
            continue;
        };
        last[robot] = Some(q);
        let steps = (MARGIN_MAX / MARGIN_STEP).round() as usize;
        let room = (1..=steps)
            .take_while(|k| reached_at(*k as f64 * MARGIN_STEP, kin).is_some())
            .count();
        out.push(Margin {
            step,
            robot: task.robots[robot].name.clone(),
            margin: Some(room as f64 * MARGIN_STEP),
        });
    }
    out
}

impl Aim {
    /// The aim with every pose moved `d` metres away from `base` in the plane, along the line
    /// from the base to its first grasp.
    fn moved_out(&self, base: [f64; 2], d: f64) -> Aim {
        let p = self.grasps[0].0.translation.vector;
        let out = nalgebra::Vector2::new(p.x - base[0], p.y - base[1]);
        let out = out.try_normalize(1e-9).unwrap_or_default() * d;
        let shift = labware::frame::translation([out.x, out.y, 0.0]);
        Aim {
            step: self.step,
            robot: self.robot,
            target: self.target.clone(),
            grasps: self
                .grasps
                .iter()
                .map(|(g, path)| (shift * g, path.iter().map(|p| shift * p).collect()))
                .collect(),
            as_started: self.as_started,
        }
    }
}

/// Seed `seed`'s layout as the pass sees it: the drawn scene, built, and its aims.
struct Layout {
    instance: compiler::SceneInstance,
    scene: Arc<Scene>,
    kins: Vec<ArmKinematics>,
    aims: Vec<Aim>,
}

impl Layout {
    /// `None` for a chain or a scene the runtime cannot build.
    fn of(task: &Task, seed: u64) -> Option<Layout> {
        if task.stages.len() != 1 {
            return None;
        }
        let instance = task.sample(seed);
        let scene = Arc::new(Scene::build(task, &instance).ok()?);
        let episode = Episode::new(scene.clone(), task, &instance);
        let mut states = episode.labware_state();
        let mut kins: Vec<ArmKinematics> = (0..scene.robots.len())
            .map(|r| ArmKinematics::new(&scene, r))
            .collect();
        let aims = aims(
            task,
            &scene,
            &mut states,
            &instance.params,
            &mut kins,
            &instance.robot_q,
        );
        Some(Layout {
            instance,
            scene,
            kins,
            aims,
        })
    }
}

/// The steps whose targets their robots miss in seed `seed`'s layout, with base hints where
/// `hint` asks for them.
fn misses(task: &Task, seed: u64, hint: bool) -> Vec<Unreachable> {
    let Some(Layout {
        instance,
        scene,
        mut kins,
        aims,
    }) = Layout::of(task, seed)
    else {
        return Vec::new();
    };
    let mut out: Vec<Unreachable> = Vec::new();
    // The arm's last solution per robot (a seed as good as the expert's, which comes from the
    // step before), and the hint per robot, searched once.
    let mut last: Vec<Option<Vec<f64>>> = vec![None; scene.robots.len()];
    let mut hints: BTreeMap<usize, Option<[f64; 3]>> = BTreeMap::new();
    for aim in &aims {
        // One report per step: its first target out of reach.
        if out.iter().any(|u| u.step == aim.step) {
            continue;
        }
        let model = scene.robots[aim.robot].model;
        let mut starts = vec![instance.robot_q[aim.robot].clone(), model.home.to_vec()];
        starts.extend(last[aim.robot].clone());
        let kin = &mut kins[aim.robot];
        match reach(model, kin, aim, &starts) {
            Ok(q) => {
                last[aim.robot] = Some(q);
                continue;
            }
            Err(miss) => {
                let base = task.robots[aim.robot].base.translation.vector;
                let base = [base.x, base.y, base.z];
                let hint = hint
                    .then(|| {
                        *hints
                            .entry(aim.robot)
                            .or_insert_with(|| base_for_every_layout(task, aim.robot))
                    })
                    .flatten();
                let (target, p) = match miss.stopped {
                    Some(k) => (
                        format!(
                            "{} and along the path it then follows, at pose {} of {}",
                            aim.target,
                            k + 1,
                            aim.grasps[0].1.len()
                        ),
                        aim.grasps[0].1[k].translation.vector,
                    ),
                    None => (aim.target.clone(), aim.grasps[0].0.translation.vector),
                };
                out.push(Unreachable {
                    step: aim.step,
                    robot: task.robots[aim.robot].name.clone(),
                    target,
                    at: [p.x, p.y, p.z],
                    short_by: miss.short_by,
                    limit: miss.limit,
                    base_hint: hint,
                    base,
                });
            }
        }
    }
    out
}

/// How an aim was missed: the closest solve (position m, rotation rad), and how far along the
/// first grasp's path the arm got, where it took the grasp but not the path.
struct Miss {
    short_by: Option<(f64, f64)>,
    stopped: Option<usize>,
    /// Where the target is within the arm's reach but only past a joint's range.
    limit: Option<JointLimit>,
}

/// A joint a target needs past its range: the arm reaches the pose, but not within its limits.
#[derive(Clone, Debug, PartialEq)]
pub struct JointLimit {
    pub joint: String,
    /// The angle the solve with the ranges widened needs (rad).
    pub needed: f64,
    pub range: (f64, f64),
}

/// How far past its range the unbounded solve may take a joint (rad): half a turn.
const LIMIT_SLACK: f64 = std::f64::consts::PI;

/// The arm's kinematics with every joint's range widened by [`LIMIT_SLACK`]: where the arm
/// solves a pose this way but not within its ranges, a joint limit is why.
struct Widened<'a>(&'a mut ArmKinematics);

impl primitives::Kinematics for Widened<'_> {
    fn dof(&self) -> usize {
        self.0.dof()
    }
    fn limits(&self) -> Vec<(f64, f64)> {
        self.0
            .limits()
            .into_iter()
            .map(|(lo, hi)| (lo - LIMIT_SLACK, hi + LIMIT_SLACK))
            .collect()
    }
    fn tcp(&mut self, q: &[f64]) -> Pose {
        self.0.tcp(q)
    }
    fn jacobian(&mut self, q: &[f64]) -> (Pose, Vec<[f64; 6]>) {
        self.0.jacobian(q)
    }
}

/// The joint furthest past its range in a solve of `pose` with the ranges widened, from the
/// first of `seeds` that solves so; `None` where none does (the pose is out of reach itself) or
/// the solve keeps within the ranges.
fn past_limit(
    model: &robots::RobotModel,
    kin: &mut ArmKinematics,
    pose: &Pose,
    seeds: &[Vec<f64>],
) -> Option<JointLimit> {
    let limits = primitives::Kinematics::limits(kin);
    let q = seeds
        .iter()
        .find_map(|seed| solve_with(model.ik, &mut Widened(kin), pose, seed).ok())?;
    let (i, excess) = q
        .iter()
        .zip(&limits)
        .map(|(v, (lo, hi))| (lo - v).max(v - hi))
        .enumerate()
        .max_by(|a, b| a.1.total_cmp(&b.1))?;
    (excess > 1e-6).then(|| JointLimit {
        joint: model.arm_joints[i].to_string(),
        needed: q[i],
        range: limits[i],
    })
}

/// The arm's solution at the end of `aim` (its grasp, then its path, each pose from the last),
/// from the first of `starts` that gets there: the first grasp, as the expert takes it; the
/// other only where the first cannot be taken at all (the expert's second try), with its own
/// path.
fn reach(
    model: &robots::RobotModel,
    kin: &mut ArmKinematics,
    aim: &Aim,
    starts: &[Vec<f64>],
) -> Result<Vec<f64>, Miss> {
    let mut miss = Miss {
        short_by: None,
        stopped: None,
        limit: None,
    };
    let note = |e: &primitives::IkError, miss: &mut Miss| {
        if let primitives::IkError::NoConvergence { pos_err, rot_err } = e {
            let closer = miss
                .short_by
                .is_none_or(|(p, r)| (*pos_err, *rot_err) < (p, r));
            if closer {
                miss.short_by = Some((*pos_err, *rot_err));
            }
        }
    };
    for (g, (grasp, path)) in aim.grasps.iter().enumerate() {
        let mut taken = false;
        for seed in starts {
            let mut q = match solve_with(model.ik, kin, grasp, seed) {
                Ok(q) => q,
                Err(e) => {
                    note(&e, &mut miss);
                    if g == 0 && miss.limit.is_none() {
                        miss.limit = past_limit(model, kin, grasp, starts);
                    }
                    continue;
                }
            };
            taken = true;
            let mut followed = true;
            for (k, at) in path.iter().enumerate() {
                match solve_with(model.ik, kin, at, &q) {
                    Ok(next) => q = next,
                    Err(e) => {
                        note(&e, &mut miss);
                        if g == 0 {
                            if miss.stopped.is_none_or(|s| k > s) {
                                miss.limit = past_limit(model, kin, at, &[q.clone()]);
                            }
                            miss.stopped = Some(miss.stopped.map_or(k, |s| s.max(k)));
                        }
                        followed = false;
                        break;
                    }
                }
            }
            if followed {
                return Ok(q);
            }
        }
        // The expert takes the other grasp only where this one cannot be taken.
        if taken {
            break;
        }
    }
    Err(miss)
}

/// The targets the pass checks, step by step: each step's first target where the step's item is
/// where it started; and for an item a robot picked up, the seat it is then placed on, with the
/// item held as the pick grasped it (the seat's tool pose depends on that).
fn aims(
    task: &Task,
    scene: &Scene,
    states: &mut [LabwareState],
    params: &compiler::params::Bindings,
    kins: &mut [ArmKinematics],
    start: &[Vec<f64>],
) -> Vec<Aim> {
    // Items in a hand since a pick (by which robot, grasped with the tool where), and items
    // that have been put somewhere else.
    let mut held: BTreeMap<String, (usize, Pose)> = BTreeMap::new();
    let mut placed = BTreeSet::new();
    // Whether an earlier step has moved some labware's joints (a lid opened).
    let mut moved_joints = false;
    let mut out = Vec::new();
    for (i, (_, step)) in task.steps().enumerate() {
        let Some(robot) = task.robot_index(&step.robot) else {
            continue;
        };
        let Some(expand) = compiler::primitives::primitive(&step.primitive).and_then(|p| p.motions)
        else {
            continue;
        };
        let args: BTreeMap<String, String> = step
            .args
            .iter()
            .map(|(k, v)| (k.clone(), render(v, params).unwrap_or_else(|_| v.clone())))
            .collect();
        let on = args.get("on").cloned();
        let kind = on
            .as_ref()
            .and_then(|on| task.labware.iter().find(|l| &l.name == on))
            .and_then(|l| labware::kind(&l.kind));
        let tool = task.liquid_tool(&step.robot, i);
        let motions = expand(&MotionStep {
            args: &args,
            kind,
            tool,
        });
        // The labware as earlier steps left its joints (a lid opened).
        let owned = states.to_vec();
        let lab = &Lab::new(task, &owned, params);
        let seats: Vec<&Motion> = motions
            .iter()
            .filter(|m| {
                matches!(
                    m,
                    Motion::Reach {
                        target: Target::Seat { .. }
                    } | Motion::Transit {
                        target: Target::Seat { .. }
                    }
                )
            })
            .collect();
        // A pick puts its item itself in the hand (an unscrewing lifts the cap, not the tube).
        let picks = step.primitive == "pick";
        let g = scene.robots[robot].model.gripper;
        if let Some(item) = &on {
            if placed.contains(item) {
                continue;
            }
            if !seats.is_empty() {
                placed.insert(item.clone());
                // Placed by the robot that picked it: the seat as that grasp carries the item.
                let Some((_, grasp)) = held.remove(item).filter(|(r, _)| *r == robot) else {
                    continue;
                };
                let frame =
                    StepFrame::new(&motions, lab, &grasp, Some(item), g.finger_reach, g.enclose);
                let Ok(frame) = frame else { continue };
                for m in seats {
                    if let Ok(Some(pose)) = frame.first_pose(std::slice::from_ref(m), lab) {
                        out.push(Aim {
                            step: i,
                            robot,
                            target: target_name(std::slice::from_ref(m)),
                            grasps: vec![(pose, Vec::new())],
                            as_started: false,
                        });
                    }
                }
                continue;
            }
            if held.contains_key(item) {
                continue;
            }
        }
        let tcp = primitives::Kinematics::tcp(&mut kins[robot], &start[robot]);
        let Ok(frame) = StepFrame::new(
            &motions,
            lab,
            &tcp,
            on.as_deref(),
            g.finger_reach,
            g.enclose,
        ) else {
            continue;
        };
        // A held tool brought onto an opening (a pipette's tip over a tube's mouth, then under
        // its surface): each place it is brought to, as the tool sits in the hand at the start,
        // at any heading about the opening's axis the expert may take.
        if matches!(first_target(&motions), Some(Target::Bring { .. })) {
            let as_started = !moved_joints && held.values().all(|(r, _)| *r != robot);
            let mut seen: Vec<&Target> = Vec::new();
            for m in &motions {
                let Motion::Reach { target } = m else {
                    continue;
                };
                if seen.contains(&target) {
                    continue;
                }
                seen.push(target);
                // The headings the expert tries where its first is blocked.
                let grasps: Vec<(Pose, Vec<Pose>)> = frame
                    .headings()
                    .filter_map(|f| f.pose_toward(target, lab, &tcp).ok())
                    .map(|p| (p, Vec::new()))
                    .collect();
                if !grasps.is_empty() {
                    out.push(Aim {
                        step: i,
                        robot,
                        target: target_name(std::slice::from_ref(m)),
                        grasps,
                        as_started,
                    });
                }
            }
            continue;
        }
        let Ok(Some(pose)) = frame.first_pose(&motions, lab) else {
            continue;
        };
        if picks && let Some(item) = &on {
            held.insert(item.clone(), (robot, pose));
        }
        // The lid (and lever) where the grip takes it, then each grasp's path.
        if let Some(Target::Affordance { labware, goals, .. }) = first_target(&motions) {
            set_goals(task, states, params, labware, goals);
        }
        let as_started = !moved_joints && held.values().all(|(r, _)| *r != robot);
        // A lift after the grasp (a pick's, a cap's): straight up, holding what was gripped.
        let lift = motions.iter().find_map(|m| match m {
            Motion::Lift { height } => Some(*height),
            _ => None,
        });
        let lifted = |at: &Pose, mut path: Vec<Pose>| {
            path.extend(lift.map(|h| labware::frame::translation([0.0, 0.0, h]) * at));
            path
        };
        // Either of a symmetric affordance's grasps, as the expert may take them.
        let grasps: Vec<(Pose, Vec<Pose>)> = frame
            .symmetric_grasps()
            .filter_map(|f| {
                let at = f.first_pose(&motions, lab).ok().flatten()?;
                let path = follow(task, states, params, &f, &motions, &at);
                Some((at, lifted(&at, path)))
            })
            .collect();
        // Where the step leaves the labware's joints, for the steps after it.
        for m in &motions {
            if let Motion::Follow { labware, goals, .. } = m {
                set_goals(task, states, params, labware, goals);
                moved_joints = true;
            }
        }
        // Where the arm comes in from: the standoff back along the target's axis (4 cm above a
        // tube's grasp), for each grasp.
        let standoff = motions.iter().find_map(|m| match m {
            Motion::Approach { standoff, .. } => Some(*standoff),
            _ => None,
        });
        let approach = standoff.map(|d| {
            let back = labware::frame::translation([0.0, 0.0, -d]);
            Aim {
                step: i,
                robot,
                target: format!(
                    "{} (coming in {:.0} cm back along it)",
                    target_name(&motions),
                    d * 100.0
                ),
                grasps: grasps.iter().map(|(g, _)| (g * back, Vec::new())).collect(),
                as_started,
            }
        });
        // The way in first, as the arm comes: the target's aim is then the arm's last solution
        // for the steps after it (the end of its arc or lift).
        out.extend(approach);
        out.push(Aim {
            step: i,
            robot,
            target: target_name(&motions),
            grasps,
            as_started,
        });
    }
    out
}

/// The tool poses of a step's `Follow` motions in order, from its grasp at `from` with `frame`,
/// each from where the one before leaves the labware's joints (`states` as the grip takes it).
fn follow(
    task: &Task,
    states: &[LabwareState],
    params: &compiler::params::Bindings,
    frame: &StepFrame,
    motions: &[Motion],
    from: &Pose,
) -> Vec<Pose> {
    let mut states = states.to_vec();
    let mut path = Vec::new();
    let mut tcp = *from;
    for m in motions {
        let Motion::Follow { labware, goals, .. } = m else {
            continue;
        };
        let lab = Lab::new(task, &states, params);
        let Ok(poses) = frame.poses(m, &lab, &tcp) else {
            return path;
        };
        path.extend(poses.iter().skip(1).copied());
        tcp = *poses.last().unwrap_or(&tcp);
        set_goals(task, &mut states, params, labware, goals);
    }
    path
}

/// Sets `labware`'s joints to `goals` as the expert resolves them (`Lab::at_goals`: roles it
/// lacks, a lever on a lid without one, are skipped); a goal it cannot resolve leaves it as is.
fn set_goals(
    task: &Task,
    states: &mut [LabwareState],
    params: &compiler::params::Bindings,
    labware: &str,
    goals: &compiler::motion::Goals,
) {
    let Some(i) = task.labware_index(labware) else {
        return;
    };
    let owned = states.to_vec();
    if let Ok(at) = Lab::new(task, &owned, params).at_goals(labware, goals) {
        states[i] = at;
    }
}

/// What a step's motions aim at first, for a reader.
fn target_name(motions: &[Motion]) -> String {
    match first_target(motions) {
        Some(Target::Affordance { labware, name, .. }) => format!("`{labware}`'s `{name}`"),
        Some(Target::Button { labware, param, .. }) => {
            format!("the button that sets `{labware}.{param}`")
        }
        Some(Target::Seat { location, above }) if *above > 0.0 => {
            format!("{:.0} mm above the seat `{location}`", above * 1000.0)
        }
        Some(Target::Seat { location, .. }) => format!("the seat `{location}`"),
        Some(Target::Carry { labware, to, .. }) => format!("`{labware}`'s `{to}`"),
        Some(Target::Bring {
            carried,
            from,
            labware,
            to,
            ..
        }) => format!("`{carried}`'s `{from}` onto `{labware}`'s `{to}`"),
        None => "its target".into(),
    }
}

/// The nearest base (m) for the robot, now at `base`, from which every one of its `aims` solves
/// (one grasp of each, from its home, then its path) with `HINT_MARGIN` to spare (the grasp
/// moved that much farther out from the base solves too) and which `clear` accepts, searched
/// ring by ring in the plane at the base's height, then on rings around each raised height in
/// turn; `None` within the search. The margin is the expert's room around a grasp: the approach
/// before it, the lift after it.
fn base_shift(
    aims: &[&Aim],
    model: &robots::RobotModel,
    kin: &mut ArmKinematics,
    base: [f64; 3],
    mut clear: impl FnMut([f64; 3]) -> bool,
) -> Option<[f64; 3]> {
    // Reached bases stood up and checked, per height: the raised search gets its own budget.
    let mut tried: BTreeMap<u64, usize> = BTreeMap::new();
    let home = model.home.to_vec();
    let rings = (HINT_RADIUS / HINT_STEP).round() as usize;
    let around = |rise: f64, first: usize| {
        (first..=rings).flat_map(move |k| {
            let directions = if k == 0 { 1 } else { HINT_DIRECTIONS };
            (0..directions).map(move |j| {
                let a = std::f64::consts::TAU * j as f64 / HINT_DIRECTIONS as f64;
                let r = k as f64 * HINT_STEP;
                [r * a.cos(), r * a.sin(), rise]
            })
        })
    };
    let level = around(0.0, 1);
    let raised = (1..=HINT_RISES).flat_map(|k| around(k as f64 * HINT_RISE, 0));
    level
        .chain(raised)
        .find(|d| {
            let height = tried.entry(d[2].to_bits()).or_default();
            if *height >= HINT_CLEAR_TRIES {
                return false;
            }
            // The base moved by d reaches what the base where it is reaches moved by -d.
            let back = labware::frame::translation([-d[0], -d[1], -d[2]]);
            let reached = aims.iter().all(|aim| {
                aim.grasps.iter().any(|(pose, path)| {
                    let near = back * pose;
                    let p = near.translation.vector;
                    let out = nalgebra::Vector2::new(p.x - base[0], p.y - base[1]);
                    let out = out.try_normalize(1e-9).unwrap_or_default() * HINT_MARGIN;
                    let far = labware::frame::translation([out.x, out.y, 0.0]) * near;
                    if solve_with(model.ik, kin, &far, &home).is_err() {
                        return false;
                    }
                    let Ok(mut q) = solve_with(model.ik, kin, &near, &home) else {
                        return false;
                    };
                    // And the path it then follows, each pose from the last.
                    path.iter().all(|at| {
                        solve_with(model.ik, kin, &(back * at), &q)
                            .map(|next| q = next)
                            .is_ok()
                    })
                })
            });
            // Reached: then stood there for real, clear of the scene on the way in.
            reached && {
                *tried.entry(d[2].to_bits()).or_default() += 1;
                clear([base[0] + d[0], base[1] + d[1], base[2] + d[2]])
            }
        })
        .map(|d| [base[0] + d[0], base[1] + d[1], base[2] + d[2]])
}

/// Whether `robot` stood at `base` (the task otherwise as it is) has an IK solution clear of
/// the scene for every aim's approach (`HINT_APPROACH` back along the grasp's axis, where the
/// expert comes in from): a base the arm reaches from can still put its upper arm through an
/// instrument.
fn clear_from(
    task: &Task,
    instance: &compiler::SceneInstance,
    robot: usize,
    base: [f64; 3],
    aims: &[&Aim],
) -> bool {
    let mut moved = task.clone();
    moved.robots[robot].base.translation.vector = nalgebra::Vector3::new(base[0], base[1], base[2]);
    let Ok(scene) = Scene::build(&moved, instance) else {
        return false;
    };
    let scene = Arc::new(scene);
    let episode = Episode::new(scene.clone(), &moved, instance);
    let mut kin = ArmKinematics::new(&scene, robot);
    let mut clearance = Clearance::new(&scene, robot);
    clearance.sync(&episode.qpos(), None);
    // Stood inside something (an instrument, the other robot), the arm touches it at its start.
    if clearance.touching_at_sync() > 0 {
        return false;
    }
    let model = scene.robots[robot].model;
    let starts = [instance.robot_q[robot].clone(), model.home.to_vec()];
    aims.iter().filter(|aim| aim.as_started).all(|aim| {
        aim.grasps.iter().any(|(grasp, _)| {
            let approach = labware::frame::translated_local(grasp, [0.0, 0.0, -HINT_APPROACH]);
            starts.iter().any(|seed| {
                solve_with(model.ik, &mut kin, &approach, seed)
                    .is_ok_and(|q| clearance.may_end_at(&q))
            })
        })
    })
}

/// E0036 for every unreachable step of a single protocol file that checked clean, at the step's
/// `with`; appended to `checked`, whose task is then dropped, as for any other error.
pub fn check(checked: &mut Checked) {
    let Some(task) = &checked.task else {
        return;
    };
    // A position metres off any bench (W0003) is a unit slip to fix first, not a reach to judge.
    if checked.diagnostics.iter().any(|d| d.code == Code::W0003) {
        return;
    }
    let (doc, _) = dsl::parse(&checked.source);
    let Document::Protocol(protocol) = &doc else {
        return;
    };
    let steps = &protocol.steps;
    let missed = unreachable(task);
    if missed.is_empty() {
        partly(checked, steps);
        return;
    }
    for m in &missed {
        let Some(step) = steps.get(m.step) else {
            continue;
        };
        let span = step.with.as_ref().map(|w| w.span).unwrap_or(step.span);
        let [x, y, z] = m.at;
        let how = match (&m.limit, m.short_by) {
            (Some(l), _) => format!(
                ": within the arm's reach, but only past joint `{}`'s range (it would need {:.2} rad; its range is {:.2}..{:.2} rad)",
                l.joint, l.needed, l.range.0, l.range.1
            ),
            (None, Some((p, r))) => format!(
                ", the closest solve {:.0} mm and {r:.2} rad off",
                p * 1000.0
            ),
            (None, None) => String::new(),
        };
        let mut d = Diagnostic::new(
            Code::E0036,
            span,
            format!(
                "`{}` cannot reach step {}'s target, {}, at ({x:.3}, {y:.3}, {z:.3}) m{how}",
                m.robot,
                m.step + 1,
                m.target
            ),
        )
        .with_note("checked in seed 0's layout, from the robot's start pose and its home");
        d = match m.base_hint {
            Some(hint) => d.with_hint(format!(
                "stand `{}` at {}: every target checked for it, in all {SAMPLED_LAYOUTS} sampled layouts, solves from there",
                m.robot,
                stand_at(hint, m.base)
            )),
            None => d.with_hint(format!(
                "no base found within {HINT_RADIUS} m of `{}`'s (or up to {:.1} m above it) that reaches every target checked for it in all {SAMPLED_LAYOUTS} sampled layouts; move the labware or the robot",
                m.robot,
                HINT_RISE * HINT_RISES as f64
            )),
        };
        checked.diagnostics.push(d);
    }
    checked.task = None;
}

/// A hinted base as the hint writes it: the position, how far it is from `base` in the plane,
/// and how much higher, where it is.
fn stand_at([hx, hy, hz]: [f64; 3], [bx, by, bz]: [f64; 3]) -> String {
    let dist = ((hx - bx).powi(2) + (hy - by).powi(2)).sqrt();
    let rise = hz - bz;
    // To the millimetre written, without a "-0.000".
    let mm = |v: f64| (v * 1000.0).round() / 1000.0 + 0.0;
    let (hx, hy, hz) = (mm(hx), mm(hy), mm(hz));
    let raised = if rise > 1e-9 {
        format!(", {rise:.2} m higher: on a riser")
    } else {
        String::new()
    };
    format!("pos_m = [{hx:.3}, {hy:.3}, {hz:.3}] ({dist:.3} m from where it is{raised})")
}

/// The nearest base for `robot` from which its targets in every sampled layout solve (as
/// [`base_shift`] searches) and its arm comes in clear in each: the hint of E0036 and of W0010.
fn base_for_every_layout(task: &Task, robot: usize) -> Option<[f64; 3]> {
    let mut layouts: Vec<Layout> = (0..SAMPLED_LAYOUTS)
        .filter_map(|seed| Layout::of(task, seed))
        .collect();
    let mut kin = layouts.first_mut()?.kins.swap_remove(robot);
    let model = layouts[0].scene.robots[robot].model;

    let all: Vec<&Aim> = layouts.iter().flat_map(|l| aims_of(l, robot)).collect();
    let base = task.robots[robot].base.translation.vector;
    let base = [base.x, base.y, base.z];
    base_shift(&all, model, &mut kin, base, |at| {
        layouts
            .iter()
            .all(|l| clear_from(task, &l.instance, robot, at, &aims_of(l, robot)))
    })
}

/// `robot`'s aims in `layout`.
fn aims_of(layout: &Layout, robot: usize) -> Vec<&Aim> {
    layout.aims.iter().filter(|a| a.robot == robot).collect()
}

/// W0010 for every step reached in seed 0's layout but not in some of the next ones, at the
/// step's `with`: the task checks, but some episodes will fail at planning.
fn partly(checked: &mut Checked, steps: &[dsl::ast::Step]) {
    let Some(task) = &checked.task else {
        return;
    };
    let planned: Vec<&compiler::PlannedStep> = task.steps().map(|(_, s)| s).collect();
    // Called where seed 0's layout misses nothing: only the next seeds are left to solve.
    let mut hints: BTreeMap<usize, Option<[f64; 3]>> = BTreeMap::new();
    for (i, seeds) in beyond_seed_0(task, &BTreeSet::new()) {
        let (Some(step), Some(planned)) = (steps.get(i), planned.get(i)) else {
            continue;
        };
        let span = step.with.as_ref().map(|w| w.span).unwrap_or(step.span);
        let list: Vec<String> = seeds.iter().map(u64::to_string).collect();
        let first = seeds[0];
        let drawn: Vec<String> = task
            .sample(first)
            .params
            .iter()
            .map(|(k, v)| format!("{k} = {v}"))
            .collect();
        let mut d = Diagnostic::new(
            Code::W0010,
            span,
            format!(
                "`{}` reaches step {}'s target in seed 0's layout but not in {} of the next {} (seeds {})",
                planned.robot,
                i + 1,
                seeds.len(),
                SAMPLED_LAYOUTS - 1,
                list.join(", ")
            ),
        );
        if !drawn.is_empty() {
            d = d.with_note(format!("seed {first} draws {}", drawn.join(", ")));
        }
        let robot = task.robots.iter().position(|r| r.name == planned.robot);
        let found = robot.and_then(|r| {
            let hint = *hints
                .entry(r)
                .or_insert_with(|| base_for_every_layout(task, r));
            hint.map(|h| (r, h))
        });
        let hint = match found {
            Some((r, hint)) => {
                let base = task.robots[r].base.translation.vector;
                format!(
                    "stand `{}` at {}: its targets in all {SAMPLED_LAYOUTS} sampled layouts solve from there; or narrow what the seeds draw (`[params]`, `[randomise]`); `autobio render FILE --seed {first}` draws that layout",
                    planned.robot,
                    stand_at(hint, [base.x, base.y, base.z])
                )
            }
            None => format!(
                "narrow what the seeds draw (`[params]`, `[randomise]`) or stand `{}` nearer; `autobio render FILE --seed {first}` draws that layout",
                planned.robot
            ),
        };
        checked.diagnostics.push(d.with_hint(hint));
    }
}
