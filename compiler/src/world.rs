//! The abstract world the compiler traces a plan through: part states, where each movable item
//! is, liquid volumes and the named liquids in them, instrument panel values, what each robot's
//! hand holds, how many times each item has been turned over in the stage, and the stage's lab
//! time. No geometry and no physics: just the facts the primitives' preconditions and effects
//! talk about.

use std::collections::BTreeMap;
use std::fmt;

/// Where a movable item is.
#[derive(Clone, Debug, PartialEq)]
pub enum Location {
    /// Standing on the bench at its declared pose.
    Bench,
    /// In a holder's slot.
    Slot { holder: String, slot: String },
    /// In a robot's gripper.
    Held { robot: String },
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Location::Bench => f.write_str("on the bench"),
            Location::Slot { holder, slot } => write!(f, "in `{holder}.{slot}`"),
            Location::Held { robot } => write!(f, "held by `{robot}`"),
        }
    }
}

/// What a robot's hand is doing.
#[derive(Clone, Debug, PartialEq)]
pub enum Hand {
    Empty,
    /// Carrying an item (it moves with the hand).
    Item(String),
    /// Holding the cap unscrewed from this tube.
    Cap(String),
    /// Gripping an item to keep it still where it is (`hold`).
    Stabilising(String),
}

impl fmt::Display for Hand {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Hand::Empty => f.write_str("empty"),
            Hand::Item(i) => write!(f, "holding `{i}`"),
            Hand::Cap(t) => write!(f, "holding the cap of `{t}`"),
            Hand::Stabilising(i) => write!(f, "holding `{i}` steady"),
        }
    }
}

#[derive(Clone, Debug, Default, PartialEq)]
pub struct World {
    /// (labware, part) -> state.
    pub parts: BTreeMap<(String, String), String>,
    /// Movable labware -> location.
    pub locations: BTreeMap<String, Location>,
    /// Containers -> volume (µL).
    pub volumes: BTreeMap<String, f64>,
    /// Items -> how many times they have been turned over and back (`invert`).
    pub inversions: BTreeMap<String, u32>,
    /// Containers -> named liquid -> how much of it they hold (µL; a share of `volumes`, the
    /// rest is unnamed liquid). Moved in proportion to a container's contents.
    pub contents: BTreeMap<String, BTreeMap<String, f64>>,
    /// (instrument, panel parameter) -> displayed value (its canonical unit).
    pub panel: BTreeMap<(String, String), f64>,
    pub hands: BTreeMap<String, Hand>,
    /// Seconds of button holding the panel steps so far have needed (the proof resets it at
    /// each stage and compares it with the stage's time limit: W0009).
    pub panel_hold_s: f64,
    /// Seconds of lab time the stage's steps so far take at least: their waits and instrument
    /// runs (motions take time on top). The proof resets it at each stage; time constraints and
    /// E0039 read it.
    pub clock_s: f64,
}

impl World {
    /// How much of the named liquid a container holds (µL; none kept: 0).
    pub fn liquid_ul(&self, container: &str, liquid: &str) -> f64 {
        self.contents
            .get(container)
            .and_then(|c| c.get(liquid))
            .copied()
            .unwrap_or(0.0)
    }

    /// Moves `volume` µL of a container's liquid to another, its named liquids in proportion to
    /// what the first holds (the volumes themselves are the caller's).
    pub fn move_contents(&mut self, from: &str, to: &str, volume: f64) {
        let have = self.volumes.get(from).copied().unwrap_or(0.0);
        if have <= 0.0 {
            return;
        }
        let share = (volume / have).min(1.0);
        let moved: Vec<(String, f64)> = self
            .contents
            .get_mut(from)
            .map(|c| {
                c.iter_mut()
                    .map(|(liquid, ul)| {
                        let m = *ul * share;
                        *ul -= m;
                        (liquid.clone(), m)
                    })
                    .collect()
            })
            .unwrap_or_default();
        let into = self.contents.entry(to.to_string()).or_default();
        for (liquid, m) in moved {
            *into.entry(liquid).or_default() += m;
        }
    }

    pub fn part(&self, labware: &str, part: &str) -> Option<&str> {
        self.parts
            .get(&(labware.to_string(), part.to_string()))
            .map(String::as_str)
    }

    pub fn set_part(&mut self, labware: &str, part: &str, state: &str) {
        self.parts
            .insert((labware.to_string(), part.to_string()), state.to_string());
    }

    pub fn hand(&self, robot: &str) -> &Hand {
        self.hands.get(robot).unwrap_or(&Hand::Empty)
    }

    /// The item in a holder's slot, if any.
    pub fn occupant(&self, holder: &str, slot: &str) -> Option<&str> {
        self.locations.iter().find_map(|(item, loc)| match loc {
            Location::Slot { holder: h, slot: s } if h == holder && s == slot => {
                Some(item.as_str())
            }
            _ => None,
        })
    }

    /// Robots gripping `item` (carrying or steadying it).
    pub fn grippers_of(&self, item: &str) -> Vec<&str> {
        self.hands
            .iter()
            .filter(|(_, h)| matches!(h, Hand::Item(i) | Hand::Stabilising(i) if i == item))
            .map(|(r, _)| r.as_str())
            .collect()
    }
}
