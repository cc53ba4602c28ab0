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
//!
//! Here the walk over the commands and its findings; `loads.rs` the labware, modules, pipettes and
//! wells as tubes, `liquids.rs` the liquids and the pipetting, `cycler.rs` the thermocycler's lid
//! and profile, `written.rs` the draft the walk ends in.

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

mod cycler;
mod liquids;
mod loads;
mod written;

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

/// Text as a step argument: braces doubled, so none reads as a parameter's placeholder.
fn braced(text: &str) -> String {
    text.replace('{', "{{").replace('}', "}}")
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
    /// Modules with no model here whose commands are kept as instrument-only steps (the
    /// labware on them stands on the bench).
    kept_modules: std::collections::BTreeSet<String>,
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
        kept_modules: Default::default(),
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
        if c.command_type == "external" {
            w.external(c);
            continue;
        }
        match commands::fate(&c.command_type) {
            Fate::Realised => w.command(c),
            Fate::Refused(commands::NO_MODULE, _) if options.keep_instrument_steps => {
                w.keep_module_command(c)
            }
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
                &if why == commands::NO_MODULE {
                    format!(
                        "{hint}; or keep it as an instrument-only step (`--keep-instrument-steps`)"
                    )
                } else {
                    hint.to_string()
                },
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
                    let elements = commands::as_cycles(p.profile);
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

    /// An instrument-only step a lowered source keeps (`external`).
    fn external(&mut self, c: &Command) {
        let text = |key: &str| c.params.get(key).and_then(|v| v.as_str()).map(braced);
        let mut args = vec![("what".to_string(), text("what").unwrap_or_default())];
        if let Some(seconds) = c.params.get("seconds").and_then(|v| v.as_f64()) {
            self.waits_s += seconds;
            args.push(("duration".into(), format!("{} s", draft::number(seconds))));
        }
        if let Some(instruction) = text("instruction") {
            args.push(("instruction".into(), instruction));
        }
        // The wells it names get their tubes (empty, unless something else fills them).
        let wells: Vec<(String, String)> = c
            .params
            .get("wells")
            .and_then(|w| serde_json::from_value(w.clone()).ok())
            .unwrap_or_default();
        for (labware, well) in wells {
            self.tube(c, &labware, &well);
        }
        self.steps.push(Step {
            primitive: "external".into(),
            args,
            with: self.robot(0),
            from: Some(c.label()),
        });
    }

    /// A command of a module with no model here, kept as an instrument-only step: its type and
    /// parameters in words (the module's id left out).
    fn keep_module_command(&mut self, c: &Command) {
        let mut params = c.params.clone();
        if let Some(m) = params.as_object_mut() {
            m.remove("moduleId");
        }
        let what = match params.as_object().filter(|m| !m.is_empty()) {
            Some(_) => format!("{} {}", c.command_type, params),
            None => c.command_type.clone(),
        };
        self.steps.push(Step {
            primitive: "external".into(),
            args: vec![("what".into(), braced(&what))],
            with: self.robot(0),
            from: Some(c.label()),
        });
    }

    fn robot(&self, i: usize) -> String {
        self.options
            .robots
            .get(i)
            .map(|(name, _)| name.clone())
            .unwrap_or_else(|| ["left", "arm"][i.min(1)].to_string())
    }

    /// The bench's places for holders: beside the cycler when the run has one.
    fn places(&self) -> &'static [[f64; 2]] {
        if self.cyclers.is_empty() {
            &PLACES
        } else {
            &PLACES_BESIDE_CYCLER
        }
    }

    /// The holders that stand on the bench (not tip racks or trash, not the plate in the cycler),
    /// in the order the run loads them.
    fn standing(&self) -> Vec<&Loaded> {
        let mut standing: Vec<&Loaded> = self
            .labware
            .values()
            .filter(|l| !matches!(l.holder, Holder::Ignored(_)) && l.on_cycler.is_none())
            .collect();
        standing.sort_by_key(|l| l.command);
        standing
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
        let places = self.places().len();
        let standing = self.standing();
        if standing.len() > places {
            let extra = standing.last().map_or(0, |l| l.command);
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
}
