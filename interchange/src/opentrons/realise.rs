//! An Opentrons run realised on our bench: the deck's labware set on the bench in reach of the
//! robots, the wells the run uses as tubes, its pipette as the hand-held one, its pipetting as
//! `aspirate` and `dispense` steps, its thermocycler as the `thermal_cycler_96` worked by a second
//! arm, and success as what the run leaves in each tube it touched.
//!
//! The decisions, each said where it is made (and in docs/import.md):
//! - **Labware**: a kind whose published definition has the same load name (any version) is that
//!   kind; a 96-well PCR plate is realised as PCR tubes in the 96-well aluminium block (or, on the
//!   thermocycler, in the cycler's block): our bench has no plate body; tip racks and trash are
//!   not items (the pipette's tip is its own). Anything else is refused (E0043).
//! - **Wells**: every well the run loads liquid into or pipettes from or into becomes a tube of the
//!   kind its holder takes, open, named `<holder>_<well>`.
//! - **The pipette**: the first robot holds the one pipette the run pipettes with: the P200
//!   (20-200 µL) or the P1000 (100-1000 µL), set to the one volume every aspirate and dispense
//!   moves (the hand-held pipette has no knob to turn between steps); each aspirate is followed by
//!   its dispense.
//! - **The bench**: the first robot at (0, -0.5), the second (which works the cycler's lid) at
//!   (0, 0.5); holders at fixed places in front of them in the order they are loaded; the cycler
//!   where `lab.pcr` has it. Whether each is in reach is the check's to say (E0036).

use super::commands::{
    self, Fate, LoadLabware, LoadLiquid, LoadModule, LoadPipette, Location, ModuleRef, Pipetting,
    ProfileElement, RunExtendedProfile, RunProfile, WaitForDuration,
};
use super::source::{Command, Source};
use crate::draft::{self, Draft, Item, Robot, Step};
use crate::json_span::Key;
use crate::{Finding, Options};
use dsl::Code;
use labware::definition::{Definition, Installed};
use serde::de::DeserializeOwned;
use std::collections::BTreeMap;

/// The bench's top (m).
const BENCH_TOP: f64 = 0.824;
/// Where holders stand (x, y centre), in the order they are loaded: without a cycler, and with
/// one (which stands at [`CYCLER_AT`]).
const PLACES: [[f64; 2]; 4] = [[0.0, -0.01], [0.0, 0.14], [0.3, -0.3], [0.3, 0.0]];
const PLACES_BESIDE_CYCLER: [[f64; 2]; 3] = [[0.3, -0.3], [0.3, -0.12], [0.35, 0.3]];
const CYCLER_AT: ([f64; 3], f64) = ([-0.05, 0.0, BENCH_TOP], -90.0);
/// The robots' bases: the pipetting arm's and the lid arm's.
const BASES: [[f64; 3]; 2] = [[0.0, -0.5, BENCH_TOP], [0.0, 0.5, BENCH_TOP]];
/// Per-episode offsets of the arms' joints (rad): the pipetting arm's as `lab.pcr_setup`'s, the
/// lid arm's as `lab.pcr_run`'s.
const JITTER: [([f64; 6], [f64; 6]); 2] = [
    (
        [-0.01, 0.0, -0.1, -0.02, 0.0, -0.1],
        [0.01, 0.1, 0.0, 0.02, 0.1, 0.1],
    ),
    (
        [-1.2, -0.2, -0.1, -0.5, -0.2, -0.2],
        [0.0, 0.0, 0.1, 0.2, 0.2, 0.2],
    ),
];
/// The hand-held pipettes by the volumes they set (µL).
const PIPETTES: [(&str, f64, f64); 2] = [("pipette_p200", 20.0, 200.0), ("pipette", 100.0, 1000.0)];
/// Lab time budgets (s): per pipetting step, per lid step, on top of everything.
const PIPETTING_S: f64 = 15.0;
const LID_S: f64 = 30.0;
const SLACK_S: f64 = 60.0;

