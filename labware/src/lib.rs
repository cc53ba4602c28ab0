//! Parametric labware: the closed catalogue of kinds the protocol language knows, and a simulation
//! model per kind that has one. A model ([`model::Instrument`]) generates its MJCF from parameters,
//! names its joints, switches and mechanisms by role, resets from declared part states, runs its
//! per-step logic, reads out part states for the judge and offers affordances for the expert.
//! The `registry!` line in this file is the one place a kind meets its model ([`registry`]).
//!
//! No mesh files are read or written: geometry is primitive geoms sized from parameters, plus the
//! SDF meshes the thread plugin generates from a model's thread parameters (dimensions
//! from the public description of the instruments). This crate knows nothing of protocols,
//! MuJoCo's API or robots: it produces text and plain numbers.
//!
//! Its tests are beside the code (each model's unit tests, the registry's) and the workspace's
//! tests/labware_models.rs and tests/processes.rs, which simulate the models.

pub mod catalogue;
pub mod definition;
pub mod display;
pub mod frame;
pub mod lid;
pub mod liquid_view;
pub mod mjcf;
pub mod model;
pub mod process;
pub mod published;
pub mod registry;
pub mod run;

pub use catalogue::{
    Button, ButtonEffect, KINDS, LabwareKind, PanelParam, PartState, SlotLayout, Slots, kind,
};
pub use frame::{Pose, Rot, Vec3};
pub use model::{
    Affordance, Display, Effects, Instrument, Joints, LabwareState, Liquid, Logic, Measure,
    Mechanism, Opening, Panel, Part, Symmetry,
};

// The registry: one line per simulation model (its module, its variant of `Model`, the kinds it
// simulates and the parameters each starts from).
registry::registry! {
    thermal_cycler::ThermalCycler {
        "thermal_cycler" => thermal_cycler::Params::default(),
        "thermal_cycler_96" => thermal_cycler::Params::with_96_wells(),
    },
    centrifuge_mini::CentrifugeMini { "centrifuge_mini" => centrifuge_mini::Params::default() },
    centrifuge::Centrifuge {
        "centrifuge_5430" => centrifuge::Params::eppendorf_5430(),
        "centrifuge_5910" => centrifuge::Params::eppendorf_5910(),
    },
    thermal_mixer::ThermalMixer { "thermal_mixer" => thermal_mixer::Params::default() },
    vortex_mixer::VortexMixer { "vortex_mixer" => vortex_mixer::Params::default() },
    rack::Rack {
        "tube_rack" => rack::Params::tube_rack(),
        "microtube_rack" => rack::Params::microtube_rack(),
        "tuberack_24_1_5ml" => rack::Params::defined("tuberack_24_1_5ml"),
        "tuberack_6_50ml" => rack::Params::defined("tuberack_6_50ml"),
        "aluminium_block_96_pcr" => rack::Params::defined("aluminium_block_96_pcr"),
    },
    tube::Tube {
        "tube_50ml" => tube::Params::conical_50ml(),
        "tube_15ml" => tube::Params::conical_15ml(),
        "tube_1_5ml" => tube::Params::microtube(),
        "cryovial" => tube::Params::cryovial(),
        "tube_0_2ml" => tube::Params::pcr_tube(),
    },
    pipette::Pipette {
        "pipette" => pipette::Params::p1000(),
        "pipette_p200" => pipette::Params::p200(),
    },
}

/// The kinds that stand on the bench alone and hold still, unused: the racks and blocks. What a
/// `distractors` perturbation may place (docs/robustness.md).
pub fn distractor_kinds() -> Vec<&'static str> {
    KINDS
        .iter()
        .map(|k| k.name)
        .filter(|k| matches!(Model::for_kind(k), Some(Model::Rack(_))))
        .collect()
}
