//! The autobio compiler: a parsed protocol or chain ([`dsl::ast::Document`]) is checked against
//! the catalogues (labware kinds, robot models, lab primitives), its parameters are given domains,
//! its steps are traced through the abstract world for every parameter combination (the state
//! proof), and it is lowered to a [`Task`]: the serialisable, versioned contract every later stage
//! (runtime, scoring) reads. [`describe`] renders a task sheet from a task.
//!
//! Checking never fails: the entry points return every diagnostic, and a task only when there are
//! no errors. [`Task::sample`] turns a task and a seed into a [`SceneInstance`], deterministically.
//! This crate runs no physics and plans no motion; its only IO is reading a chain's stage files
//! through the loader its caller passes.

mod chain;
mod check;
pub mod describe;
pub mod motion;
pub mod params;
pub mod predicates;
pub mod primitives;
mod proof;
mod task;
pub mod world;

pub use describe::describe;
pub use task::*;

use check::Cx;
use dsl::Diagnostic;
use dsl::ast::{Document, Protocol};

/// Reads a stage file named by a chain (its path as the chain resolves it).
pub type Loader<'a> = &'a dyn Fn(&str) -> Result<String, String>;

/// Checks and lowers one protocol to a one-stage task.
pub fn compile(p: &Protocol, file: &str) -> (Option<Task>, Vec<Diagnostic>) {
    let mut cx = Cx::new(None);
    let task = check::lower(&mut cx, p, file).and_then(|low| {
        if cx.has_errors() {
            return None;
        }
        let stages = [proof::ProofStage {
            id: low.id.clone(),
            file: None,
            steps: &low.steps,
            predicates: &low.predicates,
        }];
        let scene = proof::ProofScene {
            labware: &low.labware,
            kinds: &low.kinds,
            robots: low.robots.iter().map(|r| r.name.clone()).collect(),
            labware_spans: &low.labware_spans,
            file: None,
        };
        proof::prove(&mut cx, &scene, &stages, &low.params);
        Some(Task {
            schema_version: TASK_SCHEMA_VERSION,
            id: low.id.clone(),
            version: low.version,
            level: low.level.clone(),
            instruction: low.stage.instruction.clone(),
            source: file.to_string(),
            time_limit_s: low.stage.time_limit_s,
            physics: physics(),
            cameras: check::default_cameras(&low.robots),
            robots: low.robots,
            labware: low.labware,
            params: low.params,
            stages: vec![low.stage],
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
    load: Loader,
) -> (Option<Task>, Vec<Diagnostic>) {
    let (doc, mut diags) = dsl::parse(source);
    if diags.iter().any(|d| d.code == dsl::Code::E0001) {
        return (None, diags);
    }
    let (task, more) = match &doc {
        Document::Protocol(p) => compile(p, file),
        Document::Chain(c) => chain::compile_chain(c, file, load),
    };
    diags.extend(more);
    if diags.iter().any(|d| d.is_error()) {
        (None, diags)
    } else {
        (task, diags)
    }
}

/// [`compile_source_with`] reading chain stages from the file system.
pub fn compile_source(source: &str, file: &str) -> (Option<Task>, Vec<Diagnostic>) {
    compile_source_with(source, file, &|path| {
        std::fs::read_to_string(path).map_err(|e| e.to_string())
    })
}
