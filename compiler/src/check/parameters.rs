//! `[params.<name>]` tables lowered to [`ParamSpec`]s, in declaration order: each domain checked
//! (`choice`: one type, no repeats; `int` and `real`: a non-empty range of one dimension; `slot`:
//! a holder with slots, `opposite` an earlier slot parameter of a ring), `{name}` placeholders in
//! exclusions naming earlier parameters, and a value left to draw once the exclusions apply.
//! Also [`check_placeholders`], the E0023 check of any text's placeholders. It draws nothing and
//! enumerates combinations only through [`crate::params::proof_assignments`].

use super::KindMap;
use crate::params::{Domain, ParamSpec, placeholders};
use crate::report::{Cx, hint_for};
use crate::task::LabwareSpec;
use dsl::ast::{Param, ParamDomain, Protocol, Scalar, Spanned};
use dsl::{Code, Span, parse_quantity};
use std::collections::BTreeSet;

/// Each parameter with a valid domain, in declaration order. A parameter whose domain is wrong,
/// or that has no value left to draw, is left out after its error.
pub(super) fn lower_params(
    cx: &mut Cx,
    p: &Protocol,
    kinds: &KindMap,
    labware: &[Option<LabwareSpec>],
) -> Vec<ParamSpec> {
    let mut out: Vec<ParamSpec> = Vec::new();
    for param in &p.params {
        let earlier: Vec<&str> = out.iter().map(|p| p.name.as_str()).collect();
        let Some(domain) = &param.domain else {
            continue;
        };
        let domain = match domain {
            // Reported by the parser.
            ParamDomain::Choice(values) if values.is_empty() => continue,
            ParamDomain::Choice(values) => choice_domain(cx, param, values),
            ParamDomain::Int { low, high, step } => int_domain(cx, param, low, high, step.as_ref()),
            ParamDomain::Real { low, high } => real_domain(cx, param, low, high),
            ParamDomain::Slot {
                of,
                free,
                opposite,
                tubes,
            } => match opposite {
                Some(o) => opposite_domain(cx, kinds, &out, &earlier, of, o, tubes.as_ref()),
                None => slot_domain(cx, kinds, labware, of, *free),
            },
        };
        let Some(domain) = domain else {
            continue;
        };
        exclusion_placeholders(cx, param, &earlier);
        out.push(ParamSpec {
            name: param.name.value.clone(),
            domain,
            exclude: param.exclude.iter().map(|e| e.value.text()).collect(),
        });
        let (assignments, _) = crate::params::proof_assignments(&out);
        if assignments.is_empty() {
            out.pop();
            cx.err(
                Code::E0022,
                param.name.span,
                format!("parameter `{}` has no value left to draw", param.name.value),
                Some("its exclusions (or `free = true`) remove every value".into()),
            );
        }
    }
    out
}

/// A `choice` domain: one type per domain, numbers (integers and decimals) or strings or
/// booleans. The first value sets it; a value of another type is the mistake (E0004), reported
/// where it is written, not where the parameter is later used. A value listed twice is E0022.
fn choice_domain(cx: &mut Cx, param: &Param, values: &[Spanned<Scalar>]) -> Option<Domain> {
    let class = |v: &Scalar| match v {
        Scalar::Int(_) | Scalar::Float(_) => ("a number", "numbers"),
        Scalar::Str(_) => ("a string", "strings"),
        Scalar::Bool(_) => ("a boolean", "booleans"),
    };
    let first = class(&values[0].value);
    let mut mixed = false;
    for v in &values[1..] {
        let this = class(&v.value);
        if this != first {
            cx.err(
                Code::E0004,
                v.span,
                format!(
                    "`{}`'s choices are {}, but `{}` is {}",
                    param.name.value,
                    first.1,
                    v.value.text(),
                    this.0
                ),
                Some(format!(
                    "every value of one `choice` has the same type: write `{}` as {}, or quote every value",
                    v.value.text(),
                    first.0
                )),
            );
            mixed = true;
        }
    }
    if mixed {
        return None;
    }
    let mut seen = BTreeSet::new();
    for v in values {
        if !seen.insert(v.value.text()) {
            cx.err(
                Code::E0022,
                v.span,
                format!("`{}` is listed twice", v.value.text()),
                None,
            );
        }
    }
    Some(Domain::Choice {
        values: values.iter().map(|v| v.value.text()).collect(),
    })
}

