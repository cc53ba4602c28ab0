//! `press`: press one button once.

use super::prelude::*;

pub const PRIMITIVE: LabPrimitive = LabPrimitive {
    name: "press",
    description: "press one of an instrument's buttons once (with a closed gripper as the finger)",
    args: &[
        ON,
        Arg {
            name: "button",
            kind: ArgKind::Button,
            doc: "which button",
        },
    ],
    requires: "the hand is empty; the button exists; a stepped value stays within its range",
    leaves: "the button's effect: a switch toggled or a panel value stepped once",
    effect,
    motions: None,
};

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
