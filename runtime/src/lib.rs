//! The autobio runtime: runs a compiled [`compiler::Task`] on MuJoCo.
//!
//! It assembles the scene (installed robot models + table + generated labware), steps physics at
//! 500 Hz with each control action held for the task's substeps, runs instrument logic after every
//! physics step (detents, latches), renders cameras headless (EGL) and records episodes as MCAP.
//! It does not decide what to do (policies live in `scoring`) nor whether an episode succeeded
//! (verdicts live in `scoring`); it reports state.

pub mod deps;
pub mod episode;
pub mod kinematics;
pub mod record;
pub mod render;
pub mod scene;

pub use episode::{Episode, LabwareState, StepError};
pub use scene::{Scene, SceneError};
