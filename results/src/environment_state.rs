//! A task's environment state: the privileged observation a state-based policy reads (LeRobot's
//! `observation.environment_state`, ManiSkill's `state` mode), in a fixed layout per task.
//!
//! The layout is declared by the task, not by a seed: the items its success checks read (in the
//! task's labware order), each as its root's world pose (`<item>.x/.y/.z` in m, then the
//! orientation quaternion `<item>.qw/.qx/.qy/.qz`, sign chosen with `qw >= 0`), its joints by role
//! (`<item>.<role>`, rad or m, roles sorted), its loose parts' poses (`<item>.<part>.x` ...
//! `.qz`), its panel values (`<item>.<param>`, the panel's unit) and, for a container, the
//! liquid it holds (`<item>.volume_ul`) and of each named liquid a check reads in it
//! (`<item>.liquid_ul.<liquid>`); then every drawn parameter (`param.<name>`: a number's
//! value in its canonical unit, or a choice's or slot's index in its domain). The same task
//! always has the same names, whatever the seed.
//!
//! It reads states (`LabwareState`) and the drawn parameters; it runs nothing and decides nothing.
//! Images stay a policy's default observation: this is opt-in everywhere (a profile's
//! `environment_state_key`, the gym env's `obs_type`, `autobio demo --observation state`).

use compiler::Task;
use compiler::params::{Bindings, Domain};
use compiler::predicates::Check;
use labware::LabwareState;

/// One value of the layout and where it is read from.
#[derive(Clone, Debug, PartialEq)]
enum Source {
    /// The item's root pose: 0-2 position, 3-6 quaternion (w, x, y, z).
    Pose {
        item: usize,
        k: usize,
    },
    Part {
        item: usize,
        part: &'static str,
        k: usize,
    },
    Joint {
        item: usize,
        role: &'static str,
    },
    Panel {
        item: usize,
        param: &'static str,
    },
    Volume {
        item: usize,
    },
    /// A named liquid's share of the item's volume (µL).
    Liquid {
        item: usize,
        key: String,
    },
    Param {
        name: String,
    },
}

/// A task's environment-state layout (see the module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct EnvironmentState {
    names: Vec<String>,
    sources: Vec<Source>,
    /// Parameter domains, for choices' and slots' indices.
    domains: Vec<(String, Domain)>,
}

const POSE: [&str; 7] = ["x", "y", "z", "qw", "qx", "qy", "qz"];

/// The items a task's success checks read, by name.
fn checked_items(task: &Task) -> Vec<String> {
    let mut out = Vec::new();
    for p in task.stages.iter().flat_map(|s| &s.success) {
        match &p.check {
            Check::State { labware, .. } | Check::JointRange { labware, .. } => {
                out.push(labware.clone())
            }
            Check::InSlot { item, location, .. } => {
                out.push(item.clone());
                if let Some((holder, _)) = location.split_once('.') {
                    out.push(holder.to_string());
                }
            }
            Check::Volume { container, .. } => out.push(container.clone()),
            Check::Panel { instrument, .. } => out.push(instrument.clone()),
            Check::Contact { item, .. }
            | Check::Holds { item, .. }
            | Check::Position { item, .. }
            | Check::Lifted { item, .. }
            | Check::Inverted { item, .. } => out.push(item.clone()),
        }
    }
    out
}

/// The named liquids the task's checks read in a container, sorted.
fn checked_liquids(task: &Task, container: &str) -> std::collections::BTreeSet<String> {
    task.stages
        .iter()
        .flat_map(|s| &s.success)
        .filter_map(|p| match &p.check {
            Check::Volume {
                container: c,
                liquid: Some(liquid),
                ..
            } if c == container => Some(liquid.clone()),
            _ => None,
        })
        .collect()
}

