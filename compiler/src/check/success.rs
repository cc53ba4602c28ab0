//! The `[success]` table lowered to [`CheckedPredicate`]s: its weights (one per predicate, not
//! summing to zero: E0021), each predicate parsed (E0030) and resolved ([`super::resolve`]),
//! its placeholders naming parameters (E0023), and its tolerance filled in from `within`, a
//! `[tolerances]` override or the kind's default (E0035 for a tolerance the predicate does not
//! take, a `within` or override of the wrong dimension, or an override no predicate uses). It
//! evaluates no predicate (the proof and the scorer do).

use super::parameters::check_placeholders;
use super::resolve::resolve_check;
use super::{CheckedPredicate, KindMap, NamedTolerance};
use crate::predicates::{self, Check, Tolerance};
use crate::report::{Cx, hint_for};
use crate::task::Predicate;
use dsl::ast::{Protocol, Spanned};
use dsl::{Code, Dimension, parse_quantity};
use std::collections::BTreeMap;

/// `[tolerances]` overrides by name: the name as written and its value.
pub(super) type Overrides<'a> = BTreeMap<&'a str, (&'a Spanned<String>, &'a Spanned<String>)>;

/// Each predicate of `all` that parses and resolves, in order, with its tolerance and weight.
pub(super) fn lower_predicates(
    cx: &mut Cx,
    p: &Protocol,
    kinds: &KindMap,
    robots: &[String],
    params: &[&str],
    declared: &[&str],
) -> Vec<CheckedPredicate> {
    let overrides: Overrides = p
        .tolerances
        .iter()
        .map(|(n, v)| (n.value.as_str(), (n, v)))
        .collect();
    check_weights(cx, p);
    let weights = p.success.weights.as_ref();
    let mut used_tolerances: BTreeMap<String, Dimension> = BTreeMap::new();
    // The liquids loaded anywhere in the scene, which `<lw>.volume of <liquid>` may name.
    let liquids: Vec<&str> = p
        .labware
        .iter()
        .flat_map(|l| &l.state)
        .filter(|(key, _)| key.value == "liquid")
        .filter_map(|(_, v)| match &v.value {
            dsl::ast::Scalar::Str(s) => Some(s.as_str()),
            _ => None,
        })
        .collect();
    let mut out = Vec::new();
    for (i, text) in p.success.all.iter().enumerate() {
        check_placeholders(cx, text, params);
        let (body, dwell) = match predicates::split_dwell(&text.value) {
            Ok(x) => x,
            Err(e) => {
                cx.err(
                    Code::E0030,
                    text.span,
                    format!("cannot read predicate `{}`: {e}", text.value),
                    None,
                );
                continue;
            }
        };
        let parsed = match predicates::parse(body) {
            Ok(x) => x,
            Err(e) => {
                cx.err(
                    Code::E0030,
                    text.span,
                    format!("cannot read predicate `{}`: {e}", text.value),
                    Some("forms: `<lw>.<part> is <state>`, `<lw>.<part> was <state>` (at some step), `<item> in <holder>.<slot>`, `<lw>.volume = <q>`, `<lw>.volume of <liquid> = <q>`, `<lw>.<value> = <q>`, `<robot> touches <item>`, `<robot> holds <item>`, `<lw>.<joint> in [lo, hi] <unit>`, `<item> near [x, y, z] m`, `<item> lifted <length>`, `<item> inverted <n> times`".into()),
                );
                continue;
            }
        };
        // A count of turns is the stage's memory, not a state that holds for a while.
        if dwell.is_some() && matches!(parsed.form, predicates::Form::Inverted { .. }) {
            cx.err(
                Code::E0030,
                text.span,
                format!(
                    "`{}`: a count of inversions takes no time constraint",
                    text.value
                ),
                Some("write `<item> inverted <n> times` alone".into()),
            );
            continue;
        }
        let Some((check, dim)) =
            resolve_check(cx, text, &parsed.form, kinds, robots, declared, &liquids)
        else {
            continue;
        };
        let check = apply_tolerance(
            cx,
            text,
            check,
            dim,
            parsed.within,
            &overrides,
            &mut used_tolerances,
        );
        let weight = weights.and_then(|w| w.value.get(i).copied()).unwrap_or(1.0);
        out.push(CheckedPredicate {
            span: text.span,
            predicate: Predicate {
                text: text.value.clone(),
                check,
                weight,
                dwell,
                since: None,
            },
        });
    }
    check_overrides(cx, &overrides, &used_tolerances);
    out
}

