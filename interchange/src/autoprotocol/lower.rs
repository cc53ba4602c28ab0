//! An Autoprotocol document lowered into the commands the bench realisation reads
//! (`opentrons::realise`): its containers as labware loads (a `96-pcr` plate as a PCR plate, on
//! the thermocycler when a `thermocycle` runs it; each `micro-1.5` tube as a well of one 24-tube
//! rack, named after its ref), `provision` as liquid loads, `liquid_handle` and the legacy
//! `pipette` as aspirates and dispenses of one single-channel pipette, `thermocycle` as the
//! cycler's lid shut, its profile and the lid opened. Every lowered command keeps its place in
//! the source (`instructions[3] liquid_handle`, and the transport's key path), so a finding the
//! realisation makes points into the Autoprotocol file.
//!
//! Decided here (docs/import.md): mixing in place (a draw and an expel of one volume at one
//! location, one after the other) and air (`liquid_class = "air"`) are dropped, since our dispense
//! blows out and the bookkeeping is unchanged; `seal`, `unseal`, `cover` and `uncover` are dropped
//! (the cycler's heated lid closes over its tubes; a tube stands open); `spin`, `incubate` and
//! the instruments we have no model of are refused with the instruction's index and op (kept as
//! instrument-only steps, `external`, on request).

use super::spec::{CycleGroup, LiquidHandle, Pipette, Provision, Ref, Thermocycle, WellVolume};
use super::units::{self, Dimension};
use crate::Finding;
use crate::json_span::Key;
use crate::opentrons::source::{Command, Flavour, LiquidInfo, Source};
use dsl::Code;
use serde_json::{Value, json};
use std::collections::BTreeMap;

/// The container types realised, by what they become.
const PLATES: [&str; 2] = ["96-pcr", "96-pcr-fs-clear"];
const TUBES: [&str; 1] = ["micro-1.5"];
/// The published definitions they load as (the realisation's holders).
const PLATE_LOAD: (&str, u32) = ("biorad_96_wellplate_200ul_pcr", 2);
const RACK_LOAD: (&str, u32) = ("opentrons_24_tuberack_eppendorf_1.5ml_safelock_snapcap", 1);
/// The rack's places for tubes, in the order tubes fill them.
const RACK_ROWS: [char; 4] = ['A', 'B', 'C', 'D'];
const RACK_COLS: u32 = 6;

/// The ops known by name, with what becomes of them when not realised.
const DROPPED_OPS: [(&str, &str); 4] = [
    ("seal", SEALS),
    ("unseal", SEALS),
    ("cover", SEALS),
    ("uncover", SEALS),
];
const SEALS: &str = "a seal or lid on a container has no item here: the cycler's heated lid closes over its tubes, and tubes stand open";
const NOT_YET: [(&str, &str); 2] = [
    (
        "spin",
        "the tubes would be carried to a centrifuge, capped and balanced: write the steps in our language (protocols/lab/spin.toml)",
    ),
    (
        "incubate",
        "the container would be carried to an incubator or thermal mixer and capped: write the steps in our language (protocols/lab/incubation_series.toml)",
    ),
];
const NO_MODEL: [&str; 26] = [
    "absorbance",
    "fluorescence",
    "luminescence",
    "gel_separate",
    "gel_purify",
    "magnetic_transfer",
    "acoustic_transfer",
    "dispense",
    "image_plate",
    "image",
    "flow_analyze",
    "flow_cytometry",
    "sanger_sequence",
    "oligosynthesize",
    "measure_volume",
    "measure_mass",
    "measure_concentration",
    "spread",
    "autopick",
    "stamp",
    "agitate",
    "evaporate",
    "flash_freeze",
    "spectrophotometry",
    "count_cells",
    "mag_dry",
];

/// What a ref is here.
#[derive(Clone, Debug)]
enum Container {
    /// A PCR plate (its labware id is the ref's name).
    Plate,
    /// A tube: the rack's well it stands in.
    Tube(String),
}

/// The lowered document: the commands, and what the time constraints need.
pub struct Lowered {
    pub source: Source,
    /// The time constraints as the file has them.
    pub constraints: Vec<super::spec::TimeConstraint>,
    /// The instructions that use each ref, in order (a constraint's `ref_start` and `ref_end`).
    pub uses: BTreeMap<String, Vec<usize>>,
    /// How many instructions the file has.
    pub instructions: usize,
}

/// Whether a parsed document is Autoprotocol (`refs` and `instructions`).
pub fn is_autoprotocol(doc: &Value) -> bool {
    doc.get("refs").is_some() && doc.get("instructions").is_some()
}

