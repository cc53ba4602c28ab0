//! A task's quantity templates resolved for one set of drawn parameters, into typed values: each
//! container's starting liquid, each panel's starting values, and each success predicate's text
//! and target. The runtime (an episode's start) and the judge (every control step) read these and
//! never parse a template; a template that does not resolve is a [`QuantityError`], reported,
//! never skipped. The compiler's sweep already proves every template resolves over the
//! parameters' domains, so for a compiled task this cannot fail; a task written by hand can.
//!
//! It does not measure anything (the judge does) or apply values (the runtime does).

use crate::Predicate;
use crate::Task;
use crate::params::{Bindings, render};
use crate::predicates::{Check, ValueError, panel_quantity, quantity, volume_ul};

/// A quantity template that does not resolve with the drawn parameters.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("`{item}`'s {what} `{template}` does not resolve: {why}")]
pub struct QuantityError {
    pub item: String,
    pub what: &'static str,
    pub template: String,
    /// Boxed: the error travels inside the runtime's and the evaluator's errors.
    pub why: Box<ValueError>,
}

/// One success predicate with the parameters filled in.
#[derive(Clone, Debug, PartialEq)]
pub struct ResolvedPredicate {
    /// The predicate as the author wrote it, with the parameters filled in (as written where a
    /// placeholder is unknown: the text is for people, the check is what counts).
    pub text: String,
    /// A panel or volume check's target in its unit's SI value; `None` for other checks. The
    /// judge measures a predicate whose target does not resolve as unmeasurable (no value, not
    /// holding), which its verdict shows.
    pub target: Result<Option<f64>, QuantityError>,
    /// The slot the check measures against, as (holder, slot): an `in` check's location, a
    /// lift's start slot (the item's `at`); `None` for other checks, or where it does not resolve
    /// (the check is then unmeasurable).
    pub place: Option<(String, String)>,
}

/// Every quantity a task's episode needs, resolved for one set of parameters.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Quantities {
    /// Each labware item's starting liquid (µL), in task order; `None` where none is declared.
    pub start_volumes_ul: Vec<Option<f64>>,
    /// Each labware item's panel values that start away from the kind's defaults, in task order.
    pub panel_starts: Vec<Vec<(String, f64)>>,
    /// Each stage's success predicates, in order.
    pub predicates: Vec<Vec<ResolvedPredicate>>,
}

impl ResolvedPredicate {
    /// `p`, a success predicate of `task`, with `params` filled in.
    pub fn of(task: &Task, p: &Predicate, params: &Bindings) -> ResolvedPredicate {
        let err = |item: &str, what, template: &str, why| QuantityError {
            item: item.to_string(),
            what,
            template: template.to_string(),
            why: Box::new(why),
        };
        let target = match &p.check {
            Check::Panel {
                instrument,
                unit,
                value,
                ..
            } => quantity(value, params, crate::primitives::panel_dimension(unit))
                .map(Some)
                .map_err(|why| err(instrument, "panel target", value, why)),
            Check::Volume {
                container, value, ..
            } => volume_ul(value, params)
                .map(Some)
                .map_err(|why| err(container, "volume target", value, why)),
            _ => Ok(None),
        };
        let slot = |template: &str| {
            let location = render(template, params).ok()?;
            let (holder, slot) = location.split_once('.')?;
            Some((holder.to_string(), slot.to_string()))
        };
        let place = match &p.check {
            Check::InSlot { location, .. } => slot(location),
            Check::Lifted { item, .. } => task
                .labware
                .iter()
                .find(|l| &l.name == item)
                .and_then(|spec| spec.at.as_deref())
                .and_then(slot),
            _ => None,
        };
        ResolvedPredicate {
            text: render(&p.text, params).unwrap_or_else(|_| p.text.clone()),
            target,
            place,
        }
    }
}

