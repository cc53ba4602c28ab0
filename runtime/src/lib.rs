//! The autobio runtime: runs a compiled [`compiler::Task`] on MuJoCo.
//!
//! It assembles the scene (robot models prepared from installed packages + table + labware from
//! each item's instrument model), steps physics at 500 Hz with each control action held for the
//! task's substeps, runs instrument logic after every physics step (latches; detents and threads
//! are plugins), renders cameras headless (EGL) and records episodes as MCAP, one channel per robot.
//! It does not decide what to do (policies live in `scoring`) nor whether an episode succeeded
//! (verdicts live in `scoring`); it reports state.
//!
//! Its tests are the workspace's tests/step_by_hand.rs, tests/contact_and_position.rs,
//! tests/level_of_detail.rs and tests/pictures.rs.

pub mod clearance;
pub mod deps;
pub mod env;
pub mod episode;
pub mod kinematics;
pub mod picture;
pub mod render;
pub mod scene;

/// Recordings are written and read by `results` (no simulator needed to read one).
pub use results::recording as record;

pub use env::{Env, EnvError, EnvOptions, ObserveError, Observer, Transition};
pub use episode::{Episode, StepError, check_action};
pub use labware::LabwareState;
pub use scene::{Scene, SceneError};
