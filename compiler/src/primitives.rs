//! The closed catalogue of lab primitives: each one's arguments, the state it needs before it
//! starts and the state it leaves, both as prose (for the docs and `autobio describe`) and as an
//! executable effect on the abstract [`World`]. The compiler traces steps through these to prove a
//! protocol or chain can run; the `primitives` crate expands them into robot motions.

use crate::world::{Hand, Location, World};
use dsl::{Code, Dimension, parse_quantity};
use labware::{ButtonEffect, LabwareKind};
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
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Arg {
    pub name: &'static str,
    pub kind: ArgKind,
    pub doc: &'static str,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LabPrimitive {
    pub name: &'static str,
    pub description: &'static str,
    /// Arguments besides `with` (the robot that does it), all required.
    pub args: &'static [Arg],
    pub requires: &'static str,
    pub leaves: &'static str,
}

impl LabPrimitive {
    pub fn signature(&self) -> String {
        let args: Vec<String> = self
            .args
            .iter()
            .map(|a| format!("{} = <{}>", a.name, a.kind.describe()))
            .chain(std::iter::once("with = <robot name>".to_string()))
            .collect();
        format!("{}({})", self.name, args.join(", "))
    }
}

const ON: Arg = Arg {
    name: "on",
    kind: ArgKind::Labware,
    doc: "the labware acted on",
};
const VOLUME: Arg = Arg {
    name: "volume",
    kind: ArgKind::Volume,
    doc: "how much liquid",
};

pub const CATALOGUE: &[LabPrimitive] = &[
    LabPrimitive {
        name: "pick",
        description: "grasp a movable item and lift it from where it is",
        args: &[ON],
        requires: "the hand is empty; `on` is movable and nobody carries it",
        leaves: "`on` carried by the robot",
    },
    LabPrimitive {
        name: "place",
        description: "put a carried item into a holder's slot and let go",
        args: &[
            ON,
            Arg {
                name: "to",
                kind: ArgKind::Location,
                doc: "the slot, e.g. \"rack.B3\" or \"rotor.{slot}\"",
            },
        ],
        requires: "the robot carries `on`; the slot exists, accepts `on`'s kind and is empty",
        leaves: "`on` in the slot; the hand empty",
    },
    LabPrimitive {
        name: "open_lid",
        description: "unlatch a lid if latched and swing it open",
        args: &[ON],
        requires: "the hand is empty; the lid is closed or locked",
        leaves: "the lid open (and unlocked)",
    },
    LabPrimitive {
        name: "close_lid",
        description: "swing a lid shut by its handle and latch it where the instrument has a latch",
        args: &[ON],
        requires: "the hand is empty; the lid is open",
        leaves: "the lid locked (closed, for lids without a latch)",
    },
    LabPrimitive {
        name: "lock",
        description: "press a closed lid's latch or lever home",
        args: &[ON],
        requires: "the hand is empty; the lid is closed and has a latch",
        leaves: "the lid locked",
    },
    LabPrimitive {
        name: "unlock",
        description: "release a locked lid's latch or lever without opening the lid",
        args: &[ON],
        requires: "the hand is empty; the lid is locked",
        leaves: "the lid closed, unlocked",
    },
    LabPrimitive {
        name: "unscrew_cap",
        description: "twist a screw cap off a tube that stands in a slot or is held by another robot",
        args: &[ON],
        requires: "the hand is empty; the cap is on; the tube is in a slot or gripped by another robot",
        leaves: "the cap off, in the robot's hand",
    },
    LabPrimitive {
        name: "screw_cap",
        description: "screw the cap the robot holds back onto its tube",
        args: &[ON],
        requires: "the robot holds `on`'s cap; the tube is in a slot or gripped by another robot",
        leaves: "the cap on; the hand empty",
    },
    LabPrimitive {
        name: "aspirate",
        description: "draw liquid from an open container into the pipette the robot holds",
        args: &[ON, VOLUME],
        requires: "the robot carries a pipette with room for `volume`; `on` is open and holds at least `volume`",
        leaves: "`volume` moved from `on` into the pipette",
    },
    LabPrimitive {
        name: "dispense",
        description: "expel liquid from the pipette the robot holds into an open container",
        args: &[ON, VOLUME],
        requires: "the robot carries a pipette holding at least `volume`; `on` is open and has room for it",
        leaves: "`volume` moved from the pipette into `on`",
    },
    LabPrimitive {
        name: "press",
        description: "press one of an instrument's buttons once (with a closed gripper as the finger)",
        args: &[
            ON,
            Arg {
                name: "button",
                kind: ArgKind::Button,
                doc: "which button",
            },
        ],
        requires: "the hand is empty; the button exists; a stepped value stays within its range",
        leaves: "the button's effect: a switch toggled or a panel value stepped once",
    },
    LabPrimitive {
        name: "set_parameter",
        description: "step an instrument's panel value to a target with its buttons",
        args: &[
            ON,
            Arg {
                name: "param",
                kind: ArgKind::PanelParam,
                doc: "which panel value",
            },
            Arg {
                name: "value",
                kind: ArgKind::PanelValue,
                doc: "the target, e.g. \"{rpm} rpm\"",
            },
        ],
        requires: "the hand is empty; the target is within the panel's range and on its button grid",
        leaves: "the panel value at the target",
    },
    LabPrimitive {
        name: "hold",
        description: "grip an item where it is to keep it still (a second arm stabilising a tube)",
        args: &[ON],
        requires: "the hand is empty; `on` is movable",
        leaves: "the robot holding `on` steady; `on` stays where it is",
    },
    LabPrimitive {
        name: "release",
        description: "let go of an item held steady",
        args: &[],
        requires: "the robot holds something steady",
        leaves: "the hand empty",
    },
    LabPrimitive {
        name: "hand_over",
        description: "pass a carried item to another robot's gripper",
        args: &[
            ON,
            Arg {
                name: "to",
                kind: ArgKind::Robot,
                doc: "the robot that takes it",
            },
        ],
        requires: "the robot carries `on`; `to` is another robot whose hand is empty or steadies `on`",
        leaves: "`on` carried by `to`; the giving hand empty",
    },
];

