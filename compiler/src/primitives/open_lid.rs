//! `open_lid`: unlatch a lid and swing it open.

use super::lid;
use super::prelude::*;
use crate::motion::{Motion, MotionStep};

pub const PRIMITIVE: LabPrimitive = LabPrimitive {
    name: "open_lid",
    description: "unlatch a lid if latched and swing it open",
    args: &[ON],
    requires: "the hand is empty; the lid is closed or locked",
    leaves: "the lid open (and unlocked)",
    effect: lid::effect,
    motions: Some(motions),
};

/// Grip the pressed lever of the closed lid, raise it out of its notch, swing the lid open.
fn motions(step: &MotionStep) -> Vec<Motion> {
    lid::handle_motions(
        step,
        &[("lid", "closed"), ("lever", "pressed")],
        &[
            (&[("lid", "closed"), ("lever", "raised")], 10),
            (&[("lid", "open"), ("lever", "raised")], 30),
        ],
    )
}
