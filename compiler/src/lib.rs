//! The autobio compiler: a parsed protocol or chain ([`dsl::ast::Document`]) is checked against
//! the catalogues (labware kinds, robot models, lab primitives), its parameters are given domains,
//! its steps are traced through the abstract world for every parameter combination (the state
//! proof), and it is lowered to a [`Task`]: the serialisable, versioned contract every later stage
//! (runtime, scoring) reads. [`describe`] renders a task sheet from a task.
//!
//! Checking never fails: the entry points return every diagnostic, and a task only when there are
//! no errors. [`Task::sample`] turns a task and a seed into a [`SceneInstance`], deterministically.
//! This crate runs no physics and plans no motion; its only IO is reading the file
//! [`check_file`] is given and a chain's stage files, through [`stage_files`] (whose rules confine
//! a chain to its protocol root) or a loader the caller passes.
//!
//! Its tests are beside the code (`check/`, `quantities.rs`, `primitives/`: unit tests on real
//! protocol text) and in the workspace's tests/golden.rs (every shipped protocol's task and sheet),
//! tests/faulty_corpus.rs (tests/corpus/faulty/) and tests/protocol_diagnostics.rs.

pub mod bench;
mod chain;
mod check;
pub mod describe;
mod loops;
pub mod motion;
pub mod params;
pub mod perturb;
pub mod predicates;
pub mod primitives;
pub mod profile;
mod proof;
pub mod quantities;
mod report;
mod scene_file;
pub mod stage_files;
mod sweep;
mod task;
pub mod world;

pub use task::*;

use dsl::Diagnostic;
use dsl::ast::{Document, Protocol};
use report::Cx;
use stage_files::{StageFiles, StageLoader};

/// Checks and lowers one protocol to a one-stage task.
pub fn compile(p: &Protocol, file: &str) -> (Option<Task>, Vec<Diagnostic>) {
    let mut cx = Cx::new(None);
    if let Some(scene) = &p.scene {
        // The scene file is read relative to the protocol's: only the file-reading entry points
        // can merge it.
        cx.push(
            Diagnostic::new(
                dsl::Code::E0006,
                scene.span,
                "this protocol's scene file was not read",
            )
            .with_hint("compile it from its file (`check_file`, `compile_source_with`)"),
        );
        return (None, cx.diags);
    }
    let expanded;
    let p = if p.steps.iter().any(dsl::ast::Step::is_loop) {
        let mut copy = p.clone();
        loops::expand(&mut cx, &mut copy);
        expanded = copy;
        &expanded
    } else {
        p
    };
    let task = check::lower(&mut cx, p, file).and_then(|low| {
        if cx.has_errors() {
            return None;
        }
        let stages = [proof::ProofStage {
            id: low.id.clone(),
            file: None,
            steps: &low.steps,
            predicates: &low.predicates,
            declared: None,
            time_limit_s: low.stage.time_limit_s,
        }];
        let scene = proof::ProofScene {
            labware: &low.labware,
            kinds: &low.kinds,
            robots: low.robots.iter().map(|r| r.name.clone()).collect(),
            labware_spans: &low.labware_spans,
            file: None,
            param_places: p
                .params
                .iter()
                .map(|x| (x.name.value.clone(), (None, x.name.span)))
                .collect(),
        };
        proof::prove(&mut cx, &scene, &stages, &low.params);
        Some(
            Task {
                schema_version: TASK_SCHEMA_VERSION,
                id: low.id.clone(),
                version: low.version,
                level: low.level.clone(),
                instruction: low.stage.instruction.clone(),
                source: file.to_string(),
                time_limit_s: low.stage.time_limit_s,
                physics: physics(),
                cameras: check::default_cameras(&low.robots, low.camera.as_ref()),
                robots: low.robots,
                labware: low.labware,
                params: low.params,
                stages: vec![low.stage],
                imported_from: p.meta.imported_from.as_ref().map(|i| ImportedFrom {
                    file: i.file.clone(),
                    format: i.format.clone(),
                    sha256: i.sha256.clone(),
                }),
                paraphrases: p.meta.paraphrases.iter().map(|s| s.value.clone()).collect(),
                perturb: None,
            }
            .with_programmes(),
        )
        .map(|mut task| {
            if let Some(table) = &p.perturb {
                // An empty table perturbs nothing and leaves the task (and its hash) as it was.
                task.perturb = perturb::lower(&mut cx, table, &task).filter(|p| !p.is_empty());
            }
            task
        })
    });
    let ok = !cx.has_errors();
    (task.filter(|_| ok), cx.diags)
}

pub(crate) fn physics() -> Physics {
    Physics {
        timestep_s: 0.002,
        substeps: 10,
    }
}

