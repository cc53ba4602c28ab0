//! Collision checks for the expert's planner: whether one arm, at joint angles `q`, and the item
//! it carries are clear of everything else in the scene as it is now. Runs MuJoCo's own
//! collision detection (the full model's collision geoms) on a private copy of the model and
//! its own `MjData`, so the episode's state is never touched. It plans nothing (that is
//! `planner`), and it knows no instrument or joint by name: the moving set is found by body
//! owner.
//!
//! Contact pairs already touching when the check is synced (a gripper resting on a handle, a
//! tube still in its slot's sleeve) are allowed for that motion, as a motion planner's
//! allowed-collision matrix is seeded from the start state: the motion leaves those contacts,
//! it does not cause them.
//!
//! The arm keeps [`KEEP`] away from what can move (a hinged lid, a standing tube: a body on a
//! joint), and the item it carries keeps that far from everything, as a planner pads its
//! obstacles: the arm lags its commanded path by a few millimetres (more on a fast swing), a
//! path that grazed a lid open against its stop pushed it shut on the way, and a tube swung
//! past the 5430's housing at the checked millimetre clipped its rim and turned over in the
//! hand. What the arm is nearer than that where a motion starts or ends (the hand just let go
//! of the lid; a tube brought down over its slot in the rotor, or just lifted from its rack),
//! it may come as near to on the way, not nearer. The padding is a contact margin on the
//! check's own copy of the model; the episode's physics is untouched.

use crate::scene::{LabwareIds, Owner, RobotIds, Scene};
use labware::Pose;
use labware::frame::{from_wxyz, wxyz};
use mujoco_rs::prelude::*;
use std::collections::{BTreeMap, BTreeSet};
use std::sync::Arc;

/// A contact counts as a collision when the geoms overlap by more than this (m): resting
/// contacts between stacked items sit at fractions of a millimetre.
const PENETRATION: f64 = 0.001;

/// How far the arm's own bodies keep from a body that moves, and the carried item from anything
/// (m), unless they are nearer at the sync or at either end of the motion checked.
pub const KEEP: f64 = 0.015;

/// An item carried rigidly in the hand: each of its free joints follows the tool. Only the item
/// the caller names is carried: anything else in the hand would stay behind as an obstacle.
struct Carried {
    /// Each free joint's qpos address and its body's pose in the tool frame.
    free: Vec<(usize, Pose)>,
}

pub struct Clearance {
    data: MjData<Arc<MjModel>>,
    ids: RobotIds,
    robot: usize,
    labware: Vec<LabwareIds>,
    /// Per body: its owner (cloned from the scene).
    owner: Vec<Option<Owner>>,
    /// Per body: whether it moves with the arm in this check (the robot's, the carried item's).
    moving: Vec<bool>,
    carried: Option<Carried>,
    /// Body pairs (lower id first) in contact at the last sync.
    allowed: BTreeSet<(usize, usize)>,
    /// Pairs kept [`KEEP`] off (see `Contact::keeps_off`) nearer than that at the last sync: how
    /// near (m).
    near_at_sync: BTreeMap<(usize, usize), f64>,
    /// The same at the sync or at either end of the motion now checked ([`Clearance::ends_at`]).
    near: BTreeMap<(usize, usize), f64>,
    /// Per body: whether it sits on a joint of an item (can be knocked).
    movable: Vec<bool>,
    /// Validity checks since construction (a planned route reports how many it took).
    pub checks: u64,
}

impl Clearance {
    pub fn new(scene: &Scene, robot: usize) -> Clearance {
        let nbody = scene.model.ffi().nbody as usize;
        let weld = scene.model.body_weldid();
        let movable: Vec<bool> = (0..nbody)
            .map(|b| weld[b] != 0 && matches!(scene.body_owner[b], Some(Owner::Labware(_))))
            .collect();
        // The check's own model: contacts with moving bodies are found `KEEP` before they touch.
        // A body's margin bounds its geoms' (MuJoCo tests a body's bounding volumes with it before
        // its geoms: left at 0, a body of several geoms, the 5430's lid and its bar, would be
        // padded only where those volumes already touch).
        let mut model = (*scene.model).clone();
        for g in 0..model.ffi().ngeom as usize {
            let body = model.geom_bodyid()[g] as usize;
            if movable[body] {
                model.geom_margin_mut()[g] = KEEP;
            }
        }
        for (body, &moves) in movable.iter().enumerate() {
            if moves {
                let margin = &mut model.body_margin_mut()[body];
                *margin = margin.max(KEEP);
            }
        }
        Clearance {
            data: MjData::new(Arc::new(model)),
            ids: scene.robots[robot].clone(),
            robot,
            labware: scene.labware.clone(),
            owner: scene.body_owner.clone(),
            moving: vec![false; nbody],
            carried: None,
            allowed: BTreeSet::new(),
            near_at_sync: BTreeMap::new(),
            near: BTreeMap::new(),
            movable,
            checks: 0,
        }
    }

