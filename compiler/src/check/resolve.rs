//! One parsed success predicate resolved against the protocol's names: its labware (declared,
//! of a known kind, not a parameter: E0013, E0030), the part, state, joint, slot holder, volume
//! or panel value it reads (E0030, E0016, E0020) and its robot (E0013), giving a [`Check`] with
//! the tolerance it takes by default. It parses no predicate text ([`crate::predicates::parse`])
//! and applies no `within` or `[tolerances]` override ([`super::success`]).

use super::{KindMap, NamedTolerance};
use crate::params::placeholders;
use crate::predicates::{self, Check, Cmp, Form, Tolerance};
use crate::primitives::{self, resolve_location};
use crate::report::{Cx, hint_for};
use dsl::ast::Spanned;
use dsl::{Code, Dimension};
use labware::LabwareKind;

/// A resolved predicate: the check (tolerance not yet applied) and the tolerance it takes, if
/// any; `None` after an error.
type Resolved = Option<(Check, Option<NamedTolerance>)>;

/// Resolves a predicate's names. Returns the check (tolerance not yet applied) and the dimension
/// its tolerance bounds.
pub(super) fn resolve_check(
    cx: &mut Cx,
    text: &Spanned<String>,
    form: &Form,
    kinds: &KindMap,
    robots: &[String],
    declared: &[&str],
    liquids: &[&str],
) -> Resolved {
    let names = Names {
        text,
        kinds,
        robots,
        declared,
        liquids,
        labware_names: kinds.keys().map(String::as_str).collect(),
    };
    match form {
        Form::State {
            labware: lw,
            part,
            state,
            ever,
        } => names.state(cx, lw, part, state, *ever),
        Form::JointRange {
            labware: lw,
            joint,
            low,
            high,
        } => names.joint_range(cx, lw, joint, *low, *high),
        Form::InSlot { item, location } => names.in_slot(cx, item, location),
        Form::Compare {
            labware: lw,
            field,
            liquid,
            cmp,
            value,
        } => {
            let kind = names.labware(cx, lw)?;
            if let Some(liquid) = liquid {
                if field != "volume" || kind.capacity_ul.is_none() {
                    cx.err(
                        Code::E0030,
                        text.span,
                        format!(
                            "`{lw}.{field} of {liquid}`: only a container's `volume` is of a liquid"
                        ),
                        Some(format!(
                            "write `{lw}.volume of {liquid} >= 5 µL` on a container"
                        )),
                    );
                    return None;
                }
                names.liquid(cx, liquid)?;
            }
            if field == "volume" && kind.capacity_ul.is_some() {
                names.volume(cx, kind, lw, liquid.clone(), *cmp, value)
            } else {
                names.panel(cx, kind, lw, field, *cmp, value)
            }
        }
        Form::Contact { robot, item } => names.contact(cx, robot, item),
        Form::Near { item, pos } => {
            let kind = names.labware(cx, item)?;
            let v = kind.tolerance("position").unwrap_or(0.005);
            Some((
                Check::Position {
                    item: item.clone(),
                    pos: *pos,
                    tolerance: Tolerance {
                        name: "position".into(),
                        value: v,
                    },
                },
                Some(("position".into(), v, Dimension::Length)),
            ))
        }
        Form::Holds { robot, item, part } => names.holds(cx, robot, item, part.as_deref()),
        Form::Inverted { item, times } => {
            let kind = names.labware(cx, item)?;
            if !kind.movable {
                cx.err(
                    Code::E0030,
                    text.span,
                    format!(
                        "`{item}` (a {}) is not turned over: it does not move",
                        kind.name
                    ),
                    Some("count the inversions of a tube a robot carries".into()),
                );
                return None;
            }
            Some((
                Check::Inverted {
                    item: item.clone(),
                    times: *times,
                },
                None,
            ))
        }
        Form::Lifted { item, height, part } => {
            let kind = names.labware(cx, item)?;
            if let Some(part) = part {
                names.loose_part(cx, kind, part)?;
            }
            Some((
                Check::Lifted {
                    item: item.clone(),
                    height: *height,
                    part: part.clone(),
                },
                None,
            ))
        }
    }
}

