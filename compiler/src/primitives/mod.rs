//! The closed catalogue of lab primitives, one file per primitive, gathered in [`CATALOGUE`]. Each
//! primitive's file holds everything about it side by side: its signature (arguments, prose for
//! the docs and `autobio describe`), its executable effect on the abstract [`World`] (what the
//! state proof traces), and its expert motion expansion ([`crate::motion`]), which the
//! `primitives` crate resolves into robot trajectories. Adding a primitive: a new file here and one
//! line in [`CATALOGUE`].

use crate::motion::{Motion, MotionStep};
use crate::world::{Hand, Location, World};
use dsl::{Code, Dimension, parse_quantity};
use labware::LabwareKind;
use std::collections::BTreeMap;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ArgKind {
    /// A declared labware item.
    Labware,
    /// `"<holder>.<slot>"`.
    Location,
    /// A declared robot.
    Robot,
    /// A volume quantity.
    Volume,
    /// A button of the instrument named by `on`.
    Button,
    /// A panel value of the instrument named by `on`.
    PanelParam,
    /// A quantity in the unit of that panel value.
    PanelValue,
    /// A time, e.g. "45 s".
    Duration,
    /// A rotational speed, e.g. "12000 rpm".
    Speed,
    /// A temperature, e.g. "42 °C".
    Temperature,
    /// A thermal profile ([`crate::profile`]).
    Profile,
    /// A whole number of times, e.g. "5".
    Count,
    /// Free text (what an instrument-only step does).
    Text,
}

