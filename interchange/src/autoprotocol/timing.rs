//! Autoprotocol's time constraints carried onto the written steps as our step timing: a
//! constraint "`to` at most `less_than` after `from`" becomes `within` on the step that realises
//! `to` and `after` naming the step that realises `from` (given an `id`). A point is an
//! instruction's start or end, or a ref's first or last use (`ref_start`, `ref_end`: the first
//! or last instruction that names the ref). Our timing reads a step's outcome (what a check can
//! see it leave: a lid shut, a run done), so an instruction's start is its first step with an
//! outcome and its end its last; pipetting has none. What cannot be carried is said (W0011):
//! `more_than` and `ideal` (our timing bounds from above only), a point with no step that has an
//! outcome, a constraint that runs backwards, a second constraint on one step.

use super::lower::Lowered;
use super::spec::TimePoint;
use crate::Finding;
use crate::draft::{Draft, number};
use crate::json_span::Key;
use dsl::Code;

/// The instruction a step realises, from its source label (`instructions[3] liquid_handle`).
fn instruction_of(from: Option<&str>) -> Option<usize> {
    let rest = from?.strip_prefix("instructions[")?;
    rest.split_once(']')?.0.parse().ok()
}

fn has_outcome(primitive: &str) -> bool {
    compiler::primitives::primitive(primitive).is_some_and(|p| p.outcome.is_some())
}

/// A constraint not carried (W0011), at its place in the file.
fn not_carried(n: usize, message: String) -> Finding {
    Finding {
        code: Code::W0011,
        at: vec![Key::field("time_constraints"), Key::Index(n)],
        message,
        hint: None,
    }
}

/// Applies the constraints to the draft; findings for what is not carried.
pub fn apply(draft: &mut Draft, lowered: &Lowered) -> Vec<Finding> {
    let mut findings = Vec::new();
    for (n, c) in lowered.constraints.iter().enumerate() {
        if c.more_than.is_some() || c.ideal.is_some() {
            findings.push(not_carried(
                n,
                format!(
                    "time_constraints[{n}]: `more_than` and `ideal` not carried: our step timing bounds a step from above only"
                ),
            ));
        }
        let Some(less_than) = &c.less_than else {
            continue;
        };
        let seconds = match super::units::read(less_than, super::units::Dimension::Time) {
            Ok(s) if s > 0.0 => s,
            Ok(_) | Err(_) => {
                findings.push(Finding {
                    code: Code::E0044,
                    at: vec![
                        Key::field("time_constraints"),
                        Key::Index(n),
                        Key::field("less_than"),
                    ],
                    message: format!(
                        "time_constraints[{n}]: `{less_than}` is no time to follow in"
                    ),
                    hint: Some("a positive time, e.g. `30:minute`".into()),
                });
                continue;
            }
        };
        let point = |p: &TimePoint,
                     side: &str,
                     findings: &mut Vec<Finding>|
         -> Option<(usize, bool)> {
            let set = [
                p.instruction_start.map(|i| (i, false)),
                p.instruction_end.map(|i| (i, true)),
                p.ref_start.as_ref().and_then(|r| {
                    lowered
                        .uses
                        .get(r)
                        .and_then(|u| u.first())
                        .map(|i| (*i, false))
                }),
                p.ref_end.as_ref().and_then(|r| {
                    lowered
                        .uses
                        .get(r)
                        .and_then(|u| u.last())
                        .map(|i| (*i, true))
                }),
            ];
            let named = [
                p.instruction_start.is_some(),
                p.instruction_end.is_some(),
                p.ref_start.is_some(),
                p.ref_end.is_some(),
            ];
            let bad = |message: String, findings: &mut Vec<Finding>| {
                findings.push(Finding {
                    code: Code::E0041,
                    at: vec![Key::field("time_constraints"), Key::Index(n), Key::field(side)],
                    message,
                    hint: Some(
                        "a point is exactly one of `instruction_start`, `instruction_end` (an index into `instructions`), `ref_start`, `ref_end` (a ref's name)".into(),
                    ),
                });
            };
            if named.iter().filter(|x| **x).count() != 1 {
                bad(
                    format!(
                        "time_constraints[{n}].{side} names {} points, not one",
                        named.iter().filter(|x| **x).count()
                    ),
                    findings,
                );
                return None;
            }
            let Some(found) = set.into_iter().flatten().next() else {
                findings.push(not_carried(
                    n,
                    format!("time_constraints[{n}] not carried: its `{side}` names a ref no realised instruction uses"),
                ));
                return None;
            };
            if found.0 >= lowered.instructions {
                bad(
                    format!(
                        "time_constraints[{n}].{side}: instruction {} of {}",
                        found.0, lowered.instructions
                    ),
                    findings,
                );
                return None;
            }
            Some(found)
        };
        let (Some(from), Some(to)) = (
            point(&c.from, "from", &mut findings),
            point(&c.to, "to", &mut findings),
        ) else {
            continue;
        };
        let anchor = |(instruction, end): (usize, bool)| {
            let mut steps = draft
                .steps
                .iter()
                .enumerate()
                .filter(|(_, s)| {
                    instruction_of(s.from.as_deref()) == Some(instruction)
                        && has_outcome(&s.primitive)
                })
                .map(|(i, _)| i);
            if end { steps.next_back() } else { steps.next() }
        };
        let (Some(a), Some(b)) = (anchor(from), anchor(to)) else {
            let which = if anchor(from).is_none() { from.0 } else { to.0 };
            findings.push(not_carried(
                n,
                format!(
                    "time_constraints[{n}] not carried: instructions[{which}] has no step whose outcome a check can see (pipetting has none; a lid shut or a run done has)"
                ),
            ));
            continue;
        };
        if b <= a {
            findings.push(not_carried(n, format!("time_constraints[{n}] not carried: its `to` comes before its `from` in the written steps")));
            continue;
        }
        if draft.steps[b].args.iter().any(|(k, _)| k == "within") {
            findings.push(not_carried(
                n,
                format!(
                    "time_constraints[{n}] not carried: the step it times already has a constraint"
                ),
            ));
            continue;
        }
        let id = match draft.steps[a].args.iter().find(|(k, _)| k == "id") {
            Some((_, id)) => id.clone(),
            None => {
                let id = format!("step_{}", a + 1);
                draft.steps[a].args.push(("id".into(), id.clone()));
                id
            }
        };
        draft.steps[b]
            .args
            .push(("within".into(), format!("{} s", number(seconds))));
        draft.steps[b].args.push(("after".into(), id));
    }
    findings
}

#[cfg(test)]
mod tests {
    use super::instruction_of;

    #[test]
    fn a_step_knows_its_instruction_by_its_label() {
        assert_eq!(
            instruction_of(Some("instructions[12] thermocycle")),
            Some(12)
        );
        assert_eq!(
            instruction_of(Some("before instructions[3] thermocycle: x")),
            None
        );
        assert_eq!(instruction_of(None), None);
    }
}