/// What a predicate's names are resolved against; every error points at the predicate's text.
struct Names<'a> {
    text: &'a Spanned<String>,
    kinds: &'a KindMap,
    robots: &'a [String],
    declared: &'a [&'a str],
    /// The liquids the protocol loads (`state = { liquid = ".." }`).
    liquids: &'a [&'a str],
    labware_names: Vec<&'a str>,
}

impl Names<'_> {
    /// A labware item's kind. `None` for a placeholder (E0030), a name not declared (E0013) or
    /// one declared with an unknown kind (reported at the kind).
    fn labware(&self, cx: &mut Cx, name: &str) -> Option<&'static LabwareKind> {
        if !placeholders(name).is_empty() {
            cx.err(
                Code::E0030,
                self.text.span,
                format!("`{name}`: labware names in predicates cannot be parameters"),
                Some("parameters may stand for slots and values".into()),
            );
            return None;
        }
        let k = self.kinds.get(name).copied();
        // Declared with an unknown kind: that was reported at the kind.
        if k.is_none() && !self.declared.contains(&name) {
            cx.err(
                Code::E0013,
                self.text.span,
                format!("no labware named `{name}`"),
                Some(hint_for(name, &self.labware_names, "labware")),
            );
        }
        k
    }

    /// `<lw>.<part> is <state>` (or `was`): a part of the kind and one of its states.
    fn state(&self, cx: &mut Cx, lw: &str, part: &str, state: &str, ever: bool) -> Resolved {
        let kind = self.labware(cx, lw)?;
        let Some(ps) = kind.part(part) else {
            let parts: Vec<&str> = kind.parts.iter().map(|p| p.part).collect();
            cx.err(
                Code::E0030,
                self.text.span,
                format!("a {} has no part `{part}`", kind.name),
                Some(hint_for(part, &parts, "parts")),
            );
            return None;
        };
        if !ps.states.contains(&state) {
            cx.err(
                Code::E0030,
                self.text.span,
                format!("`{part}` has no state `{state}`"),
                Some(hint_for(state, ps.states, "states")),
            );
            return None;
        }
        let name = format!("{part}_{state}");
        // A part that moves on a joint is measured in the joint's unit (a lid's angle); a
        // loose part (a tube's cap) by its distance from where the state puts it.
        let dimension = match kind.joints.iter().find(|(j, _)| *j == part) {
            Some((_, "m")) | None => Dimension::Length,
            Some(_) => Dimension::Angle,
        };
        let tol = kind.tolerance(&name).map(|v| (name, v, dimension));
        Some((
            Check::State {
                labware: lw.to_string(),
                part: part.to_string(),
                state: state.to_string(),
                tolerance: None,
                ever,
            },
            tol,
        ))
    }

    /// `<lw>.<joint> in [lo, hi] <unit>`: a joint of the kind; no tolerance.
    fn joint_range(&self, cx: &mut Cx, lw: &str, joint: &str, low: f64, high: f64) -> Resolved {
        let kind = self.labware(cx, lw)?;
        if !kind.joints.iter().any(|(j, _)| *j == joint) {
            let joints: Vec<&str> = kind.joints.iter().map(|(j, _)| *j).collect();
            cx.err(
                Code::E0030,
                self.text.span,
                format!("a {} has no joint `{joint}`", kind.name),
                Some(hint_for(joint, &joints, "joints")),
            );
            return None;
        }
        Some((
            Check::JointRange {
                labware: lw.to_string(),
                joint: joint.to_string(),
                low,
                high,
            },
            None,
        ))
    }

    /// `<item> in <holder>.<slot>`: a movable item, a holder with slots and (without
    /// placeholders) a slot that exists.
    fn in_slot(&self, cx: &mut Cx, item: &str, location: &str) -> Resolved {
        let kind = self.labware(cx, item)?;
        if !kind.movable {
            cx.err(
                Code::E0030,
                self.text.span,
                format!("`{item}` (a {}) never moves into a slot", kind.name),
                None,
            );
            return None;
        }
        let holder = location.split_once('.').map(|(h, _)| h).unwrap_or("");
        let hkind = self.labware(cx, holder)?;
        if hkind.slots.is_none() {
            cx.err(
                Code::E0016,
                self.text.span,
                format!("`{holder}` (a {}) has no slots", hkind.name),
                None,
            );
            return None;
        }
        if placeholders(location).is_empty() {
            let env_kinds = self.kinds.clone();
            let env = primitives::Env {
                kinds: &env_kinds,
                robots: self.robots,
            };
            if let Err(m) = resolve_location(&env, location) {
                cx.err(Code::E0016, self.text.span, m.to_string(), None);
                return None;
            }
        }
        let v = kind.tolerance("slot_xy").unwrap_or(0.015);
        Some((
            Check::InSlot {
                item: item.to_string(),
                location: location.to_string(),
                tolerance: Tolerance {
                    name: "slot_xy".into(),
                    value: v,
                },
                height: kind.tolerance("slot_z").unwrap_or(0.005),
                tilt: crate::predicates::SLOT_TILT,
            },
            Some(("slot_xy".into(), v, Dimension::Length)),
        ))
    }

    /// A liquid a predicate names: one the protocol loads somewhere (E0013 otherwise).
    fn liquid(&self, cx: &mut Cx, liquid: &str) -> Option<()> {
        if self.liquids.contains(&liquid) {
            return Some(());
        }
        let hint = if self.liquids.is_empty() {
            "load it into a container: `state = { volume = \"200 µL\", liquid = \"water\" }`".into()
        } else {
            hint_for(liquid, self.liquids, "liquids loaded")
        };
        cx.err(
            Code::E0013,
            self.text.span,
            format!("no container starts with a liquid named `{liquid}`"),
            Some(hint),
        );
        None
    }

    /// `<lw>.volume <cmp> <q>` on a container (`of <liquid>`: that liquid's share): a volume
    /// (checked here unless it has placeholders; the proof reads those per parameter
    /// combination).
    fn volume(
        &self,
        cx: &mut Cx,
        kind: &LabwareKind,
        lw: &str,
        liquid: Option<String>,
        cmp: Cmp,
        value: &str,
    ) -> Resolved {
        if placeholders(value).is_empty()
            && let Err(e) = predicates::quantity(value, &Default::default(), Dimension::Volume)
        {
            cx.err(
                Code::E0020,
                self.text.span,
                e.to_string(),
                Some("compare a volume with a quantity: \"tube.volume = 200 µL\"".into()),
            );
            return None;
        }
        let v = kind.tolerance("volume").unwrap_or(1.0);
        Some((
            Check::Volume {
                container: lw.to_string(),
                liquid,
                cmp,
                value: value.to_string(),
                tolerance: Tolerance {
                    name: "volume".into(),
                    value: v,
                },
            },
            Some(("volume".into(), v, Dimension::Volume)),
        ))
    }

    /// `<lw>.<value> = <q>`: a panel value of the kind, compared with `=`, in its dimension.
    fn panel(
        &self,
        cx: &mut Cx,
        kind: &LabwareKind,
        lw: &str,
        field: &str,
        cmp: Cmp,
        value: &str,
    ) -> Resolved {
        let Some(p) = kind.panel_param(field) else {
            let mut fields: Vec<&str> = kind.panel.iter().map(|p| p.name).collect();
            if kind.capacity_ul.is_some() {
                fields.push("volume");
            }
            cx.err(
                Code::E0030,
                self.text.span,
                format!("a {} has no value `{field}` to compare", kind.name),
                Some(hint_for(field, &fields, "values")),
            );
            return None;
        };
        if cmp != Cmp::Eq {
            cx.err(
                Code::E0030,
                self.text.span,
                "a panel value is compared with `=`".into(),
                None,
            );
            return None;
        }
        let dim = primitives::panel_dimension(p.unit);
        if placeholders(value).is_empty()
            && let Err(e) = predicates::quantity(value, &Default::default(), dim)
        {
            cx.err(Code::E0020, self.text.span, e.to_string(), None);
            return None;
        }
        let v = kind.tolerance("display").unwrap_or(1e-6);
        Some((
            Check::Panel {
                instrument: lw.to_string(),
                param: field.to_string(),
                unit: p.unit.into(),
                initial: p.initial,
                value: value.to_string(),
                tolerance: Tolerance {
                    name: "display".into(),
                    value: v,
                },
            },
            Some(("display".into(), v, dim)),
        ))
    }

    /// `<robot> holds <item>[.<part>]`: a declared robot, item and (if given) a loose part of
    /// the item's kind; no tolerance.
    fn holds(&self, cx: &mut Cx, robot: &str, item: &str, part: Option<&str>) -> Resolved {
        self.robot(cx, robot)?;
        let kind = self.labware(cx, item)?;
        if let Some(part) = part {
            self.loose_part(cx, kind, part)?;
        }
        Some((
            Check::Holds {
                robot: robot.to_string(),
                item: item.to_string(),
                part: part.map(str::to_string),
            },
            None,
        ))
    }

    /// A part of the kind that comes away from it (a tube's cap, not a lid on a hinge): E0030
    /// otherwise.
    fn loose_part(&self, cx: &mut Cx, kind: &LabwareKind, part: &str) -> Option<()> {
        if kind.part(part).is_some() && !kind.joints.iter().any(|(j, _)| *j == part) {
            return Some(());
        }
        let loose: Vec<&str> = kind
            .parts
            .iter()
            .map(|p| p.part)
            .filter(|p| !kind.joints.iter().any(|(j, _)| j == p))
            .collect();
        let hint = if loose.is_empty() {
            format!("a {} has no loose part", kind.name)
        } else {
            hint_for(part, &loose, "loose parts")
        };
        cx.err(
            Code::E0030,
            self.text.span,
            format!("a {} has no loose part `{part}`", kind.name),
            Some(hint),
        );
        None
    }

    /// A declared robot: E0013 otherwise.
    fn robot(&self, cx: &mut Cx, robot: &str) -> Option<()> {
        if self.robots.iter().any(|r| r == robot) {
            return Some(());
        }
        let names: Vec<&str> = self.robots.iter().map(String::as_str).collect();
        cx.err(
            Code::E0013,
            self.text.span,
            format!("no robot named `{robot}`"),
            Some(hint_for(robot, &names, "robots")),
        );
        None
    }

    /// `<robot> touches <item>`: a declared robot and item; no tolerance.
    fn contact(&self, cx: &mut Cx, robot: &str, item: &str) -> Resolved {
        self.robot(cx, robot)?;
        self.labware(cx, item)?;
        Some((
            Check::Contact {
                robot: robot.to_string(),
                item: item.to_string(),
            },
            None,
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::super::testing::*;
    use crate::predicates::Check;
    use dsl::Code;

    /// BASE with its one predicate replaced by `predicate`.
    fn predicate(predicate: &str) -> String {
        edited(&[(
            "all = [\"tube in target.{row}1\"]",
            &format!("all = [\"{predicate}\"]"),
        )])
    }

    /// Each name a predicate reads is resolved; the one that is wrong is the error, with its
    /// code and message, and the predicate is left out.
    #[test]
    fn a_predicates_names_are_resolved_and_the_wrong_one_reported() {
        let cases = [
            ("tbe in target.A1", Code::E0013, "no labware named `tbe`"),
            (
                "{row}.cap is on",
                Code::E0030,
                "`{row}`: labware names in predicates cannot be parameters",
            ),
            (
                "tube.lid is on",
                Code::E0030,
                "a tube_50ml has no part `lid`",
            ),
            (
                "tube.cap is loose",
                Code::E0030,
                "`cap` has no state `loose`",
            ),
            (
                "source in target.A1",
                Code::E0030,
                "`source` (a tube_rack) never moves into a slot",
            ),
            (
                "tube in tube.A1",
                Code::E0016,
                "`tube` (a tube_50ml) has no slots",
            ),
            ("arn touches tube", Code::E0013, "no robot named `arn`"),
            ("arn holds tube.cap", Code::E0013, "no robot named `arn`"),
            (
                "arm holds tube.lid",
                Code::E0030,
                "a tube_50ml has no loose part `lid`",
            ),
            (
                "target.cap lifted 3 cm",
                Code::E0030,
                "a tube_rack has no loose part `cap`",
            ),
            (
                "tube.rotor in [0, 1] rad",
                Code::E0030,
                "a tube_50ml has no joint `rotor`",
            ),
            (
                "tube.speed = 3 rpm",
                Code::E0030,
                "a tube_50ml has no value `speed` to compare",
            ),
        ];
        for (text, code, message) in cases {
            let src = predicate(text);
            lowered(&src, |low, diags| {
                let d = one(diags, code);
                assert_eq!(d.message, message, "{text}");
                assert_eq!(covered(&src, d.span), format!("\"{text}\""));
                assert!(low.unwrap().predicates.is_empty(), "{text}");
            });
        }
    }

    /// A slot that no holder has is refused; one that exists resolves with the kind's
    /// tolerances.
    #[test]
    fn a_slot_predicate_names_a_slot_that_exists() {
        let src = predicate("tube in target.Z9");
        lowered(&src, |_, diags| {
            let d = one(diags, Code::E0016);
            assert_eq!(covered(&src, d.span), "\"tube in target.Z9\"");
        });
        lowered(&predicate("tube in target.B2"), |low, diags| {
            assert!(diags.is_empty(), "{diags:#?}");
            let Check::InSlot {
                item,
                location,
                tolerance,
                ..
            } = &low.unwrap().predicates[0].predicate.check
            else {
                panic!("an in-slot check");
            };
            assert_eq!((item.as_str(), location.as_str()), ("tube", "target.B2"));
            assert_eq!(tolerance.name, "slot_xy");
        });
    }

    /// A volume is compared with a volume (any comparison); a panel value only with `=`.
    #[test]
    fn volumes_and_panel_values_are_compared_in_their_dimension() {
        let src = predicate("tube.volume >= 2 s");
        lowered(&src, |low, diags| {
            let d = one(diags, Code::E0020);
            assert_eq!(
                d.hint.as_deref(),
                Some("compare a volume with a quantity: \"tube.volume = 200 µL\"")
            );
            assert!(low.unwrap().predicates.is_empty());
        });
        lowered(&predicate("tube.volume >= 2 mL"), |low, diags| {
            assert!(!codes(diags).contains(&Code::E0020), "{diags:#?}");
            let Check::Volume {
                container, value, ..
            } = &low.unwrap().predicates[0].predicate.check
            else {
                panic!("a volume check");
            };
            assert_eq!((container.as_str(), value.as_str()), ("tube", "2 mL"));
        });
        let mixer =
            "[labware.mixer]\nkind = \"thermal_mixer\"\npose = { pos_m = [-0.05, -0.45, 0.824] }\n";
        let src = with(mixer).replace(
            "all = [\"tube in target.{row}1\"]",
            "all = [\"mixer.speed >= 900 rpm\"]",
        );
        lowered(&src, |_, diags| {
            assert_eq!(
                one(diags, Code::E0030).message,
                "a panel value is compared with `=`"
            );
        });
    }
}