impl ArgKind {
    pub fn describe(self) -> &'static str {
        match self {
            ArgKind::Labware => "labware name",
            ArgKind::Location => "\"<holder>.<slot>\"",
            ArgKind::Robot => "robot name",
            ArgKind::Volume => "volume, e.g. \"200 µL\"",
            ArgKind::Button => "button name",
            ArgKind::PanelParam => "panel value name",
            ArgKind::PanelValue => "quantity in the panel value's unit",
            ArgKind::Duration => "time, e.g. \"45 s\"",
            ArgKind::Speed => "rotational speed in rpm",
            ArgKind::Temperature => "temperature, e.g. \"42 °C\"",
            ArgKind::Count => "whole number, e.g. 5",
            ArgKind::Text => "text",
            ArgKind::Profile => {
                "profile, e.g. \"95 °C 3 min, 30 x [95 °C 15 s, 55 °C 15 s, 72 °C 30 s]\""
            }
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Arg {
    pub name: &'static str,
    pub kind: ArgKind,
    pub doc: &'static str,
    /// May be left out (the primitive then uses the default its `doc` names).
    pub optional: bool,
}

#[derive(Clone, Copy, Debug)]
pub struct LabPrimitive {
    pub name: &'static str,
    pub description: &'static str,
    /// Arguments besides `with` (the robot that does it), required unless `optional`.
    pub args: &'static [Arg],
    pub requires: &'static str,
    pub leaves: &'static str,
    /// Checks the step's preconditions on the abstract world and applies its effect.
    /// How synthesis words one step in an instruction: `{robot}` is the robot that does it,
    /// `{<arg>}` an argument's value, and for a location `{<arg>.holder}` and `{<arg>.slot}` its
    /// two halves ([`LabPrimitive::phrase_for`]).
    pub phrase: &'static str,
    /// What the step leaves that the judge can see, as a success predicate over its arguments
    /// (`"{on} in {to}"`): where a later step's `within` times from, and what it times to.
    /// `None`: nothing a predicate reads (a wait, a press whose effect depends on the button).
    pub outcome: Option<&'static str>,
    pub effect: fn(&mut World, &Env, &BoundStep) -> Result<(), Violation>,
    /// The scripted expert's motions for one rendered step; `None`: no expert motions yet.
    pub motions: Option<fn(&MotionStep) -> Vec<Motion>>,
}

impl LabPrimitive {
    /// The step's phrase ([`LabPrimitive::phrase`]) with its robot and arguments filled in (a
    /// missing argument reads as empty).
    pub fn phrase_for(&self, robot: &str, args: &BTreeMap<String, String>) -> String {
        let arg = |k: &str| args.get(k).map(String::as_str).unwrap_or_default();
        let mut out = String::new();
        for (text, key) in placeholders(self.phrase) {
            out.push_str(text);
            match key.map(|k| (k, k.split_once('.'))) {
                None => {}
                Some(("robot", _)) => out.push_str(robot),
                Some((_, Some((name, half)))) => {
                    let value = arg(name);
                    let (holder, slot) = value.split_once('.').unwrap_or((value, ""));
                    out.push_str(if half == "slot" { slot } else { holder });
                }
                Some((key, None)) => out.push_str(arg(key)),
            }
        }
        out
    }

    /// The placeholders of [`LabPrimitive::phrase`] that name neither the robot nor one of the
    /// primitive's arguments (for a location, its `.holder` or `.slot`): none in a well-made
    /// phrase.
    pub fn phrase_unknowns(&self) -> Vec<&'static str> {
        placeholders(self.phrase)
            .filter_map(|(_, key)| key)
            .filter(|key| {
                let known = *key == "robot"
                    || match key.split_once('.') {
                        Some((name, half)) => {
                            matches!(half, "holder" | "slot")
                                && self
                                    .args
                                    .iter()
                                    .any(|a| a.name == name && a.kind == ArgKind::Location)
                        }
                        None => self.args.iter().any(|a| a.name == *key),
                    };
                !known
            })
            .collect()
    }

    pub fn signature(&self) -> String {
        let args: Vec<String> = self
            .args
            .iter()
            .map(|a| match a.optional {
                false => format!("{} = <{}>", a.name, a.kind.describe()),
                true => format!("[{} = <{}>]", a.name, a.kind.describe()),
            })
            .chain(std::iter::once("with = <robot name>".to_string()))
            .collect();
        format!("{}({})", self.name, args.join(", "))
    }
}

/// A planned step as the expert runs it: its arguments rendered for one episode and its
/// primitive's motions for them.
pub struct Expanded {
    pub args: BTreeMap<String, String>,
    pub motions: Vec<Motion>,
}

impl Expanded {
    /// Step `index` of `task` (`step`), its arguments rendered with `params` (an unknown
    /// placeholder left as written), expanded by its primitive for the kind of the item it acts
    /// `on` and the liquid tool its robot carries then; `None` where its primitive has no expert
    /// motions. The expert and the reach check both expand steps here.
    pub fn of(
        task: &crate::Task,
        index: usize,
        step: &crate::PlannedStep,
        params: &crate::params::Bindings,
    ) -> Option<Expanded> {
        let expand = primitive(&step.primitive).and_then(|p| p.motions)?;
        let args: BTreeMap<String, String> = step
            .args
            .iter()
            .map(|(k, v)| {
                let v = crate::params::render(v, params).unwrap_or_else(|_| v.clone());
                (k.clone(), v)
            })
            .collect();
        let kind = args
            .get("on")
            .and_then(|on| task.labware.iter().find(|l| &l.name == on))
            .and_then(|l| labware::kind(&l.kind));
        let motions = expand(&MotionStep {
            args: &args,
            kind,
            tool: task.liquid_tool(&step.robot, index),
        });
        Some(Expanded { args, motions })
    }
}

/// A phrase cut at its placeholders: each piece of text with the `{key}` after it (`None` after
/// the last piece). An unclosed `{` is a key running to the end.
fn placeholders(
    phrase: &'static str,
) -> impl Iterator<Item = (&'static str, Option<&'static str>)> {
    let mut rest = Some(phrase);
    std::iter::from_fn(move || {
        let text = rest?;
        let Some(open) = text.find('{') else {
            rest = None;
            return Some((text, None));
        };
        let after = &text[open + 1..];
        let close = after.find('}').unwrap_or(after.len());
        rest = Some(after.get(close + 1..).unwrap_or(""));
        Some((&text[..open], Some(&after[..close])))
    })
}

mod aspirate;
mod close_lid;
mod dispense;
mod external;
mod hand_over;
mod hold;
mod incubate;
mod invert;
mod lid;
mod liquid;
mod lock;
mod open_lid;
mod pick;
mod pick_cap;
mod place;
mod press;
mod release;
mod retract;
pub mod run;
mod screw_cap;
mod set_parameter;
mod spin;
mod thermocycle;
mod unlock;
mod unscrew_cap;
mod wait;

pub(super) const ON: Arg = Arg {
    name: "on",
    kind: ArgKind::Labware,
    doc: "the labware acted on",
    optional: false,
};
pub(super) const DURATION: Arg = Arg {
    name: "duration",
    kind: ArgKind::Duration,
    doc: "how long",
    optional: false,
};
pub(super) const VOLUME: Arg = Arg {
    name: "volume",
    kind: ArgKind::Volume,
    doc: "how much liquid",
    optional: false,
};

/// Every lab primitive, in the order the docs list them: one line each.
pub const CATALOGUE: &[&LabPrimitive] = &[
    &pick::PRIMITIVE,
    &place::PRIMITIVE,
    &open_lid::PRIMITIVE,
    &close_lid::PRIMITIVE,
    &lock::PRIMITIVE,
    &unlock::PRIMITIVE,
    &unscrew_cap::PRIMITIVE,
    &pick_cap::PRIMITIVE,
    &screw_cap::PRIMITIVE,
    &aspirate::PRIMITIVE,
    &dispense::PRIMITIVE,
    &press::PRIMITIVE,
    &set_parameter::PRIMITIVE,
    &hold::PRIMITIVE,
    &release::PRIMITIVE,
    &retract::PRIMITIVE,
    &hand_over::PRIMITIVE,
    &spin::PRIMITIVE,
    &thermocycle::PRIMITIVE,
    &incubate::PRIMITIVE,
    &wait::PRIMITIVE,
    &invert::PRIMITIVE,
    &external::PRIMITIVE,
];

/// What every primitive's file imports.
mod prelude {
    pub(super) use super::{
        Arg, ArgKind, BoundStep, DURATION, Env, LabPrimitive, ON, VOLUME, Violation,
        panel_dimension, precondition, require_carrying, resolve_location, stabilised,
        unknown_name, violation,
    };
    pub(super) use crate::world::{Hand, Location, World};
    pub(super) use dsl::{Code, Dimension};
    pub(super) use labware::{ButtonEffect, LabwareKind};
}

pub fn primitive(name: &str) -> Option<&'static LabPrimitive> {
    CATALOGUE.iter().copied().find(|p| p.name == name)
}

