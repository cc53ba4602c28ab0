//! What the four lid primitives share: the lid's state machine over `open`, `closed` and `locked`.

use super::prelude::*;
use crate::motion::{Motion, MotionStep, Target, goals};

pub(super) fn effect(w: &mut World, env: &Env, step: &BoundStep) -> Result<(), Violation> {
    let name = step.primitive.name;
    // The latch is asked about first: `lock` on a lid its kind cannot lock says why, and what to
    // do instead, rather than only that the kind does not list `lock`.
    let (lw, kind) = step.labware(env, "on")?;
    if kind.part("lid").is_none() {
        // Not a lidded kind at all: the general refusal, with what the kind does support.
        step.on_empty_handed(w, env)?;
    }
    lid_state(w, &lw, kind)?;
    let latched = kind
        .part("lid")
        .is_some_and(|p| p.states.contains(&"locked"));
    // A lid whose latch a key releases is unlocked by its own step (`unlock`: the key is pressed)
    // before `open_lid` lifts it; a lid with a lever on its handle is unlatched as it is opened.
    let keyed = kind.release_key("lid").is_some();
    let (needs, leaves): (&[&str], &str) = match name {
        "open_lid" if keyed => (&["closed"], "open"),
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
    if keyed && name == "lock" {
        // Such a latch catches the lid as it is pushed shut; once its key has released it, the
        // lid must be lifted clear before it can catch again.
        return Err(Violation {
            hint: Some(format!(
                "`{lw}` locks when its lid is pushed shut: `open_lid`, then `close_lid`"
            )),
            ..violation(
                Code::E0014,
                None,
                format!(
                    "`{lw}` (a {}) has no separate lock: its latch catches the lid as it shuts",
                    kind.name
                ),
            )
        });
    }
    let (lw, kind) = step.on_empty_handed(w, env)?;
    let state = lid_state(w, &lw, kind)?.to_string();
    if !needs.contains(&state.as_str()) {
        let hint = if keyed && name == "open_lid" && state == "locked" {
            format!(
                "add an `unlock` step on `{lw}` before this one: its latch is released by the `{}` key",
                kind.release_key("lid").map(|b| b.name).unwrap_or_default()
            )
        } else {
            format!(
                "remove this step or add one before it that leaves the lid {}",
                needs[0]
            )
        };
        return Err(precondition(
            format!(
                "`{name}` needs `{lw}.lid` to be {}, but here it is `{state}`",
                needs.join(" or "),
            ),
            &hint,
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

/// Take the lid by its `affordance` (`lid_open` or `lid_close`: the instrument says what the hand
/// does there, a grasp or a push) where the lid and lever are at `at` (live, where empty), move
/// through `path` (each a set of joint goals followed over some samples), hold there a moment,
/// let go and back off `retreat` metres.
pub(super) fn handle_motions(
    step: &MotionStep,
    affordance: &str,
    at: &[(&str, &str)],
    path: &[(&[(&str, &str)], usize)],
    retreat: f64,
) -> Vec<Motion> {
    let on = step.arg("on");
    let grip = Target::Affordance {
        labware: on.clone(),
        name: affordance.into(),
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
        affordance: affordance.into(),
        goals: goals(g),
        samples: *samples,
    }));
    // Held at the end a moment: a damped lid lags the hand, and a latch must catch it there.
    m.push(Motion::Wait { seconds: 0.5 });
    m.push(Motion::Release);
    m.push(Motion::Retreat { distance: retreat });
    m
}

/// The key that releases the lid's latch, when a key does (see [`labware::LabwareKind::release_key`]).
pub(super) fn release_key(step: &MotionStep) -> Option<&'static str> {
    Some(step.kind?.release_key("lid")?.name)
}
