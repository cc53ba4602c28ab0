//! Robots and labware lowered to their specs: each robot's model (E0011) and base, each labware
//! item's kind (E0010), where it starts (a pose, a slot or a robot's hand: E0013, E0016) and its
//! start state (part states, volume and panel values: E0017, E0020, E0021; W0007 for a start the
//! simulator cannot build yet). It does not randomise ([`super::randomise`]) or check that a
//! slot named by `at` exists ([`crate::sweep`]).

use super::KindMap;
use crate::params::placeholders;
use crate::primitives;
use crate::report::{Cx, hint_for};
use crate::task::{LabwareSpec, RobotSpec};
use dsl::ast::{Protocol, Scalar, Spanned};
use dsl::{Code, Diagnostic, Dimension, parse_quantity};
use labware::{LabwareKind, Model, Pose};
use std::collections::BTreeMap;

/// Each robot's spec, in declaration order; `None` where its model is missing or unknown.
pub(super) fn lower_robots(cx: &mut Cx, p: &Protocol) -> Vec<Option<RobotSpec>> {
    let names: Vec<&str> = robots::MODELS.iter().map(|m| m.name).collect();
    p.robots
        .iter()
        .map(|r| {
            let model = r.model.as_ref()?;
            let Some(m) = robots::model(&model.value) else {
                let hint = hint_for(&model.value, &names, "robot models");
                cx.err(
                    Code::E0011,
                    model.span,
                    format!("unknown robot model `{}`", model.value),
                    Some(hint),
                );
                return None;
            };
            Some(RobotSpec {
                name: r.name.value.clone(),
                model: m.name.into(),
                base: pose(&r.base),
                home: m.home.to_vec(),
                joint_jitter: None,
            })
        })
        .collect()
}

/// Each labware item's spec, in declaration order (`None` where its kind is missing or unknown),
/// and the kinds of those whose kind is known.
pub(super) fn lower_labware(cx: &mut Cx, p: &Protocol) -> (Vec<Option<LabwareSpec>>, KindMap) {
    let kinds: Vec<&str> = labware::KINDS.iter().map(|k| k.name).collect();
    let mut map = KindMap::new();
    let specs = p
        .labware
        .iter()
        .map(|l| lower_item(cx, p, l, &kinds, &mut map))
        .collect();
    (specs, map)
}

/// One labware item: its kind, its start place and its start state.
fn lower_item(
    cx: &mut Cx,
    p: &Protocol,
    l: &dsl::ast::Labware,
    kinds: &[&str],
    map: &mut KindMap,
) -> Option<LabwareSpec> {
    let kind = l.kind.as_ref()?;
    let Some(k) = labware::kind(&kind.value) else {
        let hint = hint_for(&kind.value, kinds, "labware kinds");
        cx.err(
            Code::E0010,
            kind.span,
            format!("unknown labware kind `{}`", kind.value),
            Some(hint),
        );
        return None;
    };
    map.insert(l.name.value.clone(), k);
    let mut spec = LabwareSpec {
        name: l.name.value.clone(),
        kind: k.name.into(),
        placement: pose(&l.pose),
        xy_jitter_m: 0.0,
        yaw_jitter_rad: 0.0,
        joint_jitter: BTreeMap::new(),
        // A run starts idle without saying so: the world reads a missing run as idle, and a
        // task that runs nothing compiles as it did before instruments ran.
        initial: k
            .parts
            .iter()
            .filter(|ps| ps.part != labware::run::RUN)
            .map(|ps| (ps.part.to_string(), ps.initial[0].to_string()))
            .collect(),
        parts: BTreeMap::new(),
        parts_radius_m: 0.0,
        at: l.at.as_ref().map(|a| a.value.clone()),
        held_by: None,
        volume: None,
        liquid: None,
        panel: BTreeMap::new(),
        params: Model::for_kind(k.name).unwrap_or(Model::Unmodelled),
    };
    if let Some(robot) = &l.held_by {
        start_in_hand(cx, p, l, k, robot, &mut spec);
    }
    if let Some(at) = &l.at
        && !k.movable
    {
        cx.err(
            Code::E0016,
            at.span,
            format!("`{}` (a {}) cannot stand in a slot", l.name.value, k.name),
            Some("place it with `pose` instead".into()),
        );
    }
    for (key, value) in &l.state {
        initial_state(cx, k, &mut spec, key, value);
    }
    if spec.liquid.is_some()
        && spec.volume.is_none()
        && let Some((key, _)) = l.state.iter().find(|(k, _)| k.value == "liquid")
    {
        cx.err(
            Code::E0002,
            key.span,
            format!("`{}` names its liquid but no `volume` of it", l.name.value),
            Some(
                "load a volume with it: `state = { volume = \"200 µL\", liquid = \"water\" }`"
                    .into(),
            ),
        );
        spec.liquid = None;
    }
    parts_apart(cx, l, k, &mut spec);
    spec.params = spec.params.for_start(&spec.initial);
    unsupported_start(cx, l, &spec);
    Some(spec)
}