/// The scene a step resolves its names against.
pub struct Env<'a> {
    pub kinds: &'a BTreeMap<String, &'static LabwareKind>,
    pub robots: &'a [String],
}

/// Why a step cannot run: the code, the argument to point at (`None`: the step's `do`), message
/// and hint.
#[derive(Clone, Debug, PartialEq)]
pub struct Violation {
    pub code: Code,
    pub arg: Option<&'static str>,
    pub message: String,
    pub hint: Option<String>,
}

pub(super) fn violation(code: Code, arg: Option<&'static str>, message: String) -> Violation {
    Violation {
        code,
        arg,
        message,
        hint: None,
    }
}

/// An argument naming something `on` does not have (E0013), with a did-you-mean over `names`.
pub(super) fn unknown_name(
    arg: &'static str,
    message: String,
    given: &str,
    names: &[&str],
    what: &str,
) -> Violation {
    Violation {
        code: Code::E0013,
        arg: Some(arg),
        message,
        hint: Some(crate::report::hint_for(given, names, what)),
    }
}

pub(super) fn precondition(message: String, hint: &str) -> Violation {
    Violation {
        code: Code::E0031,
        arg: None,
        message,
        hint: Some(hint.to_string()),
    }
}

/// A step with its argument templates rendered for one parameter combination.
pub struct BoundStep<'a> {
    pub primitive: &'static LabPrimitive,
    pub robot: &'a str,
    pub args: &'a BTreeMap<String, String>,
}

impl BoundStep<'_> {
    fn text(&self, name: &'static str) -> Result<&str, Violation> {
        self.args.get(name).map(String::as_str).ok_or_else(|| {
            violation(
                Code::E0032,
                None,
                format!("`{}` needs `{name}`", self.primitive.name),
            )
        })
    }

    pub(super) fn labware(
        &self,
        env: &Env,
        name: &'static str,
    ) -> Result<(String, &'static LabwareKind), Violation> {
        let v = self.text(name)?;
        match env.kinds.get(v) {
            Some(k) => Ok((v.to_string(), *k)),
            None => Err(violation(
                Code::E0013,
                Some(name),
                format!("no labware named `{v}`"),
            )),
        }
    }

    /// The `on` labware, checked to support this primitive.
    fn on(&self, env: &Env) -> Result<(String, &'static LabwareKind), Violation> {
        let name = self.primitive.name;
        let (lw, kind) = self.labware(env, "on")?;
        if !kind.supports(name) {
            return Err(Violation {
                code: Code::E0014,
                arg: None,
                message: format!("`{name}` cannot be applied to `{lw}` (a {})", kind.name),
                hint: Some(if kind.primitives.is_empty() {
                    format!("a {} supports no primitive as `on`", kind.name)
                } else {
                    format!("a {} supports: {}", kind.name, kind.primitives.join(", "))
                }),
            });
        }
        Ok((lw, kind))
    }

    /// The `on` labware, as [`Self::on`], for a primitive that needs the robot's hand empty.
    fn on_empty_handed(
        &self,
        w: &World,
        env: &Env,
    ) -> Result<(String, &'static LabwareKind), Violation> {
        let on = self.on(env)?;
        require_empty_hand(w, self.robot, self.primitive.name)?;
        Ok(on)
    }

    fn quantity(&self, name: &'static str, dim: Dimension) -> Result<f64, Violation> {
        quantity_arg(self.text(name)?, name, dim)
    }
}

