//! `dispense`: expel liquid from a pipette.

use super::liquid;
use super::prelude::*;

pub const PRIMITIVE: LabPrimitive = LabPrimitive {
    name: "dispense",
    description: "expel liquid from the pipette the robot holds into an open container",
    args: &[ON, VOLUME],
    requires: "the robot carries a pipette holding at least `volume`; `on` is open and has room for it",
    leaves: "`volume` moved from the pipette into `on`",
    effect: liquid::effect,
    motions: None,
};