/// Parses and compiles a protocol or chain. Chain stages are read with `load`, by their path
/// relative to `file`'s folder.
pub fn compile_source_with(
    source: &str,
    file: &str,
    load: &dyn StageLoader,
) -> (Option<Task>, Vec<Diagnostic>) {
    let (doc, mut diags) = dsl::parse(source);
    if diags.iter().any(|d| d.code == dsl::Code::E0001) {
        return (None, diags);
    }
    let (task, more) = match &doc {
        Document::Protocol(p) => {
            let mut p = p.as_ref().clone();
            let mut cx = Cx::new(None);
            let named = p.scene.is_some();
            let merged = scene_file::merge(&mut cx, &mut p, file, source, load);
            // A scene that was read is checked with the protocol, mistakes and all (every one in
            // one pass); without the scene it names, the protocol would be all errors.
            let (task, more) = if named && merged.is_none() {
                (None, Vec::new())
            } else {
                compile(&p, file)
            };
            let mut all = cx.diags;
            all.extend(more);
            if let Some(m) = merged {
                m.remap(&mut all);
            }
            (task, all)
        }
        Document::Chain(c) => chain::compile_chain(c, file, source, load),
        // A scene file is checked, and is no task.
        Document::Scene(s) => {
            let mut cx = Cx::new(None);
            check::check_scene(&mut cx, s);
            (None, cx.diags)
        }
    };
    diags.extend(more);
    if diags.iter().any(|d| d.is_error()) {
        (None, diags)
    } else {
        (task, diags)
    }
}

/// Whether `source` is a scene file (`[scene]`, shared by protocols through `scene = ".."`),
/// which is no task: folders of protocols are listed without them.
pub fn is_scene_file(source: &str) -> bool {
    matches!(dsl::parse(source).0, Document::Scene(_))
}

/// [`compile_source_with`] reading chain stages from the file system, confined to the chain's
/// folder.
pub fn compile_source(source: &str, file: &str) -> (Option<Task>, Vec<Diagnostic>) {
    compile_source_with(source, file, &StageFiles::new())
}

/// Largest protocol or chain file [`check_file`] reads.
pub const MAX_FILE_BYTES: u64 = 64 << 20;

/// A protocol or chain file, checked: the task when there are no errors, every diagnostic, and
/// the texts the diagnostics point into (the file's own and its stages').
#[derive(Debug)]
pub struct Checked {
    pub file: String,
    pub task: Option<Task>,
    pub diagnostics: Vec<Diagnostic>,
    /// The file's text (with U+FFFD for bytes that are not UTF-8, which an E0008 points at).
    pub source: String,
    pub stages: StageFiles,
}

impl Checked {
    /// The text a diagnostic points into: the file's own, or a stage file's as it was read.
    pub fn text_of(&self, d: &Diagnostic) -> Option<(String, String)> {
        match &d.file {
            None => Some((self.file.clone(), self.source.clone())),
            Some(f) => self.stages.text(f).map(|t| (f.clone(), t)),
        }
    }

    /// Where the proof found the task trivial (W0001: its success holds before the first step,
    /// so a motionless robot passes it), as `file:line:col`; `None` when it is not.
    pub fn trivial_at(&self) -> Option<String> {
        // Only the first stage's: a chain's later stage whose success already holds where the
        // stage before left the world is not won by a robot that does nothing.
        let d = self.diagnostics.iter().find(|d| {
            d.code == dsl::Code::W0001
                && !d.notes.iter().any(|n| n.contains(" starts where stage "))
        })?;
        Some(match self.text_of(d) {
            Some((file, text)) => {
                let (line, col) = dsl::render::line_col(&text, d.span.start);
                format!("{file}:{line}:{col}")
            }
            None => format!(
                "{} (byte {})",
                d.file.as_deref().unwrap_or(&self.file),
                d.span.start
            ),
        })
    }
}

/// Why a protocol file could not be checked at all.
#[derive(Debug, thiserror::Error)]
pub enum FileError {
    // The OS error is in the message, not a `source`: a chain of causes shows it once.
    #[error("cannot read protocol {path}: {error}")]
    Read { path: String, error: std::io::Error },
    #[error("cannot read protocol {path}: it is not a regular file")]
    NotAFile { path: String },
    #[error("cannot read protocol {path}: it is larger than {MAX_FILE_BYTES} bytes")]
    TooLarge { path: String },
}

/// Reads and compiles a protocol or chain file; chain stages are confined to `root` (the chain's
/// folder when `None`) under the rules of [`stage_files`]. A file that is not UTF-8 gives an
/// E0008 diagnostic at its first bad byte, not an error.
pub fn check_file(
    path: &std::path::Path,
    root: Option<&std::path::Path>,
) -> Result<Checked, FileError> {
    use std::io::Read;
    let file = path.display().to_string();
    let read = |error| FileError::Read {
        path: file.clone(),
        error,
    };
    let meta = std::fs::metadata(path).map_err(read)?;
    // A folder, a device or a pipe is refused before it is opened (a pipe would block).
    if !meta.is_file() {
        return Err(FileError::NotAFile { path: file });
    }
    let mut bytes = Vec::new();
    std::fs::File::open(path)
        .and_then(|f| f.take(MAX_FILE_BYTES + 1).read_to_end(&mut bytes))
        .map_err(read)?;
    if bytes.len() as u64 > MAX_FILE_BYTES {
        return Err(FileError::TooLarge { path: file });
    }
    let stages = match root {
        Some(r) => StageFiles::with_root(r),
        None => StageFiles::new(),
    };
    let (source, task, diagnostics) = match dsl::source::decode(&bytes) {
        Ok(text) => {
            let (task, diags) = compile_source_with(text, &file, &stages);
            (text.to_string(), task, diags)
        }
        Err(d) => (dsl::source::lossy(&bytes), None, vec![d]),
    };
    Ok(Checked {
        file,
        task,
        diagnostics,
        source,
        stages,
    })
}
