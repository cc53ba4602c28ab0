//! `close_lid`: swing a lid shut by its handle and latch it.

use super::lid;
use super::prelude::*;
use crate::motion::{Motion, MotionStep};

pub(super) const PRIMITIVE: LabPrimitive = LabPrimitive {
    name: "close_lid",
    description: "swing a lid shut by its handle and latch it where the instrument has a latch",
    args: &[ON],
    requires: "the hand is empty; the lid is open",
    leaves: "the lid locked (closed, for lids without a latch)",
    phrase: "close the lid of the {on}",
    outcome: Some("{on}.lid is closed"),
    effect: lid::effect,
    motions: Some(motions),
};

/// Grip the raised lever of the open lid, swing the lid shut, push the lever into its notch.
fn motions(step: &MotionStep) -> Vec<Motion> {
    lid::handle_motions(
        step,
        "lid_close",
        &[("lid", "open"), ("lever", "raised")],
        &[
            (&[("lid", "closed"), ("lever", "raised")], 30),
            (&[("lid", "closed"), ("lever", "press")], 10),
        ],
        0.1,
    )
}
