//! `pick_cap`: pick up a tube's cap that lies apart from its tube.

use super::prelude::*;
use crate::motion::{Motion, MotionStep, Target};

pub(super) const PRIMITIVE: LabPrimitive = LabPrimitive {
    name: "pick_cap",
    description: "pick up a tube's cap from where it lies apart from the tube",
    args: &[ON],
    requires: "the hand is empty; `on`'s cap lies apart (`state = { cap = \"apart\" }`)",
    leaves: "the cap in the robot's hand over the tube's mouth, ready for `screw_cap`",
    phrase: "pick up the cap of the {on}",
    outcome: None,
    effect,
    motions: Some(motions),
};

fn effect(w: &mut World, env: &Env, step: &BoundStep) -> Result<(), Violation> {
    let robot = step.robot;
    let (lw, _) = step.on_empty_handed(w, env)?;
    match w.part(&lw, "cap") {
        Some("apart") => {}
        Some(state) => {
            let why = if state == "on" {
                "it is on its tube"
            } else {
                "another hand has it, or the tube was made without it"
            };
            return Err(precondition(
                format!("`pick_cap` needs the cap of `{lw}` lying apart, but {why}"),
                "take a cap off its tube with `unscrew_cap`; start it apart with `state = { cap = \"apart\" }`",
            ));
        }
        None => {
            return Err(precondition(
                format!("`pick_cap` needs `{lw}` to have a cap"),
                "pick up a screw-cap tube's cap",
            ));
        }
    }
    w.set_part(&lw, "cap", "off");
    w.hands.insert(robot.into(), Hand::Cap(lw));
    Ok(())
}

/// How far the cap is lifted off the bench before it is carried (m).
const LIFT: f64 = 0.05;

/// Approach the cap from above, descend, close across it, lift it clear and carry it over its
/// tube's mouth, coaxial, at a clearance over the tube (a free-space transit: the straight
/// line from where a cap lies to the tube may pass where the arm cannot hold it level, or
/// through the rack), and wait there for the arm to settle. `screw_cap` then lowers it onto the
/// mouth.
fn motions(step: &MotionStep) -> Vec<Motion> {
    let tube = step.arg("on");
    let cap = Target::Affordance {
        labware: tube.clone(),
        name: "grasp".into(),
        goals: Vec::new(),
    };
    vec![
        Motion::Approach {
            target: cap.clone(),
            standoff: 0.04,
        },
        Motion::Reach { target: cap },
        Motion::Grasp,
        Motion::Lift { height: LIFT },
        Motion::Transit {
            target: Target::Carry {
                labware: tube,
                from: "grasp".into(),
                to: "cap_start".into(),
                above: 0.0,
            },
        },
        // Still, until the arm has caught up: `screw_cap` aims the cap from where the hand is
        // commanded to be, and a transit across the bench ends with the servos millimetres
        // behind it (set down from there, the cap landed on the mouth's rim, askew).
        Motion::Wait { seconds: SETTLE },
    ]
}

/// How long the hand stays still over the tube before `screw_cap` aims the cap (s).
const SETTLE: f64 = 0.5;