/// `parts = { <part> = <pose> }`: where each loose part that starts `apart` lies. A part given
/// a place must be a loose part of the kind that starts apart, and a part that starts apart
/// needs a place (E0017 and E0002, at the item's name for a missing place).
fn parts_apart(cx: &mut Cx, l: &dsl::ast::Labware, k: &LabwareKind, spec: &mut LabwareSpec) {
    for (part, at) in &l.parts {
        let loose = k
            .part(&part.value)
            .is_some_and(|ps| ps.initial.contains(&"apart"));
        if !loose {
            let apart: Vec<&str> = k
                .parts
                .iter()
                .filter(|ps| ps.initial.contains(&"apart"))
                .map(|ps| ps.part)
                .collect();
            cx.err(
                Code::E0017,
                part.span,
                format!(
                    "a {} has no part `{}` that can lie apart",
                    k.name, part.value
                ),
                Some(hint_for(&part.value, &apart, "parts that can lie apart")),
            );
        } else if spec.initial.get(&part.value).map(String::as_str) != Some("apart") {
            cx.err(
                Code::E0017,
                part.span,
                format!(
                    "`{}` is given a place to lie, but it does not start apart",
                    part.value
                ),
                Some(format!(
                    "start it apart: `state = {{ {} = \"apart\" }}`",
                    part.value
                )),
            );
        } else {
            spec.parts.insert(part.value.clone(), pose(at));
        }
    }
    for (part, state) in &spec.initial {
        if state == "apart"
            && !spec.parts.contains_key(part)
            && !l.parts.iter().any(|(p, _)| &p.value == part)
        {
            cx.err(
                Code::E0002,
                l.name.span,
                format!(
                    "`{}`'s {part} starts apart, but nothing says where it lies",
                    l.name.value
                ),
                Some(format!(
                    "add `parts = {{ {part} = {{ pos_m = [x, y, z] }} }}` (on the bench)"
                )),
            );
        }
    }
}

/// `held_by = "<robot>"`: the item starts in that robot's hand, if the robot exists (E0013), the
/// item can be held and it does not also start in a slot (E0016).
fn start_in_hand(
    cx: &mut Cx,
    p: &Protocol,
    l: &dsl::ast::Labware,
    k: &LabwareKind,
    robot: &Spanned<String>,
    spec: &mut LabwareSpec,
) {
    let robots: Vec<&str> = p.robots.iter().map(|r| r.name.value.as_str()).collect();
    if !robots.contains(&robot.value.as_str()) {
        cx.err(
            Code::E0013,
            robot.span,
            format!("no robot named `{}`", robot.value),
            Some(hint_for(&robot.value, &robots, "robots")),
        );
    } else if !k.movable {
        cx.err(
            Code::E0016,
            robot.span,
            format!("`{}` (a {}) cannot be held", l.name.value, k.name),
            Some("place it with `pose` instead".into()),
        );
    } else if l.at.is_some() {
        cx.err(
            Code::E0016,
            robot.span,
            format!("`{}` starts both in a slot and in a hand", l.name.value),
            Some("keep `at` or `held_by`, not both".into()),
        );
    } else {
        spec.held_by = Some(robot.value.clone());
    }
}

