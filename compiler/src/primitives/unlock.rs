//! `unlock`: release a locked lid's latch.

use super::lid;
use super::prelude::*;
use crate::motion::{Motion, MotionStep};

pub(super) const PRIMITIVE: LabPrimitive = LabPrimitive {
    name: "unlock",
    description: "release a locked lid's latch or lever without opening the lid",
    args: &[ON],
    requires: "the hand is empty; the lid is locked",
    leaves: "the lid closed, unlocked",
    phrase: "release the lid of the {on}",
    outcome: Some("{on}.lid is unlocked"),
    effect: lid::effect,
    motions: Some(motions),
};

/// How long a lid released by its key takes to come to rest ajar (the 5910's heavy, damped lid:
/// within 1 cm at its bar after 2.5 s).
const KEY_RELEASE_SETTLE_S: f64 = 2.5;

/// A latch released by a key: press the key, then wait while the released lid, which its spring
/// pushes ajar, comes to rest (a hand reaching for its bar while it still rises meets it early).
/// A lever on the lid's handle: grip it and raise it out of its notch.
fn motions(step: &MotionStep) -> Vec<Motion> {
    if let Some(key) = lid::release_key(step) {
        let mut m = super::press::key_motions(step, key);
        m.push(Motion::Wait {
            seconds: KEY_RELEASE_SETTLE_S,
        });
        return m;
    }
    lid::handle_motions(
        step,
        "lid_open",
        &[("lid", "closed"), ("lever", "pressed")],
        &[(&[("lid", "closed"), ("lever", "raised")], 10)],
        0.1,
    )
}
