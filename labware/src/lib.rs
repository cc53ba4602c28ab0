//! Parametric labware: the closed catalogue of kinds the protocol language knows, and a simulation
//! model per kind that has one. A model ([`model::Instrument`]) generates its MJCF from parameters,
//! names its joints, switches and mechanisms by role, resets from declared part states, runs its
//! per-step logic, reads out part states for the judge and offers affordances for the expert.
//! [`registry`] is the one place a kind meets its model.
//!
//! No mesh files are read or written: geometry is primitive geoms sized from parameters, plus the
//! SDF meshes the thread plugin generates from a model's thread parameters (dimensions
//! from the public description of the instruments). This crate knows nothing of protocols,
//! MuJoCo's API or robots: it produces text and plain numbers.

pub mod catalogue;
pub mod centrifuge;
pub mod centrifuge_mini;
pub mod display;
pub mod frame;
pub mod lid;
pub mod liquid_view;
pub mod mjcf;
pub mod model;
pub mod pipette;
pub mod process;
pub mod rack;
pub mod registry;
pub mod thermal_cycler;
pub mod thermal_mixer;
pub mod tube;
pub mod vortex_mixer;

pub use catalogue::{
    Button, ButtonEffect, KINDS, LabwareKind, PanelParam, PartState, SlotLayout, Slots, kind,
};
pub use frame::{Pose, Rot, Vec3};
pub use model::{
    Affordance, Display, Effects, Instrument, Joints, LabwareState, Liquid, Logic, Measure,
    Mechanism, Panel, Part, Symmetry,
};
pub use registry::Model;
