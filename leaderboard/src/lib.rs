//! The leaderboard: evaluation results (`results::EvalReport`, results schema
//! [`results::RESULTS_SCHEMA_VERSION`]) turned into reports. Today that is the results tables
//! `autobio eval` and `autobio results merge` print ([`table`]); submissions, their offline
//! verification and the site come next.
//!
//! It links no simulator: it reads what runs wrote, through `results`, and runs nothing.

pub mod table;

pub use table::{results_table, runs_table};