/// What a loaded labware is here.
#[derive(Clone, Debug)]
enum Holder {
    /// A catalogue holder (a rack, a block) whose places take `tube`.
    Kind {
        kind: &'static str,
        tube: &'static str,
    },
    /// A 96-well PCR plate: PCR tubes in a block (or in the cycler's block).
    Plate,
    /// Not an item: a tip rack, a trash.
    Ignored(&'static str),
}

#[derive(Clone, Debug)]
struct Loaded {
    command: usize,
    name: String,
    holder: Holder,
    /// The cycler module it stands on, when it does.
    on_cycler: Option<String>,
    slot: Option<String>,
}

/// A well used as a tube: its item name, kind and where it stands.
#[derive(Clone, Debug)]
struct Tube {
    name: String,
    kind: &'static str,
    at: String,
    /// µL of each named liquid (the start), then as the run leaves it.
    start: BTreeMap<String, f64>,
    now: BTreeMap<String, f64>,
    touched: bool,
    dispensed_into: bool,
    comment: String,
}

impl Tube {
    fn volume(&self, v: &BTreeMap<String, f64>) -> f64 {
        v.values().sum()
    }
}

/// The protocol's id and instruction.
pub struct Names {
    pub id: String,
    pub instruction: String,
}

struct Walk<'a> {
    src: &'a Source,
    options: &'a Options,
    names: &'a Names,
    findings: Vec<Finding>,
    labware: BTreeMap<String, Loaded>,
    cyclers: BTreeMap<String, String>,
    pipettes: BTreeMap<String, (usize, String)>,
    tubes: BTreeMap<(String, String), Tube>,
    steps: Vec<Step>,
    /// The pipette every pipetting step uses, its set volume and the command that set it.
    pipette: Option<(String, f64, usize)>,
    /// Volume in the tip (µL) by liquid, between an aspirate and its dispense.
    in_tip: Option<(BTreeMap<String, f64>, usize)>,
    pipetted_since_lid: bool,
    lid_state: Option<&'static str>,
    first_lid: Option<&'static str>,
    ran_profile: bool,
    waits_s: f64,
    profile_s: f64,
    dropped: BTreeMap<String, (usize, &'static str, usize)>,
    /// Volumes other than the set one already refused.
    other_volumes: std::collections::BTreeSet<u64>,
    /// Ids whose load was refused: their uses are not reported again (the load's error stands).
    refused: std::collections::BTreeSet<String>,
    /// Our name of each source liquid, by its id.
    liquid_names: BTreeMap<String, String>,
}

/// Realises the run; `None` with errors among the findings when it cannot be.
pub fn realise(src: &Source, options: &Options, names: &Names) -> (Option<Draft>, Vec<Finding>) {
    let mut w = Walk {
        src,
        options,
        names,
        findings: Vec::new(),
        labware: BTreeMap::new(),
        cyclers: BTreeMap::new(),
        pipettes: BTreeMap::new(),
        tubes: BTreeMap::new(),
        steps: Vec::new(),
        pipette: None,
        in_tip: None,
        pipetted_since_lid: false,
        lid_state: None,
        first_lid: None,
        ran_profile: false,
        waits_s: 0.0,
        profile_s: 0.0,
        dropped: BTreeMap::new(),
        other_volumes: Default::default(),
        refused: Default::default(),
        liquid_names: BTreeMap::new(),
    };
    for c in &src.commands {
        if c.failed {
            w.error(
                Code::E0040,
                c.path(),
                format!("{} failed in the analysis", c.label()),
                "import an analysis whose run succeeded (`result` is `ok`)",
            );
            continue;
        }
        match commands::fate(&c.command_type) {
            Fate::Realised => w.command(c),
            Fate::Dropped(why) => {
                let e = w
                    .dropped
                    .entry(c.command_type.clone())
                    .or_insert((c.index, why, 0));
                e.2 += 1;
            }
            Fate::Refused(why, hint) => w.error(
                Code::E0042,
                c.path(),
                format!("{} has no realisation here: {why}", c.label()),
                hint,
            ),
        }
    }
    w.finish()
}

impl Walk<'_> {
    fn error(&mut self, code: Code, at: Vec<Key>, message: String, hint: &str) {
        self.findings.push(Finding {
            code,
            at,
            message,
            hint: Some(hint.to_string()),
        });
    }

    fn errors(&self) -> bool {
        self.findings.iter().any(|f| !f.code.is_warning())
    }

    /// A command's typed parameters, or a finding at its `params`.
    fn params<T: DeserializeOwned>(&mut self, c: &Command) -> Option<T> {
        match serde_json::from_value(c.params.clone()) {
            Ok(p) => Some(p),
            Err(e) => {
                self.error(
                    Code::E0041,
                    c.param_path(""),
                    format!("{}: its parameters cannot be read: {e}", c.label()),
                    "see the command's schema in opentrons-shared-data (command schema 8 and later)",
                );
                None
            }
        }
    }

    /// The id a `load*` command gives: in its params, else in an analysis's result.
    fn load_id(&mut self, c: &Command, given: Option<String>, field: &str) -> Option<String> {
        let id = given.or_else(|| {
            c.result
                .get(field)
                .and_then(|v| v.as_str())
                .map(str::to_string)
        });
        if id.is_none() {
            self.error(
                Code::E0041,
                c.param_path(field),
                format!("{} gives no `{field}`", c.label()),
                "every load command names the id later commands use",
            );
        }
        id
    }

    fn duplicate(&mut self, c: &Command, field: &str, id: &str, first: usize) {
        self.error(
            Code::E0041,
            c.param_path(field),
            format!(
                "{}: `{field}` `{id}` is already the id of commands[{first}]'s",
                c.label()
            ),
            "ids must be unique (an analysis snapshot with every id replaced by `UUID` cannot be imported)",
        );
    }