/// Argument `name`'s text `v` read as a quantity of `dim` (E0020 otherwise).
pub(super) fn quantity_arg(v: &str, name: &'static str, dim: Dimension) -> Result<f64, Violation> {
    match parse_quantity(v) {
        Ok(q) if q.dimension == dim => Ok(q.si),
        Ok(q) => Err(violation(
            Code::E0020,
            Some(name),
            format!(
                "`{v}` is a {}, but `{name}` is a {}",
                q.dimension.name(),
                dim.name()
            ),
        )),
        Err(e) => Err(violation(Code::E0020, Some(name), e.to_string())),
    }
}

/// Why a location text does not name a slot of the scene.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum LocationError {
    #[error("`{text}` is not a location; write `<holder>.<slot>`")]
    NotALocation { text: String },
    #[error("no labware named `{holder}`")]
    NoLabware { holder: String },
    #[error("`{holder}` (a {kind}) has no slots")]
    NoSlots { holder: String, kind: &'static str },
    /// `slots`: the holder's slots, described.
    #[error("`{holder}` has no slot `{slot}` (its slots: {slots})")]
    NoSlot {
        holder: String,
        slot: String,
        slots: String,
    },
}

/// A location text `holder.slot` resolved against the scene: checks the holder has that slot.
pub fn resolve_location(
    env: &Env,
    text: &str,
) -> Result<(String, String, &'static LabwareKind), LocationError> {
    let Some((holder, slot)) = text.split_once('.') else {
        return Err(LocationError::NotALocation {
            text: text.to_string(),
        });
    };
    let Some(kind) = env.kinds.get(holder) else {
        return Err(LocationError::NoLabware {
            holder: holder.to_string(),
        });
    };
    let Some(slots) = kind.slots else {
        return Err(LocationError::NoSlots {
            holder: holder.to_string(),
            kind: kind.name,
        });
    };
    if !slots.layout.names().iter().any(|s| s == slot) {
        return Err(LocationError::NoSlot {
            holder: holder.to_string(),
            slot: slot.to_string(),
            slots: slots.layout.describe(),
        });
    }
    Ok((holder.to_string(), slot.to_string(), kind))
}

pub(super) fn require_empty_hand(w: &World, robot: &str, what: &str) -> Result<(), Violation> {
    match w.hand(robot) {
        Hand::Empty => Ok(()),
        h => Err(precondition(
            format!("`{what}` needs `{robot}`'s hand empty, but it is {h}"),
            "add a `place`, `release` or `screw_cap` step before this one",
        )),
    }
}

/// The robot carries `item` (E0031 otherwise, with the step that picks it up as the hint).
pub(super) fn require_carrying(
    w: &World,
    robot: &str,
    item: &str,
    what: &str,
) -> Result<(), Violation> {
    if w.hand(robot) == &Hand::Item(item.to_string()) {
        return Ok(());
    }
    Err(precondition(
        format!(
            "`{what}` needs `{robot}` to carry `{item}`, but its hand is {}",
            w.hand(robot)
        ),
        "add a `pick` step for it before this one",
    ))
}

pub(super) fn stabilised(w: &World, tube: &str, robot: &str) -> bool {
    matches!(w.locations.get(tube), Some(Location::Slot { .. }))
        || w.grippers_of(tube).iter().any(|r| *r != robot)
}

/// Runs one step on the world: checks its preconditions and applies its effects.
pub fn apply(w: &mut World, env: &Env, step: &BoundStep) -> Result<(), Violation> {
    slots_reachable(w, env, step)?;
    (step.primitive.effect)(w, env, step)
}

