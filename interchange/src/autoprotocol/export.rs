//! A compiled task's lab steps written as Autoprotocol (`autobio export PROTOCOL --to
//! autoprotocol`): its containers as `refs`, their start volumes as `provision`s, its pipetting
//! as `liquid_handle`, its instrument runs as `thermocycle`, `spin` and `incubate` on the
//! containers standing in the instrument when it runs, its step timing as `time_constraints`.
//! The robot's motions (picks, places, lids, presses, retracts) are dropped: the cloud lab's
//! own machines do them. An instrument-only step (`external`) imported from Autoprotocol writes
//! its instruction back as it was. One episode's draw of the task's parameters is written
//! (`seed`).
//!
//! Containers become refs by what they are: a 1.5 mL tube is a `micro-1.5` ref of its own name;
//! the PCR tubes standing in a 96-well block (the aluminium block's, the cycler's) are wells of
//! one `96-pcr` ref, named as the import names such tubes (`<ref>_<well>` standing in that well
//! is well `<well>` of ref `<ref>`), else after the block. So a protocol `autobio import` wrote
//! from Autoprotocol exports to a document that imports to the same protocol. Containers of other
//! kinds (15 and 50 mL tubes, cryovials) have no Autoprotocol type: a step that moves liquid in
//! them or runs an instrument on them is refused.

use super::units::{self, Dimension};
use compiler::{PlannedStep, Task};
use serde_json::{Map, Value, json};
use std::collections::BTreeMap;
use std::fmt;

/// Why a task cannot be written as Autoprotocol.
#[derive(Debug, Clone, PartialEq)]
pub enum ExportError {
    /// A step uses a container that has no Autoprotocol type.
    NoContainerType {
        step: usize,
        item: String,
        kind: String,
    },
    /// A step's arguments do not read (the task's proof would have refused them).
    Step { step: usize, reason: String },
}

impl fmt::Display for ExportError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ExportError::NoContainerType { step, item, kind } => write!(
                f,
                "step {step} uses `{item}`, a `{kind}`, which has no Autoprotocol container type (a 1.5 mL tube is `micro-1.5`; PCR tubes in a 96-well block are a `96-pcr` plate)"
            ),
            ExportError::Step { step, reason } => write!(f, "step {step}: {reason}"),
        }
    }
}

impl std::error::Error for ExportError {}

/// The document and what was left out of it.
#[derive(Debug, Clone)]
pub struct Exported {
    /// The Autoprotocol JSON, pretty-printed.
    pub json: String,
    /// What the document leaves out, one line each (`5 robot motions dropped: ...`).
    pub notes: Vec<String>,
}

/// A container as a ref's well.
#[derive(Clone, Debug, PartialEq)]
struct Aliquot {
    reference: String,
    well: usize,
}

impl Aliquot {
    fn text(&self) -> String {
        format!("{}/{}", self.reference, self.well)
    }
}

/// 96-well holders whose slots are a plate's wells.
const PLATE_HOLDERS: [&str; 2] = ["thermal_cycler_96", "aluminium_block_96_pcr"];
/// `incubate`'s places by their temperature (°C).
const WHERE: [(&str, f64); 7] = [
    ("cold_80", -80.0),
    ("cold_20", -20.0),
    ("cold_4", 4.0),
    ("ambient", 22.0),
    ("warm_30", 30.0),
    ("warm_35", 35.0),
    ("warm_37", 37.0),
];
const STANDARD_G: f64 = 9.806_65;

/// A96 slot name (`B3`) as a 0-based well index.
fn well_index(slot: &str) -> Option<usize> {
    let mut c = slot.chars();
    let row = c.next()?.to_ascii_uppercase();
    let col: usize = c.as_str().parse().ok()?;
    ('A'..='H')
        .contains(&row)
        .then_some(())
        .filter(|_| (1..=12).contains(&col))
        .map(|_| (row as usize - 'A' as usize) * 12 + col - 1)
}

struct Exporter<'a> {
    task: &'a Task,
    fill: Box<dyn Fn(&str) -> String + 'a>,
    kinds: BTreeMap<String, String>,
    /// Where each item stands now: its holder and slot.
    place: BTreeMap<String, Option<(String, String)>>,
    aliquots: BTreeMap<String, Aliquot>,
    refs: BTreeMap<String, &'static str>,
    volumes: BTreeMap<String, f64>,
    instructions: Vec<Value>,
    /// The index of the first instruction each plan step wrote (or would have: the next one).
    first_at_step: Vec<usize>,
    dropped: BTreeMap<String, usize>,
    notes: Vec<String>,
    /// What the pipette holds (µL): while it holds liquid, pipetting joins the liquid handling.
    in_tip: f64,
}

