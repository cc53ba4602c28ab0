//! A walk written as a protocol file: the scene file it stands on, its start, its steps, one
//! instruction made of each step's phrase, a time limit from the steps' budgets, and success as
//! every fact the walk leaves changed (where each moved item ends, each part state and panel
//! value that differs from the start). The text is what `autobio check` then reads; nothing
//! here decides whether it is valid.

use super::vocabulary::panel_value;
use super::walk::{Step, Walk};
use compiler::params::format_number;
use compiler::world::{Location, World};
use labware::LabwareKind;
use std::collections::BTreeMap;
use std::fmt::Write as _;

/// How much more than the sum of its steps' budgets a protocol is given: its steps start from
/// where the step before left the arm, not from the pose their sources started at.
const TIME_FACTOR: f64 = 1.25;

pub(crate) struct Header<'a> {
    pub id: &'a str,
    pub scene: &'a str,
    pub comment: &'a str,
}

pub(crate) fn protocol(
    h: &Header,
    walk: &Walk,
    kinds: &BTreeMap<String, &'static LabwareKind>,
) -> String {
    let mut s = String::new();
    for line in h.comment.lines() {
        let _ = writeln!(s, "# {line}");
    }
    let _ = writeln!(s, "format = 1\nscene = {}\n", quoted(h.scene));
    let instruction: Vec<String> = walk.steps.iter().map(phrase).collect();
    let budget: f64 = walk.steps.iter().map(|s| s.template.budget_s).sum();
    let limit = (budget * TIME_FACTOR * 2.0).ceil() / 2.0;
    let _ = writeln!(
        s,
        "[protocol]\nid = {}\nlevel = \"hard\"\ninstruction = {}\ntime_limit = \"{} s\"\n",
        quoted(h.id),
        quoted(&instruction.join(", then ")),
        format_number(limit)
    );
    let items: std::collections::BTreeSet<&String> = walk
        .start
        .states
        .keys()
        .chain(walk.start.at.keys())
        .collect();
    for item in items {
        let _ = writeln!(s, "[labware.{item}]");
        if let Some(at) = walk.start.at.get(item) {
            let _ = writeln!(s, "at = {}", quoted(at));
        }
        if let Some(states) = walk.start.states.get(item).filter(|m| !m.is_empty()) {
            let parts: Vec<String> = states
                .iter()
                .map(|(p, v)| format!("{p} = {}", quoted(v)))
                .collect();
            let _ = writeln!(s, "state = {{ {} }}", parts.join(", "));
        }
        s.push('\n');
    }
    for step in &walk.steps {
        let _ = writeln!(s, "[[steps]]\ndo = \"{}\"", step.template.primitive.name);
        for (k, v) in &step.args {
            let _ = writeln!(s, "{k} = {}", quoted(v));
        }
        let _ = writeln!(s, "with = {}\n", quoted(&step.template.robot));
    }
    let checks: Vec<String> = success(&walk.first, &walk.last, kinds)
        .iter()
        .map(|c| quoted(c))
        .collect();
    let _ = writeln!(s, "[success]\nall = [{}]", checks.join(", "));
    s
}

/// Every fact that differs between the start and the end, as success predicates.
pub(crate) fn success(
    first: &World,
    last: &World,
    kinds: &BTreeMap<String, &'static LabwareKind>,
) -> Vec<String> {
    let mut out = Vec::new();
    for (item, loc) in &last.locations {
        if first.locations.get(item) == Some(loc) {
            continue;
        }
        if let Location::Slot { holder, slot } = loc {
            out.push(format!("{item} in {holder}.{slot}"));
        }
    }
    for ((item, part), state) in &last.parts {
        let was = first.part(item, part);
        if was == Some(state.as_str()) {
            continue;
        }
        // A locked lid is also closed: a lid unlocked but still shut is told by "unlocked".
        let word = match (was, state.as_str()) {
            (Some("locked"), "closed") => "unlocked",
            (_, s) => s,
        };
        out.push(format!("{item}.{part} is {word}"));
    }
    for (key, value) in &last.panel {
        let (item, param) = key;
        let unit = kinds
            .get(item)
            .and_then(|k| k.panel_param(param))
            .map(|p| p.unit)
            .unwrap_or_default();
        if panel_value(kinds, first, key) != Some(*value) {
            out.push(format!("{item}.{param} = {} {unit}", format_number(*value)));
        }
    }
    out
}

/// One step in the instruction's words.
/// The step as its primitive words it (`LabPrimitive::phrase`, declared beside the primitive).
fn phrase(step: &Step) -> String {
    let primitive = step.template.primitive;
    primitive.phrase_for(&step.template.robot, &step.args)
}

/// A TOML basic string.
fn quoted(s: &str) -> String {
    let mut out = String::with_capacity(s.len() + 2);
    out.push('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            c if c.is_control() => out.push_str(&format!("\\u{:04X}", c as u32)),
            c => out.push(c),
        }
    }
    out.push('"');
    out
}
