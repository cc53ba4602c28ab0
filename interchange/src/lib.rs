//! Protocols from the languages labs already write: `autobio import` reads an Opentrons analysis
//! (`opentrons analyze --json-output`), a Protocol Designer file (schema 8) or an Autoprotocol
//! document and writes a protocol file in our language, realising on our bench what a liquid
//! handler's deck or a cloud lab did: its labware as racks, blocks and tubes, its single-channel
//! pipette as the hand-held one, its pipetting as `aspirate` and `dispense` steps, its
//! thermocycler as the `thermal_cycler_96` with its lid worked by an arm. What has no robot
//! realisation here is refused with a diagnostic at the command's (instruction's) index and type,
//! and its line and column in the file; what a gantry does that our steps do themselves (tips,
//! homing, moves, blow-out) is dropped and said once per type. `autoprotocol::export` writes a
//! compiled task's lab steps back as Autoprotocol.
//!
//! Flow: JSON text → `serde_json::Value` (E0040 at the parser's line and column) → the format's
//! reader (`opentrons::source`; `autoprotocol::lower`, which lowers into the same commands) →
//! realisation into a [`Draft`] (`opentrons::realise`; Autoprotocol's time constraints then
//! `autoprotocol::timing`) → the protocol's text ([`Draft::to_toml`]). The written file is
//! checked like any protocol by the caller (`autobio import` runs the check). No Python runs at
//! import time; labware definitions come from the file or from the installed
//! `opentrons-shared-data` ([`labware::definition::Installed`]).
//!
//! On request (`Options::keep_instrument_steps`) a command of an instrument we have no model of is
//! kept as an instrument-only step (`external`) instead of refused. Not here: Autoprotocol's
//! `spin` and `incubate` as robot steps. Its tests are beside the code and in tests/import.rs and
//! tests/import_autoprotocol.rs.

pub mod autoprotocol;
pub mod draft;
pub mod json_span;
pub mod opentrons;

pub use draft::Draft;
use dsl::{Code, Diagnostic};
use json_span::Key;
use sha2::{Digest, Sha256};
use std::path::PathBuf;

/// How to import.
#[derive(Clone, Debug)]
pub struct Options {
    /// The protocol's id (default: `imported.<the file's stem>`).
    pub id: Option<String>,
    /// Its instruction, the language prompt (default: from the file's protocol name).
    pub instruction: Option<String>,
    /// The robots, by name and model: the first pipettes, the second works the cycler's lid.
    /// Empty: `left` (ur5e_inspire) and `arm` (ur5e_2f85).
    pub robots: Vec<(String, String)>,
    /// Where `make setup` installed the dependencies (for labware definitions by URI).
    pub deps: PathBuf,
    /// The source file's name, for the written file's header.
    pub file_name: String,
    /// Keep a command that has no robot realisation as an instrument-only step (`external`:
    /// the robots stand by for its duration) instead of refusing it: an instrument we have no
    /// model of (a magnet, a plate reader, a temperature module; Autoprotocol's `spin` and
    /// `incubate`).
    pub keep_instrument_steps: bool,
}

/// A finding about the source: a code, where in the file (a path of keys), a message and a hint.
#[derive(Clone, Debug, PartialEq)]
pub struct Finding {
    pub code: Code,
    pub at: Vec<Key>,
    pub message: String,
    pub hint: Option<String>,
}

/// What an import gives.
#[derive(Clone, Debug)]
pub struct Imported {
    /// The format read (`Opentrons analysis JSON`, `Opentrons protocol JSON, schema 8`).
    pub format: Option<String>,
    /// SHA-256 of the source's bytes, hex.
    pub source_sha256: String,
    /// The protocol file's text; none when an error refused the import.
    pub protocol: Option<String>,
    /// Every finding, as diagnostics whose spans point into the source text.
    pub diagnostics: Vec<Diagnostic>,
    /// Each written step's source command, as `commands[12] aspirate` (in step order).
    pub step_sources: Vec<Option<String>>,
}