/// An `int` domain: low end first and a positive step (E0022).
fn int_domain(
    cx: &mut Cx,
    param: &Param,
    low: &Spanned<i64>,
    high: &Spanned<i64>,
    step: Option<&Spanned<i64>>,
) -> Option<Domain> {
    let step_v = step.map(|s| s.value).unwrap_or(1);
    if low.value > high.value {
        cx.err(
            Code::E0022,
            low.span,
            format!("`int` range [{}, {}] is empty", low.value, high.value),
            Some("write the low end first".into()),
        );
        return None;
    }
    if step_v <= 0 {
        let span = step.map(|s| s.span).unwrap_or(param.span);
        cx.err(Code::E0022, span, "`step` must be positive".into(), None);
        return None;
    }
    Some(Domain::Int {
        low: low.value,
        high: high.value,
        step: step_v,
    })
}

/// A `real` domain: two quantities of one dimension (E0020), low end first (E0022), lowered to
/// the dimension's canonical unit. Its exclusions are an error (E0022) that keeps the domain.
fn real_domain(
    cx: &mut Cx,
    param: &Param,
    low: &Spanned<String>,
    high: &Spanned<String>,
) -> Option<Domain> {
    let (lo, hi) = match (parse_quantity(&low.value), parse_quantity(&high.value)) {
        (Ok(a), Ok(b)) if a.dimension == b.dimension => (a, b),
        (Ok(a), Ok(b)) => {
            cx.err(
                Code::E0020,
                high.span,
                format!(
                    "`real` bounds differ in kind: a {} and a {}",
                    a.dimension.name(),
                    b.dimension.name()
                ),
                None,
            );
            return None;
        }
        (Err(e), _) => {
            cx.err(Code::E0020, low.span, e.to_string(), None);
            return None;
        }
        (_, Err(e)) => {
            cx.err(Code::E0020, high.span, e.to_string(), None);
            return None;
        }
    };
    if lo.si > hi.si {
        cx.err(
            Code::E0022,
            low.span,
            format!("`real` range [`{}`, `{}`] is empty", low.value, high.value),
            None,
        );
        return None;
    }
    if let Some(e) = param.exclude.first() {
        cx.err(
            Code::E0022,
            e.span,
            "a `real` parameter cannot exclude values".into(),
            Some("exclusions apply to `choice`, `int` and `slot` parameters".into()),
        );
    }
    Some(Domain::Real {
        low: lo.si,
        high: hi.si,
        unit: lo.dimension.canonical_unit().into(),
    })
}

/// The kind and slot table of a `slot` parameter's holder: declared labware (E0013) with slots
/// (E0016).
fn holder_slots(cx: &mut Cx, kinds: &KindMap, of: &Spanned<String>) -> Option<labware::Slots> {
    let Some(kind) = kinds.get(&of.value) else {
        let names: Vec<&str> = kinds.keys().map(String::as_str).collect();
        cx.err(
            Code::E0013,
            of.span,
            format!("no labware named `{}`", of.value),
            Some(hint_for(&of.value, &names, "labware")),
        );
        return None;
    };
    let Some(slots) = kind.slots else {
        cx.err(
            Code::E0016,
            of.span,
            format!("`{}` (a {}) has no slots", of.value, kind.name),
            None,
        );
        return None;
    };
    Some(slots)
}

/// A `slot` domain: the holder's slots, less those occupied at the start under `free = true`
/// (a start slot with placeholders occupies none here).
fn slot_domain(
    cx: &mut Cx,
    kinds: &KindMap,
    labware: &[Option<LabwareSpec>],
    of: &Spanned<String>,
    free: bool,
) -> Option<Domain> {
    let slots = holder_slots(cx, kinds, of)?;
    let occupied: Vec<String> = labware
        .iter()
        .flatten()
        .filter_map(|l| l.at.as_deref())
        .filter(|a| placeholders(a).is_empty())
        .filter_map(|a| a.split_once('.'))
        .filter(|(h, _)| *h == of.value)
        .map(|(_, s)| s.to_string())
        .collect();
    Some(Domain::Slot {
        holder: of.value.clone(),
        slots: slots
            .layout
            .names()
            .into_iter()
            .filter(|s| !(free && occupied.contains(s)))
            .collect(),
    })
}

