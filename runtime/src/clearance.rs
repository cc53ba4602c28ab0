//! Collision checks for the expert's planner: whether one arm, at joint angles `q`, and the item
//! it carries are clear of everything else in the scene as it is now. Runs MuJoCo's own
//! collision detection (the full model's collision geoms) on a private `MjData`, so the
//! episode's state is never touched. It plans nothing (that is `planner`), and it knows no
//! instrument or joint by name: the moving set is found by body owner.
//!
//! Contact pairs already touching when the check is synced (a gripper resting on a handle, a
//! tube still in its slot's sleeve) are allowed for that motion, as a motion planner's
//! allowed-collision matrix is seeded from the start state: the motion leaves those contacts,
//! it does not cause them.

use crate::scene::{LabwareIds, Owner, RobotIds, Scene};
use labware::Pose;
use labware::frame::{from_wxyz, wxyz};
use mujoco_rs::prelude::*;
use std::collections::BTreeSet;
use std::sync::Arc;

/// A contact counts as a collision when the geoms overlap by more than this (m): resting
/// contacts between stacked items sit at fractions of a millimetre.
const PENETRATION: f64 = 0.001;

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
    /// Validity checks since construction (a planned route reports how many it took).
    pub checks: u64,
}

impl Clearance {
    pub fn new(scene: &Scene, robot: usize) -> Clearance {
        let nbody = scene.model.ffi().nbody as usize;
        Clearance {
            data: MjData::new(scene.model.clone()),
            ids: scene.robots[robot].clone(),
            robot,
            labware: scene.labware.clone(),
            owner: scene.body_owner.clone(),
            moving: vec![false; nbody],
            carried: None,
            allowed: BTreeSet::new(),
            checks: 0,
        }
    }

    /// Takes the scene's configuration `qpos` (the episode's [`crate::Episode::qpos`]) and the
    /// item the arm carries, if any (its index in the task): each of its free bodies keeps, in
    /// every check, the pose in the tool frame it has in `qpos` (the grasp as it is, slip and
    /// all). The contacts at this configuration become the allowed pairs.
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
        self.allowed = self.colliding_pairs().into_iter().collect();
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

    /// Pairs of bodies (one moving, one not) overlapping past [`PENETRATION`] after the last
    /// collision pass.
    fn colliding_pairs(&self) -> Vec<(usize, usize)> {
        let geom_body = self.data.model().geom_bodyid();
        let mut pairs = Vec::new();
        for c in self.data.contact() {
            if c.exclude != 0 || c.dist > -PENETRATION {
                continue;
            }
            let (a, b) = (
                geom_body[c.geom[0] as usize] as usize,
                geom_body[c.geom[1] as usize] as usize,
            );
            if self.moving[a] != self.moving[b] {
                pairs.push((a.min(b), a.max(b)));
            }
        }
        pairs
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
