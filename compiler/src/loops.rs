//! Loops in a protocol's steps, expanded before anything is checked: a `repeat = N` step runs
//! its `[[steps.body]]` N times, a `for_each = { var = [..] }` step once per value with `{var}`
//! standing for it in the body's arguments and `with` (several variables step together; a
//! `"<holder>.slots"` runs over a holder's slots in its catalogue order). Loops nest. The
//! expanded steps keep the spans of the steps they came from, so every later diagnostic points
//! into the loop's body. It checks loop variables (E0015 for one that shadows an outer loop's, a
//! parameter or another of the same loop; E0013 for a holder without slots; E0021 for lists
//! of different lengths or more than [`MAX_STEPS`] steps) and nothing the steps say.

use crate::report::{Cx, hint_for};
use dsl::Code;
use dsl::ast::{LoopValues, Protocol, Scalar, Spanned, Step};
use std::collections::BTreeMap;

/// The most steps a protocol's loops may expand to.
pub(crate) const MAX_STEPS: usize = 10_000;

/// Replaces `p`'s loop steps by the steps they run.
pub(crate) fn expand(cx: &mut Cx, p: &mut Protocol) {
    if !p.steps.iter().any(Step::is_loop) {
        return;
    }
    let holders: BTreeMap<String, Option<Vec<String>>> = p
        .labware
        .iter()
        .map(|l| {
            let slots = l
                .kind
                .as_ref()
                .and_then(|k| labware::kind(&k.value))
                .and_then(|k| k.slots)
                .map(|s| s.layout.names());
            (l.name.value.clone(), slots)
        })
        .collect();
    let params: Vec<String> = p.params.iter().map(|x| x.name.value.clone()).collect();
    let steps = std::mem::take(&mut p.steps);
    let mut out = Vec::new();
    let scope = Scope {
        holders: &holders,
        params: &params,
    };
    scope.expand(cx, &steps, &BTreeMap::new(), &mut out);
    p.steps = out;
}

struct Scope<'a> {
    holders: &'a BTreeMap<String, Option<Vec<String>>>,
    params: &'a [String],
}

impl Scope<'_> {
    fn expand(
        &self,
        cx: &mut Cx,
        steps: &[Step],
        vars: &BTreeMap<String, String>,
        out: &mut Vec<Step>,
    ) {
        for s in steps {
            if out.len() > MAX_STEPS {
                return;
            }
            if !s.is_loop() {
                out.push(substitute(s, vars));
                continue;
            }
            for iteration in self.iterations(cx, s, vars) {
                self.expand(cx, &s.body, &iteration, out);
                if out.len() > MAX_STEPS {
                    cx.err(
                        Code::E0021,
                        s.span,
                        format!("the loops expand to more than {MAX_STEPS} steps"),
                        Some("fewer repeats, or a chain of protocols".into()),
                    );
                    return;
                }
            }
        }
    }

    /// The variables of each run of a loop's body (the outer ones included).
    fn iterations(
        &self,
        cx: &mut Cx,
        s: &Step,
        vars: &BTreeMap<String, String>,
    ) -> Vec<BTreeMap<String, String>> {
        if let Some(r) = &s.repeat {
            return if s.for_each.is_empty() {
                vec![vars.clone(); r.value.clamp(0, MAX_STEPS as i64) as usize]
            } else {
                Vec::new()
            };
        }
        let mut columns: Vec<(&Spanned<String>, Vec<String>)> = Vec::new();
        for (name, values) in &s.for_each {
            if vars.contains_key(&name.value)
                || self.params.contains(&name.value)
                || columns.iter().any(|(n, _)| n.value == name.value)
            {
                cx.err(
                    Code::E0015,
                    name.span,
                    format!(
                        "loop variable `{}` is already a parameter or a variable of an enclosing loop",
                        name.value
                    ),
                    Some("give the loop variable its own name".into()),
                );
                return Vec::new();
            }
            let list = match &values.value {
                LoopValues::List(items) => items.iter().map(|v| v.value.text()).collect(),
                LoopValues::Slots(holder) => match self.holders.get(holder) {
                    Some(Some(slots)) => slots.clone(),
                    Some(None) => {
                        cx.err(
                            Code::E0013,
                            values.span,
                            format!("`{holder}` has no slots to loop over"),
                            None,
                        );
                        return Vec::new();
                    }
                    None => {
                        let names: Vec<&str> = self.holders.keys().map(String::as_str).collect();
                        cx.err(
                            Code::E0013,
                            values.span,
                            format!("no labware named `{holder}`"),
                            Some(hint_for(holder, &names, "labware")),
                        );
                        return Vec::new();
                    }
                },
            };
            columns.push((name, list));
        }
        let n = columns.first().map_or(0, |(_, v)| v.len());
        if let Some((name, v)) = columns.iter().find(|(_, v)| v.len() != n) {
            cx.err(
                Code::E0021,
                name.span,
                format!(
                    "`{}` has {} values, but `{}` has {n}: variables of one loop step together",
                    name.value,
                    v.len(),
                    columns[0].0.value
                ),
                Some("give every variable the same number of values, or nest two loops".into()),
            );
            return Vec::new();
        }
        (0..n)
            .map(|i| {
                let mut it = vars.clone();
                for (name, values) in &columns {
                    it.insert(name.value.clone(), values[i].clone());
                }
                it
            })
            .collect()
    }
}

/// The step with each `{var}` in its string arguments, `with`, `id`, `after` and `within`
/// replaced by the variable's value (other placeholders left for the parameters).
fn substitute(s: &Step, vars: &BTreeMap<String, String>) -> Step {
    if vars.is_empty() {
        return s.clone();
    }
    let fill = |text: &str| {
        vars.iter().fold(text.to_string(), |t, (k, v)| {
            t.replace(&format!("{{{k}}}"), v)
        })
    };
    let mut out = s.clone();
    for (_, v) in &mut out.args {
        if let Scalar::Str(text) = &v.value {
            v.value = Scalar::Str(fill(text));
        }
    }
    for key in [&mut out.with, &mut out.id, &mut out.after, &mut out.within]
        .into_iter()
        .flatten()
    {
        key.value = fill(&key.value);
    }
    out
}