/// A `slot` parameter with `opposite`: the slot across a ring (E0016 for another layout) from
/// an earlier slot parameter of the same holder (E0023).
fn opposite_domain(
    cx: &mut Cx,
    kinds: &KindMap,
    out: &[ParamSpec],
    earlier: &[&str],
    of: &Spanned<String>,
    o: &Spanned<String>,
    tubes: Option<&Spanned<i64>>,
) -> Option<Domain> {
    let slots = holder_slots(cx, kinds, of)?;
    let labware::SlotLayout::Ring { n } = slots.layout else {
        cx.err(
            Code::E0016,
            o.span,
            format!(
                "`{}` has no opposite slots: its slots form a {}",
                of.value,
                slots.layout.describe()
            ),
            None,
        );
        return None;
    };
    let same_holder = out.iter().any(|x| {
        x.name == o.value && matches!(&x.domain, Domain::Slot { holder, .. } if *holder == of.value)
    });
    if !same_holder {
        cx.err(
            Code::E0023,
            o.span,
            format!(
                "`opposite` needs an earlier slot parameter of `{}`, found `{}`",
                of.value, o.value
            ),
            Some(hint_for(&o.value, earlier, "earlier parameters")),
        );
        return None;
    }
    let spaced = match tubes {
        None => 2,
        Some(t) => match u32::try_from(t.value) {
            Ok(k) if k >= 2 && k <= n && n % k == 0 => k,
            _ => {
                let fits: Vec<String> = (2..=n)
                    .filter(|k| n % k == 0)
                    .map(|k| k.to_string())
                    .collect();
                cx.err(
                    Code::E0021,
                    t.span,
                    format!(
                        "{} tubes cannot stand evenly spaced in `{}`'s {n} slots",
                        t.value, of.value
                    ),
                    Some(format!(
                        "evenly spaced loads there have {} tubes; make others of these (4 as two opposite pairs: two `balances` with `tubes = 2`)",
                        fits.join(", ")
                    )),
                );
                return None;
            }
        },
    };
    Some(Domain::Opposite {
        holder: of.value.clone(),
        of: o.value.clone(),
        ring: n,
        tubes: spaced,
    })
}

/// E0023 for an `exclude` value's `{name}` that is not an earlier parameter.
fn exclusion_placeholders(cx: &mut Cx, param: &Param, earlier: &[&str]) {
    for e in &param.exclude {
        if let Scalar::Str(s) = &e.value {
            for (_, name) in placeholders(s) {
                if !earlier.contains(&name.as_str()) {
                    cx.err(
                        Code::E0023,
                        e.span,
                        format!("`exclude` uses `{{{name}}}`, which is not an earlier parameter"),
                        Some(hint_for(&name, earlier, "earlier parameters")),
                    );
                }
            }
        }
    }
}

