//! The autobio runtime: runs a compiled [`compiler::Task`] on MuJoCo.
//!
//! It assembles the scene (robot models prepared from installed packages + table + labware from
//! each item's instrument model), steps physics at 500 Hz with each control action held for the
//! task's substeps, runs instrument logic after every physics step (latches, runs; detents and
//! threads are plugins), jumps lab time while only instrument timers run ([`clock`]), renders cameras headless (EGL) and records episodes as MCAP, one channel per robot.
//! It does not decide what to do (policies live in `scoring`) nor whether an episode succeeded
//! (verdicts live in `scoring`); it reports state.
//!
//! Its tests are the workspace's tests/step_by_hand.rs, tests/contact_and_position.rs,
//! tests/level_of_detail.rs and tests/pictures.rs.

pub mod blender;
pub mod cameras;
pub mod clearance;
pub mod clock;
pub mod deps;
mod env;
mod episode;
pub mod kinematics;
pub mod perturb;
pub mod picture;
pub mod render;
mod scene;

pub use env::{
    Env, EnvError, EnvOptions, Observation, ObserveError, Observer, RobotState, Transition,
};
pub use episode::{Episode, RestoreError, StepError, check_action};
pub use scene::{FreeJoint, LabwareIds, Owner, RobotIds, Scene, SceneError};
