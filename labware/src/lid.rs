//! The hinged lid the lidded instruments compose (the thermal cycler, the mini centrifuge, the
//! latched 5430 and 5910): its MuJoCo names, its rest frame, what "open" and "closed" measure,
//! its readout (a latch's `locked` flag first), its joint goals, and the latch's flag and switch
//! roles. Each instrument keeps its own geometry, handle and latch mechanics, and reaches its lid
//! through [`Lid`]; a fourth lidded kind composes the same.

use crate::frame::{Rot, x_turn};
use crate::model::{LabwareState, Measure};
use std::collections::BTreeMap;

/// The logic flag a latched lid keeps while it is latched.
pub const LOCKED: &str = "locked";
/// The role of the equality constraint that holds a latched lid shut.
pub const LOCK_SWITCH: &str = "lock";
/// The lid's joint role.
pub const JOINT: &str = "lid";

/// The MuJoCo names of a lid, under the item's prefix.
#[derive(Clone, Debug, PartialEq)]
pub struct LidNames {
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
            body: format!("{prefix}/lid"),
            joint: format!("{prefix}/lid_hinge"),
            grip: format!("{prefix}/grip"),
            lock: format!("{prefix}/lid_lock"),
        }
    }
}

/// A lid on a hinge about the instrument's x axis: its open and closed angles and the named
/// tolerances of `lid is open` and `lid is closed` (rad).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lid {
    pub open: f64,
    pub closed: f64,
    pub open_tolerance: f64,
    pub closed_tolerance: f64,
}

impl Lid {
    pub const fn new(open: f64, closed: f64, open_tolerance: f64, closed_tolerance: f64) -> Lid {
        Lid {
            open,
            closed,
            open_tolerance,
            closed_tolerance,
        }
    }

    /// The lid body's orientation at joint angle 0: the closed geometry turned open about +x.
    pub fn rest(&self) -> Rot {
        x_turn(self.open - self.closed)
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
        let tolerance = tolerance.unwrap_or(default);
        Some(Measure {
            value: angle,
            target,
            tolerance,
            holds: (angle - target).abs() <= tolerance,
        })
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
            "closed" => Some(self.closed),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn open_and_closed_are_measured_against_their_tolerances() {
        let lid = Lid {
            open: 0.0,
            closed: -1.5,
            open_tolerance: 0.1,
            closed_tolerance: 0.01,
        };
        assert!(lid.measure("closed", -1.505, None).unwrap().holds);
        assert!(!lid.measure("closed", -1.45, None).unwrap().holds);
        assert!(lid.measure("closed", -1.45, Some(0.1)).unwrap().holds);
        assert!(lid.measure("open", 0.05, None).unwrap().holds);
        assert!(lid.measure("locked", -1.5, None).is_none());
        assert_eq!(lid.goal("closed"), Some(-1.5));
        assert!(lid.is_closed(-1.495) && !lid.is_closed(-1.4));
        let names = LidNames::new("cycler");
        assert_eq!(
            [names.body, names.joint, names.grip, names.lock],
            [
                "cycler/lid",
                "cycler/lid_hinge",
                "cycler/grip",
                "cycler/lid_lock"
            ]
        );
    }
}
