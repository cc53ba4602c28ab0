//! `aspirate`: draw liquid into a pipette.

use super::liquid;
use super::prelude::*;

pub const PRIMITIVE: LabPrimitive = LabPrimitive {
    name: "aspirate",
    description: "draw liquid from an open container into the pipette the robot holds",
    args: &[ON, VOLUME],
    requires: "the robot carries a pipette with room for `volume`; `on` is open and holds at least `volume`",
    leaves: "`volume` moved from `on` into the pipette",
    effect: liquid::effect,
    motions: None,
};
