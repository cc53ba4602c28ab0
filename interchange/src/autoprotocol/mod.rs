//! Autoprotocol (autoprotocol.org), the JSON cloud labs run: `refs` (containers by name),
//! `instructions` (each with its `op`) and `time_constraints`. Imported by lowering it into the
//! commands the bench realisation reads (`lower.rs`), so an Autoprotocol PCR and an Opentrons
//! one are realised by the same code; its time constraints carried as step timing
//! (`timing.rs`); exported from a compiled task (`export.rs`). Its types are ours, written from
//! the published specification (`spec.rs`); its quantities are read by `units.rs`.
//!
//! Not here: `spin` and `incubate` realised as robot steps (they are refused with a hint, or kept
//! as instrument-only steps on request, as the instruments we have no model of are).

pub mod export;
pub mod lower;
pub mod spec;
pub mod timing;
pub mod units;

pub use lower::is_autoprotocol;
