//! `release`: let go of an item held steady.

use super::prelude::*;

pub(super) const PRIMITIVE: LabPrimitive = LabPrimitive {
    name: "release",
    description: "let go of an item held steady",
    args: &[],
    requires: "the robot holds something steady",
    leaves: "the hand empty",
    phrase: "let go of what the {robot} arm holds",
    outcome: None,
    effect,
    motions: None,
};

fn effect(w: &mut World, _env: &Env, step: &BoundStep) -> Result<(), Violation> {
    let robot = step.robot;
    if !matches!(w.hand(robot), Hand::Stabilising(_)) {
        return Err(precondition(
            format!(
                "`release` needs `{robot}` to hold something steady, but its hand is {}",
                w.hand(robot)
            ),
            "use `place` to put down a carried item",
        ));
    }
    w.hands.insert(robot.into(), Hand::Empty);
    Ok(())
}
