//! `lock`: press a closed lid's latch home.

use super::lid;
use super::prelude::*;
use crate::motion::{Motion, MotionStep};

pub(super) const PRIMITIVE: LabPrimitive = LabPrimitive {
    name: "lock",
    description: "press a closed lid's latch or lever home",
    args: &[ON],
    requires: "the hand is empty; the lid is closed and has a latch",
    leaves: "the lid locked",
    phrase: "lock the lid of the {on}",
    outcome: Some("{on}.lid is locked"),
    effect: lid::effect,
    motions: Some(motions),
};

/// Take the closed lid by its closing handle and press its lever into its notch. (A lid whose
/// latch a key releases has no separate lock: the compiler refuses `lock` on it.)
fn motions(step: &MotionStep) -> Vec<Motion> {
    lid::handle_motions(
        step,
        "lid_close",
        &[("lid", "closed"), ("lever", "raised")],
        &[(&[("lid", "closed"), ("lever", "press")], 10)],
        0.1,
    )
}
