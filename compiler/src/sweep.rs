//! Every place a protocol names a slot (a labware's `at`, a step's location argument, an `in`
//! predicate) or a quantity (a step's volume or panel value, a panel or volume predicate's target)
//! checked over the parameters' domains in one pass, before the state proof: a slot the holder
//! lacks, a holder that does not take the item, two items declared in one place, a unit that is not
//! known or of the wrong dimension. Each mistake is reported once at every place it occurs,
//! whatever else is wrong in the file, and a parameter-driven value's bad values are summed up in
//! one diagnostic (`row = C` for any `col`), not shown as the first failing combination. It decides
//! nothing about the order of steps: the proof does.

use crate::params::{Bindings, ParamSpec, placeholders, proof_assignments, render};
use crate::predicates::ValueError;
use crate::primitives::{self, Env, LocationError};
use crate::report::Cx;
use dsl::{Code, Diagnostic, Dimension, ParseQuantityError, Span};
use labware::LabwareKind;
use std::collections::{BTreeMap, BTreeSet};

/// One place a slot or a quantity is named.
pub(crate) struct Use {
    pub span: Span,
    /// As written: `target.{row}{col}`, `{temp} °C`.
    pub template: String,
    pub what: What,
}

/// What a place must name.
pub(crate) enum What {
    /// A slot, and the item that stands there (the labware placed, moved or checked) with its
    /// kind; `start`: a labware's `at` (two of them may not name the same slot).
    Slot {
        item: Option<(String, &'static LabwareKind)>,
        start: bool,
    },
    /// A quantity of this dimension.
    Quantity(Dimension),
}

/// Checks every use; `params` are the lowered parameters (a placeholder naming none is reported
/// elsewhere, so such a use is skipped here).
pub(crate) fn check(
    cx: &mut Cx,
    uses: &[Use],
    kinds: &BTreeMap<String, &'static LabwareKind>,
    declared: &[&str],
    robots: &[String],
    params: &[ParamSpec],
) {
    let env = Env { kinds, robots };
    let known: BTreeSet<&str> = params.iter().map(|p| p.name.as_str()).collect();
    // Every combination the proof traces, and whether that is every combination there is.
    let mut combinations: Option<(Vec<Bindings>, bool)> = None;
    let mut starts: BTreeMap<String, &str> = BTreeMap::new();
    for u in uses {
        let names: BTreeSet<String> = placeholders(&u.template)
            .into_iter()
            .map(|(_, n)| n)
            .collect();
        if names.iter().any(|n| !known.contains(n.as_str())) {
            continue;
        }
        // A holder declared with a kind that is not known (reported at its `kind`), or an item
        // that cannot stand in a slot at all (reported at its `at`): nothing more to say here.
        let holder = u.template.split_once('.').map_or("", |(h, _)| h);
        if declared.contains(&holder) && !kinds.contains_key(holder) {
            continue;
        }
        if let What::Slot {
            item: Some((_, kind)),
            start: true,
        } = &u.what
            && !kind.movable
        {
            continue;
        }
        if names.is_empty() {
            if let Err(m) = fits(&env, &u.template, &u.what) {
                cx.push(m.at(u.span));
            } else if let What::Slot {
                item: Some((name, _)),
                start: true,
            } = &u.what
            {
                match starts.get(&u.template) {
                    Some(other) => cx.push(
                        Diagnostic::new(
                            Code::E0016,
                            u.span,
                            format!("`{name}` and `{other}` both start in `{}`", u.template),
                        )
                        .with_hint(
                            "give each its own slot, or draw one with `slot = .., free = true`",
                        ),
                    ),
                    None => {
                        starts.insert(u.template.clone(), name);
                    }
                }
            }
            continue;
        }
        // The values of the placeholders this use names, in every combination the proof traces.
        let (all, exhaustive) = combinations.get_or_insert_with(|| proof_assignments(params));
        let exhaustive = *exhaustive;
        let projections: BTreeSet<Bindings> = all
            .iter()
            .map(|b| {
                b.iter()
                    .filter(|(k, _)| names.contains(*k))
                    .map(|(k, v)| (k.clone(), v.clone()))
                    .collect()
            })
            .collect();
        let mut bad: Vec<(Bindings, Misfit)> = Vec::new();
        let mut good: Vec<Bindings> = Vec::new();
        for b in projections {
            let Ok(place) = render(&u.template, &b) else {
                continue;
            };
            match fits(&env, &place, &u.what) {
                Ok(()) => good.push(b),
                Err(m) => bad.push((b, m)),
            }
        }
        if bad.is_empty() {
            continue;
        }
        // A misfit that does not depend on the values (the holder never takes the item, a unit
        // that is not known, no unit at all) is said once, in the author's terms: the template,
        // not one combination's rendering.
        let said: Vec<String> = bad
            .iter()
            .map(|(b, m)| match render(&u.template, b) {
                Ok(place) => m
                    .message
                    .replace(&format!("`{place}`"), &format!("`{}`", u.template)),
                Err(_) => m.message.clone(),
            })
            .collect();
        if good.is_empty() && said.iter().all(|m| *m == said[0]) {
            let (_, mut m) = bad.swap_remove(0);
            m.message = said[0].clone();
            cx.push(m.at(u.span));
            continue;
        }
        cx.push(summary(u, &bad, &good, exhaustive, kinds));
    }
}

/// Why a rendered place does not fit.
struct Misfit {
    code: Code,
    message: String,
    hint: Option<String>,
    /// Holds whatever the slot's name: the holder has no slots, or does not take the item.
    independent: bool,
}

impl Misfit {
    fn at(self, span: Span) -> Diagnostic {
        let mut d = Diagnostic::new(self.code, span, self.message);
        d.hint = self.hint;
        d
    }
}

fn fits(env: &Env, place: &str, what: &What) -> Result<(), Misfit> {
    let item = match what {
        What::Slot { item, .. } => item.as_ref(),
        What::Quantity(dim) => {
            // A unit that is not known, or of another dimension, is wrong whatever the number.
            return crate::predicates::quantity(place, &Bindings::new(), *dim)
                .map(|_| ())
                .map_err(|e| Misfit {
                    code: Code::E0020,
                    independent: matches!(
                        e,
                        ValueError::Quantity(ParseQuantityError::UnknownUnit { .. })
                            | ValueError::WrongDimension { .. }
                    ),
                    hint: matches!(e, ValueError::Quantity(ParseQuantityError::NoUnit { .. }))
                        .then(|| "a parameter used as a quantity must render with its unit".into()),
                    message: e.to_string(),
                });
        }
    };
    let (holder, _slot, hkind) = primitives::resolve_location(env, place).map_err(|e| Misfit {
        code: Code::E0016,
        independent: !matches!(e, LocationError::NoSlot { .. }),
        message: e.to_string(),
        hint: None,
    })?;
    if let Some((_, kind)) = item {
        let accepts = hkind.slots.map(|s| s.accepts).unwrap_or(&[]);
        if !accepts.contains(&kind.name) {
            return Err(Misfit {
                code: Code::E0016,
                message: format!(
                    "a slot of `{holder}` (a {}) does not take a {}",
                    hkind.name, kind.name
                ),
                hint: Some(format!("it takes: {}", accepts.join(", "))),
                independent: true,
            });
        }
    }
    Ok(())
}

/// One diagnostic for a parameter-driven place: each value that fails whatever the others are
/// (`row = C`, for any `col`), then the combinations left over, with the holder's slots; or,
/// where every combination was traced (`exhaustive`) and none fits, that no value fills it, with
/// the misfit that holds whatever the values are (the holder never takes the item) as its note.
fn summary(
    u: &Use,
    bad: &[(Bindings, Misfit)],
    good: &[Bindings],
    exhaustive: bool,
    kinds: &BTreeMap<String, &'static LabwareKind>,
) -> Diagnostic {
    let names: Vec<&String> = bad[0].0.keys().collect();
    let holder = u.template.split_once('.').map_or("", |(h, _)| h);
    let (code, names_what) = match u.what {
        What::Slot { .. } => (Code::E0016, "no slot it can use"),
        What::Quantity(_) => (Code::E0020, "no quantity it can use"),
    };
    // No value works: the template is wrong, not a domain (PCR tubes named into a rack that
    // takes none): say so rather than list every value. Said only of a proof that traced every
    // combination: a sample's misses are no proof that nothing fits.
    let none_fits = good.is_empty() && exhaustive;
    let independent = bad.iter().map(|(_, m)| m).find(|m| m.independent);
    let when = if none_fits {
        let all: Vec<String> = names.iter().map(|n| format!("`{n}`")).collect();
        format!("for any value of {}", all.join(", "))
    } else {
        format!("when {}", failing_values(&names, bad, good))
    };
    let mut d = Diagnostic::new(
        code,
        u.span,
        format!("`{}` names {names_what} {when}", u.template),
    );
    d.hint = match (&u.what, kinds.get(holder).and_then(|k| k.slots)) {
        // Narrowing a domain cannot help where nothing fits: the misfit's own hint, if any.
        _ if none_fits && independent.is_some_and(|m| m.hint.is_some()) => {
            independent.and_then(|m| m.hint.clone())
        }
        (What::Slot { .. }, Some(slots)) => Some(format!(
            "`{holder}`'s slots: {}; narrow the parameters' domains to them",
            slots.layout.describe()
        )),
        _ => bad[0].1.hint.clone(),
    };
    if let Some(m) = independent {
        d.notes.push(m.message.clone());
    }
    d
}

/// Each value that fails whatever the others are (`row = C`, for any `col`; in the values' order,
/// numbers by value), then the combinations left over.
fn failing_values(names: &[&String], bad: &[(Bindings, Misfit)], good: &[Bindings]) -> String {
    let mut phrases = Vec::new();
    let mut covered: BTreeSet<&Bindings> = BTreeSet::new();
    for name in names {
        let values: BTreeSet<&String> = bad.iter().map(|(b, _)| &b[*name]).collect();
        let mut values: Vec<&String> = values.into_iter().collect();
        // Numbers first, by value; then the rest as text (a total order, so the sort is sound).
        values.sort_by(|a, b| match (a.parse::<f64>(), b.parse::<f64>()) {
            (Ok(x), Ok(y)) => x.total_cmp(&y),
            (Ok(_), Err(_)) => std::cmp::Ordering::Less,
            (Err(_), Ok(_)) => std::cmp::Ordering::Greater,
            (Err(_), Err(_)) => a.cmp(b),
        });
        for v in values {
            if good.iter().any(|b| &b[*name] == v) {
                continue;
            }
            let others: Vec<String> = names
                .iter()
                .filter(|n| *n != name)
                .map(|n| format!("`{n}`"))
                .collect();
            phrases.push(if others.is_empty() {
                format!("`{name} = {v}`")
            } else {
                format!("`{name} = {v}` (any {})", others.join(", "))
            });
            covered.extend(bad.iter().map(|(b, _)| b).filter(|b| &b[*name] == v));
        }
    }
    let rest: Vec<&Bindings> = bad
        .iter()
        .map(|(b, _)| b)
        .filter(|b| !covered.contains(b))
        .collect();
    for b in rest.iter().take(3) {
        let parts: Vec<String> = b.iter().map(|(k, v)| format!("{k} = {v}")).collect();
        phrases.push(format!("`{}`", parts.join(", ")));
    }
    if rest.len() > 3 {
        phrases.push(format!("{} more combinations", rest.len() - 3));
    }
    phrases.join(" or ")
}
