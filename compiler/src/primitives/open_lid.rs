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

/// A lid with a lever on its handle: grip the pressed lever of the closed lid, raise it out of
/// its notch, swing the lid open. A lid a key has released (see `unlock`): lift it by its
/// handle from where it rests all the way open (a lid let go short of open, even past the balance
/// of its spring, swings on into the hand that let it go).
fn motions(step: &MotionStep) -> Vec<Motion> {
    if lid::release_key(step).is_some() {
        return lid::handle_motions(step, "lid_open", &[], &[(&[("lid", "open")], 30)], 0.04);
    }
    lid::handle_motions(
        step,
        "lid_open",
        &[("lid", "closed"), ("lever", "pressed")],
        &[
            (&[("lid", "closed"), ("lever", "raised")], 10),
            (&[("lid", "open"), ("lever", "raised")], 30),
        ],
        0.1,
    )
}