/// Imports a source text.
pub fn import(text: &str, options: &Options) -> Imported {
    let source_sha256 = hex::encode(Sha256::digest(text.as_bytes()));
    let mut out = Imported {
        format: None,
        source_sha256,
        protocol: None,
        diagnostics: Vec::new(),
        step_sources: Vec::new(),
    };
    let doc: serde_json::Value = match serde_json::from_str(text) {
        Ok(v) => v,
        Err(e) => {
            let at = offset(text, e.line(), e.column());
            out.diagnostics.push(
                Diagnostic::error(
                    Code::E0040,
                    dsl::Span::new(at, (at + 1).min(text.len()).max(at)),
                    format!("the file is not JSON: {e}"),
                )
                .with_hint("an Opentrons file or an Autoprotocol document is one JSON document"),
            );
            return out;
        }
    };
    let mut findings = Vec::new();
    let lowered: Option<autoprotocol::lower::Lowered>;
    let read;
    let src = if autoprotocol::is_autoprotocol(&doc) {
        let (l, f) = autoprotocol::lower::lower(&doc, options);
        findings = f;
        match l {
            Some(l) => {
                lowered = Some(l);
                &lowered.as_ref().expect("just set").source
            }
            None => {
                out.diagnostics = findings.into_iter().map(|f| diagnostic(text, f)).collect();
                return out;
            }
        }
    } else if opentrons::source::is_opentrons(&doc) {
        lowered = None;
        read = match opentrons::source::read(&doc) {
            Ok(s) => s,
            Err(u) => {
                let mut d =
                    Diagnostic::error(Code::E0040, json_span::nearest(text, &u.at), u.message);
                if let Some(h) = u.hint {
                    d = d.with_hint(h);
                }
                out.diagnostics.push(d);
                return out;
            }
        };
        &read
    } else {
        out.diagnostics.push(
            Diagnostic::error(
                Code::E0040,
                json_span::nearest(text, &[]),
                "neither an Opentrons analysis or protocol (schema 8) nor an Autoprotocol document",
            )
            .with_hint(
                "an analysis has `robotType` and `commands`; a protocol has `$otSharedSchema` `#/protocol/schemas/8`; Autoprotocol has `refs` and `instructions`",
            ),
        );
        return out;
    };
    let format = src.flavour.describe();
    out.format = Some(format.clone());
    let names = opentrons::realise::Names {
        id: options
            .id
            .clone()
            .unwrap_or_else(|| default_id(&options.file_name)),
        instruction: options.instruction.clone().unwrap_or_else(|| {
            match doc
                .pointer("/metadata/protocolName")
                .and_then(serde_json::Value::as_str)
                .map(str::trim)
                .filter(|n| !n.is_empty())
            {
                // Braces are written doubled: a `{` would read as a placeholder.
                Some(name) => format!(
                    "carry out the protocol \"{}\"",
                    name.replace('{', "{{").replace('}', "}}")
                ),
                None => "carry out the imported protocol".into(),
            }
        }),
    };
    let (mut draft, realised) = opentrons::realise::realise(src, options, &names);
    findings.extend(realised);
    if let (Some(draft), Some(lowered)) = (&mut draft, &lowered) {
        findings.extend(autoprotocol::timing::apply(draft, lowered));
    }
    // "No step a robot does" says nothing more when something else was refused; for a
    // lowered file it speaks of its instructions.
    let no_steps = |f: &Finding| f.code == Code::E0042 && f.at == [Key::field("commands")];
    if findings
        .iter()
        .any(|f| !f.code.is_warning() && !no_steps(f))
    {
        findings.retain(|f| !no_steps(f));
    } else if lowered.is_some() {
        for f in findings.iter_mut().filter(|f| no_steps(f)) {
            f.at = vec![Key::field("instructions")];
            f.hint =
                Some("it needs pipetting (`liquid_handle`, `pipette`) or a `thermocycle`".into());
        }
    }
    let refused = findings.iter().any(|f| !f.code.is_warning());
    out.diagnostics = findings.into_iter().map(|f| diagnostic(text, f)).collect();
    if refused {
        return out;
    }
    if let Some(mut draft) = draft {
        draft.imported_from = Some((
            options.file_name.clone(),
            format.clone(),
            out.source_sha256.clone(),
        ));
        draft.header = vec![
            format!("Imported by `autobio import` from {} ({format}, {}).", options.file_name, src.robot_type),
            "Each step's comment names the source command it realises; see docs/import.md for what maps to what.".into(),
        ];
        out.step_sources = draft.steps.iter().map(|s| s.from.clone()).collect();
        out.protocol = Some(draft.to_toml());
    }
    out
}

/// A finding as a diagnostic whose span is the JSON value its path names (or the nearest one
/// the text has), with the path as a note.
fn diagnostic(text: &str, f: Finding) -> Diagnostic {
    let mut d = Diagnostic::error(f.code, json_span::nearest(text, &f.at), f.message);
    if let Some(h) = f.hint {
        d = d.with_hint(h);
    }
    d.notes.push(format!("at {}", json_span::pointer(&f.at)));
    d
}

/// `imported.<stem>`: the file's stem in the characters an id may hold.
fn default_id(file_name: &str) -> String {
    let stem = std::path::Path::new(file_name)
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("protocol");
    let slug: String = stem
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.') {
                c
            } else {
                '_'
            }
        })
        .take(100)
        .collect();
    format!("imported.{slug}")
}

/// The byte offset of a 1-based line and column.
fn offset(text: &str, line: usize, column: usize) -> usize {
    let start: usize = text
        .split_inclusive('\n')
        .take(line.saturating_sub(1))
        .map(str::len)
        .sum();
    (start + column.saturating_sub(1)).min(text.len())
}
