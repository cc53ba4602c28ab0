//! `screw_cap`: screw a held cap back on.

use super::prelude::*;
use crate::motion::{Motion, MotionStep, Target};

pub(super) const PRIMITIVE: LabPrimitive = LabPrimitive {
    name: "screw_cap",
    description: "screw the cap the robot holds back onto its tube",
    args: &[ON],
    requires: "the robot holds `on`'s cap; the tube is in a slot or gripped by another robot",
    leaves: "the cap on; the hand empty",
    phrase: "screw the cap onto the {on}",
    outcome: Some("{on}.cap is on"),
    effect,
    motions: Some(motions),
};

fn effect(w: &mut World, env: &Env, step: &BoundStep) -> Result<(), Violation> {
    let robot = step.robot;
    let (lw, _) = step.on(env)?;
    if w.hand(robot) != &Hand::Cap(lw.clone()) {
        return Err(precondition(
            format!(
                "`screw_cap` needs `{robot}` to hold the cap of `{lw}`, but its hand is {}",
                w.hand(robot)
            ),
            "unscrew that cap with the same robot first",
        ));
    }
    if !stabilised(w, &lw, robot) {
        return Err(precondition(
            format!("`screw_cap` needs `{lw}` held still (in a slot or gripped by another robot)"),
            "add a `hold` by another robot, or `place` the tube in a rack first",
        ));
    }
    w.set_part(&lw, "cap", "on");
    w.hands.insert(robot.into(), Hand::Empty);
    Ok(())
}

/// How far one grip turns the cap (rad): as `unscrew_cap`'s.
const TURN_PER_GRIP: f64 = 8.0 * std::f64::consts::PI / 9.0;
/// Grips to screw the cap down from where it is set on the mouth (1.3 to 2.3 turns above its
/// seat) to the seat: up to 960 degrees. Each turn stops where the cap is seated, so the grips
/// left over once it is turn it no further.
const GRIPS: usize = 6;
/// How far the open hand rises off the cap between grips (m).
const CLEAR: f64 = 0.015;

/// Carry the held cap onto the tube's mouth, coaxial, and turn it clockwise (seen from above),
/// following it down the thread, regrasping between turns; then let go and back off.
fn motions(step: &MotionStep) -> Vec<Motion> {
    let tube = step.arg("on");
    let carry = |above: f64| Target::Carry {
        labware: tube.clone(),
        from: "grasp".into(),
        to: "cap_start".into(),
        above,
    };
    let onto = carry(0.0);
    let cap = Target::Affordance {
        labware: tube.clone(),
        name: "grasp".into(),
        goals: Vec::new(),
    };
    let seated = Target::Affordance {
        labware: tube.clone(),
        name: "cap_seated".into(),
        goals: Vec::new(),
    };
    // Straight lines, not a planned approach: the cap travels in the hand, which the planner's
    // collision model (items carried whole) does not know of. Over the mouth first, then onto
    // it, measured again: the second reach corrects what the first left over (the stricter
    // alignment screwing on needs).
    let mut m = vec![
        Motion::Reach {
            target: carry(0.01),
        },
        Motion::Reach {
            target: onto.clone(),
        },
        // Let go on the mouth: the cap settles coaxial on the tube's neck (its skirt and the
        // neck centre it), where the arm's own error had set it up to 1.7 mm aside, enough to
        // cross the thread. Then grip it again where it sits.
        Motion::Release,
        Motion::Reach {
            target: cap.clone(),
        },
        Motion::Grasp,
    ];
    for grip in 0..GRIPS {
        m.push(Motion::Turn {
            angle: TURN_PER_GRIP,
            thread: Some(onto.clone()),
            stop: Some(seated.clone()),
        });
        m.push(Motion::Release);
        if grip + 1 < GRIPS {
            // Up off the cap before turning back: open fingers turned at its height sweep
            // into the holding hand below it once the cap nears its seat.
            m.extend([
                Motion::Lift { height: CLEAR },
                Motion::TurnBack,
                Motion::Reach {
                    target: cap.clone(),
                },
                Motion::Grasp,
            ]);
        }
    }
    m.push(Motion::Retreat { distance: 0.05 });
    m
}