struct Lowering {
    commands: Vec<Command>,
    findings: Vec<Finding>,
    containers: BTreeMap<String, Container>,
    /// Our item names, by ref.
    names: BTreeMap<String, String>,
    liquids: BTreeMap<String, LiquidInfo>,
    tube_names: BTreeMap<(String, String), String>,
    rack: Option<String>,
    pipette_loaded: bool,
    dropped: BTreeMap<String, (usize, String, usize)>,
    uses: BTreeMap<String, Vec<usize>>,
    /// Refs refused (their error stands; their uses are not reported again).
    refused: std::collections::BTreeSet<String>,
    /// Instructions with no realisation kept as instrument-only steps.
    keep: bool,
    /// The ref the cycler holds (the first thermocycle's).
    cycled: Option<String>,
}

/// The rack's labware id (no ref can have it: refs are keyed by their own names).
const RACK_ID: &str = "\u{0}rack";
const CYCLER_ID: &str = "\u{0}cycler";
const PIPETTE_ID: &str = "\u{0}pipette";

/// Lowers a document, or says why it cannot be read at all.
pub fn lower(doc: &Value, options: &crate::Options) -> (Option<Lowered>, Vec<Finding>) {
    let mut l = Lowering {
        commands: Vec::new(),
        findings: Vec::new(),
        containers: BTreeMap::new(),
        names: BTreeMap::new(),
        liquids: BTreeMap::new(),
        tube_names: BTreeMap::new(),
        rack: None,
        pipette_loaded: false,
        dropped: BTreeMap::new(),
        uses: BTreeMap::new(),
        refused: Default::default(),
        keep: options.keep_instrument_steps,
        cycled: None,
    };
    let Some(refs) = doc.get("refs").and_then(Value::as_object) else {
        l.error(
            Code::E0040,
            vec![Key::field("refs")],
            "`refs` is not an object of containers by name".into(),
            "refs map each container's name to `{\"new\": \"96-pcr\", \"discard\": true}` or `{\"id\": ...}`",
        );
        return (None, l.findings);
    };
    let Some(instructions) = doc.get("instructions").and_then(Value::as_array) else {
        l.error(
            Code::E0040,
            vec![Key::field("instructions")],
            "`instructions` is not a list".into(),
            "instructions are a list of objects, each with its `op`",
        );
        return (None, l.findings);
    };
    let constraints = match doc.get("time_constraints") {
        None | Some(Value::Null) => Vec::new(),
        Some(v) => match serde_json::from_value::<Vec<super::spec::TimeConstraint>>(v.clone()) {
            Ok(c) => c,
            Err(e) => {
                l.error(
                    Code::E0040,
                    vec![Key::field("time_constraints")],
                    format!("`time_constraints` cannot be read: {e}"),
                    "each constraint has `from` and `to` (one of `instruction_start`, `instruction_end`, `ref_start`, `ref_end`) and `less_than`, `more_than` or `ideal`",
                );
                return (None, l.findings);
            }
        },
    };
    // Which plate the (first) thermocycle runs: it stands in the cycler's block from the start.
    let cycled = instructions.iter().find_map(|i| {
        (i.get("op").and_then(Value::as_str) == Some("thermocycle"))
            .then(|| i.get("object").and_then(Value::as_str))
            .flatten()
            .map(str::to_string)
    });
    let robots: Vec<String> = if options.robots.is_empty() {
        vec!["left".into(), "arm".into()]
    } else {
        options.robots.iter().map(|(n, _)| n.clone()).collect()
    };
    l.refs(refs, cycled.as_deref(), &robots);
    l.cycled = cycled;
    for (index, instruction) in instructions.iter().enumerate() {
        l.instruction(index, instruction);
    }
    for (op, (index, why, n)) in std::mem::take(&mut l.dropped) {
        l.findings.push(Finding {
            code: Code::W0011,
            at: vec![Key::field("instructions"), Key::Index(index)],
            message: format!("{n} `{op}` dropped: {why}"),
            hint: None,
        });
    }
    let source = Source {
        flavour: Flavour::Autoprotocol,
        robot_type: "refs and instructions".into(),
        commands: l.commands,
        liquids: l.liquids,
        definitions: BTreeMap::new(),
        tube_names: l.tube_names,
    };
    (
        Some(Lowered {
            source,
            constraints,
            uses: l.uses,
            instructions: instructions.len(),
        }),
        l.findings,
    )
}