/// E0021 for weights that are not one per predicate, or that sum to zero.
fn check_weights(cx: &mut Cx, p: &Protocol) {
    let weights = p.success.weights.as_ref();
    if let Some(w) = weights
        && w.value.len() != p.success.all.len()
    {
        cx.err(
            Code::E0021,
            w.span,
            format!(
                "{} weights for {} predicates",
                w.value.len(),
                p.success.all.len()
            ),
            Some("give one weight per predicate in `all`".into()),
        );
    }
    if let Some(w) = weights
        && w.value.iter().sum::<f64>() <= 0.0
    {
        cx.err(Code::E0021, w.span, "the weights sum to zero".into(), None);
    }
}

/// Each `[tolerances]` override names a tolerance some predicate uses (E0035) and is a quantity
/// (E0020) of the dimension it bounds (E0035).
fn check_overrides(cx: &mut Cx, overrides: &Overrides, used: &BTreeMap<String, Dimension>) {
    for (name, (n, v)) in overrides {
        let Some(dim) = used.get(*name) else {
            let in_use: Vec<&str> = used.keys().map(String::as_str).collect();
            cx.err(
                Code::E0035,
                n.span,
                format!("no predicate uses a tolerance named `{name}`"),
                Some(hint_for(name, &in_use, "tolerances in use")),
            );
            continue;
        };
        match parse_quantity(&v.value) {
            Ok(q) if q.dimension == *dim => {}
            Ok(q) => cx.err(
                Code::E0035,
                v.span,
                format!(
                    "tolerance `{name}` bounds a {}, but `{}` is a {}",
                    dim.name(),
                    v.value,
                    q.dimension.name()
                ),
                Some(format!("use one of: {}", dim.example_units())),
            ),
            Err(e) => cx.err(Code::E0020, v.span, e.to_string(), None),
        }
    }
}

/// Fills in the tolerance: inline `within`, else a `[tolerances]` override, else the kind's default.
pub(super) fn apply_tolerance(
    cx: &mut Cx,
    text: &Spanned<String>,
    mut check: Check,
    tol: Option<NamedTolerance>,
    within: Option<(f64, Dimension)>,
    overrides: &Overrides,
    used: &mut BTreeMap<String, Dimension>,
) -> Check {
    let Some((name, default, dim)) = tol else {
        if within.is_some() {
            cx.err(
                Code::E0035,
                text.span,
                "this predicate takes no tolerance".into(),
                Some("remove `within ..`".into()),
            );
        }
        return check;
    };
    used.insert(name.clone(), dim);
    let mut value = default;
    if let Some((_, v)) = overrides.get(name.as_str())
        && let Ok(q) = parse_quantity(&v.value)
        && q.dimension == dim
    {
        value = q.si;
    }
    if let Some((v, d)) = within {
        if d == dim {
            value = v;
        } else {
            cx.err(
                Code::E0035,
                text.span,
                format!(
                    "`within` gives a {}, but this predicate's tolerance is a {}",
                    d.name(),
                    dim.name()
                ),
                Some(format!("use one of: {}", dim.example_units())),
            );
        }
    }
    let t = Tolerance { name, value };
    match &mut check {
        Check::State { tolerance, .. } => *tolerance = Some(t),
        Check::InSlot { tolerance, .. }
        | Check::Volume { tolerance, .. }
        | Check::Panel { tolerance, .. }
        | Check::Position { tolerance, .. } => *tolerance = t,
        Check::JointRange { .. }
        | Check::Contact { .. }
        | Check::Holds { .. }
        | Check::Lifted { .. }
        | Check::Inverted { .. } => {}
    }
    check
}

#[cfg(test)]
mod tests {
    use super::super::testing::*;
    use crate::predicates::Check;
    use dsl::Code;

    /// The slot tolerance of the one predicate: `within`, else the override, else the kind's.
    fn slot_tolerance(src: &str) -> f64 {
        lowered(src, |low, diags| {
            assert!(diags.is_empty(), "{diags:#?}");
            match &low.unwrap().predicates[0].predicate.check {
                Check::InSlot { tolerance, .. } => tolerance.value,
                other => panic!("{other:?}"),
            }
        })
    }

