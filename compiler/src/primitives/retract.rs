//! `retract`: take the arm back to its home pose, out of the way of what others do next (a lid
//! that swings shut over the slot the arm has just loaded). It changes nothing in the lab's
//! state; the expert goes there in joint space, around whatever stands in the way.

use super::prelude::*;
use crate::motion::{Motion, MotionStep};

pub const PRIMITIVE: LabPrimitive = LabPrimitive {
    name: "retract",
    description: "take the arm back to its home pose, clear of the bench",
    args: &[],
    requires: "the hand is empty",
    leaves: "the arm at its home pose; the lab as it was",
    phrase: "bring the {robot} arm back to its rest pose",
    outcome: None,
    effect,
    motions: Some(motions),
};

fn effect(w: &mut World, _env: &Env, step: &BoundStep) -> Result<(), Violation> {
    super::require_empty_hand(w, step.robot, PRIMITIVE.name)
}

fn motions(_step: &MotionStep) -> Vec<Motion> {
    vec![Motion::Home]
}