/// An item name from a ref's: letters, digits and `_`, starting with a letter.
fn item_name(name: &str) -> String {
    let mut out: String = name
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    if !out.starts_with(|c: char| c.is_ascii_alphabetic()) {
        out.insert_str(0, "ref_");
    }
    out.truncate(60);
    out
}

/// A 96-well plate's well as written in an aliquot (a 0-based index along the rows, or a name
/// such as `b3`) by its name (`B3`); none for a well the plate does not have.
fn plate_well(well: &str) -> Option<String> {
    match well.parse::<usize>() {
        Ok(i) if i < 96 => Some(format!("{}{}", (b'A' + (i / 12) as u8) as char, i % 12 + 1)),
        Ok(_) => None,
        Err(_) => {
            let upper = well.to_ascii_uppercase();
            let mut c = upper.chars();
            let row = c.next().filter(|r| ('A'..='H').contains(r));
            let col: Option<u32> = c.as_str().parse().ok().filter(|c| (1..=12).contains(c));
            row.zip(col).map(|(r, c)| format!("{r}{c}"))
        }
    }
}

/// Whether `item` is the name a well of plate `plate` gets (`<plate>_<well>`).
fn names_a_well_of(item: &str, plate: &str) -> bool {
    item.strip_prefix(plate)
        .and_then(|rest| rest.strip_prefix('_'))
        .is_some_and(|well| {
            let mut c = well.chars();
            c.next().is_some_and(|r| ('a'..='h').contains(&r))
                && c.as_str()
                    .parse::<u32>()
                    .is_ok_and(|n| (1..=12).contains(&n))
        })
}

impl Lowering {
    fn error(&mut self, code: Code, at: Vec<Key>, message: String, hint: &str) {
        self.findings.push(Finding {
            code,
            at,
            message,
            hint: Some(hint.to_string()),
        });
    }

    fn drop(&mut self, op: &str, index: usize, why: &str) {
        let e = self
            .dropped
            .entry(op.to_string())
            .or_insert((index, why.to_string(), 0));
        e.2 += 1;
    }

    fn push(
        &mut self,
        command_type: &str,
        params: Value,
        at: Vec<Key>,
        label: String,
        name_hint: Option<String>,
    ) {
        let index = self.commands.len();
        self.commands.push(Command {
            index,
            command_type: command_type.into(),
            params,
            result: Value::Null,
            failed: false,
            origin: Some((at, label)),
            name_hint,
        });
    }