/// Writes the task's lab steps for the episode `seed` draws.
pub fn export(task: &Task, seed: u64) -> Result<Exported, ExportError> {
    let scene = task.sample(seed);
    let params = scene.params.clone();
    let fill = Box::new(move |t: &str| {
        compiler::params::render(t, &params).unwrap_or_else(|_| t.to_string())
    });
    let mut x = Exporter {
        task,
        kinds: task
            .labware
            .iter()
            .map(|l| (l.name.clone(), l.kind.clone()))
            .collect(),
        place: BTreeMap::new(),
        aliquots: BTreeMap::new(),
        refs: BTreeMap::new(),
        volumes: BTreeMap::new(),
        instructions: Vec::new(),
        first_at_step: Vec::new(),
        dropped: BTreeMap::new(),
        notes: Vec::new(),
        in_tip: 0.0,
        fill,
    };
    x.containers();
    x.provisions();
    let steps: Vec<&PlannedStep> = task.steps().map(|(_, s)| s).collect();
    for (i, step) in steps.iter().enumerate() {
        x.first_at_step.push(x.instructions.len());
        x.step(i, step)?;
    }
    let constraints = x.constraints(&steps);
    if !x.dropped.is_empty() {
        let list: Vec<String> = x
            .dropped
            .iter()
            .map(|(p, n)| format!("{n} `{p}`"))
            .collect();
        x.notes.push(format!(
            "robot motions dropped (the cloud lab's machines make their own): {}",
            list.join(", ")
        ));
    }
    let refs: Map<String, Value> = x
        .refs
        .iter()
        .map(|(name, kind)| (name.clone(), json!({"new": kind, "discard": true})))
        .collect();
    let mut doc = Map::new();
    doc.insert("refs".into(), Value::Object(refs));
    doc.insert("instructions".into(), Value::Array(x.instructions));
    if !constraints.is_empty() {
        doc.insert("time_constraints".into(), Value::Array(constraints));
    }
    let mut json = serde_json::to_string_pretty(&Value::Object(doc)).expect("values serialise");
    json.push('\n');
    Ok(Exported {
        json,
        notes: x.notes,
    })
}

