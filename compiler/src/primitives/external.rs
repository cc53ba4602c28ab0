//! `external`: a step an instrument off our bench does, an instrument-only step (a plate reader's
//! read, a magnet engaged, a spin in a centrifuge the scene does not have): the robots stand by
//! for its `duration`. `autobio import --keep-instrument-steps` writes one where an imported
//! command has no robot realisation; its `instruction` keeps the source's Autoprotocol
//! instruction, which `autobio export --to autoprotocol` writes back. The proof advances the lab
//! clock by its duration and changes nothing else: what the instrument does to the lab is not
//! modelled, so no success predicate can see it.

use super::prelude::*;
use crate::motion::{Motion, MotionStep};

pub(super) const PRIMITIVE: LabPrimitive = LabPrimitive {
    name: "external",
    description: "an instrument-only step, done off the bench while the robots stand by",
    args: &[
        Arg {
            name: "what",
            kind: ArgKind::Text,
            doc: "what the instrument does, in words (\"read the plate's absorbance at 600 nm\")",
            optional: false,
        },
        Arg {
            name: "duration",
            kind: ArgKind::Duration,
            doc: "how long the robots stand by (0 s if left out)",
            optional: true,
        },
        Arg {
            name: "instruction",
            kind: ArgKind::Text,
            doc: "the imported Autoprotocol instruction as JSON, which an export writes back",
            optional: true,
        },
    ],
    requires: "a duration of 0 s or more; an `instruction` that is a JSON object with an `op`",
    leaves: "everything as it was, the duration later: what the instrument does is not modelled",
    phrase: "let the lab's instrument {what}",
    outcome: None,
    effect,
    motions: Some(motions),
};

fn effect(w: &mut World, _env: &Env, step: &BoundStep) -> Result<(), Violation> {
    if step.args.contains_key("duration") {
        let seconds = step.quantity("duration", Dimension::Time)?;
        if seconds < 0.0 {
            return Err(violation(
                Code::E0021,
                Some("duration"),
                format!("an instrument-only step lasts 0 s or more, not {seconds} s"),
            ));
        }
        w.clock_s += seconds;
    }
    if let Some(text) = step.args.get("instruction") {
        let op = serde_json::from_str::<serde_json::Value>(text)
            .ok()
            .and_then(|v| v.get("op").and_then(|o| o.as_str()).map(str::to_string));
        if op.is_none() {
            return Err(violation(
                Code::E0021,
                Some("instruction"),
                "`instruction` is not an Autoprotocol instruction (a JSON object with an `op`)"
                    .to_string(),
            ));
        }
    }
    Ok(())
}

fn motions(step: &MotionStep) -> Vec<Motion> {
    let seconds = dsl::parse_quantity(&step.arg("duration")).map_or(0.0, |q| q.si);
    vec![Motion::Wait { seconds }]
}