    /// Every ref: what it is, its item name, and its load.
    fn refs(
        &mut self,
        refs: &serde_json::Map<String, Value>,
        cycled: Option<&str>,
        robots: &[String],
    ) {
        // Names an item may not take: the robots', the cycler's, the pipette's.
        let mut taken: Vec<String> = robots.to_vec();
        taken.extend(["cycler".to_string(), "pipette".to_string()]);
        let mut tubes = Vec::new();
        let mut plates = Vec::new();
        for (name, value) in refs {
            let at = vec![Key::field("refs"), Key::field(name)];
            // Refused until it is realised below.
            self.refused.insert(name.clone());
            let r: Ref = match serde_json::from_value(value.clone()) {
                Ok(r) => r,
                Err(e) => {
                    self.error(
                        Code::E0040,
                        at,
                        format!("ref `{name}` cannot be read: {e}"),
                        "a ref is `{\"new\": \"<container type>\", \"discard\": true}` or `{\"id\": \"<container id>\", \"store\": {\"where\": \"cold_4\"}}`",
                    );
                    continue;
                }
            };
            if r.id.is_some() && r.new.is_some() {
                self.error(
                    Code::E0041,
                    at,
                    format!("ref `{name}` has both `id` and `new`"),
                    "a ref is a new container of a type or an existing one by id, not both",
                );
                continue;
            }
            let Some(kind) = r.new.clone().or(r.container_type.clone()) else {
                self.error(
                    Code::E0043,
                    at,
                    format!("ref `{name}` is an existing container (`id`) of no stated type"),
                    "add its type (`\"type\": \"96-pcr\"`, as autoprotocol-python's manifests write it), or make it `new`",
                );
                continue;
            };
            let mut item = item_name(name);
            while taken.contains(&item) {
                item.push('_');
            }
            taken.push(item.clone());
            if PLATES.contains(&kind.as_str()) {
                self.refused.remove(name);
                plates.push((name.clone(), item));
            } else if TUBES.contains(&kind.as_str()) {
                self.refused.remove(name);
                tubes.push((name.clone(), item));
            } else {
                self.error(
                    Code::E0043,
                    at,
                    format!("ref `{name}`: container type `{kind}` has no kind here"),
                    &format!(
                        "the types realised are {} (PCR tubes in a block or the cycler) and {} (a 1.5 mL tube in a rack)",
                        PLATES.join(", "),
                        TUBES.join(", ")
                    ),
                );
            }
        }
        // A tube's name is not one a plate's well gets; tubes fill the rack in their names'
        // order (what an export writes them back under).
        for (_, tube) in &mut tubes {
            while plates.iter().any(|(_, plate)| names_a_well_of(tube, plate)) {
                tube.push('_');
            }
        }
        tubes.sort_by(|a, b| a.1.cmp(&b.1));
        if let Some(c) = cycled
            && plates.iter().any(|(n, _)| n == c)
        {
            self.push(
                "loadModule",
                json!({"moduleId": CYCLER_ID, "model": "thermocyclerModuleV2", "location": {"slotName": "7"}}),
                vec![Key::field("instructions")],
                "the thermocycle's cycler".into(),
                None,
            );
        }
        if !tubes.is_empty() {
            let capacity = RACK_ROWS.len() * RACK_COLS as usize;
            if tubes.len() > capacity {
                let (name, _) = &tubes[capacity];
                self.error(
                    Code::E0042,
                    vec![Key::field("refs"), Key::field(name)],
                    format!(
                        "{} micro-1.5 tubes, more than the one rack's {capacity} places",
                        tubes.len()
                    ),
                    "use at most 24 tubes",
                );
                for (name, _) in tubes.drain(capacity..) {
                    self.refused.insert(name);
                }
            }
            let mut rack = "tube_rack".to_string();
            while taken.contains(&rack) {
                rack.push('_');
            }
            self.push(
                "loadLabware",
                json!({"labwareId": RACK_ID, "loadName": RACK_LOAD.0, "namespace": "opentrons",
                       "version": RACK_LOAD.1, "location": {"slotName": "1"}}),
                vec![Key::field("refs")],
                "the rack the refs' micro-1.5 tubes stand in".into(),
                Some(rack.clone()),
            );
            self.rack = Some(rack);
            for (i, (name, item)) in tubes.into_iter().enumerate() {
                let well = format!(
                    "{}{}",
                    RACK_ROWS[i / RACK_COLS as usize],
                    i as u32 % RACK_COLS + 1
                );
                self.tube_names
                    .insert((RACK_ID.to_string(), well.clone()), item.clone());
                self.names.insert(name.clone(), item);
                self.containers.insert(name, Container::Tube(well));
            }
        }
        for (name, item) in plates {
            let location = if cycled == Some(name.as_str()) {
                json!({"moduleId": CYCLER_ID})
            } else {
                json!({"slotName": "2"})
            };
            self.push(
                "loadLabware",
                json!({"labwareId": name, "loadName": PLATE_LOAD.0, "namespace": "opentrons",
                       "version": PLATE_LOAD.1, "location": location}),
                vec![Key::field("refs"), Key::field(&name)],
                format!("refs.{name} (a 96-well PCR plate)"),
                Some(item.clone()),
            );
            self.names.insert(name.clone(), item);
            self.containers.insert(name, Container::Plate);
        }
    }

    /// An aliquot (`ref/3`, `ref/A4`) as the labware id and well the realisation knows.
    fn aliquot(&mut self, text: &str, at: &[Key], index: usize) -> Option<(String, String)> {
        let (name, well) = text.rsplit_once('/').unwrap_or((text, "0"));
        let Some(container) = self.containers.get(name).cloned() else {
            if self.refused.contains(name) {
                return None;
            }
            self.error(
                Code::E0041,
                at.to_vec(),
                format!("`{text}` names ref `{name}`, which `refs` does not have"),
                "an aliquot is `<ref>/<well>`, with the ref's name as `refs` has it",
            );
            return None;
        };
        let uses = self.uses.entry(name.to_string()).or_default();
        if uses.last() != Some(&index) {
            uses.push(index);
        }
        match container {
            Container::Tube(rack_well) => {
                if !(well == "0" || well.eq_ignore_ascii_case("A1")) {
                    self.error(
                        Code::E0041,
                        at.to_vec(),
                        format!("`{text}`: a micro-1.5 tube has one well, `0`"),
                        "write the tube's aliquot as `<ref>/0`",
                    );
                    return None;
                }
                Some((RACK_ID.to_string(), rack_well))
            }
            Container::Plate => match plate_well(well) {
                Some(w) => Some((name.to_string(), w)),
                None => {
                    self.error(
                        Code::E0041,
                        at.to_vec(),
                        format!("`{text}`: a 96-pcr plate has wells 0 to 95 (A1 to H12)"),
                        "a well is a 0-based index or a name such as `B3`",
                    );
                    None
                }
            },
        }
    }