/// W0007 for a start the language allows but the item's model cannot set up yet: said here,
/// not first by `eval` when it builds the scene.
fn unsupported_start(cx: &mut Cx, l: &dsl::ast::Labware, spec: &LabwareSpec) {
    if let Some(why) = spec
        .params
        .instrument()
        .and_then(|m| m.unsupported_start(&spec.initial))
    {
        let span = l.state.first().map_or(l.name.span, |(_, v)| v.span);
        cx.push(
            Diagnostic::new(
                Code::W0007,
                span,
                format!("the simulator cannot start `{}` this way yet", l.name.value),
            )
            .with_note(why)
            .with_hint(
                "the protocol checks and compiles; `eval` and `demo` cannot build its scene",
            ),
        );
    }
}

/// One `state = { key = value }` entry: a part state, the volume, or a panel value.
fn initial_state(
    cx: &mut Cx,
    k: &'static LabwareKind,
    spec: &mut LabwareSpec,
    key: &Spanned<String>,
    value: &Spanned<Scalar>,
) {
    let text = value.value.text();
    if let Some(ps) = k.part(&key.value) {
        if !ps.initial.contains(&text.as_str()) {
            cx.err(
                Code::E0017,
                value.span,
                format!("`{}` cannot start `{text}`", key.value),
                Some(state_hint(&text, ps.initial)),
            );
        } else {
            spec.initial.insert(key.value.clone(), text);
        }
        return;
    }
    if key.value == "liquid" && k.capacity_ul.is_some() {
        match &value.value {
            Scalar::Str(name) if is_liquid_name(name) => spec.liquid = Some(name.clone()),
            _ => cx.err(
                Code::E0021,
                value.span,
                format!("`{text}` is not a liquid's name"),
                Some(
                    "name it with letters, digits, `_` and `-`, starting with a letter, not a word predicates use: \"pbs_10x\""
                        .into(),
                ),
            ),
        }
        return;
    }
    let dim = if key.value == "volume" && k.capacity_ul.is_some() {
        Some(Dimension::Volume)
    } else {
        k.panel_param(&key.value)
            .map(|p| primitives::panel_dimension(p.unit))
    };
    let Some(dim) = dim else {
        let mut keys: Vec<&str> = k.parts.iter().map(|p| p.part).collect();
        if k.capacity_ul.is_some() {
            keys.extend(["volume", "liquid"]);
        }
        keys.extend(k.panel.iter().map(|p| p.name));
        cx.err(
            Code::E0017,
            key.span,
            format!("a {} has no state `{}`", k.name, key.value),
            Some(hint_for(&key.value, &keys, "state keys")),
        );
        return;
    };
    let Scalar::Str(s) = &value.value else {
        cx.err(
            Code::E0020,
            value.span,
            format!("`{}` needs a unit", key.value),
            Some(format!(
                "write it as a string such as \"{text} {}\"",
                dim.canonical_unit()
            )),
        );
        return;
    };
    // A value with placeholders is read per parameter combination by the proof.
    if placeholders(s).is_empty() && !start_quantity_ok(cx, k, key, value.span, s, dim) {
        return;
    }
    if key.value == "volume" {
        spec.volume = Some(s.clone());
    } else {
        spec.panel.insert(key.value.clone(), s.clone());
    }
}

/// A liquid's name as a predicate can read it back (`tube.volume of <name> >= 5 µL`): a letter,
/// then letters, digits, `_` or `-`, at most 40 in all, and not a word of the predicate grammar.
fn is_liquid_name(name: &str) -> bool {
    !dsl::PREDICATE_WORDS.contains(&name)
        && name.len() <= 40
        && name.chars().next().is_some_and(|c| c.is_ascii_alphabetic())
        && name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '_' | '-'))
}

