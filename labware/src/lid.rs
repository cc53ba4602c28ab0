//! The hinged lid the lidded instruments compose (the thermal cycler, the mini centrifuge, the
//! latched 5430 and 5910): its parameters ([`LidBody`], carried flat among the instrument's
//! own), its MuJoCo names, its rest frame, the MJCF of its hinge, inertia and latch constraint,
//! the angle it starts at, what "open" and "closed" measure, its readout (a latch's `locked` flag
//! first), its joint goals, the handle affordance and the latch's flag and switch roles; and
//! [`Lidded`], what an instrument with a lid answers through [`crate::Instrument::lidded`]. Each
//! instrument keeps its own geometry (shell, handle), its latch's mechanics and what "locked"
//! and "unlocked" measure (its [`Part`]); a fourth lidded kind composes the same.

use crate::frame::{Pose, Rot, Vec3, pose, x_turn};
use crate::mjcf::{box_inertia, pose_attrs, v3};
use crate::model::{Affordance, Joints, LabwareState, Lidded, Measure, Part, Symmetry};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// The logic flag a latched lid keeps while it is latched.
pub const LOCKED: &str = "locked";
/// The role of the equality constraint that holds a latched lid shut.
pub const LOCK_SWITCH: &str = "lock";
/// The lid's joint role.
pub const JOINT: &str = crate::model::LID;

/// The MuJoCo names of a lidded instrument's base and lid, under the item's prefix.
#[derive(Clone, Debug, PartialEq)]
pub struct LidNames {
    /// The instrument's base body, which carries the hinge.
    pub base: String,
    pub body: String,
    pub joint: String,
    /// The site of the handle the hand takes.
    pub grip: String,
    /// The latch's equality constraint (latched lids only).
    pub lock: String,
}

impl LidNames {
    pub fn new(prefix: &str) -> LidNames {
        LidNames {
            base: format!("{prefix}/base"),
            body: format!("{prefix}/lid"),
            joint: format!("{prefix}/lid_hinge"),
            grip: format!("{prefix}/grip"),
            lock: format!("{prefix}/lid_lock"),
        }
    }

    /// The MJCF of the whole instrument at `placement`: its base body with the base's `geoms`
    /// and the lid's body ([`Lid::body_xml`]) in it.
    pub fn instrument_xml(&self, placement: &Pose, geoms: &str, lid: &str) -> String {
        format!(
            "<body name=\"{}\" {}>\n{geoms}{lid}</body>\n",
            self.base,
            pose_attrs(placement)
        )
    }

    /// The latch's switch by role, for [`crate::Instrument::switches`].
    pub fn switches(&self) -> Vec<(&'static str, String)> {
        vec![(LOCK_SWITCH, self.lock.clone())]
    }
}

/// The lid's body as an instrument's parameters carry it: flattened among the instrument's own
/// fields, so that its keys read `lid_depth`, `lid_half_width`... as they always have.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct LidBody {
    /// Extent from the hinge to the front edge, half width and half thickness (m).
    #[serde(rename = "lid_depth")]
    pub depth: f64,
    #[serde(rename = "lid_half_width")]
    pub half_width: f64,
    #[serde(rename = "lid_half_thickness")]
    pub half_thickness: f64,
    /// Mass (kg) and the hinge's damping (N·m·s/rad).
    #[serde(rename = "lid_mass")]
    pub mass: f64,
    #[serde(rename = "lid_damping")]
    pub damping: f64,
}

impl LidBody {
    /// The lid on its hinge: its open and closed angles, the named tolerances of `lid is open`
    /// and `lid is closed` (rad), and no spring.
    pub fn hinged(
        self,
        [open, closed]: [f64; 2],
        [open_tolerance, closed_tolerance]: [f64; 2],
    ) -> Lid {
        Lid {
            body: self,
            open,
            closed,
            spring: None,
            open_tolerance,
            closed_tolerance,
            closing_to: None,
        }
    }

    /// Half extents of the lid as a box: across, from the hinge to the front edge, thickness.
    pub fn half(&self) -> Vec3 {
        [self.half_width, self.depth / 2.0, self.half_thickness]
    }
}