    fn quantity(&mut self, text: &str, dim: Dimension, at: &[Key]) -> Option<f64> {
        match units::read(text, dim) {
            Ok(v) => Some(v),
            Err(e) => {
                self.error(
                    Code::E0044,
                    at.to_vec(),
                    e.to_string(),
                    "a quantity is `<number>:<unit>`, e.g. `25:microliter`, `30:second`, `95:celsius`",
                );
                None
            }
        }
    }

    fn typed<T: serde::de::DeserializeOwned>(
        &mut self,
        value: &Value,
        at: &[Key],
        label: &str,
    ) -> Option<T> {
        match serde_json::from_value(value.clone()) {
            Ok(t) => Some(t),
            Err(e) => {
                self.error(
                    Code::E0041,
                    at.to_vec(),
                    format!("{label}: its fields cannot be read: {e}"),
                    "see the instruction in Autoprotocol's specification (autoprotocol.org)",
                );
                None
            }
        }
    }

    fn instruction(&mut self, index: usize, value: &Value) {
        let at = vec![Key::field("instructions"), Key::Index(index)];
        let Some(op) = value.get("op").and_then(Value::as_str) else {
            self.error(
                Code::E0040,
                at,
                format!("instructions[{index}] has no `op`"),
                "every instruction names its operation in `op`",
            );
            return;
        };
        let label = format!("instructions[{index}] {op}");
        match op {
            "provision" => {
                if let Some(p) = self.typed::<Provision>(value, &at, &label) {
                    self.provision(&p, &at, &label, index);
                }
            }
            "liquid_handle" => {
                if let Some(h) = self.typed::<LiquidHandle>(value, &at, &label) {
                    self.liquid_handle(&h, &at, &label, index);
                }
            }
            "pipette" => {
                if let Some(p) = self.typed::<Pipette>(value, &at, &label) {
                    self.pipette(&p, &at, &label, index);
                }
            }
            "thermocycle" => {
                if let Some(t) = self.typed::<Thermocycle>(value, &at, &label) {
                    self.thermocycle(&t, &at, &label, index);
                }
            }
            op => {
                let instrument = NOT_YET.iter().any(|(o, _)| *o == op) || NO_MODEL.contains(&op);
                if let Some((_, why)) = DROPPED_OPS.iter().find(|(o, _)| *o == op) {
                    self.drop(op, index, why);
                } else if instrument && self.keep {
                    self.keep_instruction(op, value, at, label, index);
                } else if let Some((_, hint)) = NOT_YET.iter().find(|(o, _)| *o == op) {
                    self.error(
                        Code::E0042,
                        at,
                        format!("{label} has no realisation yet"),
                        &format!("{hint}; or keep it as an instrument-only step (`--keep-instrument-steps`)"),
                    );
                } else if NO_MODEL.contains(&op) {
                    self.error(
                        Code::E0042,
                        at,
                        format!("{label} has no realisation here: the instrument has no model on our bench"),
                        "remove the instruction, write the protocol's robot steps in our language by hand, or keep it as an instrument-only step (`--keep-instrument-steps`)",
                    );
                } else {
                    let mut at = at;
                    at.push(Key::field("op"));
                    self.error(
                        Code::E0042,
                        at,
                        format!("{label}: `{op}` is an op the importer does not know"),
                        "check the op's spelling against Autoprotocol's specification",
                    );
                }
            }
        }
    }

    /// A ref used by instruction `index` (what a time constraint's `ref_start` and `ref_end`
    /// find).
    fn use_ref(&mut self, name: &str, index: usize) {
        if self.containers.contains_key(name) {
            let uses = self.uses.entry(name.to_string()).or_default();
            if uses.last() != Some(&index) {
                uses.push(index);
            }
        }
    }

