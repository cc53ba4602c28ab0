//! `incubate`: run a thermal mixer's block at a temperature, shaking, for a time, from its start
//! key.

use super::prelude::*;
use super::run;
use crate::motion::{Motion, MotionStep};

pub(super) const PRIMITIVE: LabPrimitive = LabPrimitive {
    name: "incubate",
    description: "incubate what stands in a thermal mixer's block at a temperature, shaking at a speed, for a time: press its start key and wait until its timer ends",
    args: &[
        ON,
        Arg {
            name: "temperature",
            kind: ArgKind::Temperature,
            doc: "the block's temperature, e.g. \"37 °C\"",
            optional: false,
        },
        Arg {
            name: "speed",
            kind: ArgKind::Speed,
            doc: "the shaking speed, e.g. \"800 rpm\"",
            optional: false,
        },
        DURATION,
    ],
    requires: "the hand is empty; every tube in the block capped",
    leaves: "the run done (`<mixer>.run is done`), the tubes where they were",
    phrase: "incubate in the {on} at {temperature}, shaking at {speed}, for {duration}",
    outcome: Some("{on}.run is done"),
    effect,
    motions: Some(motions),
};

fn effect(w: &mut World, env: &Env, step: &BoundStep) -> Result<(), Violation> {
    let (lw, kind) = step.on_empty_handed(w, env)?;
    let programme = run::step_programme(step, kind)?;
    run::require_capped(w, &lw, PRIMITIVE.name)?;
    run::ran(w, &lw, &programme);
    Ok(())
}

/// Press the start key, then keep still until the timer ends.
fn motions(step: &MotionStep) -> Vec<Motion> {
    let mut m = super::press::key_motions(step, "start");
    m.push(run::await_run(step, PRIMITIVE.name));
    m
}
