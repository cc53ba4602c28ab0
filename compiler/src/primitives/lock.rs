//! `lock`: press a closed lid's latch home.

use super::lid;
use super::prelude::*;

pub const PRIMITIVE: LabPrimitive = LabPrimitive {
    name: "lock",
    description: "press a closed lid's latch or lever home",
    args: &[ON],
    requires: "the hand is empty; the lid is closed and has a latch",
    leaves: "the lid locked",
    effect: lid::effect,
    motions: None,
};