    fn command(&mut self, c: &Command) {
        match c.command_type.as_str() {
            "loadLabware" => self.load_labware(c),
            "loadModule" => self.load_module(c),
            "loadPipette" => self.load_pipette(c),
            "loadLiquid" => self.load_liquid(c),
            "aspirate" | "dispense" => self.pipetting(c),
            "waitForDuration" => {
                if let Some(p) = self.params::<WaitForDuration>(c) {
                    if !(p.seconds.is_finite() && p.seconds >= 0.0) {
                        self.error(
                            Code::E0044,
                            c.param_path("seconds"),
                            format!("{}: {} s is no time to wait", c.label(), p.seconds),
                            "a wait is zero seconds or more",
                        );
                        return;
                    }
                    self.waits_s += p.seconds;
                    self.steps.push(Step {
                        primitive: "wait".into(),
                        args: vec![("duration".into(), format!("{} s", draft::number(p.seconds)))],
                        with: self.robot(0),
                        from: Some(c.label()),
                    });
                }
            }
            "thermocycler/openLid" | "thermocycler/closeLid" => self.lid(c),
            "thermocycler/runProfile" => {
                if let Some(p) = self.params::<RunProfile>(c) {
                    let elements: Vec<ProfileElement> =
                        p.profile.into_iter().map(ProfileElement::Step).collect();
                    self.profile(c, &p.module_id, &elements);
                }
            }
            "thermocycler/runExtendedProfile" => {
                if let Some(p) = self.params::<RunExtendedProfile>(c) {
                    self.profile(c, &p.module_id, &p.profile_elements);
                }
            }
            other => self.error(
                Code::E0042,
                c.path(),
                format!("{}: `{other}` has no realisation yet", c.label()),
                "remove the command",
            ),
        }
    }

    fn robot(&self, i: usize) -> String {
        self.options
            .robots
            .get(i)
            .map(|(name, _)| name.clone())
            .unwrap_or_else(|| ["left", "arm"][i.min(1)].to_string())
    }

    fn load_labware(&mut self, c: &Command) {
        let Some(p) = self.params::<LoadLabware>(c) else {
            return;
        };
        let Some(id) = self.load_id(c, p.labware_id.clone(), "labwareId") else {
            return;
        };
        if let Some(first) = self.labware.get(&id).map(|l| l.command) {
            self.duplicate(c, "labwareId", &id, first);
            return;
        }
        let holder = self.holder(c, &p);
        let (on_cycler, slot) = match &p.location {
            Location::Slot { slot_name } => (None, Some(slot_name.clone())),
            Location::Module { module_id } => match self.cyclers.get(module_id) {
                Some(_) if matches!(holder, Some(Holder::Kind { .. })) => {
                    self.error(
                        Code::E0042,
                        c.param_path("location"),
                        format!(
                            "{}: `{}` on the thermocycler: only a 96-well PCR plate stands in the cycler's block here",
                            c.label(),
                            p.load_name
                        ),
                        "load a 96-well PCR plate on the thermocycler",
                    );
                    self.refused.insert(id);
                    return;
                }
                Some(_) => (Some(module_id.clone()), None),
                None if self.refused.contains(module_id) => {
                    self.refused.insert(id);
                    return;
                }
                None => {
                    if !matches!(holder, Some(Holder::Ignored(_))) {
                        self.error(
                            Code::E0041,
                            c.param_path("location"),
                            format!(
                                "{}: `{}` stands on module `{module_id}`, which no realised `loadModule` loaded",
                                c.label(),
                                p.load_name
                            ),
                            "load the module before its labware; only the thermocycler is realised",
                        );
                    }
                    (None, None)
                }
            },
            Location::OnLabware { labware_id } => {
                let (code, why) = if *labware_id == id {
                    (
                        Code::E0041,
                        format!("{}: `{}` stands on itself", c.label(), p.load_name),
                    )
                } else if !self.labware.contains_key(labware_id) {
                    (
                        Code::E0041,
                        format!(
                            "{}: `{}` stands on `{labware_id}`, which no earlier `loadLabware` loaded",
                            c.label(),
                            p.load_name
                        ),
                    )
                } else {
                    (
                        Code::E0042,
                        format!(
                            "{}: `{}` stands on other labware (`{labware_id}`): adapters and stacks are not realised",
                            c.label(),
                            p.load_name
                        ),
                    )
                };
                if code == Code::E0041 || !matches!(holder, Some(Holder::Ignored(_))) {
                    self.error(
                        code,
                        c.param_path("location"),
                        why,
                        "load it in a deck slot",
                    );
                }
                self.refused.insert(id);
                return;
            }
            Location::Area { .. } | Location::Named(_) => (None, None),
        };
        let Some(holder) = holder else {
            self.refused.insert(id);
            return;
        };
        let base = match holder {
            Holder::Kind { kind, .. } if kind.starts_with("tuberack") => "rack",
            Holder::Kind { .. } => "block",
            Holder::Plate => "plate",
            Holder::Ignored(_) => "ignored",
        };
        let n = self
            .labware
            .values()
            .filter(|l| l.name.starts_with(base))
            .count();
        let name = if n == 0 {
            base.to_string()
        } else {
            format!("{base}{}", n + 1)
        };
        self.labware.insert(
            id,
            Loaded {
                command: c.index,
                name,
                holder,
                on_cycler,
                slot,
            },
        );
    }

