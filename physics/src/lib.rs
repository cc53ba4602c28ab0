//! Lab physics for autobio, the four mechanisms of the paper's "AutoBio Physics":
//! - [`thread`]: screw threads as bounded-helix SDFs (MuJoCo SDF plugin `autobio.thread`);
//! - [`detent`]: click positions as a passive force (MuJoCo passive plugin `autobio.detent`);
//! - [`eccentric`]: the vortex mixer's orbit from two negatively coupled hinges (pure MJCF);
//! - [`liquid`]: quasi-static liquid (surface normal as a damped spherical pendulum, surface height
//!   from the volume) with exact volume bookkeeping between containers.
//!
//! `plugin` (feature `plugin`, which the runtime turns on) is the only code in autobio that
//! touches MuJoCo's plugin FFI; call `register` before compiling a model that names `autobio.*`
//! plugins. Without it the crate is pure math and MJCF text, with no MuJoCo: `labware` builds its
//! mechanisms and processes on it. This crate generates MJCF fragments and computes forces and
//! geometry; it does not assemble scenes (runtime) or know about protocols.
//!
//! Its tests are beside the code (the force and SDF math) and the workspace's tests/settle.rs,
//! tests/vortex_mixing.rs and tests/liquid_scene.rs (the plugins inside MuJoCo).

pub mod detent;
pub mod eccentric;
pub mod liquid;
#[cfg(feature = "plugin")]
mod plugin;
pub mod scenes;
pub mod thread;

#[cfg(feature = "plugin")]
pub use plugin::{PluginError, instance_errors, register};