/// The slots of an instrument with a lid (a centrifuge's rotor) can be reached only while the lid
/// is open: a step that takes its `on` item out of such a slot, or puts something into one
/// (`to`), needs that lid open. For every primitive and every lidded kind, so no primitive can
/// forget it.
fn slots_reachable(w: &World, env: &Env, step: &BoundStep) -> Result<(), Violation> {
    let mut reached: Vec<(String, &'static str)> = Vec::new();
    if let Some(on) = step.args.get("on")
        && let Some(Location::Slot { holder, .. }) = w.locations.get(on)
    {
        reached.push((holder.clone(), "on"));
    }
    if let Some(to) = step.args.get("to")
        && let Ok((holder, _, _)) = resolve_location(env, to)
    {
        reached.push((holder, "to"));
    }
    for (holder, arg) in reached {
        let Some(kind) = env.kinds.get(holder.as_str()) else {
            continue;
        };
        if !kind.parts.iter().any(|p| p.part == "lid") {
            continue;
        }
        let state = w.part(&holder, "lid").unwrap_or("closed");
        if state == "open" {
            continue;
        }
        let opens = if state == "locked" {
            format!("add `unlock` and then `open_lid` on `{holder}` before this step")
        } else {
            format!("add an `open_lid` step on `{holder}` before this step")
        };
        return Err(Violation {
            code: Code::E0031,
            arg: Some(arg),
            message: format!(
                "`{}` reaches into a slot of `{holder}`, whose lid is {state}: its slots can be reached only while the lid is open",
                step.primitive.name
            ),
            hint: Some(opens),
        });
    }
    Ok(())
}

/// The dimension of a panel value from its unit symbol.
pub fn panel_dimension(unit: &str) -> Dimension {
    match unit {
        "rpm" => Dimension::Speed,
        "°C" => Dimension::Temperature,
        "µL" => Dimension::Volume,
        _ => Dimension::Time,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_primitive_has_an_effect_and_a_kind() {
        for p in CATALOGUE.iter() {
            let used = labware::KINDS.iter().any(|k| k.supports(p.name));
            // `release`, `retract`, `wait` and `external` take no `on`; `lock` is for a latch
            // locked by hand apart from closing, which no kind has yet (the catalogue says so).
            assert!(
                used || ["release", "retract", "lock", "wait", "external"].contains(&p.name),
                "{} is used by no kind",
                p.name
            );
        }
        for k in labware::KINDS {
            for p in k.primitives {
                assert!(primitive(p).is_some(), "{} lists unknown {p}", k.name);
            }
        }
    }

    /// Primitives whose expert motions are not written yet, named here on purpose: the expert
    /// refuses their steps, and synthesis never draws them (it draws only steps the shipped
    /// protocols' experts run). A primitive missing from both this list and its motions fails.
    const NO_EXPERT_MOTIONS_YET: [&str; 2] = ["hand_over", "release"];

    #[test]
    fn every_primitive_file_is_registered_with_a_phrase_and_its_motions() {
        // Every file here that declares a primitive is in the catalogue under its own name.
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("src/primitives");
        let mut declared = Vec::new();
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            let text = std::fs::read_to_string(&path).unwrap();
            // This file (the catalogue, and this test's own words) is no primitive's.
            if path.file_name().is_some_and(|n| n == "mod.rs") {
                continue;
            }
            if text.contains("const PRIMITIVE: LabPrimitive") {
                declared.push(path.file_stem().unwrap().to_string_lossy().into_owned());
            }
        }
        declared.sort();
        let mut registered: Vec<String> = CATALOGUE.iter().map(|p| p.name.to_string()).collect();
        registered.sort();
        assert_eq!(
            declared, registered,
            "a primitive file missing from CATALOGUE"
        );
        assert!(
            registered.len() >= 16,
            "the folder was not read: {registered:?}"
        );
        for p in CATALOGUE.iter() {
            assert!(!p.phrase.trim().is_empty(), "{} has no phrase", p.name);
            assert_eq!(
                p.phrase_unknowns(),
                Vec::<&str>::new(),
                "{}'s phrase",
                p.name
            );
            assert_eq!(
                p.motions.is_none(),
                NO_EXPERT_MOTIONS_YET.contains(&p.name),
                "{}: expert motions and NO_EXPERT_MOTIONS_YET disagree",
                p.name
            );
        }
    }

    #[test]
    fn a_phrase_is_filled_in_and_a_wrong_placeholder_is_found() {
        let place = primitive("place").unwrap();
        let args: BTreeMap<String, String> = [("on", "tube"), ("to", "rack.B3")]
            .into_iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect();
        assert_eq!(
            place.phrase_for("arm", &args),
            "put the tube in slot B3 of the rack"
        );
        let retract = primitive("retract").unwrap();
        assert_eq!(
            retract.phrase_for("left", &BTreeMap::new()),
            "bring the left arm back to its rest pose"
        );
        // A placeholder naming no argument, a half of an argument that is no location, and an
        // unclosed brace are each reported.
        let wrong = LabPrimitive {
            phrase: "move the {thing} by {on.slot} to {to.holder",
            ..*place
        };
        assert_eq!(wrong.phrase_unknowns(), vec!["thing", "on.slot"]);
        let unclosed = LabPrimitive {
            phrase: "move {nowhere",
            ..*place
        };
        assert_eq!(unclosed.phrase_unknowns(), vec!["nowhere"]);
    }
}
