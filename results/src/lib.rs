//! What episodes and runs produce, readable without a simulator: the judge and its verdicts
//! ([`verdict`]), an episode's result and the trajectory-hash rule ([`episode`]), how an episode
//! ended and what a re-enactment gives ([`end`]), run records,
//! statistics and merging shards ([`run`]), model profiles ([`profile`]), camera frames
//! ([`Image`]), MCAP recordings, written and read ([`recording`]), and suites ([`suite`]).
//!
//! It links no simulator (no MuJoCo, no EGL): a leaderboard, a verifier's bookkeeping and CI for
//! submissions build on it alone. It does not run episodes (the runtime and `scoring` do) and
//! does not render reports (the leaderboard does).
//!
//! Its tests are beside the code and in the workspace's tests/merge.rs, tests/resume.rs and
//! tests/no_simulator.rs (that it links no simulator).

pub mod end;
pub mod environment_state;
pub mod episode;
mod image;
pub mod profile;
pub mod recording;
pub mod run;
pub mod suite;
pub mod verdict;

pub use image::Image;