    /// Takes the scene's configuration `qpos` (the episode's [`crate::Episode::qpos`]) and the
    /// item the arm carries, if any (its index in the task): each of its free bodies keeps, in
    /// every check, the pose in the tool frame it has in `qpos` (the grasp as it is, slip and
    /// all). The contacts at this configuration become the allowed pairs, and what the arm (or
    /// what it carries) is nearer than [`KEEP`] to here it may come as near to in every check
    /// until the next sync.
    pub fn sync(&mut self, qpos: &[f64], carried: Option<usize>) {
        self.data.qpos_mut().copy_from_slice(qpos);
        self.data.kinematics();
        let robot = self.robot;
        self.moving = self
            .owner
            .iter()
            .map(|o| match o {
                Some(Owner::Robot(r)) => *r == robot,
                Some(Owner::Labware(l)) => carried == Some(*l),
                None => false,
            })
            .collect();
        let tool_from_world = self.tcp().inverse();
        self.carried = carried.map(|item| Carried {
            free: self.labware[item]
                .free
                .iter()
                .map(|f| (f.qpos, tool_from_world * self.free_pose(f.qpos)))
                .collect(),
        });
        self.data.collision();
        self.allowed = self
            .contacts()
            .filter(|c| c.depth_past(PENETRATION))
            .map(|c| c.pair)
            .collect();
        let mut near = BTreeMap::new();
        self.add_near(&mut near);
        self.near_at_sync = near.clone();
        self.near = near;
    }

    fn free_pose(&self, adr: usize) -> Pose {
        let q = &self.data.qpos()[adr..adr + 7];
        labware::frame::pose([q[0], q[1], q[2]], from_wxyz([q[3], q[4], q[5], q[6]]))
    }

    fn tcp(&self) -> Pose {
        let s = self.ids.tcp_site;
        labware::frame::pose(
            self.data.site_xpos()[s],
            labware::frame::from_rows(&self.data.site_xmat()[s]),
        )
    }

    /// Adds the pairs kept [`KEEP`] off that are nearer than that after the last collision pass
    /// to `near`, keeping the nearest distance of each pair.
    fn add_near(&self, near: &mut BTreeMap<(usize, usize), f64>) {
        for c in self.contacts().filter(|c| c.keeps_off) {
            let d = near.entry(c.pair).or_insert(c.dist);
            *d = d.min(c.dist);
        }
    }

    /// Checks from now on are for a motion from arm angles `start` to `end`: what the arm is
    /// nearer than [`KEEP`] to at either, it may come as near to on the way (the pairs near at
    /// the sync stay allowed; those of an earlier motion's ends do not).
    pub fn ends_at(&mut self, start: &[f64], end: &[f64]) {
        let mut near = self.near_at_sync.clone();
        for q in [start, end] {
            self.place(q);
            self.add_near(&mut near);
        }
        self.near = near;
    }

    /// Whether the arm at `q` overlaps anything beyond the allowed pairs, the padding around
    /// moving bodies aside: whether a motion may end there.
    pub fn may_end_at(&mut self, q: &[f64]) -> bool {
        self.checks += 1;
        self.place(q);
        !self
            .contacts()
            .any(|c| c.depth_past(PENETRATION) && !self.allowed.contains(&c.pair))
    }

