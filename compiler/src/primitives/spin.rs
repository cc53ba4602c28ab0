//! `spin`: run a centrifuge at a speed for a time, from its start key.

use super::prelude::*;
use super::run;
use crate::motion::{Motion, MotionStep};

pub(super) const PRIMITIVE: LabPrimitive = LabPrimitive {
    name: "spin",
    description: "spin a centrifuge at a speed for a time: press its start key and wait until the rotor has stopped",
    args: &[
        ON,
        Arg {
            name: "speed",
            kind: ArgKind::Speed,
            doc: "the rotor's speed, e.g. \"12000 rpm\", or the force a kit asks for, e.g. \"16000 x g\" (converted at the rotor's radius)",
            optional: false,
        },
        DURATION,
        Arg {
            name: "ramp",
            kind: ArgKind::Duration,
            doc: "how long the rotor takes to come up to speed, and to stop, e.g. \"30 s\" (optional: 10 s, the 5430's fastest; 1 s to 2 min)",
            optional: true,
        },
    ],
    requires: "the hand is empty; the lid closed and latched; the rotor balanced; every tube in it capped",
    leaves: "the run done (`<centrifuge>.run is done`), the tubes where they were",
    phrase: "spin the {on} at {speed} for {duration}",
    outcome: Some("{on}.run is done"),
    effect,
    motions: Some(motions),
};

fn effect(w: &mut World, env: &Env, step: &BoundStep) -> Result<(), Violation> {
    let (lw, kind) = step.on_empty_handed(w, env)?;
    let programme = run::step_programme(step, kind)?;
    run::require_shut(w, &lw, kind, PRIMITIVE.name)?;
    run::require_capped(w, &lw, PRIMITIVE.name)?;
    run::require_balanced(w, &lw, kind)?;
    run::ran(w, &lw, &programme);
    Ok(())
}

/// Press the start key as a finger presses a key, then keep still until the rotor has stopped.
fn motions(step: &MotionStep) -> Vec<Motion> {
    let mut m = super::press::key_motions(step, "start");
    m.push(run::await_run(step, PRIMITIVE.name));
    m
}
