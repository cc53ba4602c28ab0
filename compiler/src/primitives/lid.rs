//! What the four lid primitives share: the lid's state machine over `open`, `closed` and `locked`.

use super::prelude::*;
use crate::motion::{Motion, MotionStep, Target, goals};

pub(super) fn effect(w: &mut World, env: &Env, step: &BoundStep) -> Result<(), Violation> {
    let name = step.primitive.name;
    let (lw, kind) = step.on_empty_handed(w, env)?;
    let state = lid_state(w, &lw, kind)?.to_string();
    let latched = kind
        .part("lid")
        .is_some_and(|p| p.states.contains(&"locked"));
    let (needs, leaves): (&[&str], &str) = match name {
        "open_lid" => (&["closed", "locked"], "open"),
        "close_lid" => (&["open"], if latched { "locked" } else { "closed" }),
        "lock" => (&["closed"], "locked"),
        _ => (&["locked"], "closed"),
    };
    if !latched && matches!(name, "lock" | "unlock") {
        return Err(violation(
            Code::E0014,
            None,
            format!("`{lw}` (a {}) has no latch to {name}", kind.name),
        ));
    }
    if !needs.contains(&state.as_str()) {
        return Err(precondition(
            format!(
                "`{name}` needs `{lw}.lid` to be {}, but here it is `{state}`",
                needs.join(" or "),
            ),
            &format!(
                "remove this step or add one before it that leaves the lid {}",
                needs[0]
            ),
        ));
    }
    w.set_part(&lw, "lid", leaves);
    Ok(())
}

fn lid_state<'w>(w: &'w World, lw: &str, kind: &LabwareKind) -> Result<&'w str, Violation> {
    match (kind.part("lid"), w.part(lw, "lid")) {
        (Some(_), Some(s)) => Ok(s),
        _ => Err(violation(
            Code::E0014,
            Some("on"),
            format!("`{lw}` (a {}) has no lid", kind.name),
        )),
    }
}

/// Grip the handle where the lid and lever are at `at`, move through `path` (each a set of joint
/// goals followed over some samples), let go and back off.
pub(super) fn handle_motions(
    step: &MotionStep,
    at: &[(&str, &str)],
    path: &[(&[(&str, &str)], usize)],
) -> Vec<Motion> {
    let on = step.arg("on");
    let grip = Target::Affordance {
        labware: on.clone(),
        name: "grip".into(),
        goals: goals(at),
    };
    let mut m = vec![
        Motion::Approach {
            target: grip.clone(),
            standoff: 0.07,
        },
        Motion::Reach { target: grip },
        Motion::Grasp,
    ];
    m.extend(path.iter().map(|(g, samples)| Motion::Follow {
        labware: on.clone(),
        affordance: "grip".into(),
        goals: goals(g),
        samples: *samples,
    }));
    m.push(Motion::Release);
    m.push(Motion::Retreat { distance: 0.1 });
    m
}
