//! `unscrew_cap`: twist a cap off a stabilised tube.

use super::prelude::*;

pub const PRIMITIVE: LabPrimitive = LabPrimitive {
    name: "unscrew_cap",
    description: "twist a screw cap off a tube that stands in a slot or is held by another robot",
    args: &[ON],
    requires: "the hand is empty; the cap is on; the tube is in a slot or gripped by another robot",
    leaves: "the cap off, in the robot's hand",
    effect,
    motions: None,
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