/// A lid on a hinge about the instrument's x axis: its body, its open and closed angles, a
/// spring towards open if it has one, and the named tolerances of `lid is open` and `lid is
/// closed` (rad).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lid {
    pub body: LidBody,
    pub open: f64,
    pub closed: f64,
    /// Spring stiffness towards open (N·m/rad).
    pub spring: Option<f64>,
    pub open_tolerance: f64,
    pub closed_tolerance: f64,
    /// Where the expert drives the lid to close it, where that is past its closed angle (a lid
    /// pressed down so that its latch catches against its spring); `None`: the closed angle.
    pub closing_to: Option<f64>,
}

impl Lid {
    /// The lid body's orientation at joint angle 0: the closed geometry turned open about +x.
    pub fn rest(&self) -> Rot {
        x_turn(self.open - self.closed)
    }

    /// The lid's frame at joint angle `angle`, its hinge at `hinge` (in the frame `hinge` is
    /// given in): x along the hinge, y towards the front edge, z the lid's outward normal.
    pub fn frame(&self, hinge: Vec3, angle: f64) -> Pose {
        pose(hinge, self.rest() * x_turn(angle))
    }

    /// The MJCF of the lid's body at `hinge` (in the base's frame): the `<body>` at rest, its
    /// hinge joint over the lid's range, its inertia as a box of the lid's extents centred at
    /// `centre` (in the lid's frame), and the instrument's `geoms` for it (its shell, handle).
    pub fn body_xml(&self, names: &LidNames, hinge: Vec3, centre: Vec3, geoms: &str) -> String {
        let b = &self.body;
        let spring = self.spring.map_or(String::new(), |k| {
            format!(" stiffness=\"{k}\" springref=\"{}\"", self.open)
        });
        format!(
            r#"  <body name="{body}" {frame}>
    <joint name="{joint}" type="hinge" axis="1 0 0" range="{lo} {hi}" damping="{damping}"{spring} solreflimit="0.004 1" solimplimit="0.95 0.99 0.0005"/>
    <inertial pos="{centre}" mass="{mass}" diaginertia="{inertia}"/>
{geoms}  </body>
"#,
            body = names.body,
            frame = pose_attrs(&pose(hinge, self.rest())),
            joint = names.joint,
            lo = self.closed.min(self.open),
            hi = self.closed.max(self.open),
            damping = b.damping,
            centre = v3(centre),
            mass = b.mass,
            inertia = v3(box_inertia(b.mass, b.half())),
        )
    }

    /// The MJCF of the whole instrument at `placement`: its base body with the base's `geoms`
    /// and the lid's body ([`Lid::body_xml`]) in it.
    pub fn instrument_xml(names: &LidNames, placement: &Pose, geoms: &str, lid: &str) -> String {
        format!(
            "<body name=\"{}\" {}>\n{geoms}{lid}</body>\n",
            names.base,
            pose_attrs(placement)
        )
    }

    /// The latch's equality constraint, off until the latch switches it on: it holds the lid at
    /// its closed angle.
    pub fn lock_xml(&self, names: &LidNames) -> String {
        format!(
            "<joint name=\"{}\" joint1=\"{}\" polycoef=\"{} 0 0 0 0\" active=\"false\" solref=\"0.01 1\"/>\n",
            names.lock, names.joint, self.closed
        )
    }

    /// The declared start state of the lid (`open` when none is declared) and the angle it
    /// starts at: open when declared open, else closed.
    pub fn start<'a>(&self, initial: &'a BTreeMap<String, String>) -> (&'a str, f64) {
        let state = initial.get(JOINT).map(String::as_str).unwrap_or("open");
        (
            state,
            if state == "open" {
                self.open
            } else {
                self.closed
            },
        )
    }

    /// The lid's angle among a step's joints (open when it is missing).
    pub fn angle(&self, joints: &Joints) -> f64 {
        joints.get(JOINT).copied().unwrap_or(self.open)
    }

    pub fn is_closed(&self, angle: f64) -> bool {
        (angle - self.closed).abs() < self.closed_tolerance
    }

    /// `lid is open` / `lid is closed` at `angle` (tolerance: the predicate's, else the lid's);
    /// `None` for any other state (a latch's `locked` is the instrument's).
    pub fn measure(&self, state: &str, angle: f64, tolerance: Option<f64>) -> Option<Measure> {
        let (target, default) = match state {
            "open" => (self.open, self.open_tolerance),
            "closed" => (self.closed, self.closed_tolerance),
            _ => return None,
        };
        Some(Measure::near(angle, target, tolerance.unwrap_or(default)))
    }

    /// The lid's state for recordings and reports: `locked` while latched, else `closed` or
    /// `open` by its angle.
    pub fn readout(&self, s: &LabwareState) -> BTreeMap<String, String> {
        let state = if s.flag(LOCKED) {
            "locked"
        } else if self.is_closed(s.joint(JOINT)) {
            "closed"
        } else {
            "open"
        };
        BTreeMap::from([(JOINT.to_string(), state.to_string())])
    }

    /// The angle of a named goal (`open`, `closed`).
    pub fn goal(&self, goal: &str) -> Option<f64> {
        match goal {
            "open" => Some(self.open),
            "closed" => Some(self.closing_to.unwrap_or(self.closed)),
            _ => None,
        }
    }
}