    /// What labware is here, from its load name and its definition (the file's, else the
    /// installed package's).
    fn holder(&mut self, c: &Command, p: &LoadLabware) -> Option<Holder> {
        // A holder made from the same definition (an instrument whose block has the same wells,
        // the `thermal_cycler_96`, is not that labware).
        if let Some(k) = labware::KINDS.iter().find(|k| {
            k.primitives.is_empty()
                && k.definition
                    .and_then(|uri| uri.split('/').nth(1))
                    .is_some_and(|load| load == p.load_name)
        }) {
            let tube = k.slots.and_then(|s| s.accepts.first().copied())?;
            return Some(Holder::Kind { kind: k.name, tube });
        }
        let uri = p.uri();
        let def = self.definition(c, &uri)?;
        if def.parameters.is_tiprack {
            return Some(Holder::Ignored("a tip rack"));
        }
        if def.metadata.display_category == "trash" || p.load_name.contains("trash") {
            return Some(Holder::Ignored("a trash"));
        }
        let pcr_plate = def
            .grid()
            .is_ok_and(|g| g.rows == 8 && g.cols == 12 && (g.col_pitch - 0.009).abs() < 1e-4)
            && def
                .wells
                .values()
                .all(|w| w.depth <= 21.0 && w.total_liquid_volume <= 200.0);
        if pcr_plate {
            return Some(Holder::Plate);
        }
        self.error(
            Code::E0043,
            c.param_path("loadName"),
            format!(
                "{}: `{uri}` ({}, category `{}`) has no kind here",
                c.label(),
                def.metadata.display_name,
                def.metadata.display_category
            ),
            "the kinds made from published definitions are listed by `autobio describe --catalogue`; a 96-well PCR plate is realised as PCR tubes",
        );
        None
    }

    fn definition(&mut self, c: &Command, uri: &str) -> Option<Definition> {
        let from_file = self
            .src
            .definitions
            .get(uri)
            .or_else(|| c.result.get("definition"))
            .map(|v| v.to_string());
        let parsed = match from_file {
            Some(text) => Definition::parse(&text, uri),
            None => Installed::under(&self.options.deps).load(uri),
        };
        match parsed {
            Ok(d) => Some(d),
            Err(e) => {
                self.error(
                    Code::E0043,
                    c.param_path("loadName"),
                    format!("{}: labware `{uri}` cannot be resolved: {e}", c.label()),
                    "a definition must be in the file's `labwareDefinitions` or installed by `make setup` (opentrons-shared-data)",
                );
                None
            }
        }
    }

    fn load_module(&mut self, c: &Command) {
        let Some(p) = self.params::<LoadModule>(c) else {
            return;
        };
        let Some(id) = self.load_id(c, p.module_id.clone(), "moduleId") else {
            return;
        };
        if p.model.starts_with("thermocyclerModule") {
            if !self.cyclers.is_empty() {
                self.error(
                    Code::E0042,
                    c.path(),
                    format!("{}: a second thermocycler", c.label()),
                    "our bench has one cycler per protocol",
                );
                return;
            }
            self.cyclers.insert(id, "cycler".into());
        } else {
            self.refused.insert(id);
            self.error(
                Code::E0042,
                c.param_path("model"),
                format!(
                    "{}: module `{}` has no realisation here: {}",
                    c.label(),
                    p.model,
                    "the thermocycler is the one module our bench has"
                ),
                "remove the module and its steps, or write them in our language by hand",
            );
        }
    }

    fn load_pipette(&mut self, c: &Command) {
        let Some(p) = self.params::<LoadPipette>(c) else {
            return;
        };
        let Some(id) = self.load_id(c, p.pipette_id.clone(), "pipetteId") else {
            return;
        };
        if let Some((first, _)) = self.pipettes.get(&id) {
            let first = *first;
            self.duplicate(c, "pipetteId", &id, first);
            return;
        }
        self.pipettes.insert(id, (c.index, p.pipette_name));
    }

    fn tube_kind_name(&self, lw: &Loaded) -> Option<(String, &'static str, String)> {
        match &lw.holder {
            Holder::Kind { tube, .. } => Some((lw.name.clone(), tube, lw.name.clone())),
            Holder::Plate => {
                let holder = match &lw.on_cycler {
                    Some(m) => self.cyclers[m].clone(),
                    None => lw.name.clone(),
                };
                Some((lw.name.clone(), "tube_0_2ml", holder))
            }
            Holder::Ignored(_) => None,
        }
    }

    /// The tube a well is, made on first use.
    fn tube(&mut self, c: &Command, labware_id: &str, well: &str) -> Option<(String, String)> {
        let Some(lw) = self.labware.get(labware_id).cloned() else {
            if self.refused.contains(labware_id) {
                return None;
            }
            self.error(
                Code::E0041,
                c.param_path("labwareId"),
                format!("{}: labware `{labware_id}` was never loaded", c.label()),
                "a `loadLabware` must load it before it is used",
            );
            return None;
        };
        let Some((base, kind, holder)) = self.tube_kind_name(&lw) else {
            if let Holder::Ignored(what) = lw.holder {
                self.error(
                    Code::E0042,
                    c.param_path("labwareId"),
                    format!("{}: uses {what}, which is not an item here", c.label()),
                    "pipette from and into tubes, racks, blocks or PCR plates",
                );
            }
            return None;
        };
        let slots = if lw.on_cycler.is_some() {
            labware::kind("thermal_cycler_96")
        } else {
            match lw.holder {
                Holder::Kind { kind, .. } => labware::kind(kind),
                _ => labware::kind("aluminium_block_96_pcr"),
            }
        }
        .and_then(|k| k.slots);
        if !slots.is_some_and(|s| s.layout.names().iter().any(|n| n == well)) {
            self.error(
                Code::E0041,
                c.param_path("wellName"),
                format!("{}: `{}` has no well `{well}`", c.label(), lw.name),
                "wells are named as the labware's definition names them (`A1`)",
            );
            return None;
        }
        let key = (labware_id.to_string(), well.to_string());
        let name = format!("{base}_{}", well.to_ascii_lowercase());
        self.tubes.entry(key).or_insert_with(|| Tube {
            name: name.clone(),
            kind,
            at: format!("{holder}.{well}"),
            start: BTreeMap::new(),
            now: BTreeMap::new(),
            touched: false,
            dispensed_into: false,
            comment: format!("well {well} of commands[{}]'s labware", lw.command),
        });
        Some((labware_id.to_string(), well.to_string()))
    }

