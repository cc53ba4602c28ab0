//! Success predicates: the small grammar of `[success] all = [..]`, the compiled [`Check`]s, and
//! their evaluation on the abstract world (for the compiler's proof; the scoring crate evaluates
//! them on measured state).
//!
//! Forms (`{param}` placeholders may stand for names, slots and values):
//! - `<labware>.<part> is <state>`                 part state (lid closed, cap off, power on)
//! - `<labware>.<part> was <state>`                the part has been in that state at some control
//!   step of the stage (stateful: once seen it holds; a round trip in one protocol is "was open"
//!   and "is closed")
//! - `<labware>.<joint> in [<lo>, <hi>] <unit>`    joint range (rad, deg or m)
//! - `<item> in <holder>.<slot>`                   object in slot
//! - `<container>.volume <op> <quantity>`          volume, op one of `=`, `>=`, `<=`
//! - `<container>.volume of <liquid> <op> <q>`      how much of a named liquid it holds
//! - `<instrument>.<panel value> = <quantity>`     display value
//! - `<robot> touches <item>`                      contact (any of the robot's bodies)
//! - `<robot> holds <item>[.<part>]`               a finger of the robot's gripper or hand
//!   touches the item, or that part of it (upstream's finger-on-cap checks)
//! - `<item> near [<x>, <y>, <z>] <unit>`          pose within tolerance
//! - `<item> lifted <quantity>`                    raised at least this far above where it
//!   started (its start slot's seat, else its placement): held clear, not resting
//! - `<item>.<part> lifted <quantity>`             a loose part raised at least this far above
//!   its seat on the item, along the item's axis (a cap off its tube's thread)
//! - `<item> inverted <n> times`                    turned upside down and back upright at least
//!   n times during the stage (stateful: the judge counts each turn over and back)
//!
//! Any form but contact, holds, joint range, `lifted` and `inverted` may end in `within <quantity>` to give its
//! tolerance inline.
//!
//! A time constraint: any form followed by `for <q> to <q>`, `for at most <q>` or `for at least
//! <q>` ([`Dwell`]) holds when the form has held for that long in total during the stage (a tube
//! in a 42 °C block `for 30 s to 40 s`, and no longer): the judge measures it on the episode's
//! clock; the proof bounds it from below by the waits and runs while the form holds (E0039).

use crate::params::{Bindings, UnknownPlaceholder, render};
use crate::world::{Hand, Location, World};
use dsl::{Dimension, ParseQuantityError, parse_quantity};
use serde::{Deserialize, Serialize};

/// How long a predicate must have held in total during its stage (s): at least, at most, or
/// both.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Dwell {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub at_least_s: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub at_most_s: Option<f64>,
}

impl Dwell {
    /// Whether `held_s` seconds in total, measured to within `resolution` seconds (the judge
    /// sees a form that starts holding mid-step at the step's end: one control step per time
    /// it started), keep the constraint.
    pub fn kept(&self, held_s: f64, resolution: f64) -> bool {
        let slack = resolution + 1e-9;
        self.at_least_s.is_none_or(|lo| held_s >= lo - slack)
            && self.at_most_s.is_none_or(|hi| held_s <= hi + slack)
    }
}