impl EnvironmentState {
    /// The layout of `task` (see the module docs).
    pub fn of(task: &Task) -> EnvironmentState {
        let checked = checked_items(task);
        let mut names = Vec::new();
        let mut sources = Vec::new();
        for (item, spec) in task.labware.iter().enumerate() {
            if !checked.contains(&spec.name) {
                continue;
            }
            let name = &spec.name;
            for (k, axis) in POSE.iter().enumerate() {
                names.push(format!("{name}.{axis}"));
                sources.push(Source::Pose { item, k });
            }
            let Some(model) = spec.params.instrument() else {
                continue;
            };
            let mut roles: Vec<&'static str> =
                model.joints(name).into_iter().map(|(r, _)| r).collect();
            roles.sort_unstable();
            roles.dedup();
            for role in roles {
                names.push(format!("{name}.{role}"));
                sources.push(Source::Joint { item, role });
            }
            let mut parts: Vec<&'static str> = model
                .part_bodies(name)
                .into_iter()
                .map(|(r, _)| r)
                .collect();
            parts.sort_unstable();
            parts.dedup();
            for part in parts {
                for (k, axis) in POSE.iter().enumerate() {
                    names.push(format!("{name}.{part}.{axis}"));
                    sources.push(Source::Part { item, part, k });
                }
            }
            if let (Some(kind), Some(panel)) = (labware::catalogue::kind(&spec.kind), model.panel())
            {
                for p in kind.panel {
                    let probe = LabwareState::probe(name);
                    if panel.panel_value(p.name, &probe).is_some() {
                        names.push(format!("{name}.{}", p.name));
                        sources.push(Source::Panel {
                            item,
                            param: p.name,
                        });
                    }
                }
            }
            if model.liquid().and_then(|l| l.interior()).is_some() {
                names.push(format!("{name}.volume_ul"));
                sources.push(Source::Volume { item });
                for liquid in checked_liquids(task, name) {
                    let key = labware::process::liquid_key(&liquid);
                    names.push(format!("{name}.{key}"));
                    sources.push(Source::Liquid { item, key });
                }
            }
        }
        for p in &task.params {
            names.push(format!("param.{}", p.name));
            sources.push(Source::Param {
                name: p.name.clone(),
            });
        }
        EnvironmentState {
            names,
            sources,
            domains: task
                .params
                .iter()
                .map(|p| (p.name.clone(), p.domain.clone()))
                .collect(),
        }
    }

    /// The values' names, in layout order.
    pub fn names(&self) -> &[String] {
        &self.names
    }

    pub fn len(&self) -> usize {
        self.names.len()
    }

    pub fn is_empty(&self) -> bool {
        self.names.is_empty()
    }

    /// The values for one control step's labware states (task order) and the episode's drawn
    /// parameters. A value that cannot be read (a state without that joint) is 0.
    pub fn values(&self, task: &Task, labware: &[LabwareState], params: &Bindings) -> Vec<f64> {
        self.sources
            .iter()
            .map(|s| self.value(task, s, labware, params).unwrap_or(0.0))
            .collect()
    }

    fn value(
        &self,
        task: &Task,
        source: &Source,
        labware: &[LabwareState],
        params: &Bindings,
    ) -> Option<f64> {
        match source {
            Source::Pose { item, k } => Some(pose_value(&labware.get(*item)?.pose, *k)),
            Source::Part { item, part, k } => {
                Some(pose_value(labware.get(*item)?.parts.get(*part)?, *k))
            }
            Source::Joint { item, role } => labware.get(*item)?.joints.get(*role).copied(),
            Source::Panel { item, param } => task
                .labware
                .get(*item)?
                .params
                .instrument()?
                .panel()?
                .panel_value(param, labware.get(*item)?),
            Source::Liquid { item, key } => {
                Some(labware.get(*item)?.logic.get(key).copied().unwrap_or(0.0))
            }
            Source::Volume { item } => Some(
                labware
                    .get(*item)?
                    .logic
                    .get(labware::process::VOLUME_UL)
                    .copied()
                    .unwrap_or(0.0),
            ),
            Source::Param { name } => {
                let drawn = params.get(name)?;
                let domain = &self.domains.iter().find(|(n, _)| n == name)?.1;
                param_value(domain, drawn, &self.domains)
            }
        }
    }
}

/// Component `k` of a pose: position (m), then the unit quaternion (w, x, y, z) with `w >= 0`.
fn pose_value(pose: &labware::frame::Pose, k: usize) -> f64 {
    let t = pose.translation.vector;
    let q = pose.rotation.quaternion();
    let sign = if q.w < 0.0 { -1.0 } else { 1.0 };
    match k {
        0..=2 => t[k],
        3 => sign * q.w,
        4 => sign * q.i,
        5 => sign * q.j,
        _ => sign * q.k,
    }
}

/// A drawn parameter as a number: a number's value (its text's leading number, in the canonical
/// unit the draw wrote it in), a choice's or slot's index in its domain.
fn param_value(domain: &Domain, drawn: &str, all: &[(String, Domain)]) -> Option<f64> {
    let index = |values: &[String]| values.iter().position(|v| v == drawn).map(|i| i as f64);
    match domain {
        Domain::Choice { values } => index(values),
        Domain::Slot { slots, .. } => index(slots),
        Domain::Opposite { holder, .. } => all.iter().find_map(|(_, d)| match d {
            Domain::Slot { holder: h, slots } if h == holder => index(slots),
            _ => None,
        }),
        Domain::Int { .. } | Domain::Real { .. } => leading_number(drawn),
    }
}

fn leading_number(text: &str) -> Option<f64> {
    let end = text
        .find(|c: char| !(c.is_ascii_digit() || matches!(c, '.' | '-' | '+' | 'e' | 'E')))
        .unwrap_or(text.len());
    text[..end].trim().parse().ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_lead_their_units() {
        assert_eq!(leading_number("95 °C"), Some(95.0));
        assert_eq!(leading_number("-2.5e-1"), Some(-0.25));
        assert_eq!(leading_number("slot_3"), None);
    }
}
