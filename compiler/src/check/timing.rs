//! Step timing: `within = "45 s"` on a step, of the step `after` names by its `id` (the step
//! before it, without `after`), lowered to a success predicate the judge measures on the
//! episode's clock: the later step's outcome must first hold at most that long after the earlier
//! step's outcome first held (Autoprotocol's time constraints between instructions). A step's
//! outcome is what its primitive leaves that a predicate reads
//! ([`crate::primitives::LabPrimitive::outcome`]: `place` leaves `"{on} in {to}"`, a run
//! `"{on}.run is done"`), filled in with the step's arguments. Checks here: ids unique (E0015),
//! `after` naming an earlier step (E0013, E0031), `within` a positive time (E0020), both steps
//! with an outcome (E0031); the proof checks the time against the plan's waits and runs (E0039).

use super::resolve::resolve_check;
use super::success::{Overrides, apply_tolerance};
use super::{CheckedPredicate, CheckedStep, KindMap};
use crate::predicates::{self, Check};
use crate::report::{Cx, hint_for};
use crate::task::{Predicate, Since};
use dsl::ast::Spanned;
use dsl::{Code, Dimension, parse_quantity};
use std::collections::BTreeMap;

/// One predicate per timed step, in step order.
pub(super) fn lower_timing(
    cx: &mut Cx,
    steps: &[CheckedStep],
    kinds: &KindMap,
    robots: &[String],
    declared: &[&str],
) -> Vec<CheckedPredicate> {
    let mut ids: BTreeMap<&str, usize> = BTreeMap::new();
    for (i, s) in steps.iter().enumerate() {
        let Some(id) = &s.ast.id else { continue };
        if ids.insert(id.value.as_str(), i).is_some() {
            cx.err(
                Code::E0015,
                id.span,
                format!("two steps have the id `{}`", id.value),
                Some(
                    "give each step its own id (a step in a loop's body: put `{var}` in it)".into(),
                ),
            );
        }
    }
    let mut out = Vec::new();
    for (i, s) in steps.iter().enumerate() {
        let Some(within) = &s.ast.within else {
            if let Some(after) = &s.ast.after {
                cx.err(
                    Code::E0002,
                    after.span,
                    "`after` names the step to time from, but the step has no `within`".into(),
                    Some("add the time it must follow in, e.g. within = \"45 s\"".into()),
                );
            }
            continue;
        };
        let Some(seconds) = time_of(cx, within) else {
            continue;
        };
        let Some(from) = earlier(cx, s, i, &ids) else {
            continue;
        };
        let (Some(a), Some(b)) = (outcome(cx, &steps[from], within), outcome(cx, s, within)) else {
            continue;
        };
        let check = |cx: &mut Cx, text: &str| check_of(cx, text, within, kinds, robots, declared);
        let (Some(a_check), Some(b_check)) = (check(cx, &a), check(cx, &b)) else {
            continue;
        };
        out.push(CheckedPredicate {
            span: within.span,
            predicate: Predicate {
                text: format!("{b} within {} of {a}", within.value),
                check: b_check,
                weight: 1.0,
                dwell: None,
                since: Some(Since {
                    text: a,
                    check: a_check,
                    within_s: seconds,
                }),
            },
        });
    }
    out
}

/// `within` as seconds, a positive time (E0020, E0021).
fn time_of(cx: &mut Cx, within: &Spanned<String>) -> Option<f64> {
    match parse_quantity(&within.value) {
        Ok(q) if q.dimension == Dimension::Time && q.si > 0.0 => Some(q.si),
        Ok(q) if q.dimension == Dimension::Time => {
            cx.err(
                Code::E0021,
                within.span,
                format!("`within = \"{}\"` is no time to follow in", within.value),
                Some("a time after the earlier step, e.g. within = \"45 s\"".into()),
            );
            None
        }
        Ok(q) => {
            cx.err(
                Code::E0020,
                within.span,
                format!(
                    "`{}` is a {}, but `within` is a time",
                    within.value,
                    q.dimension.name()
                ),
                Some("e.g. within = \"45 s\" or \"2 min\"".into()),
            );
            None
        }
        Err(e) => {
            cx.err(Code::E0020, within.span, e.to_string(), None);
            None
        }
    }
}