    fn load_liquid(&mut self, c: &Command) {
        let Some(p) = self.params::<LoadLiquid>(c) else {
            return;
        };
        let Some(info) = self.src.liquids.get(&p.liquid_id) else {
            self.error(
                Code::E0041,
                c.param_path("liquidId"),
                format!(
                    "{}: liquid `{}` is not among the file's liquids",
                    c.label(),
                    p.liquid_id
                ),
                "declare it under `liquids`",
            );
            return;
        };
        let liquid = self.liquid(&info.display_name, &p.liquid_id);
        for (well, volume) in &p.volume_by_well {
            let Some(key) = self.tube(c, &p.labware_id, well) else {
                continue;
            };
            let capacity = labware::kind(self.tubes[&key].kind)
                .and_then(|k| k.capacity_ul)
                .unwrap_or(0.0);
            let before = self.tubes[&key].volume(&self.tubes[&key].start);
            if !(volume.is_finite() && *volume >= 0.0 && before + *volume <= capacity) {
                let mut at = c.param_path("volumeByWell");
                at.push(Key::field(well));
                self.error(
                    Code::E0044,
                    at,
                    format!(
                        "{}: {volume} µL in well `{well}`, whose tube here (`{}`) holds {} µL",
                        c.label(),
                        self.tubes[&key].kind,
                        draft::number(capacity)
                    ),
                    "a well starts with 0 µL up to what its tube holds",
                );
                continue;
            }
            let t = self.tubes.get_mut(&key).expect("made above");
            if t.start.keys().any(|l| *l != liquid) {
                let mut at = c.param_path("volumeByWell");
                at.push(Key::field(well));
                self.error(
                    Code::E0042,
                    at,
                    format!("{}: a second liquid loaded into well `{well}`", c.label()),
                    "a tube here starts with one named liquid",
                );
                continue;
            }
            *t.start.entry(liquid.clone()).or_default() += volume;
            *t.now.entry(liquid.clone()).or_default() += volume;
        }
    }

    /// A liquid's name in our language, one per source liquid: a name two liquids would share gets
    /// the second one's id appended.
    fn liquid(&mut self, display: &str, id: &str) -> String {
        if let Some(name) = self.liquid_names.get(id) {
            return name.clone();
        }
        let mut name = liquid_name(display, id);
        if self.liquid_names.values().any(|n| *n == name) {
            let suffix: String = id.chars().filter(|c| c.is_ascii_alphanumeric()).collect();
            name = format!(
                "{}_{}",
                &name[..name.len().min(30)],
                suffix.chars().take(8).collect::<String>()
            );
            let mut n = 2;
            while self.liquid_names.values().any(|x| *x == name) {
                name = format!("{}_{n}", &name[..name.len().min(36)]);
                n += 1;
            }
        }
        self.liquid_names.insert(id.to_string(), name.clone());
        name
    }

