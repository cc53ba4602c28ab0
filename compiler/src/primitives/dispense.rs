//! `dispense`: expel liquid from a pipette.

use super::liquid;
use super::prelude::*;
use crate::motion::{Motion, MotionStep, goals};

pub(super) const PRIMITIVE: LabPrimitive = LabPrimitive {
    name: "dispense",
    description: "expel liquid from the pipette the robot holds into an open container",
    args: &[ON, VOLUME],
    requires: "the robot carries a pipette holding at least `volume`; `on` is open and has room for it",
    leaves: "`volume` moved from the pipette into `on`",
    phrase: "dispense the {on}",
    outcome: None,
    effect: liquid::effect,
    motions: Some(motions),
};

/// As a person dispenses: the tip into the container (below its mouth, against nothing), the
/// plunger pressed through the first stop to blow-out, a moment for the last of it, the tip
/// withdrawn with the plunger still down (so that nothing is drawn back), then the thumb off.
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
            target: to("mouth", -liquid::INTO_MOUTH),
        },
        Motion::PressPart {
            labware: tool.clone(),
            goals: goals(&[("plunger", "first_stop"), ("blow_out", "blow_out")]),
            timeout_s: liquid::PRESS_TIMEOUT_S,
        },
        Motion::Wait {
            seconds: liquid::FLOW_S,
        },
        Motion::Reach {
            target: to("mouth", liquid::WITHDRAW),
        },
        Motion::EasePart { seconds: 0.5 },
    ]
}