/// The index of the step `s` (the `i`-th) is timed from: the one its `after` names, which must
/// come before it, else the step before it.
fn earlier(cx: &mut Cx, s: &CheckedStep, i: usize, ids: &BTreeMap<&str, usize>) -> Option<usize> {
    let Some(after) = &s.ast.after else {
        if i == 0 {
            let span = s.ast.within.as_ref().map_or(s.ast.span, |w| w.span);
            cx.err(
                Code::E0031,
                span,
                "the first step has no step before it to be timed from".into(),
                Some("time a later step from it instead: give this one an `id` and the later one `after`".into()),
            );
            return None;
        }
        return Some(i - 1);
    };
    match ids.get(after.value.as_str()) {
        Some(&j) if j < i => Some(j),
        Some(_) => {
            cx.err(
                Code::E0031,
                after.span,
                format!(
                    "`after = \"{}\"` names this step or a later one; a step is timed from an earlier one",
                    after.value
                ),
                Some("move `within` and `after` to the later of the two steps".into()),
            );
            None
        }
        None => {
            cx.err(
                Code::E0013,
                after.span,
                format!("no step has the id `{}`", after.value),
                Some(hint_for(
                    &after.value,
                    &ids.keys().copied().collect::<Vec<_>>(),
                    "step ids (a step names itself with `id = \"...\"`)",
                )),
            );
            None
        }
    }
}

/// A step's outcome as predicate text, its arguments filled in (E0031 for a primitive that
/// leaves nothing a predicate reads).
fn outcome(cx: &mut Cx, s: &CheckedStep, within: &Spanned<String>) -> Option<String> {
    let Some(template) = s.primitive.outcome else {
        cx.err(
            Code::E0031,
            within.span,
            format!(
                "a `{}` step leaves nothing the judge can see, so it cannot be timed from or to",
                s.primitive.name
            ),
            Some(
                "time the steps around it: `place`, `close_lid`, `spin` and the like leave a state"
                    .into(),
            ),
        );
        return None;
    };
    let mut text = template.replace("{with}", &s.planned.robot);
    for (k, v) in &s.planned.args {
        text = text.replace(&format!("{{{k}}}"), v);
    }
    Some(text)
}

/// The outcome text read and resolved as a success predicate is (its errors at `within`).
fn check_of(
    cx: &mut Cx,
    text: &str,
    within: &Spanned<String>,
    kinds: &KindMap,
    robots: &[String],
    declared: &[&str],
) -> Option<Check> {
    let spanned = Spanned::new(text.to_string(), within.span);
    let parsed = match predicates::parse(text) {
        Ok(p) => p,
        Err(e) => {
            cx.err(
                Code::E0030,
                within.span,
                format!("the step's outcome `{text}` cannot be read as a predicate: {e}"),
                None,
            );
            return None;
        }
    };
    let (check, dim) = resolve_check(cx, &spanned, &parsed.form, kinds, robots, declared, &[])?;
    let overrides = Overrides::new();
    let mut used = BTreeMap::new();
    Some(apply_tolerance(
        cx, &spanned, check, dim, None, &overrides, &mut used,
    ))
}

#[cfg(test)]
mod tests {
    use crate::primitives::CATALOGUE;

    /// Every outcome names only its primitive's arguments and `with`, and reads as a predicate
    /// once filled in.
    #[test]
    fn every_outcome_fills_from_its_primitives_arguments() {
        for p in CATALOGUE {
            let Some(template) = p.outcome else { continue };
            let mut text = template.replace("{with}", "arm");
            for a in p.args {
                let value = match a.name {
                    "to" => "rack.A1",
                    "value" => "900 rpm",
                    "param" => "speed",
                    _ => "tube",
                };
                text = text.replace(&format!("{{{}}}", a.name), value);
            }
            assert!(!text.contains('{'), "{}: {text}", p.name);
            crate::predicates::parse(&text).unwrap_or_else(|e| panic!("{}: {text}: {e}", p.name));
        }
    }
}