impl Quantities {
    /// `task`'s templates resolved with `params`.
    pub fn resolve(task: &Task, params: &Bindings) -> Result<Quantities, QuantityError> {
        let mut out = Quantities::default();
        for spec in &task.labware {
            let err = |what, template: &str, why| QuantityError {
                item: spec.name.clone(),
                what,
                template: template.to_string(),
                why: Box::new(why),
            };
            out.start_volumes_ul.push(match &spec.volume {
                Some(text) => {
                    Some(volume_ul(text, params).map_err(|why| err("starting volume", text, why))?)
                }
                None => None,
            });
            let mut panel = Vec::new();
            for (param, text) in &spec.panel {
                let value = panel_quantity(text, params)
                    .ok_or_else(|| err("starting panel value", text, ValueError::NotPanelValue))?;
                panel.push((param.clone(), value));
            }
            out.panel_starts.push(panel);
        }
        for stage in &task.stages {
            let resolved: Vec<ResolvedPredicate> = stage
                .success
                .iter()
                .map(|p| ResolvedPredicate::of(task, p, params))
                .collect();
            if let Some(Err(e)) = resolved.iter().map(|r| &r.target).find(|t| t.is_err()) {
                return Err(e.clone());
            }
            out.predicates.push(resolved);
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn transfer() -> Task {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../protocols/pipette/transfer.toml"
        );
        let text = std::fs::read_to_string(path).unwrap();
        let (task, diags) = crate::compile_source(&text, "transfer.toml");
        task.unwrap_or_else(|| panic!("{diags:#?}"))
    }

    #[test]
    fn a_sampled_instance_resolves_to_typed_values() {
        let task = transfer();
        let instance = task.sample(3);
        let q = Quantities::resolve(&task, &instance.params).unwrap();
        let item = |name: &str| task.labware.iter().position(|l| l.name == name).unwrap();
        let fill_ml: f64 = instance.params["fill"].to_string().parse().unwrap();
        let volume_ul: f64 = instance.params["volume"].to_string().parse().unwrap();
        assert_eq!(q.start_volumes_ul[item("source")], Some(fill_ml * 1000.0));
        assert_eq!(q.start_volumes_ul[item("target")], None);
        assert_eq!(
            q.panel_starts[item("pipette")],
            vec![("set_volume".to_string(), volume_ul)]
        );
        // The target volume check, resolved to µL; the tip's state has no target.
        let checks = &q.predicates[0];
        assert_eq!(checks[0].target, Ok(Some(volume_ul)));
        assert_eq!(
            checks[0].text,
            format!("target.volume = {} µL", instance.params["volume"])
        );
        assert_eq!(checks[2].target, Ok(None));
    }

    #[test]
    fn a_template_that_does_not_resolve_is_an_error_naming_it() {
        let mut task = transfer();
        let source = task
            .labware
            .iter()
            .position(|l| l.name == "source")
            .unwrap();
        task.labware[source].volume = Some("{nowhere} mL".into());
        let params = task.sample(0).params;
        let e = Quantities::resolve(&task, &params).unwrap_err();
        assert_eq!(e.item, "source");
        assert_eq!(e.template, "{nowhere} mL");
        assert!(
            e.to_string().contains("unknown placeholder `{nowhere}`"),
            "{e}"
        );
        // A panel start that is no panel quantity, and a target of the wrong dimension.
        let mut task = transfer();
        let pipette = task
            .labware
            .iter()
            .position(|l| l.name == "pipette")
            .unwrap();
        task.labware[pipette]
            .panel
            .insert("set_volume".into(), "fast".into());
        assert_eq!(
            Quantities::resolve(&task, &params).unwrap_err().what,
            "starting panel value"
        );
        let mut task = transfer();
        let Check::Volume { value, .. } = &mut task.stages[0].success[0].check else {
            panic!("the first check is the volume");
        };
        *value = "3 s".into();
        let e = Quantities::resolve(&task, &params).unwrap_err();
        assert_eq!((e.item.as_str(), e.what), ("target", "volume target"));
    }
}