/// Splits a time constraint off a predicate's text: `"<form> for 30 s to 40 s"`, `"<form> for at
/// most 40 s"`, `"<form> for at least 30 s"` ([`Dwell`]); the text unchanged and `None` when it
/// has none.
pub fn split_dwell(text: &str) -> Result<(&str, Option<Dwell>), PredicateError> {
    let Some((body, bounds)) = text.rsplit_once(" for ") else {
        return Ok((text, None));
    };
    let time = |q: &str| -> Result<f64, PredicateError> {
        let parsed = parse_quantity(q.trim())?;
        if parsed.dimension != Dimension::Time || parsed.si < 0.0 {
            return Err(PredicateError::NotDwell {
                text: bounds.trim().to_string(),
            });
        }
        Ok(parsed.si)
    };
    let bounds_t = bounds.trim();
    let dwell = if let Some(q) = bounds_t.strip_prefix("at most ") {
        Dwell {
            at_least_s: None,
            at_most_s: Some(time(q)?),
        }
    } else if let Some(q) = bounds_t.strip_prefix("at least ") {
        Dwell {
            at_least_s: Some(time(q)?),
            at_most_s: None,
        }
    } else if let Some((lo, hi)) = bounds_t.split_once(" to ") {
        let (lo, hi) = (time(lo)?, time(hi)?);
        if lo > hi {
            return Err(PredicateError::NotDwell {
                text: bounds_t.to_string(),
            });
        }
        Dwell {
            at_least_s: Some(lo),
            at_most_s: Some(hi),
        }
    } else {
        return Err(PredicateError::NotDwell {
            text: bounds_t.to_string(),
        });
    };
    Ok((body.trim(), Some(dwell)))
}

/// A tolerance with the name a `[tolerances]` table can override it by.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Tolerance {
    pub name: String,
    /// In the canonical unit of what it bounds (rad, m, µL, the panel's unit).
    pub value: f64,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Cmp {
    #[serde(rename = "=")]
    Eq,
    #[serde(rename = ">=")]
    Ge,
    #[serde(rename = "<=")]
    Le,
}

/// One compiled predicate. Fields documented as templates may hold `{param}` placeholders.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "check", rename_all = "snake_case")]
pub enum Check {
    State {
        labware: String,
        part: String,
        state: String,
        tolerance: Option<Tolerance>,
        /// `was`: the part has been in the state at some control step of the stage, not
        /// necessarily now (the judge and the proof remember it).
        #[serde(default, skip_serializing_if = "std::ops::Not::not")]
        ever: bool,
    },
    JointRange {
        labware: String,
        joint: String,
        low: f64,
        high: f64,
    },
    InSlot {
        item: String,
        /// Template `holder.slot`.
        location: String,
        /// In-plane distance from the slot's seat (`slot_xy`).
        tolerance: Tolerance,
        /// Height above or below the seat (m; the item kind's `slot_z`) and tilt from upright
        /// (rad) within which the item still stands in the slot.
        #[serde(default = "default_slot_height")]
        height: f64,
        #[serde(default = "default_slot_tilt")]
        tilt: f64,
    },
    Volume {
        container: String,
        /// The named liquid whose share is compared; `None`: the whole volume.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        liquid: Option<String>,
        cmp: Cmp,
        /// Template quantity text.
        value: String,
        tolerance: Tolerance,
    },
    Panel {
        instrument: String,
        param: String,
        /// The panel value's unit and the value it shows at the start.
        unit: String,
        initial: f64,
        /// Template quantity text.
        value: String,
        tolerance: Tolerance,
    },
    Contact {
        robot: String,
        item: String,
    },
    /// A finger of the robot touches the item, or its `part` (a tube's cap).
    Holds {
        robot: String,
        item: String,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        part: Option<String>,
    },
    Position {
        item: String,
        pos: [f64; 3],
        tolerance: Tolerance,
    },
    /// The item stands at least `height` (m) above where it started; with `part`, that part
    /// stands at least `height` above its seat on the item.
    Lifted {
        item: String,
        height: f64,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        part: Option<String>,
    },
    /// The item has been turned upside down (tilted past [`INVERTED_RAD`]) and back upright
    /// (within [`UPRIGHT_RAD`]) at least `times` times in the stage: the judge counts.
    Inverted {
        item: String,
        times: u32,
    },
}

/// An item's tilt from upright (rad) past which it counts as upside down (150°), and within which
/// it counts as upright again (30°): an inversion is a turn from one to the other and back.
pub const INVERTED_RAD: f64 = 150.0 * std::f64::consts::PI / 180.0;
pub const UPRIGHT_RAD: f64 = 30.0 * std::f64::consts::PI / 180.0;

fn default_slot_height() -> f64 {
    0.005
}

/// Largest tilt (rad) of an item that still stands upright in a slot.
pub const SLOT_TILT: f64 = 0.15;