    fn pipetting(&mut self, c: &Command) {
        let Some(p) = self.params::<Pipetting>(c) else {
            return;
        };
        let Some((_, name)) = self.pipettes.get(&p.pipette_id).cloned() else {
            self.error(
                Code::E0041,
                c.param_path("pipetteId"),
                format!("{}: pipette `{}` was never loaded", c.label(), p.pipette_id),
                "a `loadPipette` must load it first",
            );
            return;
        };
        if name.contains("multi") || name.contains("_96") {
            self.error(
                Code::E0042,
                c.param_path("pipetteId"),
                format!("{}: `{name}` is a multi-channel pipette", c.label()),
                "a hand holds a single-channel pipette here: use a single-channel one",
            );
            return;
        }
        if !(p.volume.is_finite() && p.volume > 0.0) {
            self.error(
                Code::E0044,
                c.param_path("volume"),
                format!("{}: {} µL is no volume to move", c.label(), p.volume),
                "a volume is a positive number of microlitres",
            );
            return;
        }
        match &self.pipette {
            None if !PIPETTES
                .iter()
                .any(|(_, lo, hi)| (lo..=hi).contains(&&p.volume)) =>
            {
                self.error(
                    Code::E0044,
                    c.param_path("volume"),
                    format!(
                        "{}: {} µL, which no hand-held pipette here sets",
                        c.label(),
                        draft::number(p.volume)
                    ),
                    "the P200 sets 20-200 µL, the P1000 100-1000 µL",
                );
                return;
            }
            None => self.pipette = Some((p.pipette_id.clone(), p.volume, c.index)),
            Some((id, _, first)) if *id != p.pipette_id => {
                let first = *first;
                self.error(
                    Code::E0042,
                    c.param_path("pipetteId"),
                    format!(
                        "{}: a second pipette (commands[{first}] pipetted with another)",
                        c.label()
                    ),
                    "one hand-held pipette per protocol here",
                );
                return;
            }
            Some((_, set, first)) if (*set - p.volume).abs() > 1e-9 => {
                let (set, first) = (*set, *first);
                // Each other volume is said once, at its first command.
                if !self.other_volumes.insert(p.volume.to_bits()) {
                    return;
                }
                self.error(
                    Code::E0042,
                    c.param_path("volume"),
                    format!(
                        "{}: {} µL, but the pipette is set to {} µL (commands[{first}])",
                        c.label(),
                        draft::number(p.volume),
                        draft::number(set)
                    ),
                    "the hand-held pipette has no knob: every aspirate and dispense moves the one volume it is set to",
                );
                return;
            }
            _ => {}
        }
        let aspirate = c.command_type == "aspirate";
        let Some(key) = self.tube(c, &p.labware_id, &p.well_name) else {
            // What was refused is said at its load; the tip's contents go on as the run has them.
            self.in_tip = aspirate.then(|| (BTreeMap::new(), c.index));
            return;
        };
        match (&self.in_tip, aspirate) {
            (Some((_, at)), true) => {
                let at = *at;
                self.error(
                    Code::E0042,
                    c.path(),
                    format!(
                        "{}: a second aspirate before commands[{at}]'s is dispensed",
                        c.label()
                    ),
                    "each aspirate is followed by its dispense here (no multi-dispense)",
                );
                return;
            }
            (None, false) => {
                self.error(
                    Code::E0042,
                    c.path(),
                    format!("{}: a dispense with nothing aspirated", c.label()),
                    "aspirate the volume first",
                );
                return;
            }
            _ => {}
        }
        let t = self.tubes.get_mut(&key).expect("made by tube()");
        t.touched = true;
        if aspirate {
            let have = t.volume(&t.now);
            if have + 1e-6 < p.volume {
                let msg = format!(
                    "{}: {} µL from well `{}`, which holds {} µL then",
                    c.label(),
                    draft::number(p.volume),
                    p.well_name,
                    draft::number(have)
                );
                self.in_tip = Some((BTreeMap::new(), c.index));
                self.error(
                    Code::E0044,
                    c.param_path("volume"),
                    msg,
                    "a well is drawn from only what a `loadLiquid` put there (or a dispense since)",
                );
                return;
            }
            let share: BTreeMap<String, f64> = t
                .now
                .iter()
                .map(|(l, v)| {
                    (
                        l.clone(),
                        if have > 0.0 { v * p.volume / have } else { 0.0 },
                    )
                })
                .collect();
            for (l, v) in &share {
                *t.now.get_mut(l).expect("present") -= v;
            }
            self.in_tip = Some((share, c.index));
        } else {
            let (tip, _) = self.in_tip.take().expect("checked above");
            for (l, v) in tip {
                *t.now.entry(l).or_default() += v;
            }
            t.dispensed_into = true;
        }
        let (item, primitive) = (t.name.clone(), c.command_type.clone());
        self.pipetted_since_lid = true;
        self.steps.push(Step {
            primitive,
            args: vec![
                ("on".into(), item),
                ("volume".into(), format!("{} µL", draft::number(p.volume))),
            ],
            with: self.robot(0),
            from: Some(c.label()),
        });
    }

    fn cycler(&mut self, c: &Command, module_id: &str) -> Option<String> {
        let name = self.cyclers.get(module_id).cloned();
        if name.is_none() && !self.refused.contains(module_id) {
            self.error(
                Code::E0041,
                c.param_path("moduleId"),
                format!(
                    "{}: module `{module_id}` is no loaded thermocycler",
                    c.label()
                ),
                "a `loadModule` of a thermocycler must load it first",
            );
        }
        name
    }

    fn lid(&mut self, c: &Command) {
        let Some(p) = self.params::<ModuleRef>(c) else {
            return;
        };
        let Some(cycler) = self.cycler(c, &p.module_id) else {
            return;
        };
        let close = c.command_type.ends_with("closeLid");
        let state = if close { "closed" } else { "open" };
        if self.first_lid.is_none() {
            self.first_lid = Some(if close { "open" } else { "closed" });
        }
        if self.lid_state == Some(state) {
            return;
        }
        if close && self.pipetted_since_lid {
            // The pipetting arm stands back first: the lid swings over where it worked.
            self.steps.push(Step {
                primitive: "retract".into(),
                args: vec![],
                with: self.robot(0),
                from: Some(format!(
                    "before {}: the pipetting arm out of the lid's way",
                    c.label()
                )),
            });
        }
        self.pipetted_since_lid = false;
        self.lid_state = Some(state);
        self.steps.push(Step {
            primitive: if close { "close_lid" } else { "open_lid" }.into(),
            args: vec![("on".into(), cycler)],
            with: self.robot(1),
            from: Some(c.label()),
        });
    }