/// Whether a start volume or panel value `s` (no placeholders) is a quantity of `dim` (E0020)
/// within the kind's range (E0021).
fn start_quantity_ok(
    cx: &mut Cx,
    k: &LabwareKind,
    key: &Spanned<String>,
    span: dsl::Span,
    s: &str,
    dim: Dimension,
) -> bool {
    match parse_quantity(s) {
        Ok(q) if q.dimension != dim => {
            cx.err(
                Code::E0020,
                span,
                format!(
                    "`{s}` is a {}, but `{}` is a {}",
                    q.dimension.name(),
                    key.value,
                    dim.name()
                ),
                Some(format!("use one of: {}", dim.example_units())),
            );
            false
        }
        Err(e) => {
            cx.err(Code::E0020, span, e.to_string(), None);
            false
        }
        Ok(q) => {
            let range = if key.value == "volume" {
                Some((0.0, k.capacity_ul.unwrap_or(0.0), "µL"))
            } else {
                k.panel_param(&key.value).map(|p| (p.min, p.max, p.unit))
            };
            if let Some((lo, hi, unit)) = range
                && !(lo..=hi).contains(&q.si)
            {
                cx.err(
                    Code::E0021,
                    span,
                    format!(
                        "`{}` of a {} ranges {lo}..{hi} {unit}, found `{s}`",
                        key.value, k.name
                    ),
                    None,
                );
                return false;
            }
            true
        }
    }
}

/// What to declare for a state word a part cannot start in: the word an author means by a
/// negation or another form (`unlocked` is `closed`: shut, not latched), else the closest word.
fn state_hint(word: &str, initial: &[&str]) -> String {
    let meant = match word.to_lowercase().as_str() {
        "unlocked" | "shut" | "close" | "unlatched" => Some("closed"),
        "opened" => Some("open"),
        "lock" | "latched" => Some("locked"),
        "removed" => Some("off"),
        "screwed" | "capped" => Some("on"),
        _ => None,
    };
    match meant.filter(|m| initial.contains(m)) {
        Some(m) => format!(
            "declare `{m}`; the states it can start in: {}",
            initial.join(", ")
        ),
        None => hint_for(word, initial, "initial states"),
    }
}

/// A declared pose (`pos` and `yaw`, each zero when left out) as a frame.
pub(crate) fn pose(p: &dsl::ast::Pose) -> Pose {
    let pos = p.pos.as_ref().map(|s| s.value).unwrap_or([0.0; 3]);
    labware::frame::yaw(pos, p.yaw.as_ref().map(|y| y.value).unwrap_or(0.0))
}

#[cfg(test)]
mod tests {
    use super::super::testing::*;
    use dsl::Code;

    /// An unknown robot model and labware kind are reported at the name, with the closest one.
    #[test]
    fn an_unknown_model_and_kind_are_e0011_and_e0010_at_the_name() {
        let src = edited(&[
            ("model = \"ur5e_2f85\"", "model = \"ur5e_2f86\""),
            ("kind = \"tube_50ml\"", "kind = \"tube_50mL\""),
        ]);
        lowered(&src, |low, diags| {
            assert!(low.is_none(), "no task without the robot and the tube");
            assert_eq!(codes(diags)[..2], [Code::E0011, Code::E0010], "{diags:#?}");
            let robot = one(diags, Code::E0011);
            assert_eq!(covered(&src, robot.span), "\"ur5e_2f86\"");
            assert_eq!(robot.hint.as_deref(), Some("did you mean `ur5e_2f85`?"));
            assert_eq!(
                one(diags, Code::E0010).hint.as_deref(),
                Some("did you mean `tube_50ml`?")
            );
        });
    }

