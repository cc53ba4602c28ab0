//! `screw_cap`: screw a held cap back on.

use super::prelude::*;

pub const PRIMITIVE: LabPrimitive = LabPrimitive {
    name: "screw_cap",
    description: "screw the cap the robot holds back onto its tube",
    args: &[ON],
    requires: "the robot holds `on`'s cap; the tube is in a slot or gripped by another robot",
    leaves: "the cap on; the hand empty",
    effect,
    motions: None,
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