    /// A kept instruction's text with its refs under their item names (`ref/3` too), and the
    /// wells it names, so that each has its tube and an export writes its ref.
    fn renamed(&mut self, value: &Value, index: usize, wells: &mut Vec<(String, String)>) -> Value {
        match value {
            Value::String(text) => {
                let (name, well) = text.rsplit_once('/').unwrap_or((text, ""));
                let Some(item) = self.names.get(name).cloned() else {
                    return value.clone();
                };
                self.use_ref(name, index);
                let well_of = match self.containers.get(name) {
                    Some(Container::Tube(rack_well)) => {
                        Some((RACK_ID.to_string(), rack_well.clone()))
                    }
                    Some(Container::Plate) if well.is_empty() => {
                        Some((name.to_string(), "A1".to_string()))
                    }
                    Some(Container::Plate) => plate_well(well).map(|w| (name.to_string(), w)),
                    None => None,
                };
                wells.extend(well_of);
                Value::String(if well.is_empty() {
                    item
                } else {
                    format!("{item}/{well}")
                })
            }
            Value::Array(items) => Value::Array(
                items
                    .iter()
                    .map(|v| self.renamed(v, index, wells))
                    .collect(),
            ),
            Value::Object(map) => Value::Object(
                map.iter()
                    .map(|(k, v)| {
                        (
                            k.clone(),
                            if k == "op" {
                                v.clone()
                            } else {
                                self.renamed(v, index, wells)
                            },
                        )
                    })
                    .collect(),
            ),
            other => other.clone(),
        }
    }

    /// An instruction kept as an instrument-only step: what it does in words, its duration
    /// when it has one, and the instruction itself with its refs under their item names (which
    /// an export writes back).
    fn keep_instruction(
        &mut self,
        op: &str,
        value: &Value,
        at: Vec<Key>,
        label: String,
        index: usize,
    ) {
        let mut wells = Vec::new();
        let instruction = self.renamed(value, index, &mut wells);
        let what = match instruction.get("object").and_then(Value::as_str) {
            Some(object) => format!("{op} {object}"),
            None => op.replace('_', " "),
        };
        let mut params =
            json!({"what": what, "instruction": instruction.to_string(), "wells": wells});
        if let Some(d) = value.get("duration").and_then(Value::as_str) {
            let mut at_d = at.clone();
            at_d.push(Key::field("duration"));
            match self.quantity(d, Dimension::Time, &at_d) {
                Some(seconds) if seconds >= 0.0 => params["seconds"] = json!(seconds),
                Some(seconds) => {
                    self.error(
                        Code::E0044,
                        at_d,
                        format!("{label}: {seconds} s is no time to stand by"),
                        "a duration is 0 s or more",
                    );
                    return;
                }
                None => return,
            }
        }
        self.push("external", params, at, label, None);
    }

    fn provision(&mut self, p: &Provision, at: &[Key], label: &str, index: usize) {
        self.liquids
            .entry(p.resource_id.clone())
            .or_insert_with(|| LiquidInfo {
                display_name: p.resource_id.clone(),
                description: None,
            });
        for (j, to) in p.to.iter().enumerate() {
            let mut here = at.to_vec();
            here.extend([Key::field("to"), Key::Index(j)]);
            let Some((labware, well)) = self.aliquot(&to.well, &here, index) else {
                continue;
            };
            here.push(Key::field("volume"));
            let Some(volume) = self.quantity(&to.volume, Dimension::Volume, &here) else {
                continue;
            };
            self.push(
                "loadLiquid",
                json!({"liquidId": p.resource_id, "labwareId": labware, "volumeByWell": {well: volume}}),
                here,
                label.to_string(),
                None,
            );
        }
    }

    fn pipetting(
        &mut self,
        aspirate: bool,
        aliquot: &str,
        volume: f64,
        at: Vec<Key>,
        label: &str,
        index: usize,
    ) {
        let Some((labware, well)) = self.aliquot(aliquot, &at, index) else {
            return;
        };
        if !self.pipette_loaded {
            self.pipette_loaded = true;
            self.push(
                "loadPipette",
                json!({"pipetteId": PIPETTE_ID, "pipetteName": "single-channel pipette", "mount": "left"}),
                at.clone(),
                label.to_string(),
                None,
            );
        }
        self.push(
            if aspirate { "aspirate" } else { "dispense" },
            json!({"pipetteId": PIPETTE_ID, "labwareId": labware, "wellName": well, "volume": volume}),
            at,
            label.to_string(),
            None,
        );
    }