fn default_slot_tilt() -> f64 {
    SLOT_TILT
}

/// The predicate's syntactic shape before names are resolved.
#[derive(Clone, Debug, PartialEq)]
pub enum Form {
    State {
        labware: String,
        part: String,
        state: String,
        /// Written with `was`: at some step of the stage, not necessarily now.
        ever: bool,
    },
    JointRange {
        labware: String,
        joint: String,
        low: f64,
        high: f64,
    },
    InSlot {
        item: String,
        location: String,
    },
    Compare {
        labware: String,
        field: String,
        /// `<lw>.volume of <liquid>`: the named liquid's share of the volume.
        liquid: Option<String>,
        cmp: Cmp,
        value: String,
    },
    Contact {
        robot: String,
        item: String,
    },
    Holds {
        robot: String,
        item: String,
        part: Option<String>,
    },
    Near {
        item: String,
        pos: [f64; 3],
    },
    Lifted {
        item: String,
        height: f64,
        part: Option<String>,
    },
    Inverted {
        item: String,
        times: u32,
    },
}

/// A parsed predicate: its form and an inline `within` tolerance (value and dimension).
#[derive(Clone, Debug, PartialEq)]
pub struct Parsed {
    pub form: Form,
    pub within: Option<(f64, Dimension)>,
}

/// Why a predicate's text does not read as one of the forms. Its messages are lowercase and say
/// which form was expected.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum PredicateError {
    /// The `within` tolerance, or a `lifted` height, is not a quantity.
    #[error(transparent)]
    Quantity(#[from] ParseQuantityError),
    #[error("a `[` without its `]`")]
    UnclosedBracket,
    #[error("expected `[`")]
    NoOpeningBracket,
    #[error("expected `[..]`")]
    NoBrackets,
    #[error("`[{inner}]` must hold numbers")]
    NotNumbers { inner: String },
    #[error("`[{inner}]` must hold {count} numbers")]
    WrongCount { inner: String, count: usize },
    #[error("`{lhs}` must be `<labware>.<part>`")]
    NotLabwarePart { lhs: String },
    #[error("`{state}` is not a state name")]
    NotStateName { state: String },
    #[error("`{lhs}` must be `<labware>.<joint>`")]
    NotLabwareJoint { lhs: String },
    #[error("`{unit}` is not a unit of angle or length")]
    NotJointUnit { unit: String },
    #[error("a joint range is an angle or a length, not a {}", .0.name())]
    JointDimension(Dimension),
    #[error("the range [{low}, {high}] is empty")]
    EmptyRange { low: f64, high: f64 },
    #[error("`{name}` is not an item name")]
    NotItemName { name: String },
    #[error("`{location}` must be `<holder>.<slot>`")]
    NotLocation { location: String },
    #[error("write `<robot> touches <item>`")]
    NotContact,
    #[error("write `<robot> holds <item>` or `<robot> holds <item>.<part>`")]
    NotHolds,
    #[error("`{unit}` is not a unit of length")]
    NotLengthUnit { unit: String },
    #[error("`{height}` is not a height: write a length above zero, e.g. `lifted 5 cm`")]
    NotHeight { height: String },
    #[error("expected `is`, `was`, `in`, `=`, `>=`, `<=`, `touches`, `holds`, `near` or `lifted`")]
    NoForm,
    #[error("`{lhs}` must be `<labware>.<value>`")]
    NotLabwareValue { lhs: String },
    #[error("a comparison needs a value with a unit")]
    NoValue,
    #[error("`{text}` is not a count: write `<item> inverted 5 times`")]
    NotCount { text: String },
    #[error("`{name}` is not a liquid's name: write `<container>.volume of <liquid> >= 5 µL`")]
    NotLiquidName { name: String },
    #[error(
        "`for {text}` is not a time constraint: write `for 30 s to 40 s`, `for at most 40 s` or `for at least 30 s`"
    )]
    NotDwell { text: String },
}

