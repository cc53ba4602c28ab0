//! Scoring, the evaluation harness: the episode loop that couples a policy to the runtime and
//! judges it every control step, the policies it runs by name (`policies`: the scripted expert
//! from the `expert` crate, the no-motion control, replays of recordings) and models over the
//! network under a profile (`remote`), evaluation runs that write journals, versioned results
//! and run records (`eval`), replays and re-enactments of recordings (`replay`), and stage times.
//!
//! It does not simulate (the runtime does), plan motions (the expert does), synthesise protocols
//! (`synth`), write datasets (`dataset`, `demos`) or aggregate across submissions (the
//! leaderboard does). Its tests are the workspace's (tests/episode_failures.rs,
//! tests/model_servers.rs, tests/model_faults.rs, tests/replay.rs, tests/resume.rs and the
//! episodes of every task).

pub mod episode;
pub mod eval;
pub mod policies;
pub mod remote;
pub mod replay;
pub mod stage_time;
