//! `press`: press one button once.

use super::prelude::*;
use crate::motion::{Motion, MotionStep, Target};

pub(super) const PRIMITIVE: LabPrimitive = LabPrimitive {
    name: "press",
    description: "press one of an instrument's buttons once (with a closed gripper as the finger)",
    args: &[
        ON,
        Arg {
            name: "button",
            kind: ArgKind::Button,
            doc: "which button",
            optional: false,
        },
    ],
    requires: "the hand is empty; the button exists; a stepped value stays within its range",
    leaves: "the button's effect: a switch toggled, a panel value stepped once or a latch released",
    phrase: "press the {button} button of the {on}",
    outcome: None,
    effect,
    motions: Some(motions),
};

fn motions(step: &MotionStep) -> Vec<Motion> {
    key_motions(step, &step.arg("button"))
}

/// With the gripper closed as a finger: come in front of the button (its affordance bears its
/// name), push it in past its press force, hold it there long enough to register, back off and
/// open the hand.
pub(super) fn key_motions(step: &MotionStep, button: &str) -> Vec<Motion> {
    let key = Target::Affordance {
        labware: step.arg("on"),
        name: button.to_string(),
        goals: Vec::new(),
    };
    vec![
        Motion::Grasp,
        Motion::Approach {
            target: key.clone(),
            standoff: 0.04,
        },
        Motion::Press {
            target: key,
            depth: 0.0027,
        },
        Motion::Wait { seconds: 0.5 },
        Motion::Retreat { distance: 0.04 },
        Motion::Release,
    ]
}

fn effect(w: &mut World, env: &Env, step: &BoundStep) -> Result<(), Violation> {
    let (lw, kind) = step.on_empty_handed(w, env)?;
    let b = step.text("button")?;
    let Some(button) = kind.button(b) else {
        let names: Vec<&str> = kind.buttons.iter().map(|b| b.name).collect();
        let message = format!("`{lw}` (a {}) has no button `{b}`", kind.name);
        return Err(unknown_name("button", message, b, &names, "buttons"));
    };
    match button.effect {
        ButtonEffect::Toggle { part, a, b } => {
            let next = if w.part(&lw, part) == Some(a) { b } else { a };
            w.set_part(&lw, part, next);
        }
        ButtonEffect::Release { part, from, to } => {
            if w.part(&lw, part) == Some(from) {
                w.set_part(&lw, part, to);
            }
        }
        ButtonEffect::Start => {
            let run = kind
                .primitives
                .iter()
                .find(|p| ["spin", "incubate", "thermocycle"].contains(p))
                .copied()
                .unwrap_or("spin");
            return Err(Violation {
                code: Code::E0031,
                arg: Some("button"),
                message: format!(
                    "`{lw}`'s `{b}` key starts a run, whose programme a `{run}` step carries"
                ),
                hint: Some(format!(
                    "write a `{run}` step on `{lw}`: it presses `{b}` and waits for the run"
                )),
            });
        }
        ButtonEffect::Step { param, sign } => {
            let p = kind.panel_param(param).expect("catalogue is consistent");
            let key = (lw.clone(), param.to_string());
            let v = w.panel.get(&key).copied().unwrap_or(p.initial) + sign as f64 * p.step;
            if v < p.min - 1e-9 || v > p.max + 1e-9 {
                return Err(precondition(
                    format!(
                        "pressing `{}` would take `{lw}.{param}` to {v} {}, outside {}..{}",
                        button.name, p.unit, p.min, p.max
                    ),
                    "remove this press",
                ));
            }
            w.panel.insert(key, v);
        }
    }
    Ok(())
}
