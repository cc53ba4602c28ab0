//! `hand_over`: pass a carried item to another robot.

use super::prelude::*;

pub(super) const PRIMITIVE: LabPrimitive = LabPrimitive {
    name: "hand_over",
    description: "pass a carried item to another robot's gripper",
    args: &[
        ON,
        Arg {
            name: "to",
            kind: ArgKind::Robot,
            doc: "the robot that takes it",
            optional: false,
        },
    ],
    requires: "the robot carries `on`; `to` is another robot whose hand is empty or steadies `on`",
    leaves: "`on` carried by `to`; the giving hand empty",
    phrase: "hand the {on} to the {to} arm",
    outcome: None,
    effect,
    motions: None,
};

fn effect(w: &mut World, env: &Env, step: &BoundStep) -> Result<(), Violation> {
    let robot = step.robot;
    let (lw, _) = step.on(env)?;
    let to = step.text("to")?.to_string();
    if !env.robots.contains(&to) {
        return Err(violation(
            Code::E0013,
            Some("to"),
            format!("no robot named `{to}`"),
        ));
    }
    if to == robot {
        return Err(violation(
            Code::E0021,
            Some("to"),
            format!("`{robot}` cannot hand over to itself"),
        ));
    }
    require_carrying(w, robot, &lw, PRIMITIVE.name)?;
    match w.hand(&to) {
        Hand::Empty => {}
        Hand::Stabilising(i) if *i == lw => {}
        h => {
            return Err(precondition(
                format!("`hand_over` needs `{to}`'s hand free, but it is {h}"),
                "have it put down what it holds first",
            ));
        }
    }
    w.locations
        .insert(lw.clone(), Location::Held { robot: to.clone() });
    w.hands.insert(to, Hand::Item(lw));
    w.hands.insert(robot.into(), Hand::Empty);
    Ok(())
}