/// An instrument that composes a [`Lid`]: every such instrument is [`Lidded`] (the
/// `Instrument::lidded` component) through the lid's own goals and readout.
pub trait HasLid: Part {
    /// The lid, from the instrument's parameters.
    fn lid(&self) -> Lid;
}

impl<T: HasLid> Lidded for T {
    fn lid_goal(&self, goal: &str) -> Option<f64> {
        self.lid().goal(goal)
    }

    fn lid_readout(&self, s: &LabwareState) -> BTreeMap<String, String> {
        self.lid().readout(s)
    }
}

/// The affordance of a lid taken by one handle to open it and to close it (`lid_open`,
/// `lid_close`): a grasp at `grip`, the same with the fingers swapped.
pub fn handle(name: &str, grip: impl FnOnce() -> Pose) -> Option<Affordance> {
    matches!(name, "lid_open" | "lid_close").then(|| Affordance {
        pose: grip(),
        symmetry: Symmetry::HalfTurn,
        touch: false,
        lead: 0.0,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lid() -> Lid {
        let body = LidBody {
            depth: 0.2,
            half_width: 0.1,
            half_thickness: 0.01,
            mass: 1.0,
            damping: 0.1,
        };
        body.hinged([0.0, -1.5], [0.1, 0.01])
    }

    #[test]
    fn open_and_closed_are_measured_against_their_tolerances() {
        let lid = lid();
        assert!(lid.measure("closed", -1.505, None).unwrap().holds);
        assert!(!lid.measure("closed", -1.45, None).unwrap().holds);
        assert!(lid.measure("closed", -1.45, Some(0.1)).unwrap().holds);
        assert!(lid.measure("open", 0.05, None).unwrap().holds);
        assert!(lid.measure("locked", -1.5, None).is_none());
        assert_eq!(lid.goal("closed"), Some(-1.5));
        assert!(lid.is_closed(-1.495) && !lid.is_closed(-1.4));
        let names = LidNames::new("cycler");
        assert_eq!(
            [names.base, names.body, names.joint, names.grip, names.lock],
            [
                "cycler/base",
                "cycler/lid",
                "cycler/lid_hinge",
                "cycler/grip",
                "cycler/lid_lock"
            ]
        );
    }

    #[test]
    fn a_sprung_lid_writes_its_spring_and_starts_where_declared() {
        let plain = lid();
        let names = LidNames::new("c");
        let xml = plain.body_xml(&names, [0.0; 3], [0.0, 0.1, 0.0], "");
        assert!(xml.contains("range=\"-1.5 0\"") && !xml.contains("stiffness"));
        assert!(xml.starts_with("  <body name=\"c/lid\" ") && xml.ends_with("/>\n  </body>\n"));
        let sprung = Lid {
            spring: Some(3.0),
            ..plain
        };
        let xml = sprung.body_xml(&names, [0.0; 3], [0.0, 0.1, 0.0], "");
        assert!(xml.contains("damping=\"0.1\" stiffness=\"3\" springref=\"0\" "));
        assert!(plain.lock_xml(&names).contains("polycoef=\"-1.5 0 0 0 0\""));
        let locked = BTreeMap::from([(JOINT.to_string(), "locked".to_string())]);
        assert_eq!(plain.start(&locked), ("locked", -1.5));
        assert_eq!(plain.start(&BTreeMap::new()), ("open", 0.0));
        let joints = BTreeMap::from([(JOINT.to_string(), -0.3)]);
        assert_eq!(plain.angle(&joints), -0.3);
        assert_eq!(plain.angle(&BTreeMap::new()), 0.0);
    }
}