    /// The contacts of the last collision pass between a moving body and one that is not.
    fn contacts(&self) -> impl Iterator<Item = Contact> + '_ {
        let geom_body = self.data.model().geom_bodyid();
        self.data.contact().iter().filter_map(move |c| {
            let (a, b) = (
                geom_body[c.geom[0] as usize] as usize,
                geom_body[c.geom[1] as usize] as usize,
            );
            if c.exclude != 0 || self.moving[a] == self.moving[b] {
                return None;
            }
            let (arm, other) = if self.moving[a] { (a, b) } else { (b, a) };
            Some(Contact {
                pair: (a.min(b), a.max(b)),
                dist: c.dist,
                // A carried item's bodies have the padding's margin (they are on joints), so
                // its contacts with fixed bodies are found `KEEP` out too.
                keeps_off: match self.owner[arm] {
                    Some(Owner::Robot(_)) => self.movable[other],
                    _ => true,
                },
            })
        })
    }

    /// Pairs (one moving, one not) that collide after the last collision pass: overlapping past
    /// [`PENETRATION`], or a pair kept [`KEEP`] off (an arm body and a moving one, the carried
    /// item and anything) nearer than that and than at the motion's ends.
    fn colliding_pairs(&self) -> Vec<(usize, usize)> {
        self.contacts()
            .filter(|c| {
                c.depth_past(PENETRATION)
                    || (c.keeps_off && c.dist < self.near.get(&c.pair).map_or(KEEP, |d| d - NEARER))
            })
            .map(|c| c.pair)
            .collect()
    }

    fn place(&mut self, q: &[f64]) {
        for (k, &adr) in self.ids.qpos.iter().enumerate() {
            self.data.qpos_mut()[adr] = q[k];
        }
        self.data.kinematics();
        if let Some(carried) = &self.carried {
            let tcp = self.tcp();
            let poses: Vec<(usize, Pose)> = carried
                .free
                .iter()
                .map(|(adr, p)| (*adr, tcp * p))
                .collect();
            for (adr, p) in poses {
                let t = p.translation.vector;
                let r = wxyz(&p.rotation);
                self.data.qpos_mut()[adr..adr + 7]
                    .copy_from_slice(&[t.x, t.y, t.z, r[0], r[1], r[2], r[3]]);
            }
            self.data.kinematics();
        }
        self.data.collision();
    }

    /// The bodies (moving, obstacle) that collide at arm angles `q`, beyond the allowed pairs.
    pub fn collisions(&mut self, q: &[f64]) -> Vec<(usize, usize)> {
        self.checks += 1;
        self.place(q);
        let mut pairs = self.colliding_pairs();
        pairs.retain(|p| !self.allowed.contains(p));
        pairs.sort_unstable();
        pairs.dedup();
        pairs
    }

    /// How many body pairs (one moving, one not) overlapped at the last sync, the moving one on
    /// a joint: the contacts the checks since allow. An arm stood inside something shows here;
    /// a robot's fixed base resting on its riser or the bench does not.
    pub fn touching_at_sync(&self) -> usize {
        let weld = self.data.model().body_weldid();
        self.allowed
            .iter()
            .filter(|(a, b)| {
                let moving = if self.moving[*a] { *a } else { *b };
                weld[moving] != 0
            })
            .count()
    }

    /// Whether the arm at `q` (with what it carries) is clear of everything else.
    pub fn is_clear(&mut self, q: &[f64]) -> bool {
        self.collisions(q).is_empty()
    }

    /// A body's name in the model, for diagnostics.
    pub fn body_name(&self, body: usize) -> String {
        self.data
            .model()
            .id_to_name(MjtObjBase::mjOBJ_BODY, body)
            .unwrap_or("?")
            .to_string()
    }
}

/// How much nearer than at a motion's ends an arm body may come to a moving body it already was within
/// [`KEEP`] of (m): the check's own rounding, not room to approach.
const NEARER: f64 = 0.0005;

/// One contact of a collision pass, as the checks read it.
struct Contact {
    /// The two bodies, lower id first.
    pair: (usize, usize),
    /// Signed distance (m): negative is overlap.
    dist: f64,
    /// An arm body against a body that moves, or the carried item against anything: kept
    /// [`KEEP`] off.
    keeps_off: bool,
}

impl Contact {
    fn depth_past(&self, depth: f64) -> bool {
        self.dist < -depth
    }
}