    fn liquid_handle(&mut self, h: &LiquidHandle, at: &[Key], label: &str, index: usize) {
        if let Some(s) = &h.shape
            && (s.rows, s.columns) != (1, 1)
        {
            let mut here = at.to_vec();
            here.push(Key::field("shape"));
            self.error(
                Code::E0042,
                here,
                format!(
                    "{label}: a {} x {} head: a hand holds a single-channel pipette here",
                    s.rows, s.columns
                ),
                "liquid-handle one well at a time (`shape` 1 x 1)",
            );
            return;
        }
        if let Some(mode) = h.mode.as_deref().filter(|m| *m != "air_displacement") {
            let mut here = at.to_vec();
            here.push(Key::field("mode"));
            self.error(
                Code::E0042,
                here,
                format!("{label}: mode `{mode}`: the hand-held pipette displaces air"),
                "use `air_displacement` (or leave `mode` out)",
            );
            return;
        }
        // What each location gives or takes: the sum of its liquid transports (a prime drawn
        // and returned, mixing cycles and the transfer's own draw or expel net out to the move).
        for (j, loc) in h.locations.iter().enumerate() {
            let mut net = 0.0;
            let (mut drew, mut expelled) = (false, false);
            let mut first: Option<Vec<Key>> = None;
            for (k, t) in loc.transports.iter().enumerate() {
                let Some(volume) = &t.volume else { continue };
                let mut here = at.to_vec();
                here.extend([
                    Key::field("locations"),
                    Key::Index(j),
                    Key::field("transports"),
                    Key::Index(k),
                    Key::field("volume"),
                ]);
                let Some(v) = self.quantity(volume, Dimension::Volume, &here) else {
                    continue;
                };
                let air = t
                    .mode_params
                    .as_ref()
                    .and_then(|m| m.liquid_class.as_deref())
                    == Some("air");
                if air {
                    self.drop(
                        "liquid_handle air",
                        index,
                        "air drawn before or after the liquid (an air gap, a blow-out's air): our dispense blows out",
                    );
                    continue;
                }
                net += v;
                drew |= v < 0.0;
                expelled |= v > 0.0;
                first.get_or_insert(here);
            }
            let Some(mut here) = first else { continue };
            here.truncate(here.len() - 3);
            if drew && expelled {
                self.drop(
                    "liquid_handle mixing",
                    index,
                    "liquid drawn and expelled at one well (mixing, a prime returned): only what the well gives or takes is a step",
                );
            }
            if net.abs() < 1e-9 {
                continue;
            }
            let Some(location) = &loc.location else {
                self.error(
                    Code::E0041,
                    here,
                    format!("{label}: locations[{j}] moves liquid but names no aliquot"),
                    "give the location its `location` (`<ref>/<well>`)",
                );
                continue;
            };
            here.push(Key::field("location"));
            self.pipetting(net < 0.0, location, net.abs(), here, label, index);
        }
    }

    fn pipette(&mut self, p: &Pipette, at: &[Key], label: &str, index: usize) {
        for (g, group) in p.groups.iter().enumerate() {
            let mut here = at.to_vec();
            here.extend([Key::field("groups"), Key::Index(g)]);
            for (t, transfer) in group.transfer.iter().enumerate() {
                let mut at_t = here.clone();
                at_t.extend([Key::field("transfer"), Key::Index(t)]);
                let mut at_v = at_t.clone();
                at_v.push(Key::field("volume"));
                let Some(v) = self.quantity(&transfer.volume, Dimension::Volume, &at_v) else {
                    continue;
                };
                self.pipetting(true, &transfer.from, v, at_t.clone(), label, index);
                self.pipetting(false, &transfer.to, v, at_t, label, index);
            }
            let each = |l: &mut Lowering,
                        from: &str,
                        to: &WellVolume,
                        at_w: Vec<Key>,
                        to_is_dest: bool| {
                let mut at_v = at_w.clone();
                at_v.push(Key::field("volume"));
                if let Some(v) = l.quantity(&to.volume, Dimension::Volume, &at_v) {
                    let (src, dst) = if to_is_dest {
                        (from, to.well.as_str())
                    } else {
                        (to.well.as_str(), from)
                    };
                    l.pipetting(true, src, v, at_w.clone(), label, index);
                    l.pipetting(false, dst, v, at_w, label, index);
                }
            };
            if let Some(d) = &group.distribute {
                for (w, to) in d.to.iter().enumerate() {
                    let mut at_w = here.clone();
                    at_w.extend([Key::field("distribute"), Key::field("to"), Key::Index(w)]);
                    each(self, &d.from, to, at_w, true);
                }
            }
            if let Some(c) = &group.consolidate {
                for (w, from) in c.from.iter().enumerate() {
                    let mut at_w = here.clone();
                    at_w.extend([Key::field("consolidate"), Key::field("from"), Key::Index(w)]);
                    each(self, &c.to, from, at_w, false);
                }
            }
            if !group.mix.is_empty() {
                self.drop(
                    "pipette mix",
                    index,
                    "mixing in place: it leaves the volumes as they were",
                );
            }
        }
    }

