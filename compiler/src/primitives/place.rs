//! `place`: put a carried item into a slot.

use super::prelude::*;
use crate::motion::{Motion, MotionStep, Target};

pub(super) const PRIMITIVE: LabPrimitive = LabPrimitive {
    name: "place",
    description: "put a carried item into a holder's slot and let go",
    args: &[
        ON,
        Arg {
            name: "to",
            kind: ArgKind::Location,
            doc: "the slot, e.g. \"rack.B3\" or \"rotor.{slot}\"",
            optional: false,
        },
    ],
    requires: "the robot carries `on`; the slot exists, accepts `on`'s kind and is empty",
    leaves: "`on` in the slot; the hand empty",
    phrase: "put the {on} in slot {to.slot} of the {to.holder}",
    outcome: Some("{on} in {to}"),
    effect,
    motions: Some(motions),
};

fn effect(w: &mut World, env: &Env, step: &BoundStep) -> Result<(), Violation> {
    let robot = step.robot;
    let (lw, kind) = step.on(env)?;
    let to = step.text("to")?.to_string();
    let (holder, slot, hkind) = resolve_location(env, &to)
        .map_err(|m| violation(Code::E0016, Some("to"), m.to_string()))?;
    let accepts = hkind.slots.map(|s| s.accepts).unwrap_or(&[]);
    if !accepts.contains(&kind.name) {
        return Err(Violation {
            code: Code::E0016,
            arg: Some("to"),
            message: format!(
                "a slot of `{holder}` (a {}) does not take a {}",
                hkind.name, kind.name
            ),
            hint: Some(format!("it takes: {}", accepts.join(", "))),
        });
    }
    require_carrying(w, robot, &lw, PRIMITIVE.name)?;
    if let Some(other) = w.occupant(&holder, &slot) {
        return Err(precondition(
            format!("`place` needs `{to}` empty, but `{other}` is in it"),
            "choose a free slot, or draw it with `slot = ..., free = true`",
        ));
    }
    w.locations
        .insert(lw.clone(), Location::Slot { holder, slot });
    w.hands.insert(robot.into(), Hand::Empty);
    Ok(())
}

/// Transit above the slot at the carrying height, go to 4 cm out along the seat's axis, then down
/// that axis onto the seat, release, retreat.
fn motions(step: &MotionStep) -> Vec<Motion> {
    let to = step.arg("to");
    vec![
        Motion::Transit {
            target: Target::Seat {
                location: to.clone(),
                above: 0.0,
            },
        },
        // Down the seat's axis from 4 cm out (a rotor slot's mouth is 3 cm up it): a rack's axis
        // is vertical, a fixed-angle rotor's leans.
        Motion::Reach {
            target: Target::Seat {
                location: to.clone(),
                above: 0.04,
            },
        },
        Motion::Reach {
            target: Target::Seat {
                location: to,
                above: 0.001,
            },
        },
        Motion::Release,
        Motion::Retreat { distance: 0.10 },
    ]
}