    /// A start state said another way (`shut`) is E0017 with the word meant; the word itself
    /// lowers to the item's initial state.
    #[test]
    fn a_start_state_said_another_way_is_e0017_naming_the_word_meant() {
        let cycler = "[labware.cycler]\nkind = \"thermal_cycler\"\npose = { pos_m = [-0.05, -0.45, 0.824] }\nstate = { lid = \"STATE\" }\n";
        let src = with(&cycler.replace("STATE", "shut"));
        lowered(&src, |_, diags| {
            let d = one(diags, Code::E0017);
            assert_eq!(d.message, "`lid` cannot start `shut`");
            assert_eq!(covered(&src, d.span), "\"shut\"");
            assert_eq!(
                d.hint.as_deref(),
                Some("declare `closed`; the states it can start in: open, closed, locked")
            );
        });
        lowered(&with(&cycler.replace("STATE", "closed")), |low, diags| {
            assert!(!codes(diags).contains(&Code::E0017), "{diags:#?}");
            let spec = &low.unwrap().labware[3];
            assert_eq!(spec.name, "cycler");
            assert_eq!(spec.initial["lid"], "closed");
        });
        // A key the kind does not have at all.
        let src = with(&cycler.replace("lid = \"STATE\"", "cap = \"on\""));
        lowered(&src, |_, diags| {
            let d = one(diags, Code::E0017);
            assert_eq!(d.message, "a thermal_cycler has no state `cap`");
            assert_eq!(covered(&src, d.span), "cap");
        });
    }

    /// A start volume is kept as written when it is a volume within the tube's capacity, and
    /// refused when it has no unit, the wrong unit or too much liquid.
    #[test]
    fn a_start_volume_is_kept_as_written_or_refused_with_its_reason() {
        let tube = |volume: &str| {
            edited(&[(
                "at = \"source.A1\"",
                &format!("at = \"source.A1\"\nstate = {{ volume = {volume} }}"),
            )])
        };
        lowered(&tube("\"20 mL\""), |low, diags| {
            assert!(diags.is_empty(), "{diags:#?}");
            assert_eq!(low.unwrap().labware[2].volume.as_deref(), Some("20 mL"));
        });
        let cases = [
            ("20", Code::E0020, "`volume` needs a unit"),
            (
                "\"20 s\"",
                Code::E0020,
                "`20 s` is a time, but `volume` is a volume",
            ),
            (
                "\"60 mL\"",
                Code::E0021,
                "`volume` of a tube_50ml ranges 0..50000 µL, found `60 mL`",
            ),
        ];
        for (volume, code, message) in cases {
            let src = tube(volume);
            lowered(&src, |low, diags| {
                let d = one(diags, code);
                assert_eq!(d.message, message);
                assert_eq!(covered(&src, d.span), volume);
                assert_eq!(low.unwrap().labware[2].volume, None, "{volume}");
            });
        }
    }

    /// `held_by` puts an item in a declared robot's hand, but not a fixed item, and not an item
    /// that also starts in a slot.
    #[test]
    fn held_by_needs_a_declared_robot_a_movable_item_and_no_slot() {
        let held =
            |robot: &str| edited(&[("at = \"source.A1\"", &format!("held_by = \"{robot}\""))]);
        lowered(&held("arm"), |low, _| {
            assert_eq!(low.unwrap().labware[2].held_by.as_deref(), Some("arm"));
        });
        let src = held("arn");
        lowered(&src, |_, diags| {
            let d = one(diags, Code::E0013);
            assert_eq!(d.message, "no robot named `arn`");
            assert_eq!(covered(&src, d.span), "\"arn\"");
        });
        let both = edited(&[(
            "at = \"source.A1\"",
            "at = \"source.A1\"\nheld_by = \"arm\"",
        )]);
        lowered(&both, |low, diags| {
            assert_eq!(
                one(diags, Code::E0016).message,
                "`tube` starts both in a slot and in a hand"
            );
            assert_eq!(low.unwrap().labware[2].held_by, None);
        });
        let rack = edited(&[(
            "pose = { pos_m = [0.3, 0.2, 0.854], yaw_deg = 90 }",
            "pose = { pos_m = [0.3, 0.2, 0.854], yaw_deg = 90 }\nheld_by = \"arm\"",
        )]);
        lowered(&rack, |_, diags| {
            assert_eq!(
                one(diags, Code::E0016).message,
                "`target` (a tube_rack) cannot be held"
            );
        });
    }
}