pub fn primitive(name: &str) -> Option<&'static LabPrimitive> {
    CATALOGUE.iter().find(|p| p.name == name)
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

fn violation(code: Code, arg: Option<&'static str>, message: String) -> Violation {
    Violation {
        code,
        arg,
        message,
        hint: None,
    }
}

fn precondition(message: String, hint: &str) -> Violation {
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

    fn labware(
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

    fn quantity(&self, name: &'static str, dim: Dimension) -> Result<f64, Violation> {
        let v = self.text(name)?;
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
            Err(e) => Err(violation(Code::E0020, Some(name), e)),
        }
    }
}

/// A location text `holder.slot` resolved against the scene: checks the holder has that slot.
pub fn resolve_location(
    env: &Env,
    text: &str,
) -> Result<(String, String, &'static LabwareKind), String> {
    let Some((holder, slot)) = text.split_once('.') else {
        return Err(format!(
            "`{text}` is not a location; write `<holder>.<slot>`"
        ));
    };
    let Some(kind) = env.kinds.get(holder) else {
        return Err(format!("no labware named `{holder}`"));
    };
    let Some(slots) = kind.slots else {
        return Err(format!("`{holder}` (a {}) has no slots", kind.name));
    };
    if !slots.layout.names().iter().any(|s| s == slot) {
        return Err(format!(
            "`{holder}` has no slot `{slot}` (its slots: {})",
            slots.layout.describe()
        ));
    }
    Ok((holder.to_string(), slot.to_string(), kind))
}

fn require_empty_hand(w: &World, robot: &str, what: &str) -> Result<(), Violation> {
    match w.hand(robot) {
        Hand::Empty => Ok(()),
        h => Err(precondition(
            format!("`{what}` needs `{robot}`'s hand empty, but it is {h}"),
            "add a `place`, `release` or `screw_cap` step before this one",
        )),
    }
}

fn lid_state<'w>(w: &'w World, lw: &str, kind: &LabwareKind) -> Result<&'w str, Violation> {
    match (kind.part("lid"), w.part(lw, "lid")) {
        (Some(_), Some(s)) => Ok(s),
        _ => Err(violation(
            Code::E0014,
            Some("on"),
            format!("`{lw}` (a {}) has no lid", kind.name),
        )),
    }
}

