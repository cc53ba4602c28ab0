//! `retract`: take the arm back to its home pose, out of the way of what others do next (a lid
//! that swings shut over the slot the arm has just loaded). It changes nothing in the lab's
//! state; the expert goes there in joint space, around whatever stands in the way. A hand that
//! carries a pipette takes it along (the pipetting hand holds its pipette throughout).

use super::prelude::*;
use crate::motion::{Motion, MotionStep};

pub(super) const PRIMITIVE: LabPrimitive = LabPrimitive {
    name: "retract",
    description: "take the arm back to its home pose, clear of the bench",
    args: &[],
    requires: "the hand is empty, or carries a pipette (which goes home with it)",
    leaves: "the arm at its home pose; the lab as it was",
    phrase: "bring the {robot} arm back to its rest pose",
    outcome: None,
    effect,
    motions: Some(motions),
};

/// A pipette stays in the hand that pipettes with it: the arm takes it home, out of the way of a
/// lid that swings shut over the tubes it has just filled.
fn effect(w: &mut World, env: &Env, step: &BoundStep) -> Result<(), Violation> {
    if let Hand::Item(item) = w.hand(step.robot)
        && env.kinds.get(item).is_some_and(|k| k.liquid_tool)
    {
        return Ok(());
    }
    super::require_empty_hand(w, step.robot, PRIMITIVE.name)
}

fn motions(_step: &MotionStep) -> Vec<Motion> {
    vec![Motion::Home]
}
