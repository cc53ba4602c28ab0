//! `hold`: steady an item in place.

use super::prelude::*;

pub const PRIMITIVE: LabPrimitive = LabPrimitive {
    name: "hold",
    description: "grip an item where it is to keep it still (a second arm stabilising a tube)",
    args: &[ON],
    requires: "the hand is empty; `on` is movable",
    leaves: "the robot holding `on` steady; `on` stays where it is",
    effect,
    motions: None,
};

fn effect(w: &mut World, env: &Env, step: &BoundStep) -> Result<(), Violation> {
    let robot = step.robot;
    let (lw, _) = step.on_empty_handed(w, env)?;
    w.hands.insert(robot.into(), Hand::Stabilising(lw));
    Ok(())
}
