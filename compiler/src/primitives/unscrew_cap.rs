//! `unscrew_cap`: twist a cap off a stabilised tube.

use super::prelude::*;
use crate::motion::{Motion, MotionStep, Target};

pub(super) const PRIMITIVE: LabPrimitive = LabPrimitive {
    name: "unscrew_cap",
    description: "twist a screw cap off a tube that stands in a slot or is held by another robot",
    args: &[ON],
    requires: "the hand is empty; the cap is on; the tube is in a slot or gripped by another robot",
    leaves: "the cap off, in the robot's hand",
    phrase: "unscrew the cap of the {on}",
    outcome: Some("{on}.cap is off"),
    effect,
    motions: Some(motions),
};

fn effect(w: &mut World, env: &Env, step: &BoundStep) -> Result<(), Violation> {
    let robot = step.robot;
    let (lw, _) = step.on_empty_handed(w, env)?;
    if w.part(&lw, "cap") != Some("on") {
        return Err(precondition(
            format!("`unscrew_cap` needs the cap of `{lw}` on, but it is off"),
            "remove this step, or screw the cap on first",
        ));
    }
    if !stabilised(w, &lw, robot) {
        return Err(precondition(
            format!(
                "`unscrew_cap` needs `{lw}` held still (in a slot or gripped by another robot), but it is {}",
                w.locations.get(&lw).unwrap_or(&Location::Bench)
            ),
            "add a `hold` by another robot, or `place` the tube in a rack first",
        ));
    }
    w.set_part(&lw, "cap", "off");
    w.hands.insert(robot.into(), Hand::Cap(lw));
    Ok(())
}

/// How far one grip turns the cap (rad): 160 degrees, what a wrist that turns a half turn either
/// way can do from near the middle of its range.
const TURN_PER_GRIP: f64 = 8.0 * std::f64::consts::PI / 9.0;
/// Grips to turn the cap off: 640 degrees, 5.3 mm up a 3 mm pitch, past where the nut leaves the
/// bolt (measured: after 1.7 turns the lift draws a 50 mL cap off).
const GRIPS: usize = 4;

/// Grasp the cap from above and turn it anticlockwise (seen from above), following it up the
/// thread, regrasping as a hand does: let go, turn back with the fingers open, grip again where
/// the cap now is. Then lift it clear.
fn motions(step: &MotionStep) -> Vec<Motion> {
    let cap = Target::Affordance {
        labware: step.arg("on"),
        name: "grasp".into(),
        goals: Vec::new(),
    };
    let mut m = vec![
        Motion::Approach {
            target: cap.clone(),
            standoff: 0.04,
        },
        Motion::Reach {
            target: cap.clone(),
        },
        Motion::Grasp,
    ];
    for grip in 0..GRIPS {
        m.push(Motion::Turn {
            angle: -TURN_PER_GRIP,
            thread: Some(cap.clone()),
            stop: None,
        });
        if grip + 1 < GRIPS {
            m.extend([
                Motion::Release,
                Motion::TurnBack,
                Motion::Reach {
                    target: cap.clone(),
                },
                Motion::Grasp,
            ]);
        }
    }
    m.push(Motion::Lift { height: 0.05 });
    m
}