fn stabilised(w: &World, tube: &str, robot: &str) -> bool {
    matches!(w.locations.get(tube), Some(Location::Slot { .. }))
        || w.grippers_of(tube).iter().any(|r| *r != robot)
}

/// Runs one step on the world: checks its preconditions and applies its effects.
pub fn apply(w: &mut World, env: &Env, step: &BoundStep) -> Result<(), Violation> {
    let robot = step.robot;
    let name = step.primitive.name;
    // `release` is the one primitive without an object: it only empties a steadying hand.
    if name == "release" {
        if !matches!(w.hand(robot), Hand::Stabilising(_)) {
            return Err(precondition(
                format!(
                    "`release` needs `{robot}` to hold something steady, but its hand is {}",
                    w.hand(robot)
                ),
                "use `place` to put down a carried item",
            ));
        }
        w.hands.insert(robot.into(), Hand::Empty);
        return Ok(());
    }
    let (lw, kind) = step.labware(env, "on")?;
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
    match name {
        "pick" => {
            require_empty_hand(w, robot, name)?;
            if let Some(Location::Held { robot: r }) = w.locations.get(&lw) {
                return Err(precondition(
                    format!("`pick` needs `{lw}` free, but `{r}` carries it"),
                    "hand it over with `hand_over` instead",
                ));
            }
            w.locations.insert(
                lw.clone(),
                Location::Held {
                    robot: robot.into(),
                },
            );
            w.hands.insert(robot.into(), Hand::Item(lw));
        }
        "place" => {
            let to = step.text("to")?.to_string();
            let (holder, slot, hkind) =
                resolve_location(env, &to).map_err(|m| violation(Code::E0016, Some("to"), m))?;
            let accepts = hkind.slots.map(|s| s.accepts).unwrap_or(&[]);
            if !accepts.contains(&kind.name) {
                return Err(Violation {
                    code: Code::E0016,
                    arg: Some("to"),
                    message: format!(
                        "a slot of `{holder}` (a {}) does not take a {}",
                        hkind.name, kind.name
                    ),
                    hint: Some(format!("it takes: {}", accepts.join(", "))),
                });
            }
            if w.hand(robot) != &Hand::Item(lw.clone()) {
                return Err(precondition(
                    format!(
                        "`place` needs `{robot}` to carry `{lw}`, but its hand is {}",
                        w.hand(robot)
                    ),
                    "add a `pick` step for it before this one",
                ));
            }
            if let Some(other) = w.occupant(&holder, &slot) {
                return Err(precondition(
                    format!("`place` needs `{to}` empty, but `{other}` is in it"),
                    "choose a free slot, or draw it with `slot = ..., free = true`",
                ));
            }
            w.locations
                .insert(lw.clone(), Location::Slot { holder, slot });
            w.hands.insert(robot.into(), Hand::Empty);
        }
        "open_lid" | "close_lid" | "lock" | "unlock" => {
            require_empty_hand(w, robot, name)?;
            let state = lid_state(w, &lw, kind)?.to_string();
            let latched = kind
                .part("lid")
                .is_some_and(|p| p.states.contains(&"locked"));
            let (needs, leaves): (&[&str], &str) = match name {
                "open_lid" => (&["closed", "locked"], "open"),
                "close_lid" => (&["open"], if latched { "locked" } else { "closed" }),
                "lock" => (&["closed"], "locked"),
                _ => (&["locked"], "closed"),
            };
            if !latched && matches!(name, "lock" | "unlock") {
                return Err(violation(
                    Code::E0014,
                    None,
                    format!("`{lw}` (a {}) has no latch to {name}", kind.name),
                ));
            }
            if !needs.contains(&state.as_str()) {
                return Err(precondition(
                    format!(
                        "`{name}` needs `{lw}.lid` to be {}, but here it is `{state}`",
                        needs.join(" or "),
                    ),
                    &format!(
                        "remove this step or add one before it that leaves the lid {}",
                        needs[0]
                    ),
                ));
            }
            w.set_part(&lw, "lid", leaves);
        }
        "unscrew_cap" => {
            require_empty_hand(w, robot, name)?;
            if w.part(&lw, "cap") != Some("on") {
                return Err(precondition(
                    format!("`unscrew_cap` needs the cap of `{lw}` on, but it is off"),
                    "remove this step, or screw the cap on first",
                ));
            }
            if !stabilised(w, &lw, robot) {
                return Err(precondition(
                    format!(
                        "`unscrew_cap` needs `{lw}` held still (in a slot or gripped by another robot), but it is {}",
                        w.locations.get(&lw).unwrap_or(&Location::Bench)
                    ),
                    "add a `hold` by another robot, or `place` the tube in a rack first",
                ));
            }
            w.set_part(&lw, "cap", "off");
            w.hands.insert(robot.into(), Hand::Cap(lw));
        }
        "screw_cap" => {
            if w.hand(robot) != &Hand::Cap(lw.clone()) {
                return Err(precondition(
                    format!(
                        "`screw_cap` needs `{robot}` to hold the cap of `{lw}`, but its hand is {}",
                        w.hand(robot)
                    ),
                    "unscrew that cap with the same robot first",
                ));
            }
            if !stabilised(w, &lw, robot) {
                return Err(precondition(
                    format!(
                        "`screw_cap` needs `{lw}` held still (in a slot or gripped by another robot)"
                    ),
                    "add a `hold` by another robot, or `place` the tube in a rack first",
                ));
            }
            w.set_part(&lw, "cap", "on");
            w.hands.insert(robot.into(), Hand::Empty);
        }
        "aspirate" | "dispense" => {
            let volume = step.quantity("volume", Dimension::Volume)?;
            if volume <= 0.0 {
                return Err(violation(
                    Code::E0021,
                    Some("volume"),
                    format!("`{name}` needs a positive volume, found {volume} µL"),
                ));
            }
            let pipette = match w.hand(robot) {
                Hand::Item(p) if env.kinds.get(p).is_some_and(|k| k.name == "pipette") => p.clone(),
                h => {
                    return Err(precondition(
                        format!("`{name}` needs `{robot}` to carry a pipette, but its hand is {h}"),
                        "add a `pick` of the pipette before this step",
                    ));
                }
            };
            if w.part(&lw, "cap") == Some("on") {
                return Err(precondition(
                    format!("`{name}` needs `{lw}` open, but its cap is on"),
                    "add an `unscrew_cap` step before this one",
                ));
            }
            let (from, to) = if name == "aspirate" {
                (lw.clone(), pipette)
            } else {
                (pipette, lw.clone())
            };
            let have = w.volumes.get(&from).copied().unwrap_or(0.0);
            let room = env.kinds[&to].capacity_ul.unwrap_or(0.0)
                - w.volumes.get(&to).copied().unwrap_or(0.0);
            if have < volume {
                return Err(precondition(
                    format!(
                        "`{name}` of {volume} µL needs that much in `{from}`, but it holds {have} µL"
                    ),
                    "lower the volume or fill the container first",
                ));
            }
            if room < volume {
                return Err(precondition(
                    format!(
                        "`{name}` of {volume} µL needs that much room in `{to}`, but it has {room} µL"
                    ),
                    "lower the volume or empty it first",
                ));
            }
            *w.volumes.entry(from).or_default() -= volume;
            *w.volumes.entry(to).or_default() += volume;
        }
        "press" => {
            require_empty_hand(w, robot, name)?;
            let b = step.text("button")?;
            let Some(button) = kind.button(b) else {
                let names: Vec<&str> = kind.buttons.iter().map(|b| b.name).collect();
                return Err(Violation {
                    code: Code::E0013,
                    arg: Some("button"),
                    message: format!("`{lw}` (a {}) has no button `{b}`", kind.name),
                    hint: Some(crate::check::hint_for(b, &names, "buttons")),
                });
            };
            match button.effect {
                ButtonEffect::Toggle { part, a, b } => {
                    let next = if w.part(&lw, part) == Some(a) { b } else { a };
                    w.set_part(&lw, part, next);
                }
                ButtonEffect::Step { param, sign } => {
                    let p = kind.panel_param(param).expect("catalogue is consistent");
                    let key = (lw.clone(), param.to_string());
                    let v = w.panel.get(&key).copied().unwrap_or(p.initial) + sign as f64 * p.step;
                    if v < p.min - 1e-9 || v > p.max + 1e-9 {
                        return Err(precondition(
                            format!(
                                "pressing `{}` would take `{lw}.{param}` to {v} {}, outside {}..{}",
                                button.name, p.unit, p.min, p.max
                            ),
                            "remove this press",
                        ));
                    }
                    w.panel.insert(key, v);
                }
            }
        }
        "set_parameter" => {
            require_empty_hand(w, robot, name)?;
            let pname = step.text("param")?;
            let Some(p) = kind.panel_param(pname) else {
                let names: Vec<&str> = kind.panel.iter().map(|p| p.name).collect();
                return Err(Violation {
                    code: Code::E0013,
                    arg: Some("param"),
                    message: format!("`{lw}` (a {}) has no panel value `{pname}`", kind.name),
                    hint: Some(crate::check::hint_for(pname, &names, "panel values")),
                });
            };
            let dim = panel_dimension(p.unit);
            let value = step.quantity("value", dim)?;
            if value < p.min || value > p.max {
                return Err(violation(
                    Code::E0021,
                    Some("value"),
                    format!(
                        "`{lw}.{pname}` ranges {}..{} {}, but the target is {value} {}",
                        p.min, p.max, p.unit, p.unit
                    ),
                ));
            }
            let steps = (value - p.initial) / p.step;
            if (steps - steps.round()).abs() > 1e-6 {
                return Err(Violation {
                    code: Code::E0021,
                    arg: Some("value"),
                    message: format!(
                        "`{lw}.{pname}` moves in steps of {} {} from {}, so it cannot show {value}",
                        p.step, p.unit, p.initial
                    ),
                    hint: Some("pick a value on the button grid".into()),
                });
            }
            w.panel.insert((lw.clone(), pname.to_string()), value);
        }
        "hold" => {
            require_empty_hand(w, robot, name)?;
            w.hands.insert(robot.into(), Hand::Stabilising(lw));
        }
        "hand_over" => {
            let to = step.text("to")?.to_string();
            if !env.robots.contains(&to) {
                return Err(violation(
                    Code::E0013,
                    Some("to"),
                    format!("no robot named `{to}`"),
                ));
            }
            if to == robot {
                return Err(violation(
                    Code::E0021,
                    Some("to"),
                    format!("`{robot}` cannot hand over to itself"),
                ));
            }
            if w.hand(robot) != &Hand::Item(lw.clone()) {
                return Err(precondition(
                    format!(
                        "`hand_over` needs `{robot}` to carry `{lw}`, but its hand is {}",
                        w.hand(robot)
                    ),
                    "add a `pick` step for it before this one",
                ));
            }
            match w.hand(&to) {
                Hand::Empty => {}
                Hand::Stabilising(i) if *i == lw => {}
                h => {
                    return Err(precondition(
                        format!("`hand_over` needs `{to}`'s hand free, but it is {h}"),
                        "have it put down what it holds first",
                    ));
                }
            }
            w.locations
                .insert(lw.clone(), Location::Held { robot: to.clone() });
            w.hands.insert(to, Hand::Item(lw));
            w.hands.insert(robot.into(), Hand::Empty);
        }
        other => unreachable!("primitive `{other}` is in the catalogue but has no effect"),
    }
    Ok(())
}

/// The dimension of a panel value from its unit symbol.
pub fn panel_dimension(unit: &str) -> Dimension {
    match unit {
        "rpm" => Dimension::Speed,
        "°C" => Dimension::Temperature,
        _ => Dimension::Time,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_primitive_has_an_effect_and_a_kind() {
        for p in CATALOGUE {
            let used = labware::KINDS.iter().any(|k| k.supports(p.name));
            assert!(used || p.name == "release", "{} is used by no kind", p.name);
        }
        for k in labware::KINDS {
            for p in k.primitives {
                assert!(primitive(p).is_some(), "{} lists unknown {p}", k.name);
            }
        }
    }
}