    fn profile(&mut self, c: &Command, module_id: &str, elements: &[ProfileElement]) {
        let Some(cycler) = self.cycler(c, module_id) else {
            return;
        };
        if self.ran_profile {
            self.error(
                Code::E0042,
                c.path(),
                format!("{}: a second profile on the cycler", c.label()),
                "our cycler runs one profile per protocol: put every hold and cycle in one",
            );
            return;
        }
        let mut bad = None;
        for e in elements {
            let (steps, repetitions) = match e {
                ProfileElement::Step(s) => (std::slice::from_ref(s), 1),
                ProfileElement::Cycle { steps, repetitions } => (steps.as_slice(), *repetitions),
            };
            if steps.is_empty() || repetitions == 0 || repetitions > 1000 {
                bad = Some(format!(
                    "a cycle of {} holds repeated {repetitions} times",
                    steps.len()
                ));
            }
            for s in steps {
                if !(s.hold_seconds.is_finite()
                    && s.hold_seconds > 0.0
                    && s.hold_seconds <= 86_400.0)
                {
                    bad = Some(format!("a hold of {} s", s.hold_seconds));
                } else if !(s.celsius.is_finite() && (4.0..=99.0).contains(&s.celsius)) {
                    bad = Some(format!("a hold at {} °C", s.celsius));
                }
            }
        }
        if let Some(what) = bad {
            self.error(
                Code::E0044,
                c.param_path(""),
                format!("{}: {what}", c.label()),
                "holds last more than 0 s and up to a day, at 4 to 99 °C (the cycler's block); cycles repeat 1 to 1,000 times and hold something",
            );
            return;
        }
        self.ran_profile = true;
        let holds: f64 = elements
            .iter()
            .map(|e| match e {
                ProfileElement::Step(s) => s.hold_seconds,
                ProfileElement::Cycle { steps, repetitions } => {
                    f64::from(*repetitions) * steps.iter().map(|s| s.hold_seconds).sum::<f64>()
                }
            })
            .sum();
        self.profile_s += holds;
        self.steps.push(Step {
            primitive: "thermocycle".into(),
            args: vec![
                ("on".into(), cycler),
                ("profile".into(), commands::profile_text(elements)),
            ],
            with: self.robot(1),
            from: Some(c.label()),
        });
    }

    fn finish(mut self) -> (Option<Draft>, Vec<Finding>) {
        if let Some((_, at)) = &self.in_tip {
            let at = *at;
            let c = &self.src.commands[at];
            self.error(
                Code::E0042,
                c.path(),
                format!("{}: aspirated and never dispensed", c.label()),
                "dispense what the pipette holds before the run ends",
            );
        }
        if self.steps.is_empty() && !self.errors() {
            self.findings.push(Finding {
                code: Code::E0042,
                at: vec![Key::field("commands")],
                message: "the run has no step a robot does here".into(),
                hint: Some("it needs pipetting or a thermocycler's lid or profile".into()),
            });
        }
        for (t, (index, why, n)) in std::mem::take(&mut self.dropped) {
            self.findings.push(Finding {
                code: Code::W0011,
                at: self.src.commands[index].path(),
                message: format!("{n} `{t}` dropped: {why}"),
                hint: None,
            });
        }
        let places = if self.cyclers.is_empty() {
            PLACES.len()
        } else {
            PLACES_BESIDE_CYCLER.len()
        };
        let standing: Vec<usize> = self
            .labware
            .values()
            .filter(|l| !matches!(l.holder, Holder::Ignored(_)) && l.on_cycler.is_none())
            .map(|l| l.command)
            .collect();
        if standing.len() > places {
            let extra = standing.iter().copied().max().unwrap_or(0);
            let c = &self.src.commands[extra];
            self.findings.push(Finding {
                code: Code::E0042,
                at: c.path(),
                message: format!(
                    "{}: {} racks, blocks and plates, more than the bench's {places} places in reach",
                    c.label(),
                    standing.len()
                ),
                hint: Some("use fewer labware, or write the bench by hand".into()),
            });
        }
        if self.errors() {
            return (None, self.findings);
        }
        let draft = self.draft();
        (Some(draft), self.findings)
    }

