//! The places a protocol names a slot or a quantity, collected for [`crate::sweep::check`] (which
//! checks each under every parameter combination): each labware's `at`, each step's location,
//! volume and panel-value arguments, and each slot, volume and panel predicate. It reports
//! nothing itself; a step with an unknown primitive or a missing argument contributes nothing.

use super::{CheckedPredicate, KindMap};
use crate::predicates::Check;
use crate::primitives;
use crate::sweep::{Use, What};
use dsl::Dimension;
use dsl::ast::{Protocol, Step};

/// Every place the protocol names a slot or a quantity, for [`crate::sweep::check`]: each
/// labware's `at`, each step's location arguments (the item being the step's `on`), volumes and
/// panel values, each `in` predicate and each volume or panel predicate's target.
pub(super) fn sweep_uses(
    p: &Protocol,
    kinds: &KindMap,
    predicates: &[CheckedPredicate],
) -> Vec<Use> {
    let mut uses: Vec<Use> = p
        .labware
        .iter()
        .filter_map(|l| {
            l.at.as_ref().map(|at| Use {
                span: at.span,
                template: at.value.clone(),
                what: What::Slot {
                    item: item(kinds, &l.name.value),
                    start: true,
                },
            })
        })
        .collect();
    for step in &p.steps {
        step_uses(step, kinds, &mut uses);
    }
    for cp in predicates {
        predicate_use(cp, kinds, &mut uses);
    }
    uses
}

/// A labware item with its kind, when its kind is known.
fn item(kinds: &KindMap, name: &str) -> Option<(String, &'static labware::LabwareKind)> {
    kinds.get(name).map(|k| (name.to_string(), *k))
}

/// One step's location, volume and panel-value arguments.
fn step_uses(step: &Step, kinds: &KindMap, uses: &mut Vec<Use>) {
    let Some(prim) = step
        .primitive
        .as_ref()
        .and_then(|n| primitives::primitive(&n.value))
    else {
        return;
    };
    let on = step.arg("on").map(|v| v.value.text());
    let panel = on
        .as_deref()
        .and_then(|o| kinds.get(o))
        .zip(step.arg("param").map(|v| v.value.text()))
        .and_then(|(k, param)| k.panel_param(&param));
    for a in prim.args {
        let Some(v) = step.arg(a.name) else {
            continue;
        };
        let what = match a.kind {
            primitives::ArgKind::Location => What::Slot {
                item: on.as_deref().and_then(|o| item(kinds, o)),
                start: false,
            },
            primitives::ArgKind::Volume => What::Quantity(Dimension::Volume),
            primitives::ArgKind::PanelValue => match panel {
                Some(pp) => What::Quantity(primitives::panel_dimension(pp.unit)),
                None => continue,
            },
            _ => continue,
        };
        uses.push(Use {
            span: v.span,
            template: v.value.text(),
            what,
        });
    }
}

/// An `in` predicate's slot, or a volume or panel predicate's target quantity.
fn predicate_use(cp: &CheckedPredicate, kinds: &KindMap, uses: &mut Vec<Use>) {
    let (template, what) = match &cp.predicate.check {
        Check::InSlot {
            item: name,
            location,
            ..
        } => (
            location.clone(),
            What::Slot {
                item: item(kinds, name),
                start: false,
            },
        ),
        Check::Volume { value, .. } => (value.clone(), What::Quantity(Dimension::Volume)),
        Check::Panel { value, unit, .. } => (
            value.clone(),
            What::Quantity(primitives::panel_dimension(unit)),
        ),
        _ => return,
    };
    uses.push(Use {
        span: cp.span,
        template,
        what,
    });
}

#[cfg(test)]
mod tests {
    use super::super::testing::*;
    use super::sweep_uses;
    use crate::sweep::What;
    use dsl::ast::Document;

    /// The uses of a protocol, as (template, slot item and whether it is a start, or the
    /// quantity's dimension).
    fn uses_of(src: &str) -> Vec<(String, String)> {
        let Document::Protocol(p) = dsl::parse(src).0 else {
            panic!("a protocol");
        };
        lowered(src, |low, _| {
            let low = low.unwrap();
            sweep_uses(&p, &low.kinds, &low.predicates)
                .into_iter()
                .map(|u| {
                    let what = match u.what {
                        What::Slot { item, start } => format!(
                            "slot of {} start {start}",
                            item.map_or("?".into(), |(n, k)| format!("{n} ({})", k.name))
                        ),
                        What::Quantity(d) => d.name().to_string(),
                    };
                    (u.template, what)
                })
                .collect()
        })
    }

    /// The start slot, the step's slot and the predicate's slot, in that order; a volume step
    /// and a volume predicate are quantities.
    #[test]
    fn every_slot_and_quantity_is_a_use_in_the_protocols_order() {
        let slot = |t: &str, start| {
            (
                t.to_string(),
                format!("slot of tube (tube_50ml) start {start}"),
            )
        };
        assert_eq!(
            uses_of(BASE),
            [
                slot("source.A1", true),
                slot("target.{row}1", false),
                slot("target.{row}1", false)
            ]
        );
        let volumes = edited(&[
            (
                "at = \"source.A1\"",
                "at = \"source.A1\"\nstate = { cap = \"off\", volume = \"20 mL\" }",
            ),
            (
                "\"tube in target.{row}1\"",
                "\"tube in target.{row}1\", \"tube.volume = 5 mL\"",
            ),
        ]);
        let uses = uses_of(&volumes);
        assert_eq!(uses.len(), 4, "{uses:?}");
        assert_eq!(uses[3], ("5 mL".to_string(), "volume".to_string()));
    }
}
