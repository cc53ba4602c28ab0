//! `hold`: steady an item in place.

use super::prelude::*;
use crate::motion::{Motion, MotionStep, Target};

pub(super) const PRIMITIVE: LabPrimitive = LabPrimitive {
    name: "hold",
    description: "grip an item where it is to keep it still (a second arm stabilising a tube)",
    args: &[ON],
    requires: "the hand is empty; `on` is movable",
    leaves: "the robot holding `on` steady; `on` stays where it is",
    phrase: "hold the {on} steady",
    outcome: None,
    effect,
    motions: Some(motions),
};

fn effect(w: &mut World, env: &Env, step: &BoundStep) -> Result<(), Violation> {
    let robot = step.robot;
    let (lw, _) = step.on_empty_handed(w, env)?;
    w.hands.insert(robot.into(), Hand::Stabilising(lw));
    Ok(())
}

/// Come in from the side, take the body deep in the fingers where it stands, close, keep still.
fn motions(step: &MotionStep) -> Vec<Motion> {
    let hold = Target::Affordance {
        labware: step.arg("on"),
        name: "hold".into(),
        goals: Vec::new(),
    };
    vec![
        Motion::Approach {
            target: hold.clone(),
            standoff: 0.06,
        },
        Motion::Enclose { target: hold },
        Motion::Grasp,
    ]
}
