//! Parametric labware: each kind generates its MJCF from parameters, names its affordances (grasp
//! frames, joints, press points) for the primitives, and carries its instrument logic (latches,
//! detents) for the runtime.
//!
//! No meshes are read or written: geometry is primitive geoms sized from parameters
//! (dimensions from the public description of the instruments). This crate knows nothing of
//! protocols, MuJoCo's API or robots: it produces text and plain numbers.

pub mod catalogue;
pub mod frame;
pub mod thermal_cycler;

pub use catalogue::{
    Button, ButtonEffect, KINDS, LabwareKind, PanelParam, PartState, SlotLayout, Slots, kind,
};
pub use frame::{Pose, Quat, Vec3};