impl Exporter<'_> {
    fn kind(&self, item: &str) -> &str {
        self.kinds.get(item).map_or("", String::as_str)
    }

    /// Every container's ref and well, from where it stands at the start.
    fn containers(&mut self) {
        for l in &self.task.labware {
            let at = l.at.as_deref().map(|a| (self.fill)(a));
            let place = at
                .as_deref()
                .and_then(|a| a.split_once('.'))
                .map(|(h, s)| (h.to_string(), s.to_string()));
            self.place.insert(l.name.clone(), place);
            if let Some(v) = l.volume.as_deref().map(|v| (self.fill)(v))
                && let Ok(q) = dsl::parse_quantity(&v)
            {
                self.volumes.insert(l.name.clone(), q.si);
            }
        }
        // Tubes of their own first, so a plate's name gives way to a tube's.
        for l in &self.task.labware {
            if l.kind == "tube_1_5ml" {
                self.refs.insert(l.name.clone(), "micro-1.5");
                self.aliquots.insert(
                    l.name.clone(),
                    Aliquot {
                        reference: l.name.clone(),
                        well: 0,
                    },
                );
            }
        }
        let mut plates: BTreeMap<String, String> = BTreeMap::new();
        for l in &self.task.labware {
            if l.kind != "tube_0_2ml" {
                continue;
            }
            let Some((holder, slot)) = self.place[&l.name].clone() else {
                continue;
            };
            if !PLATE_HOLDERS.contains(&self.kind(&holder)) {
                continue;
            }
            let Some(well) = well_index(&slot) else {
                continue;
            };
            let prefix = l
                .name
                .strip_suffix(&format!("_{}", slot.to_ascii_lowercase()))
                .filter(|p| !p.is_empty());
            let mut reference = match prefix {
                Some(p) if plates.get(p).is_none_or(|h| *h == holder) => p.to_string(),
                _ => holder.clone(),
            };
            while self.refs.get(&reference).is_some_and(|k| *k != "96-pcr")
                || plates.get(&reference).is_some_and(|h| *h != holder)
            {
                reference.push_str("_plate");
            }
            plates.insert(reference.clone(), holder.clone());
            self.refs.insert(reference.clone(), "96-pcr");
            self.aliquots
                .insert(l.name.clone(), Aliquot { reference, well });
        }
    }

    /// The start volumes as `provision`s, one per liquid in the order items are declared.
    fn provisions(&mut self) {
        let mut by_liquid: Vec<(String, Vec<Value>)> = Vec::new();
        for l in &self.task.labware {
            let (Some(a), Some(v)) = (self.aliquots.get(&l.name), self.volumes.get(&l.name)) else {
                continue;
            };
            if *v <= 0.0 {
                continue;
            }
            let liquid = l
                .liquid
                .as_deref()
                .map(|x| (self.fill)(x))
                .unwrap_or_else(|| "unnamed_liquid".into());
            let to = json!({"well": a.text(), "volume": units::write(*v, Dimension::Volume)});
            match by_liquid.iter_mut().find(|(n, _)| *n == liquid) {
                Some((_, list)) => list.push(to),
                None => by_liquid.push((liquid, vec![to])),
            }
        }
        for (liquid, to) in by_liquid {
            self.instructions
                .push(json!({"op": "provision", "resource_id": liquid, "to": to}));
        }
    }

    fn args(&self, step: &PlannedStep) -> BTreeMap<String, String> {
        step.args
            .iter()
            .map(|(k, v)| (k.clone(), (self.fill)(v)))
            .collect()
    }

    fn aliquot(&self, i: usize, item: &str) -> Result<Aliquot, ExportError> {
        self.aliquots
            .get(item)
            .cloned()
            .ok_or_else(|| ExportError::NoContainerType {
                step: i + 1,
                item: item.to_string(),
                kind: self.kind(item).to_string(),
            })
    }

    fn quantity(
        &self,
        i: usize,
        args: &BTreeMap<String, String>,
        name: &str,
    ) -> Result<f64, ExportError> {
        args.get(name)
            .and_then(|v| dsl::parse_quantity(v).ok())
            .map(|q| q.si)
            .ok_or_else(|| ExportError::Step {
                step: i + 1,
                reason: format!("`{name}` does not read as a quantity"),
            })
    }

    /// The refs of the containers standing in `holder` now, in name order.
    fn refs_in(&self, i: usize, holder: &str) -> Result<Vec<(String, Vec<String>)>, ExportError> {
        let mut out: Vec<(String, Vec<String>)> = Vec::new();
        for (item, place) in &self.place {
            if place.as_ref().is_none_or(|(h, _)| h != holder) {
                continue;
            }
            if labware::kind(self.kind(item)).is_none_or(|k| k.capacity_ul.is_none()) {
                continue;
            }
            let a = self.aliquot(i, item)?;
            match out.iter_mut().find(|(r, _)| *r == a.reference) {
                Some((_, items)) => items.push(item.clone()),
                None => out.push((a.reference, vec![item.clone()])),
            }
        }
        Ok(out)
    }

    fn step(&mut self, i: usize, step: &PlannedStep) -> Result<(), ExportError> {
        let args = self.args(step);
        let on = step.labware.as_deref().map(|o| (self.fill)(o));
        let kind = on.as_deref().map(|o| self.kind(o).to_string());
        match step.primitive.as_str() {
            "aspirate" | "dispense" => {
                let on = on.unwrap_or_default();
                let a = self.aliquot(i, &on)?;
                let v = self.quantity(i, &args, "volume")?;
                let draw = step.primitive == "aspirate";
                *self.volumes.entry(on).or_default() += if draw { -v } else { v };
                let signed = if draw { -v } else { v };
                let location = json!({"location": a.text(), "transports": [{"volume": units::write(signed, Dimension::Volume)}]});
                // What the pipette draws and expels until it is empty is one liquid handling.
                let joins = self.in_tip > 1e-9
                    && self
                        .instructions
                        .last()
                        .is_some_and(|last| last["op"] == "liquid_handle");
                self.in_tip = (self.in_tip - signed).max(0.0);
                match self.instructions.last_mut() {
                    Some(last) if joins => {
                        last["locations"]
                            .as_array_mut()
                            .expect("written so")
                            .push(location);
                    }
                    _ => self.instructions.push(json!({
                        "op": "liquid_handle",
                        "locations": [location],
                        "mode": "air_displacement",
                        "shape": {"rows": 1, "columns": 1, "format": "SBS96"},
                    })),
                }
            }
            "thermocycle" => {
                let text = args.get("profile").cloned().unwrap_or_default();
                let groups =
                    compiler::profile::parse_groups(&text).map_err(|e| ExportError::Step {
                        step: i + 1,
                        reason: e.to_string(),
                    })?;
                let groups: Vec<Value> = groups
                    .iter()
                    .map(|(n, holds)| {
                        json!({"cycles": n, "steps": holds.iter().map(|h| json!({
                            "temperature": units::write(h.celsius, Dimension::Temperature),
                            "duration": units::write(h.seconds, Dimension::Time),
                        })).collect::<Vec<_>>()})
                    })
                    .collect();
                for (reference, items) in self.refs_in(i, on.as_deref().unwrap_or_default())? {
                    let volume = items
                        .iter()
                        .map(|t| self.volumes.get(t).copied().unwrap_or(0.0))
                        .fold(0.0, f64::max);
                    self.instructions.push(json!({
                        "op": "thermocycle",
                        "object": reference,
                        "groups": groups,
                        "volume": units::write(volume, Dimension::Volume),
                    }));
                }
            }
            "spin" | "incubate" => {
                let Some(Ok(programme)) =
                    compiler::primitives::run::programme(&step.primitive, &args, kind.as_deref())
                else {
                    return Err(ExportError::Step {
                        step: i + 1,
                        reason: format!("the `{}`'s programme does not read", step.primitive),
                    });
                };
                let on = on.unwrap_or_default();
                let refs = self.refs_in(i, &on)?;
                for (reference, _) in refs {
                    let instruction = match &programme {
                        labware::run::Programme::Spin { rpm, seconds, .. } => {
                            let radius = kind
                                .as_deref()
                                .and_then(labware::Model::for_kind)
                                .as_ref()
                                .and_then(labware::Model::instrument)
                                .and_then(|m| m.rcf_radius_m())
                                .unwrap_or(0.098);
                            let omega = rpm * std::f64::consts::TAU / 60.0;
                            let g = (omega * omega * radius / STANDARD_G).round();
                            json!({"op": "spin", "object": reference,
                                   "acceleration": units::write(g, Dimension::Acceleration),
                                   "duration": units::write(*seconds, Dimension::Time)})
                        }
                        labware::run::Programme::Incubate {
                            celsius,
                            rpm,
                            seconds,
                        } => {
                            let where_ = WHERE
                                .iter()
                                .min_by(|a, b| {
                                    (a.1 - celsius).abs().total_cmp(&(b.1 - celsius).abs())
                                })
                                .map_or("ambient", |w| w.0);
                            let mut o = json!({"op": "incubate", "object": reference, "where": where_,
                                   "duration": units::write(*seconds, Dimension::Time),
                                   "shaking": *rpm > 0.0,
                                   "target_temperature": units::write(*celsius, Dimension::Temperature)});
                            if *rpm > 0.0 {
                                o["shaking_params"] =
                                    json!({"frequency": units::write(*rpm, Dimension::Speed)});
                            }
                            o
                        }
                        labware::run::Programme::Thermocycle { .. } => continue,
                    };
                    self.instructions.push(instruction);
                }
            }
            "external" => match args
                .get("instruction")
                .and_then(|t| serde_json::from_str::<Value>(t).ok())
                .filter(|v| v.get("op").is_some())
            {
                // An instrument-only step imported from Autoprotocol: its instruction as it was.
                Some(instruction) => self.instructions.push(instruction),
                None => self.notes.push(format!(
                    "instrument-only step {} (`{}`) not written: it carries no Autoprotocol instruction",
                    i + 1,
                    args.get("what").map_or("", String::as_str)
                )),
            },
            "place" => {
                if let (Some(on), Some(to)) = (on, args.get("to")) {
                    let place = to
                        .split_once('.')
                        .map(|(h, s)| (h.to_string(), s.to_string()));
                    self.place.insert(on, place);
                }
                *self.dropped.entry("place".into()).or_default() += 1;
            }
            "pick" | "hand_over" => {
                if let Some(on) = on {
                    self.place.insert(on, None);
                }
                *self.dropped.entry(step.primitive.clone()).or_default() += 1;
            }
            other => {
                *self.dropped.entry(other.to_string()).or_default() += 1;
            }
        }
        Ok(())
    }

    /// The instructions plan step `i` wrote (a draw's liquid handling is written at the draw).
    fn written_by(&self, i: usize) -> std::ops::Range<usize> {
        let end = self
            .first_at_step
            .get(i + 1)
            .copied()
            .unwrap_or(self.instructions.len());
        self.first_at_step[i]..end
    }

    /// Plan step `i` as a point in time of the document: the end of the instructions it wrote
    /// (as the `earlier` step of a constraint) or their start; for a step that wrote none (a lid shut before a run, opened after it), the
    /// start of the nearest instruction written after it or the end of the nearest written
    /// before it (the later on a tie), as an import realises an instruction's start and end.
    fn point(&self, i: usize, earlier: bool) -> Option<Value> {
        let wrote = self.written_by(i);
        if !wrote.is_empty() {
            return Some(if earlier {
                json!({"instruction_end": wrote.end - 1})
            } else {
                json!({"instruction_start": wrote.start})
            });
        }
        let steps = self.first_at_step.len();
        let before = (0..i).rev().find(|p| !self.written_by(*p).is_empty());
        let after = (i + 1..steps).find(|q| !self.written_by(*q).is_empty());
        match (before, after) {
            (Some(p), Some(q)) if i - p < q - i => {
                Some(json!({"instruction_end": self.written_by(p).end - 1}))
            }
            (_, Some(q)) => Some(json!({"instruction_start": self.written_by(q).start})),
            (Some(p), None) => Some(json!({"instruction_end": self.written_by(p).end - 1})),
            (None, None) => None,
        }
    }

    /// The task's step timing (`within`, `after`) as constraints between the instructions the
    /// two steps stand for ([`Self::point`]): from the earlier's end, to the later's start.
    fn constraints(&mut self, steps: &[&PlannedStep]) -> Vec<Value> {
        let outcome = |s: &PlannedStep| -> Option<String> {
            let template = compiler::primitives::primitive(&s.primitive)?.outcome?;
            let mut text = template.replace("{with}", &s.robot);
            for (k, v) in &s.args {
                text = text.replace(&format!("{{{k}}}"), v);
            }
            Some((self.fill)(&text))
        };
        let outcomes: Vec<Option<String>> = steps.iter().map(|s| outcome(s)).collect();
        let mut out = Vec::new();
        for stage in &self.task.stages {
            for p in &stage.success {
                let Some(since) = &p.since else { continue };
                let later = (self.fill)(p.text.split(" within ").next().unwrap_or_default());
                let earlier = (self.fill)(&since.text);
                // The latest earlier step with a later one after it (two runs on one
                // instrument have one outcome text).
                let found = (0..outcomes.len()).rev().find_map(|a| {
                    if outcomes[a].as_deref() != Some(earlier.as_str()) {
                        return None;
                    }
                    (a + 1..outcomes.len())
                        .find(|b| outcomes[*b].as_deref() == Some(later.as_str()))
                        .map(|b| (a, b))
                });
                let (a, b) = (found.map(|f| f.0), found.map(|f| f.1));
                let (Some(a), Some(b)) = (a, b) else {
                    self.notes.push(format!(
                        "step timing `{}` not written: its steps were not found",
                        (self.fill)(&p.text)
                    ));
                    continue;
                };
                let (Some(from), Some(to)) = (self.point(a, true), self.point(b, false)) else {
                    self.notes.push(format!(
                        "step timing `{}` not written: the protocol writes no lab instruction",
                        (self.fill)(&p.text)
                    ));
                    continue;
                };
                out.push(json!({
                    "from": from,
                    "to": to,
                    "less_than": units::write(since.within_s, Dimension::Time),
                }));
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::well_index;

    #[test]
    fn wells_count_along_rows() {
        assert_eq!(well_index("A1"), Some(0));
        assert_eq!(well_index("B3"), Some(14));
        assert_eq!(well_index("H12"), Some(95));
        assert_eq!(well_index("I1"), None);
        assert_eq!(well_index("A13"), None);
    }
}
