//! The autobio protocol language, front end: TOML text to a spanned [`ast::Protocol`] plus
//! [`Diagnostic`]s.
//!
//! This crate does no IO and never panics: [`parse`] always returns an AST (possibly partial) and
//! every problem it found, each with a byte span into the source, a stable code, a lowercase
//! message quoting the input, and a hint where one exists. It knows the *shape* of a protocol
//! (tables, keys, types, units); it does not know which labware kinds, robots or primitives exist —
//! name resolution against those catalogues is the compiler's job. Rendering diagnostics for humans
//! is the CLI's job ([`render`] gives the plain building blocks: line/column and the source line).
//!
//! Its tests are beside the code (unit tests) and in the workspace's tests/protocol_diagnostics.rs,
//! tests/faulty_corpus.rs and tests/golden.rs (golden ASTs in tests/golden/).

pub mod ast;
mod diagnostic;
mod parse;
mod quantity;
pub mod render;
pub mod source;

pub use diagnostic::{Code, Diagnostic, Severity, Span, did_you_mean};
pub use parse::{parse, perturb_dimensions};
pub use quantity::{Dimension, ParseQuantityError, Quantity, parse_quantity};

/// The words success predicates are made of, which a named liquid may not be (`tube.volume of
/// <liquid> >= 5 µL` must read back).
pub const PREDICATE_WORDS: &[&str] = &[
    "in", "is", "was", "of", "near", "holds", "touches", "lifted", "inverted", "within", "for",
];

/// The protocol-language version this crate reads (`format = 1` at the top of a file).
pub const FORMAT_VERSION: i64 = 1;
