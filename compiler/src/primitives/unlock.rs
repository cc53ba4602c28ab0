//! `unlock`: release a locked lid's latch.

use super::lid;
use super::prelude::*;
use crate::motion::{Motion, MotionStep};

pub const PRIMITIVE: LabPrimitive = LabPrimitive {
    name: "unlock",
    description: "release a locked lid's latch or lever without opening the lid",
    args: &[ON],
    requires: "the hand is empty; the lid is locked",
    leaves: "the lid closed, unlocked",
    effect: lid::effect,
    motions: Some(motions),
};

/// A latch released by a key: press the key. A lever on the lid's handle: grip it and raise it
/// out of its notch.
fn motions(step: &MotionStep) -> Vec<Motion> {
    if let Some(key) = lid::release_key(step) {
        return super::press::key_motions(step, key);
    }
    lid::handle_motions(
        step,
        "lid_open",
        &[("lid", "closed"), ("lever", "pressed")],
        &[(&[("lid", "closed"), ("lever", "raised")], 10)],
        0.1,
    )
}
