//! `aspirate`: draw liquid into a pipette.

use super::liquid;
use super::prelude::*;
use crate::motion::{Motion, MotionStep, goals};

pub(super) const PRIMITIVE: LabPrimitive = LabPrimitive {
    name: "aspirate",
    description: "draw liquid from an open container into the pipette the robot holds",
    args: &[ON, VOLUME],
    requires: "the robot carries a pipette with room for `volume`; `on` is open and holds at least `volume`",
    leaves: "`volume` moved from `on` into the pipette",
    phrase: "aspirate the {on}",
    outcome: None,
    effect: liquid::effect,
    motions: Some(motions),
};

/// As a person pipettes: over the mouth, the plunger pressed to its first stop (air out, above
/// the liquid), the tip down to under the surface, the thumb eased off slowly (the set volume
/// flows in), a moment for the last of it, and the tip straight up out of the container.
fn motions(step: &MotionStep) -> Vec<Motion> {
    let Some(tool) = step.tool.clone() else {
        return Vec::new();
    };
    let on = step.arg("on");
    let to = |name: &str, above: f64| liquid::tip_onto(&tool, &on, name, above);
    vec![
        Motion::Transit {
            target: to("mouth", liquid::OVER_MOUTH),
        },
        Motion::Reach {
            target: to("mouth", liquid::OVER_MOUTH),
        },
        Motion::PressPart {
            labware: tool.clone(),
            goals: goals(&[("plunger", "first_stop")]),
            timeout_s: liquid::PRESS_TIMEOUT_S,
        },
        Motion::Reach {
            target: to("draw", 0.0),
        },
        Motion::EasePart {
            seconds: liquid::EASE_S,
        },
        Motion::Wait {
            seconds: liquid::FLOW_S,
        },
        Motion::Reach {
            target: to("mouth", liquid::WITHDRAW),
        },
    ]
}
