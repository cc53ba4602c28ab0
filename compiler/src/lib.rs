//! The autobio compiler: a parsed protocol ([`dsl::ast::Protocol`]) is checked against the
//! catalogues (labware kinds, robot models, lab primitives), its steps are traced through the
//! labware states each primitive needs and leaves, and it is lowered to a [`Task`]: the serialisable,
//! versioned contract every later stage (runtime, scoring) reads.
//!
//! Checking never fails: [`compile`] returns every diagnostic and a task only when there are no
//! errors. [`Task::sample`] turns a task and a seed into a [`SceneInstance`], deterministically.
//! This crate runs no physics and plans no motion.

mod check;
pub mod primitives;
pub mod robots;
mod task;

pub use check::compile;
pub use task::*;

/// Parses and compiles protocol source in one call.
pub fn compile_source(source: &str, file: &str) -> (Option<Task>, Vec<dsl::Diagnostic>) {
    let (ast, mut diags) = dsl::parse(source);
    if diags.iter().any(|d| d.code == dsl::Code::E0001) {
        return (None, diags);
    }
    let (task, more) = compile(&ast, file);
    diags.extend(more);
    if diags.iter().any(|d| d.is_error()) {
        (None, diags)
    } else {
        (task, diags)
    }
}