    fn draft(&self) -> Draft {
        let cycler = !self.cyclers.is_empty();
        let n_robots = if cycler { 2 } else { 1 };
        let robots = (0..n_robots)
            .map(|i| Robot {
                name: self.robot(i),
                model: self
                    .options
                    .robots
                    .get(i)
                    .map_or(["ur5e_inspire", "ur5e_2f85"][i].to_string(), |(_, m)| {
                        m.clone()
                    }),
                base: BASES[i],
                joints_rad: Some(JITTER[i]),
            })
            .collect();
        let mut labware = Vec::new();
        if cycler {
            let (pos, yaw) = CYCLER_AT;
            labware.push(Item {
                name: "cycler".into(),
                kind: "thermal_cycler_96".into(),
                pose: Some((pos, yaw)),
                at: None,
                held_by: None,
                state: vec![("lid".into(), self.first_lid.unwrap_or("open").into())],
                comment: Some("the thermocycler module".into()),
            });
        }
        let places: &[[f64; 2]] = if cycler {
            &PLACES_BESIDE_CYCLER
        } else {
            &PLACES
        };
        let mut standing: Vec<&Loaded> = self
            .labware
            .values()
            .filter(|l| !matches!(l.holder, Holder::Ignored(_)) && l.on_cycler.is_none())
            .collect();
        standing.sort_by_key(|l| l.command);
        // More holders than places are refused in `finish`.
        for (i, l) in standing.iter().enumerate() {
            let kind = match l.holder {
                Holder::Kind { kind, .. } => kind,
                _ => "aluminium_block_96_pcr",
            };
            let [x, y] = places[i.min(places.len() - 1)];
            let z = BENCH_TOP + labware::rack::Params::defined(kind).size[2] / 2.0;
            labware.push(Item {
                name: l.name.clone(),
                kind: kind.into(),
                pose: Some(([x, y, z], 0.0)),
                at: None,
                held_by: None,
                state: vec![],
                comment: Some(format!(
                    "commands[{}]{}",
                    l.command,
                    l.slot
                        .as_ref()
                        .map(|s| format!(", deck slot {s}"))
                        .unwrap_or_default()
                )),
            });
        }
        let mut tubes: Vec<&Tube> = self.tubes.values().collect();
        tubes.sort_by(|a, b| a.name.cmp(&b.name));
        for t in &tubes {
            let mut state = vec![("cap".to_string(), "off".to_string())];
            let start = t.volume(&t.start);
            if start > 0.0 {
                state.push(("volume".into(), format!("{} µL", draft::number(start))));
                if let Some(l) = t.start.keys().next() {
                    state.push(("liquid".into(), l.clone()));
                }
            }
            labware.push(Item {
                name: t.name.clone(),
                kind: t.kind.into(),
                pose: None,
                at: Some(t.at.clone()),
                held_by: None,
                state,
                comment: Some(t.comment.clone()),
            });
        }
        if let Some((id, set, _)) = &self.pipette {
            let name = &self.pipettes[id].1;
            let kind = PIPETTES
                .iter()
                .find(|(_, lo, hi)| (lo..=hi).contains(&set))
                .map(|(k, _, _)| *k);
            labware.push(Item {
                name: "pipette".into(),
                kind: kind.unwrap_or("pipette").into(),
                pose: None,
                at: None,
                held_by: Some(self.robot(0)),
                state: vec![("set_volume".into(), format!("{} µL", draft::number(*set)))],
                comment: Some(format!("the run's `{name}`, held by hand")),
            });
        }
        let mut success = Vec::new();
        for t in &tubes {
            if !t.touched {
                continue;
            }
            let total = t.volume(&t.now);
            let named: Vec<(&String, &f64)> = t.now.iter().filter(|(_, v)| **v > 1e-9).collect();
            if t.dispensed_into && named.len() == 1 && (named[0].1 - total).abs() < 1e-6 {
                success.push(format!(
                    "{}.volume of {} = {} µL",
                    t.name,
                    named[0].0,
                    draft::number(total)
                ));
            } else {
                success.push(format!("{}.volume = {} µL", t.name, draft::number(total)));
            }
            if t.at.starts_with("cycler.") {
                success.push(format!("{} in {}", t.name, t.at));
            }
        }
        if cycler {
            if self.ran_profile {
                success.push("cycler.run is done".into());
            }
            match self.lid_state {
                Some("open") => success.push("cycler.lid is open".into()),
                Some("closed") => success.push("cycler.lid is locked".into()),
                _ => {}
            }
        }
        let n_pipetting = self
            .steps
            .iter()
            .filter(|s| s.primitive == "aspirate" || s.primitive == "dispense")
            .count() as f64;
        let n_lid = self
            .steps
            .iter()
            .filter(|s| s.primitive.ends_with("_lid") || s.primitive == "retract")
            .count() as f64;
        // A profile's ramps come on top of its holds (docs: a 2,730 s profile lasts about
        // 3,880 s): half again, plus ten minutes.
        let profile = if self.ran_profile {
            self.profile_s * 1.5 + 600.0
        } else {
            0.0
        };
        let time_limit =
            SLACK_S + PIPETTING_S * n_pipetting + LID_S * n_lid + self.waits_s + profile;
        Draft {
            header: Vec::new(),
            id: self.names.id.clone(),
            level: "hard",
            instruction: self.names.instruction.clone(),
            imported_from: None,
            time_limit_s: (time_limit / 10.0).ceil() * 10.0,
            robots,
            labware,
            steps: self.steps.clone(),
            success,
        }
    }
}

/// A liquid's name as our language writes it: its display name in lower case, other characters
/// as `_`, starting with a letter (else `liquid_<id>`).
fn liquid_name(display: &str, id: &str) -> String {
    let mut s: String = display
        .trim()
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() {
                c.to_ascii_lowercase()
            } else {
                '_'
            }
        })
        .collect();
    while s.contains("__") {
        s = s.replace("__", "_");
    }
    let s = s.trim_matches('_').to_string();
    let ok = s.chars().next().is_some_and(|c| c.is_ascii_alphabetic())
        && s.len() <= 40
        && !dsl::PREDICATE_WORDS.contains(&s.as_str());
    if ok {
        s
    } else {
        let id: String = id
            .chars()
            .filter(|c| c.is_ascii_alphanumeric())
            .take(30)
            .collect();
        format!("liquid_{id}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn liquid_names_are_ours() {
        assert_eq!(liquid_name("Master Mix (2X)", "0"), "master_mix_2x");
        assert_eq!(liquid_name("H2O", "1"), "h2o");
        assert_eq!(liquid_name("10x buffer", "b-1"), "liquid_b1");
        assert_eq!(liquid_name("in", "2"), "liquid_2");
    }
}