    /// `within` beats a `[tolerances]` override, which beats the kind's default.
    #[test]
    fn a_tolerance_comes_from_within_then_the_override_then_the_kind() {
        let kind = slot_tolerance(BASE);
        let overridden = with("[tolerances]\nslot_xy = \"3 mm\"\n");
        assert!((slot_tolerance(&overridden) - 0.003).abs() < 1e-12);
        let within = overridden.replace("{row}1\"]", "{row}1 within 2 mm\"]");
        assert!((slot_tolerance(&within) - 0.002).abs() < 1e-12);
        assert!(kind > 0.003, "the default is another value: {kind}");
    }

    /// A tolerance of the wrong dimension, one no predicate uses, and a `within` on a predicate
    /// that takes none are E0035.
    #[test]
    fn tolerances_of_the_wrong_kind_or_unused_are_e0035() {
        let src = with("[tolerances]\nslot_xy = \"5 deg\"\nvolume = \"1 µL\"\n");
        lowered(&src, |low, diags| {
            assert_eq!(codes(diags), [Code::E0035, Code::E0035], "{diags:#?}");
            // Overrides are reported by name: `slot_xy` before `volume`.
            assert_eq!(
                diags[0].message,
                "tolerance `slot_xy` bounds a length, but `5 deg` is a plane angle"
            );
            assert_eq!(covered(&src, diags[0].span), "\"5 deg\"");
            assert_eq!(
                diags[1].message,
                "no predicate uses a tolerance named `volume`"
            );
            assert_eq!(covered(&src, diags[1].span), "volume");
            // The wrong override is ignored: the kind's default stays.
            let Check::InSlot { tolerance, .. } = &low.unwrap().predicates[0].predicate.check
            else {
                panic!("an in-slot check");
            };
            assert!(tolerance.value > 0.005);
        });
        let src = edited(&[("{row}1\"]", "{row}1 within 5 deg\"]")]);
        lowered(&src, |_, diags| {
            assert_eq!(
                one(diags, Code::E0035).message,
                "`within` gives a plane angle, but this predicate's tolerance is a length"
            );
        });
        let src = edited(&[(
            "\"tube in target.{row}1\"",
            "\"arm touches tube within 1 mm\"",
        )]);
        lowered(&src, |_, diags| {
            assert_eq!(
                one(diags, Code::E0035).message,
                "this predicate takes no tolerance"
            );
        });
    }

    /// Weights are one per predicate and not all zero (E0021); under progress scoring each
    /// predicate carries its weight.
    #[test]
    fn weights_are_one_per_predicate_and_carried_by_each() {
        let weights = |w: &str| {
            edited(&[(
                "all = [",
                &format!("scoring = \"progress\"\nweights = {w}\nall = ["),
            )])
        };
        let src = weights("[0.5, 0.5]");
        lowered(&src, |_, diags| {
            let d = one(diags, Code::E0021);
            assert_eq!(d.message, "2 weights for 1 predicates");
            assert_eq!(covered(&src, d.span), "[0.5, 0.5]");
        });
        lowered(&weights("[0.0]"), |_, diags| {
            assert_eq!(one(diags, Code::E0021).message, "the weights sum to zero");
        });
        lowered(&weights("[2.5]"), |low, diags| {
            assert!(diags.is_empty(), "{diags:#?}");
            assert_eq!(low.unwrap().predicates[0].predicate.weight, 2.5);
        });
    }

    /// A predicate that is none of the forms is E0030, listing them, and is left out.
    #[test]
    fn an_unreadable_predicate_is_e0030_listing_the_forms() {
        let src = edited(&[("\"tube in target.{row}1\"", "\"tube somewhere\"")]);
        lowered(&src, |low, diags| {
            let d = one(diags, Code::E0030);
            assert!(
                d.message
                    .starts_with("cannot read predicate `tube somewhere`: "),
                "{d:?}"
            );
            assert!(d.hint.as_deref().unwrap().starts_with("forms: "));
            assert!(low.unwrap().predicates.is_empty());
        });
    }
}
