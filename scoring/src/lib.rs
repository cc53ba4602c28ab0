//! Scoring: policies (the scripted expert, the no-motion control, replays of recordings, and
//! models over the network under a profile), the episode loop that couples a policy to the
//! runtime, verdicts from success predicates, and evaluation runs that write versioned results
//! and run records.
//!
//! It does not simulate (the runtime does) and does not aggregate across submissions (the
//! leaderboard does).

pub mod episode;
pub mod eval;
pub mod expert;
pub mod policies;
pub mod policy;
pub mod reach;
pub mod remote;
pub mod replay;
pub mod route;
pub mod stage_time;
pub mod synth;

/// Profiles and verdicts live in `results` (no simulator needed to read them).
pub use results::{profile, verdict};

pub use episode::{EpisodeError, EpisodeOptions, EpisodeResult, Outcome, run_episode};
pub use eval::{EvalError, EvalReport, EvalSummary, RESULTS_SCHEMA_VERSION, evaluate};
pub use policies::{HoldPolicy, POLICIES, PolicySpec};
pub use policy::{Observation, Policy, PolicyError, StageEvent};
pub use results::verdict::{Judge, PredicateValue, StageVerdict, Verdict};
