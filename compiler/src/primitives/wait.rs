//! `wait`: keep still for a time (an incubation on the bench, a tube left in a hot block).

use super::prelude::*;
use crate::motion::{Motion, MotionStep};

pub(super) const PRIMITIVE: LabPrimitive = LabPrimitive {
    name: "wait",
    description: "keep still for a time, holding whatever the hand holds",
    args: &[DURATION],
    requires: "a duration of more than 0 s",
    leaves: "everything as it was, the time later",
    phrase: "wait for {duration}",
    outcome: None,
    effect,
    motions: Some(motions),
};

fn effect(w: &mut World, _env: &Env, step: &BoundStep) -> Result<(), Violation> {
    let seconds = step.quantity("duration", Dimension::Time)?;
    if seconds <= 0.0 {
        return Err(violation(
            Code::E0021,
            Some("duration"),
            format!("a wait lasts more than 0 s, not {seconds} s"),
        ));
    }
    w.clock_s += seconds;
    Ok(())
}

fn motions(step: &MotionStep) -> Vec<Motion> {
    let seconds = dsl::parse_quantity(&step.arg("duration")).map_or(0.0, |q| q.si);
    vec![Motion::Wait { seconds }]
}