/// Why a quantity template does not read as the quantity needed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ValueError {
    #[error(transparent)]
    UnknownPlaceholder(#[from] UnknownPlaceholder),
    #[error(transparent)]
    Quantity(#[from] ParseQuantityError),
    #[error("`{text}` is a {}, but a {} is needed", .found.name(), .needed.name())]
    WrongDimension {
        text: String,
        found: Dimension,
        needed: Dimension,
    },
    /// A panel's starting value ([`panel_quantity`]) that reads as no panel quantity.
    #[error("not a speed, temperature, time or volume")]
    NotPanelValue,
}

fn split_dot(s: &str) -> Option<(String, String)> {
    let (a, b) = s.split_once('.')?;
    (!a.is_empty() && !b.is_empty() && !b.contains('.')).then(|| (a.to_string(), b.to_string()))
}

/// `<item>` or `<item>.<part>`; `None` for an empty name or a second dot.
fn item_and_part(s: &str) -> Option<(String, Option<String>)> {
    match s.split_once('.') {
        None => (!s.is_empty()).then(|| (s.to_string(), None)),
        Some(_) => split_dot(s).map(|(item, part)| (item, Some(part))),
    }
}

fn bracketed(s: &str, n: usize) -> Result<(Vec<f64>, &str), PredicateError> {
    let s = s.trim_start();
    let inner_end = s.find(']').ok_or(PredicateError::UnclosedBracket)?;
    let inner = s
        .strip_prefix('[')
        .ok_or(PredicateError::NoOpeningBracket)?
        .get(..inner_end - 1)
        .ok_or(PredicateError::NoBrackets)?;
    let nums: Result<Vec<f64>, _> = inner.split(',').map(|x| x.trim().parse::<f64>()).collect();
    let nums = nums.map_err(|_| PredicateError::NotNumbers {
        inner: inner.to_string(),
    })?;
    if nums.len() != n || nums.iter().any(|x| !x.is_finite()) {
        return Err(PredicateError::WrongCount {
            inner: inner.to_string(),
            count: n,
        });
    }
    Ok((nums, s[inner_end + 1..].trim()))
}

/// Reads one predicate. Errors are lowercase and say which form was expected.
pub fn parse(text: &str) -> Result<Parsed, PredicateError> {
    let text = text.trim();
    let (body, within) = match text.rsplit_once(" within ") {
        Some((b, q)) => {
            let q = parse_quantity(q)?;
            (b.trim(), Some((q.si, q.dimension)))
        }
        None => (text, None),
    };
    let state_form = body
        .split_once(" is ")
        .map(|(l, r)| (l, r, false))
        .or_else(|| body.split_once(" was ").map(|(l, r)| (l, r, true)));
    let form = if let Some((lhs, state, ever)) = state_form {
        let (labware, part) =
            split_dot(lhs.trim()).ok_or_else(|| PredicateError::NotLabwarePart {
                lhs: lhs.trim().to_string(),
            })?;
        let state = state.trim();
        if state.is_empty() || state.contains(' ') {
            return Err(PredicateError::NotStateName {
                state: state.to_string(),
            });
        }
        Form::State {
            labware,
            part,
            state: state.to_string(),
            ever,
        }
    } else if let Some((lhs, rest)) = body.split_once(" in ") {
        let lhs = lhs.trim();
        let rest = rest.trim();
        if rest.starts_with('[') {
            let (labware, joint) =
                split_dot(lhs).ok_or_else(|| PredicateError::NotLabwareJoint {
                    lhs: lhs.to_string(),
                })?;
            let (v, unit) = bracketed(rest, 2)?;
            let q =
                parse_quantity(&format!("1 {unit}")).map_err(|_| PredicateError::NotJointUnit {
                    unit: unit.to_string(),
                })?;
            if !matches!(q.dimension, Dimension::Angle | Dimension::Length) {
                return Err(PredicateError::JointDimension(q.dimension));
            }
            if v[0] > v[1] {
                return Err(PredicateError::EmptyRange {
                    low: v[0],
                    high: v[1],
                });
            }
            Form::JointRange {
                labware,
                joint,
                low: v[0] * q.si,
                high: v[1] * q.si,
            }
        } else {
            if lhs.contains(' ') || lhs.is_empty() {
                return Err(PredicateError::NotItemName {
                    name: lhs.to_string(),
                });
            }
            split_dot(rest).ok_or_else(|| PredicateError::NotLocation {
                location: rest.to_string(),
            })?;
            Form::InSlot {
                item: lhs.to_string(),
                location: rest.to_string(),
            }
        }
    } else if let Some((robot, item)) = body.split_once(" touches ") {
        let (robot, item) = (robot.trim(), item.trim());
        if robot.contains(' ') || item.contains(' ') || robot.is_empty() || item.is_empty() {
            return Err(PredicateError::NotContact);
        }
        Form::Contact {
            robot: robot.into(),
            item: item.into(),
        }
    } else if let Some((robot, target)) = body.split_once(" holds ") {
        let (robot, target) = (robot.trim(), target.trim());
        if robot.contains(' ') || target.contains(' ') || robot.is_empty() || target.is_empty() {
            return Err(PredicateError::NotHolds);
        }
        let (item, part) = item_and_part(target).ok_or(PredicateError::NotHolds)?;
        Form::Holds {
            robot: robot.into(),
            item,
            part,
        }
    } else if let Some((item, rest)) = body.split_once(" inverted ") {
        let item = item.trim();
        if item.contains(' ') || item.contains('.') || item.is_empty() {
            return Err(PredicateError::NotItemName {
                name: item.to_string(),
            });
        }
        let rest = rest.trim();
        let count = rest
            .strip_suffix(" times")
            .or_else(|| rest.strip_suffix(" time"))
            .and_then(|n| n.trim().parse::<u32>().ok())
            .filter(|n| *n >= 1)
            .ok_or_else(|| PredicateError::NotCount {
                text: rest.to_string(),
            })?;
        Form::Inverted {
            item: item.to_string(),
            times: count,
        }
    } else if let Some((item, rest)) = body.split_once(" near ") {
        let (v, unit) = bracketed(rest, 3)?;
        let q = parse_quantity(&format!("1 {unit}"))
            .ok()
            .filter(|q| q.dimension == Dimension::Length)
            .ok_or_else(|| PredicateError::NotLengthUnit {
                unit: unit.to_string(),
            })?;
        Form::Near {
            item: item.trim().to_string(),
            pos: [v[0] * q.si, v[1] * q.si, v[2] * q.si],
        }
    } else if let Some((item, height)) = body.split_once(" lifted ") {
        let item = item.trim();
        let not_item = || PredicateError::NotItemName {
            name: item.to_string(),
        };
        if item.contains(' ') || item.is_empty() {
            return Err(not_item());
        }
        let (item, part) = item_and_part(item).ok_or_else(not_item)?;
        let q = parse_quantity(height.trim())?;
        if q.dimension != Dimension::Length || q.si <= 0.0 {
            return Err(PredicateError::NotHeight {
                height: height.trim().to_string(),
            });
        }
        Form::Lifted {
            item,
            height: q.si,
            part,
        }
    } else {
        let (lhs, cmp, rhs) = [(">=", Cmp::Ge), ("<=", Cmp::Le), ("=", Cmp::Eq)]
            .iter()
            .find_map(|(op, c)| body.split_once(op).map(|(l, r)| (l, *c, r)))
            .ok_or(PredicateError::NoForm)?;
        let (lhs, liquid) = match lhs.trim().split_once(" of ") {
            Some((value, liquid)) => {
                let liquid = liquid.trim();
                if liquid.is_empty() || liquid.contains(' ') {
                    return Err(PredicateError::NotLiquidName {
                        name: liquid.to_string(),
                    });
                }
                (value, Some(liquid.to_string()))
            }
            None => (lhs, None),
        };
        let (labware, field) =
            split_dot(lhs.trim()).ok_or_else(|| PredicateError::NotLabwareValue {
                lhs: lhs.trim().to_string(),
            })?;
        let value = rhs.trim();
        if value.is_empty() {
            return Err(PredicateError::NoValue);
        }
        Form::Compare {
            labware,
            field,
            liquid,
            cmp,
            value: value.to_string(),
        }
    };
    Ok(Parsed { form, within })
}

/// A template quantity rendered and read in `dim`.
pub fn quantity(template: &str, bound: &Bindings, dim: Dimension) -> Result<f64, ValueError> {
    let text = render(template, bound)?;
    let q = parse_quantity(&text)?;
    if q.dimension != dim {
        return Err(ValueError::WrongDimension {
            text,
            found: q.dimension,
            needed: dim,
        });
    }
    Ok(q.si)
}

/// A volume template (`"{fill} mL"`) rendered and read in µL.
pub fn volume_ul(template: &str, bound: &Bindings) -> Result<f64, ValueError> {
    quantity(template, bound, Dimension::Volume)
}

/// A panel value template (`"37 °C"`, `"{rpm} rpm"`) rendered and read in its own unit's
/// dimension (rpm, °C, s or µL); `None` when it does not read as a panel quantity.
pub fn panel_quantity(template: &str, bound: &Bindings) -> Option<f64> {
    let text = render(template, bound).ok()?;
    let q = parse_quantity(&text).ok()?;
    matches!(
        q.dimension,
        Dimension::Speed | Dimension::Temperature | Dimension::Time | Dimension::Volume
    )
    .then_some(q.si)
}

impl Check {
    /// A `was` check: it holds once the state has been seen at some step of the stage.
    pub fn is_history(&self) -> bool {
        matches!(self, Check::State { ever: true, .. })
    }

    /// Why this check's target value cannot be read under these parameter values (a volume or
    /// panel value template that renders to a bare number or the wrong unit); `None` when it can.
    pub fn target_error(&self, bound: &Bindings) -> Option<ValueError> {
        match self {
            Check::Volume { value, .. } => quantity(value, bound, Dimension::Volume).err(),
            Check::Panel { value, unit, .. } => {
                quantity(value, bound, crate::primitives::panel_dimension(unit)).err()
            }
            _ => None,
        }
    }

    /// The value of this check in the abstract world, when the abstract world decides it (part
    /// states, slots, volumes, panel values, carrying); `None` for what only physics can tell.
    pub fn eval_abstract(&self, w: &World, bound: &Bindings) -> Option<bool> {
        match self {
            Check::State {
                labware,
                part,
                state,
                ..
            } => {
                let s = w.part(labware, part)?;
                // The world runs an instrument's run to its end in one step: it never sees one
                // running, so whether one ran long enough is the judge's to measure.
                if part == labware::run::RUN && state == "running" {
                    return None;
                }
                Some(match state.as_str() {
                    // A locked lid is also closed; an open or merely closed one is unlocked.
                    "closed" => s == "closed" || s == "locked",
                    "unlocked" => s != "locked",
                    // A cap lying apart from its tube is off it.
                    "off" => s == "off" || s == "apart",
                    st => s == st,
                })
            }
            Check::InSlot { item, location, .. } => {
                let loc = render(location, bound).ok()?;
                let (holder, slot) = loc.split_once('.')?;
                Some(
                    matches!(w.locations.get(item), Some(Location::Slot { holder: h, slot: s }) if h == holder && s == slot),
                )
            }
            Check::Volume {
                container,
                liquid,
                cmp,
                value,
                tolerance,
            } => {
                let target = quantity(value, bound, Dimension::Volume).ok()?;
                let v = match liquid {
                    Some(liquid) => w.liquid_ul(container, liquid),
                    None => w.volumes.get(container).copied().unwrap_or(0.0),
                };
                Some(compare(v, *cmp, target, tolerance.value))
            }
            Check::Panel {
                instrument,
                param,
                unit,
                initial,
                value,
                tolerance,
            } => {
                let target =
                    quantity(value, bound, crate::primitives::panel_dimension(unit)).ok()?;
                let v = w
                    .panel
                    .get(&(instrument.clone(), param.clone()))
                    .copied()
                    .unwrap_or(*initial);
                Some(compare(v, Cmp::Eq, target, tolerance.value))
            }
            Check::Contact { robot, item }
            | Check::Holds {
                robot,
                item,
                part: None,
            } => match w.hand(robot) {
                Hand::Item(i) | Hand::Stabilising(i) if i == item => Some(true),
                _ => None,
            },
            // A cap in the hand that took it off is held, and clear of its seat.
            Check::Holds {
                robot,
                item,
                part: Some(_),
            } => match w.hand(robot) {
                Hand::Cap(i) if i == item => Some(true),
                _ => None,
            },
            Check::Lifted {
                item,
                part: Some(part),
                ..
            } => match w.part(item, part)? {
                "off" if w.hands.values().any(|h| h == &Hand::Cap(item.clone())) => Some(true),
                "on" => Some(false),
                _ => None,
            },
            // Held is lifted; standing in a slot or on the bench is not.
            Check::Lifted { item, .. } => match w.locations.get(item)? {
                Location::Held { .. } => Some(true),
                Location::Slot { .. } | Location::Bench => Some(false),
            },
            Check::Inverted { item, times } => {
                Some(w.inversions.get(item).copied().unwrap_or(0) >= *times)
            }
            Check::JointRange { .. } | Check::Position { .. } => None,
        }
    }
}

pub fn compare(value: f64, cmp: Cmp, target: f64, tolerance: f64) -> bool {
    match cmp {
        Cmp::Eq => (value - target).abs() <= tolerance,
        Cmp::Ge => value >= target - tolerance,
        Cmp::Le => value <= target + tolerance,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_every_form() {
        let ok = [
            "cycler.lid is closed",
            "cycler.lid in [-1.95, -1.85] rad",
            "tube in rack.{slot}",
            "tube.volume >= 200 µL",
            "mixer.speed = {rpm} rpm",
            "arm touches tube",
            "arm holds tube",
            "opener holds tube.cap",
            "tube near [0.3, 0.2, 0.83] m within 5 mm",
            "tube lifted 9.5 cm",
            "tube.cap lifted 3 cm",
        ];
        for t in ok {
            assert!(parse(t).is_ok(), "{t}: {:?}", parse(t));
        }
        let p = parse("tube near [0.3, 0.2, 0.83] m within 5 mm").unwrap();
        assert_eq!(p.within, Some((0.005, Dimension::Length)));
    }

    /// Each form reads to its parts, with units converted to the canonical ones.
    #[test]
    fn each_form_reads_to_its_parts_in_canonical_units() {
        let form = |t: &str| parse(t).unwrap_or_else(|e| panic!("{t}: {e}")).form;
        let s = |v: &str| v.to_string();
        assert_eq!(
            form("cycler.lid is closed"),
            Form::State {
                labware: s("cycler"),
                part: s("lid"),
                state: s("closed"),
                ever: false,
            }
        );
        assert_eq!(
            form("cycler.lid was open"),
            Form::State {
                labware: s("cycler"),
                part: s("lid"),
                state: s("open"),
                ever: true,
            }
        );
        // Degrees become radians; millimetres metres.
        let Form::JointRange { low, high, .. } = form("cycler.lid in [-110, -105] deg") else {
            panic!("a joint range")
        };
        assert!(
            (low + 110f64.to_radians()).abs() < 1e-12 && (high + 105f64.to_radians()).abs() < 1e-12
        );
        let Form::JointRange { low, high, .. } = form("rack.slide in [10, 25] mm") else {
            panic!("a joint range")
        };
        assert!((low - 0.010).abs() < 1e-12 && (high - 0.025).abs() < 1e-12);
        assert_eq!(
            form("tube in rack.{slot}"),
            Form::InSlot {
                item: s("tube"),
                location: s("rack.{slot}")
            }
        );
        assert_eq!(
            form("tube.volume >= 1.5 mL"),
            Form::Compare {
                labware: s("tube"),
                field: s("volume"),
                liquid: None,
                cmp: Cmp::Ge,
                value: s("1.5 mL")
            }
        );
        assert_eq!(
            form("diluted.volume of pbs_10x <= 500 µL"),
            Form::Compare {
                labware: s("diluted"),
                field: s("volume"),
                liquid: Some(s("pbs_10x")),
                cmp: Cmp::Le,
                value: s("500 µL")
            }
        );
        // A compared value is kept as text and read in its unit later: 1.5 mL is 1,500 µL.
        assert_eq!(
            quantity("1.5 mL", &Bindings::new(), Dimension::Volume),
            Ok(1500.0)
        );
        let rpm = Bindings::from([("rpm".to_string(), "900".to_string())]);
        assert_eq!(quantity("{rpm} rpm", &rpm, Dimension::Speed), Ok(900.0));
        assert!(quantity("{rpm} rpm", &rpm, Dimension::Volume).is_err());
        assert_eq!(
            form("arm touches tube"),
            Form::Contact {
                robot: s("arm"),
                item: s("tube")
            }
        );
        assert_eq!(
            form("opener holds tube.cap"),
            Form::Holds {
                robot: s("opener"),
                item: s("tube"),
                part: Some(s("cap"))
            }
        );
        assert_eq!(
            form("arm holds tube"),
            Form::Holds {
                robot: s("arm"),
                item: s("tube"),
                part: None
            }
        );
        assert_eq!(
            form("tube.cap lifted 30 mm"),
            Form::Lifted {
                item: s("tube"),
                height: 0.03,
                part: Some(s("cap"))
            }
        );
        let Form::Near { pos, .. } = form("tube near [300, 200, 830] mm") else {
            panic!("a position")
        };
        assert!(
            pos.iter()
                .zip([0.3, 0.2, 0.83])
                .all(|(a, b)| (a - b).abs() < 1e-12),
            "{pos:?}"
        );
        // An inline tolerance in degrees, read as radians.
        let p = parse("cycler.lid is closed within 2 deg").unwrap();
        assert_eq!(p.within, Some((2f64.to_radians(), Dimension::Angle)));
    }

    #[test]
    fn rejects_malformed_forms() {
        // Each refused for its own reason, not just refused.
        let verb =
            "expected `is`, `was`, `in`, `=`, `>=`, `<=`, `touches`, `holds`, `near` or `lifted`";
        for (t, why) in [
            ("cycler lid closed", verb),
            ("cycler.lid is", verb),
            ("cycler.lid in [1] rad", "`[1]` must hold 2 numbers"),
            ("cycler.lid in [2, 1] rad", "the range [2, 1] is empty"),
            ("tube near [1, 2] m", "`[1, 2]` must hold 3 numbers"),
            ("opener holds", verb),
            ("opener holds tube.cap.top", "write `<robot> holds <item>`"),
            (
                "tube.cap.top lifted 3 cm",
                "`tube.cap.top` is not an item name",
            ),
            ("tube.volume = ", "a comparison needs a value with a unit"),
            (
                "tube.volume of 10x pbs >= 5 µL",
                "`10x pbs` is not a liquid's name",
            ),
            (
                "cycler.lid is closed within 3 parsecs",
                "unknown unit `parsecs` in `3 parsecs`",
            ),
        ] {
            match parse(t) {
                Ok(p) => panic!("{t} parsed as {p:?}"),
                Err(e) => assert!(e.to_string().contains(why), "{t}: {e}"),
            }
        }
    }

    #[test]
    fn a_template_that_does_not_read_says_why() {
        let why = |t: &str| {
            quantity(t, &Bindings::new(), Dimension::Volume)
                .unwrap_err()
                .to_string()
        };
        assert_eq!(why("{fill} mL"), "unknown placeholder `{fill}`");
        assert_eq!(why("5 s"), "`5 s` is a time, but a volume is needed");
        assert_eq!(why("5"), "`5` has no unit");
        assert_eq!(
            ValueError::NotPanelValue.to_string(),
            "not a speed, temperature, time or volume"
        );
    }
}
