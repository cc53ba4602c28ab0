//! `thermocycle`: run a thermal profile on a thermal cycler, which starts as its lid locks.

use super::prelude::*;
use super::run;
use crate::motion::{Motion, MotionStep};

pub(super) const PRIMITIVE: LabPrimitive = LabPrimitive {
    name: "thermocycle",
    description: "run a thermal profile (holds and cycles interleaved) on a thermal cycler under its heated lid, and wait until it ends; the cycler starts it as its lid locks",
    args: &[
        ON,
        Arg {
            name: "profile",
            kind: ArgKind::Profile,
            doc: "holds and cycles, e.g. \"95 °C 3 min, 30 x [95 °C 15 s, 55 °C 15 s, 72 °C 30 s], 72 °C 5 min\"",
            optional: false,
        },
    ],
    requires: "the hand is empty; the lid closed and locked; no profile run on this cycler yet (one profile per protocol: put every hold and cycle in it)",
    leaves: "the run done (`<cycler>.run is done`)",
    phrase: "run the profile {profile} on the {on}",
    outcome: Some("{on}.run is done"),
    effect,
    motions: Some(motions),
};

fn effect(w: &mut World, env: &Env, step: &BoundStep) -> Result<(), Violation> {
    let (lw, kind) = step.on_empty_handed(w, env)?;
    let programme = run::step_programme(step, kind)?;
    run::require_shut(w, &lw, kind, PRIMITIVE.name)?;
    if w.part(&lw, labware::run::RUN).is_some_and(|s| s != "idle") {
        return Err(precondition(
            format!("`{lw}` has run a profile already; a cycler runs one profile per protocol"),
            "put every hold and cycle in one profile (cycles and holds interleave), or chain a second protocol",
        ));
    }
    run::ran(w, &lw, &programme);
    Ok(())
}

/// The profile starts as the lid locks (the step before locked it): keep still until it ends.
fn motions(step: &MotionStep) -> Vec<Motion> {
    vec![run::await_run(step, PRIMITIVE.name)]
}