/// Reports `{name}` placeholders that name no parameter.
pub(super) fn check_placeholders(cx: &mut Cx, text: &Spanned<String>, params: &[&str]) {
    for (offset, name) in placeholders(&text.value) {
        if !params.contains(&name.as_str()) {
            // +1 skips the opening quote of a basic string; exact for strings without escapes.
            let start = text.span.start + 1 + offset;
            let span = Span::new(start, (start + name.len() + 2).min(text.span.end));
            cx.err(
                Code::E0023,
                span,
                format!("unknown placeholder `{{{name}}}`"),
                Some(hint_for(&name, params, "parameters")),
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::testing::*;
    use crate::params::Domain;
    use dsl::Code;

    /// A `choice` of numbers with a string among them is E0004 at the string, and the parameter
    /// is left out; a value listed twice is E0022 at the second.
    #[test]
    fn a_choice_of_mixed_types_is_e0004_at_the_odd_value() {
        let src = edited(&[("choice = [\"A\", \"B\"]", "choice = [1, 2, \"B\"]")]);
        lowered(&src, |low, diags| {
            let d = one(diags, Code::E0004);
            assert_eq!(
                d.message,
                "`row`'s choices are numbers, but `B` is a string"
            );
            assert_eq!(covered(&src, d.span), "\"B\"");
            assert!(low.unwrap().params.is_empty());
        });
        let src = edited(&[("choice = [\"A\", \"B\"]", "choice = [\"A\", \"B\", \"A\"]")]);
        lowered(&src, |low, diags| {
            let d = one(diags, Code::E0022);
            assert_eq!(d.message, "`A` is listed twice");
            assert_eq!(d.span.start, src.rfind("\"A\"").unwrap());
            assert_eq!(
                low.unwrap().params[0].domain,
                Domain::Choice {
                    values: vec!["A".into(), "B".into(), "A".into()]
                }
            );
        });
    }

    /// `int` and `real` ranges: an empty range and a step that is not positive are E0022, real
    /// bounds of two dimensions E0020; a good `real` lowers to its canonical unit.
    #[test]
    fn numeric_ranges_are_non_empty_of_one_dimension_and_lowered_to_si() {
        let param = |table: &str| with(&format!("[params.n]\n{table}\n"));
        let cases = [
            (
                "int = [5, 1]",
                Code::E0022,
                "`int` range [5, 1] is empty",
                "5",
            ),
            (
                "int = [1, 5]\nstep = 0",
                Code::E0022,
                "`step` must be positive",
                "0",
            ),
            (
                "real = [\"1 s\", \"2 mm\"]",
                Code::E0020,
                "`real` bounds differ in kind: a time and a length",
                "\"2 mm\"",
            ),
            (
                "real = [\"2 s\", \"1 s\"]",
                Code::E0022,
                "`real` range [`2 s`, `1 s`] is empty",
                "\"2 s\"",
            ),
        ];
        for (table, code, message, at) in cases {
            let src = param(table);
            lowered(&src, |low, diags| {
                let d = one(diags, code);
                assert_eq!(d.message, message);
                assert_eq!(covered(&src, d.span), at, "{table}");
                assert_eq!(low.unwrap().params.len(), 1, "only `row`: {table}");
            });
        }
        lowered(&param("real = [\"100 µL\", \"1 mL\"]"), |low, diags| {
            assert!(diags.is_empty(), "{diags:#?}");
            assert_eq!(
                low.unwrap().params[1].domain,
                Domain::Real {
                    low: 100.0,
                    high: 1000.0,
                    unit: "µL".into()
                }
            );
        });
    }

    /// `free = true` leaves out the slots items start in; without it they stay.
    #[test]
    fn a_free_slot_parameter_leaves_out_the_start_slots() {
        for (free, has_a1) in [("\nfree = true", false), ("", true)] {
            lowered(
                &with(&format!("[params.spot]\nslot = \"source\"{free}\n")),
                |low, diags| {
                    assert!(diags.is_empty(), "{diags:#?}");
                    let Domain::Slot { holder, slots } = &low.unwrap().params[1].domain else {
                        panic!("a slot domain");
                    };
                    assert_eq!(holder, "source");
                    assert!(slots.contains(&"A2".to_string()));
                    assert_eq!(slots.contains(&"A1".to_string()), has_a1, "free: {free:?}");
                },
            );
        }
    }

    /// `opposite` needs a ring of slots and an earlier slot parameter of the same holder.
    #[test]
    fn opposite_needs_a_ring_and_an_earlier_slot_of_the_same_holder() {
        let centrifuge = "[labware.centrifuge]\nkind = \"centrifuge_5430\"\npose = { pos_m = [0.0, 0.35, 0.824] }\n";
        let src = with(&format!(
            "{centrifuge}\n[params.first]\nslot = \"centrifuge\"\n\n[params.across]\nslot = \"centrifuge\"\nopposite = \"first\"\n"
        ));
        lowered(&src, |low, diags| {
            assert!(diags.is_empty(), "{diags:#?}");
            assert_eq!(
                low.unwrap().params[2].domain,
                Domain::Opposite {
                    holder: "centrifuge".into(),
                    of: "first".into(),
                    ring: 30,
                    tubes: 2,
                }
            );
        });
        // `balances` with `tubes`: the next slot of an evenly spaced load of that many.
        let src = with(&format!(
            "{centrifuge}\n[params.first]\nslot = \"centrifuge\"\n\n[params.second]\nslot = \"centrifuge\"\nbalances = \"first\"\ntubes = 3\n"
        ));
        lowered(&src, |low, diags| {
            assert!(diags.is_empty(), "{diags:#?}");
            let Domain::Opposite { tubes, ring, .. } = &low.unwrap().params[2].domain else {
                panic!("a balancing domain");
            };
            assert_eq!((*tubes, *ring), (3, 30));
        });
        assert_eq!(crate::params::spaced("1", 30, 3).as_deref(), Some("11"));
        assert_eq!(crate::params::spaced("25", 30, 3).as_deref(), Some("5"));
        // Four tubes do not stand evenly spaced in 30 slots; `tubes` alone; two spellings.
        for (extra, code) in [
            ("balances = \"first\"\ntubes = 4", Code::E0021),
            ("tubes = 3", Code::E0002),
            ("balances = \"first\"\nopposite = \"first\"", Code::E0007),
        ] {
            let src = with(&format!(
                "{centrifuge}\n[params.first]\nslot = \"centrifuge\"\n\n[params.second]\nslot = \"centrifuge\"\n{extra}\n"
            ));
            lowered(&src, |_, diags| {
                let d = one(diags, code);
                if code == Code::E0021 {
                    assert!(
                        d.hint
                            .as_deref()
                            .unwrap_or_default()
                            .contains("2, 3, 5, 6, 10, 15, 30"),
                        "{d:?}"
                    );
                }
            });
        }
        let src = with(&format!(
            "{centrifuge}\n[params.across]\nslot = \"centrifuge\"\nopposite = \"row\"\n"
        ));
        lowered(&src, |_, diags| {
            let d = one(diags, Code::E0023);
            assert_eq!(
                d.message,
                "`opposite` needs an earlier slot parameter of `centrifuge`, found `row`"
            );
            assert_eq!(covered(&src, d.span), "\"row\"");
        });
        let src = with(
            "[params.first]\nslot = \"source\"\n\n[params.across]\nslot = \"source\"\nopposite = \"first\"\n",
        );
        lowered(&src, |_, diags| {
            assert!(
                one(diags, Code::E0016)
                    .message
                    .starts_with("`source` has no opposite slots: its slots form a ")
            );
        });
    }

    /// Exclusions that name a later parameter are E0023; exclusions that leave nothing to draw
    /// drop the parameter with E0022 at its name.
    #[test]
    fn exclusions_name_earlier_parameters_and_leave_a_value_to_draw() {
        let src = edited(&[(
            "choice = [\"A\", \"B\"]",
            "choice = [\"A\", \"B\"]\nexclude = [\"A\", \"B\"]",
        )]);
        lowered(&src, |low, diags| {
            let d = one(diags, Code::E0022);
            assert_eq!(d.message, "parameter `row` has no value left to draw");
            assert_eq!(covered(&src, d.span), "row");
            assert!(low.unwrap().params.is_empty());
        });
        let src = edited(&[(
            "choice = [\"A\", \"B\"]",
            "choice = [\"A\", \"B\"]\nexclude = [\"{col}\"]",
        )]);
        lowered(&src, |_, diags| {
            assert_eq!(
                one(diags, Code::E0023).message,
                "`exclude` uses `{col}`, which is not an earlier parameter"
            );
        });
    }

    /// A placeholder naming no parameter is E0023 on exactly its braces, with the closest name.
    #[test]
    fn an_unknown_placeholder_is_e0023_on_its_braces() {
        let src = edited(&[("row {row}\"", "row {rox}\"")]);
        lowered(&src, |_, diags| {
            let d = one(diags, Code::E0023);
            assert_eq!(d.message, "unknown placeholder `{rox}`");
            assert_eq!(covered(&src, d.span), "{rox}");
            assert_eq!(d.hint.as_deref(), Some("did you mean `row`?"));
        });
    }
}
