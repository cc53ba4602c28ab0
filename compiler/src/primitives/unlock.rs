//! `unlock`: release a locked lid's latch.

use super::lid;
use super::prelude::*;

pub const PRIMITIVE: LabPrimitive = LabPrimitive {
    name: "unlock",
    description: "release a locked lid's latch or lever without opening the lid",
    args: &[ON],
    requires: "the hand is empty; the lid is locked",
    leaves: "the lid closed, unlocked",
    effect: lid::effect,
    motions: None,
};