    fn thermocycle(&mut self, t: &Thermocycle, at: &[Key], label: &str, index: usize) {
        let mut at_object = at.to_vec();
        at_object.push(Key::field("object"));
        self.use_ref(&t.object, index);
        match self.containers.get(&t.object) {
            Some(Container::Plate) if self.cycled.as_deref() != Some(t.object.as_str()) => {
                self.error(
                    Code::E0042,
                    at_object,
                    format!(
                        "{label}: `{}` is a second plate to thermocycle: the cycler holds `{}` from the start (a plate is not carried here)",
                        t.object,
                        self.cycled.as_deref().unwrap_or_default()
                    ),
                    "thermocycle one plate per protocol",
                );
                return;
            }
            Some(Container::Plate) => {}
            Some(Container::Tube(_)) => {
                self.error(
                    Code::E0042,
                    at_object,
                    format!("{label}: `{}` is a tube: the cycler's block takes PCR tubes (a 96-pcr plate here)", t.object),
                    "thermocycle a 96-pcr plate",
                );
                return;
            }
            None if self.refused.contains(&t.object) => return,
            None => {
                self.error(
                    Code::E0041,
                    at_object,
                    format!("{label}: `{}` is no ref of the file", t.object),
                    "name a ref of `refs`",
                );
                return;
            }
        }
        if t.dyes.is_some() || t.melting.is_some() || t.dataref.is_some() {
            self.drop(
                "thermocycle reads",
                index,
                "a qPCR's reads (dyes, melting, dataref): the cycler here has no optics",
            );
        }
        let mut elements = Vec::new();
        for (g, group) in t.groups.iter().enumerate() {
            let Some(steps) = self.cycle_steps(group, at, g, label) else {
                return;
            };
            if group.cycles == 1 {
                elements.extend(steps);
            } else {
                elements.push(json!({"repetitions": group.cycles, "steps": steps}));
            }
        }
        let lid = |l: &mut Lowering, t: &str| {
            l.push(
                t,
                json!({"moduleId": CYCLER_ID}),
                at.to_vec(),
                label.to_string(),
                None,
            );
        };
        lid(self, "thermocycler/closeLid");
        self.push(
            "thermocycler/runExtendedProfile",
            json!({"moduleId": CYCLER_ID, "profileElements": elements}),
            at.to_vec(),
            label.to_string(),
            None,
        );
        lid(self, "thermocycler/openLid");
    }

    fn cycle_steps(
        &mut self,
        group: &CycleGroup,
        at: &[Key],
        g: usize,
        label: &str,
    ) -> Option<Vec<Value>> {
        let mut out = Vec::new();
        for (s, step) in group.steps.iter().enumerate() {
            let mut here = at.to_vec();
            here.extend([
                Key::field("groups"),
                Key::Index(g),
                Key::field("steps"),
                Key::Index(s),
            ]);
            let Some(temperature) = &step.temperature else {
                self.error(
                    Code::E0042,
                    here,
                    format!("{label}: a gradient step (or one with no temperature): our cycler's block holds one temperature"),
                    "give every step one `temperature`",
                );
                return None;
            };
            let mut at_t = here.clone();
            at_t.push(Key::field("temperature"));
            let celsius = self.quantity(temperature, Dimension::Temperature, &at_t)?;
            let mut at_d = here;
            at_d.push(Key::field("duration"));
            let seconds = self.quantity(&step.duration, Dimension::Time, &at_d)?;
            out.push(json!({"celsius": celsius, "holdSeconds": seconds}));
        }
        Some(out)
    }
}

#[cfg(test)]
mod tests {
    use super::{item_name, names_a_well_of, plate_well};

    #[test]
    fn wells_names_and_reserved_names() {
        assert_eq!(plate_well("0").as_deref(), Some("A1"));
        assert_eq!(plate_well("13").as_deref(), Some("B2"));
        assert_eq!(plate_well("95").as_deref(), Some("H12"));
        assert_eq!(plate_well("b3").as_deref(), Some("B3"));
        assert_eq!(plate_well("96"), None);
        assert_eq!(plate_well("I1"), None);
        assert_eq!(plate_well("A13"), None);
        assert_eq!(item_name("2x-mix"), "ref_2x_mix");
        assert_eq!(item_name("μ tube"), "ref___tube");
        assert_eq!(item_name(&"9".repeat(80)).len(), 60);
        assert!(names_a_well_of("pcr_a1", "pcr") && names_a_well_of("pcr_h12", "pcr"));
        assert!(!names_a_well_of("pcr_mix", "pcr") && !names_a_well_of("pcr_a13", "pcr"));
    }
}
