//! `pick`: grasp a movable item and lift it.

use super::prelude::*;
use crate::motion::{Motion, MotionStep, Target};

pub(super) const PRIMITIVE: LabPrimitive = LabPrimitive {
    name: "pick",
    description: "grasp a movable item and lift it from where it is",
    args: &[ON],
    requires: "the hand is empty; `on` is movable and nobody carries it",
    leaves: "`on` carried by the robot",
    phrase: "pick up the {on}",
    outcome: Some("{with} holds {on}"),
    effect,
    motions: Some(motions),
};

fn effect(w: &mut World, env: &Env, step: &BoundStep) -> Result<(), Violation> {
    let robot = step.robot;
    let (lw, _) = step.on_empty_handed(w, env)?;
    if let Some(Location::Held { robot: r }) = w.locations.get(&lw) {
        return Err(precondition(
            format!("`pick` needs `{lw}` free, but `{r}` carries it"),
            "hand it over with `hand_over` instead",
        ));
    }
    w.locations.insert(
        lw.clone(),
        Location::Held {
            robot: robot.into(),
        },
    );
    w.hands.insert(robot.into(), Hand::Item(lw));
    Ok(())
}

/// Approach the grasp from above, descend, close, lift clear.
fn motions(step: &MotionStep) -> Vec<Motion> {
    let grasp = Target::Affordance {
        labware: step.arg("on"),
        name: "grasp".into(),
        goals: Vec::new(),
    };
    vec![
        Motion::Approach {
            target: grasp.clone(),
            standoff: 0.04,
        },
        Motion::Reach { target: grasp },
        Motion::Grasp,
        Motion::Lift { height: 0.10 },
    ]
}
