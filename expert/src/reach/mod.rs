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

use aims::aims;
use compiler::motion::{Motion, Target};
use compiler::{Checked, Task};
use dsl::{Code, Diagnostic};
use hint::base_for_every_layout;
use labware::{LabwareState, Pose};
use primitives::ik::solve_with;
use primitives::{Lab, StepFrame, first_target};
use runtime::clearance::Clearance;
use runtime::kinematics::ArmKinematics;
use runtime::{Episode, Scene};
use std::collections::{BTreeMap, BTreeSet};
use std::sync::Arc;

mod aims;
mod diagnostics;
mod hint;
mod store;

pub use diagnostics::check;
pub use store::Store;

/// One step's target that no start solves.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
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

/// What the reach pass leaves unchecked in a file as a whole, for `check` to say: a chain's
/// stages are each checked in their own file, not where the chain leaves the world.
pub fn not_checked(checked: &Checked) -> Option<&'static str> {
    let task = checked.task.as_ref()?;
    (task.stages.len() > 1)
        .then_some("not checked across the chain's stages; each stage file is checked alone")
}

/// Every step of `task` (a single stage) whose first target its robot cannot reach in seed 0's
/// layout; empty when all are reached, or when the pass does not apply (a chain, a scene the
/// runtime cannot build). Outcomes `store` keeps are not solved again.
pub fn unreachable(task: &Task, store: &Store) -> Vec<Unreachable> {
    misses(task, 0, true, store)
}

/// Whether every step of `task` is reached in each sampled layout (what [`check`] would say
/// nothing about), without searching for a base hint where one is not: synthesis's test.
pub fn reached_everywhere(task: &Task) -> bool {
    let store = Store::none();
    misses(task, 0, false, &store).is_empty()
        && beyond_seed_0(task, &BTreeSet::new(), &store).is_empty()
}

/// Layouts the pass samples: seed 0's (E0036) and the next ones (W0010).
pub const SAMPLED_LAYOUTS: u64 = 8;

/// For each step its robot reaches in seed 0's layout but not in some of the next
/// `SAMPLED_LAYOUTS - 1` seeds' (other slots drawn, labware placed elsewhere in its
/// randomisation), those seeds, in order; steps missed in seed 0 are E0036's, not listed.
pub fn partly_unreachable(task: &Task, store: &Store) -> BTreeMap<usize, Vec<u64>> {
    let first: BTreeSet<usize> = misses(task, 0, false, store)
        .iter()
        .map(|u| u.step)
        .collect();
    beyond_seed_0(task, &first, store)
}

/// The steps not in `first` (those missed in seed 0's layout) that the next seeds miss. The
/// layouts are solved on as many threads as the machine has cores (each builds its own scene);
/// the outcome does not depend on how many.
fn beyond_seed_0(task: &Task, first: &BTreeSet<usize>, store: &Store) -> BTreeMap<usize, Vec<u64>> {
    let seeds: Vec<u64> = (1..SAMPLED_LAYOUTS).collect();
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let next = std::sync::atomic::AtomicUsize::new(0);
    let mut solved: Vec<(u64, Vec<Unreachable>)> = std::thread::scope(|s| {
        let workers: Vec<_> = (0..threads.min(seeds.len()))
            .map(|_| {
                s.spawn(|| {
                    let mut mine = Vec::new();
                    loop {
                        let k = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                        let Some(&seed) = seeds.get(k) else {
                            return mine;
                        };
                        mine.push((seed, misses(task, seed, false, store)));
                    }
                })
            })
            .collect();
        workers
            .into_iter()
            .flat_map(|w| w.join().expect("a reach worker panicked"))
            .collect()
    });
    solved.sort_by_key(|(seed, _)| *seed);
    let mut out: BTreeMap<usize, Vec<u64>> = BTreeMap::new();
    for (seed, missed) in solved {
        for u in missed {
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
/// `hint` asks for them: as `store` keeps them, else solved.
fn misses(task: &Task, seed: u64, hint: bool, store: &Store) -> Vec<Unreachable> {
    store.misses(task, seed, hint, || solve_misses(task, seed, hint))
}

/// [`misses`], solved in the layout's scene.
fn solve_misses(task: &Task, seed: u64, hint: bool) -> Vec<Unreachable> {
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
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
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
    let note = |e: &primitives::ik::IkError, miss: &mut Miss| {
        if let primitives::ik::IkError::NoConvergence { pos_err, rot_err } = e {
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
