//! `set_parameter`: step a panel value to a target with its buttons, or turn its dial to the
//! notch nearest the target.

use super::prelude::*;
use crate::motion::{Motion, MotionStep, Target};

pub(super) const PRIMITIVE: LabPrimitive = LabPrimitive {
    name: "set_parameter",
    description: "set an instrument's panel value to a target with its buttons or its dial",
    args: &[
        ON,
        Arg {
            name: "param",
            kind: ArgKind::PanelParam,
            doc: "which panel value",
            optional: false,
        },
        Arg {
            name: "value",
            kind: ArgKind::PanelValue,
            doc: "the target, e.g. \"{rpm} rpm\"",
            optional: false,
        },
    ],
    requires: "the hand is empty; the target is within the panel's range and on its button grid (a dial takes any target in range, to its nearest notch)",
    leaves: "the panel value at the target (a dial's at the notch nearest it)",
    phrase: "set the {on}'s {param} to {value}",
    outcome: Some("{on}.{param} = {value}"),
    effect,
    motions: Some(motions),
};

/// With the gripper closed as a finger: come in front of the button that moves the value toward
/// the target, push it in and hold it while it repeats until the panel shows the target, back off.
/// A value set with a dial: grip the knob, turn it to the target's notch, let go, back off.
fn motions(step: &MotionStep) -> Vec<Motion> {
    let dial = step
        .kind
        .and_then(|k| k.panel_param(&step.arg("param")))
        .and_then(|p| p.dial);
    if let Some(knob) = dial {
        return dial_motions(step, knob);
    }
    let button = Target::Button {
        labware: step.arg("on"),
        param: step.arg("param"),
        value: step.arg("value"),
    };
    vec![
        Motion::Grasp,
        Motion::Approach {
            target: button.clone(),
            standoff: 0.04,
        },
        Motion::Press {
            target: button,
            depth: 0.0027,
        },
        Motion::HoldUntil {
            labware: step.arg("on"),
            param: step.arg("param"),
            value: step.arg("value"),
            timeout_s: 20.0,
        },
        Motion::Retreat { distance: 0.04 },
    ]
}

/// How far one grip turns a dial (rad): the hand sweeps half of it either side of where it came
/// in. A parallel gripper round a knob low on an instrument's front (62 mm above the bench, the
/// lowest dial in the catalogue) strikes something past about 0.7 rad either way.
const DIAL_PER_GRIP: f64 = 1.2;

fn dial_motions(step: &MotionStep, knob: &str) -> Vec<Motion> {
    let grip = Target::Affordance {
        labware: step.arg("on"),
        name: knob.to_string(),
        goals: Vec::new(),
    };
    vec![
        Motion::Release,
        Motion::Approach {
            target: grip.clone(),
            standoff: 0.05,
        },
        Motion::Reach { target: grip },
        Motion::Grasp,
        Motion::TurnDial {
            labware: step.arg("on"),
            param: step.arg("param"),
            value: step.arg("value"),
            per_grip: DIAL_PER_GRIP,
        },
        Motion::Release,
        Motion::Retreat { distance: 0.05 },
    ]
}

fn effect(w: &mut World, env: &Env, step: &BoundStep) -> Result<(), Violation> {
    let (lw, kind) = step.on_empty_handed(w, env)?;
    let pname = step.text("param")?;
    let Some(p) = kind.panel_param(pname) else {
        let names: Vec<&str> = kind.panel.iter().map(|p| p.name).collect();
        let message = format!("`{lw}` (a {}) has no panel value `{pname}`", kind.name);
        return Err(unknown_name(
            "param",
            message,
            pname,
            &names,
            "panel values",
        ));
    };
    let dim = panel_dimension(p.unit);
    let value = step.quantity("value", dim)?;
    if value < p.min || value > p.max {
        return Err(violation(
            Code::E0021,
            Some("value"),
            format!(
                "`{lw}.{pname}` ranges {}..{} {}, but the target is {value} {}",
                p.min, p.max, p.unit, p.unit
            ),
        ));
    }
    let steps = (value - p.initial) / p.step;
    if p.dial.is_none() && (steps - steps.round()).abs() > 1e-6 {
        return Err(Violation {
            code: Code::E0021,
            arg: Some("value"),
            message: format!(
                "`{lw}.{pname}` moves in steps of {} {} from {}, so it cannot show {value}",
                p.step, p.unit, p.initial
            ),
            hint: Some("pick a value on the button grid".into()),
        });
    }
    // A dial rests in the notch nearest the target.
    let value = p.set_value(value);
    let key = (lw.clone(), pname.to_string());
    let from = w.panel.get(&key).copied().unwrap_or(p.initial);
    w.panel_hold_s += p.hold_seconds(from, value);
    w.panel.insert(key, value);
    Ok(())
}
