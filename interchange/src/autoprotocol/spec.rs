//! Autoprotocol's document as typed values, written from its published specification (the ASC
//! documents' `Specification/`: refs, instructions, time constraints; it has no JSON Schema) and
//! from what autoprotocol-python writes where the specification is silent (`thermocycle`'s
//! groups, `provision`). Quantities stay text here (`"25:microliter"`); `units.rs` reads them.
//! Only the instructions the importer realises or drops are typed; every other `op` is known by
//! name (`fate`), so an unknown field of a realised one is named rather than ignored silently
//! where it would change what happens (a gradient, a multi-channel shape).

use serde::{Deserialize, Serialize};

/// A container the protocol uses: a new one of a type, or an existing one by id.
#[derive(Clone, Debug, Default, Deserialize, Serialize, PartialEq)]
pub struct Ref {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub id: Option<String>,
    /// The container type's short name (`96-pcr`, `micro-1.5`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub new: Option<String>,
    /// Not in the specification's ref, but in autoprotocol-python's manifests and Strateos'
    /// previews: an existing container's type.
    #[serde(default, rename = "type", skip_serializing_if = "Option::is_none")]
    pub container_type: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub store: Option<Store>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub discard: Option<bool>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cover: Option<String>,
}

#[derive(Clone, Debug, Default, Deserialize, Serialize, PartialEq)]
pub struct Store {
    #[serde(rename = "where", default, skip_serializing_if = "Option::is_none")]
    pub where_: Option<String>,
}

/// `liquid_handle`: locations visited in order, each with the transports done there (a negative
/// volume draws, a positive one expels; a transport without a volume is a move).
#[derive(Clone, Debug, Deserialize, Serialize)]
pub struct LiquidHandle {
    pub locations: Vec<Location>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mode: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shape: Option<Shape>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mode_params: Option<serde_json::Value>,
}

#[derive(Clone, Debug, Deserialize, Serialize)]
pub struct Location {
    /// An aliquot, `ref/well` (a 0-based index or a well name).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub location: Option<String>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub transports: Vec<Transport>,
}

#[derive(Clone, Debug, Deserialize, Serialize)]
pub struct Transport {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub volume: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mode_params: Option<TransportModeParams>,
}

#[derive(Clone, Debug, Deserialize, Serialize)]
pub struct TransportModeParams {
    /// `air`, `default`, `viscous`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub liquid_class: Option<String>,
}

/// Which tips a liquid handling uses at once: 1 x 1 is a single channel.
#[derive(Clone, Debug, Deserialize, Serialize)]
pub struct Shape {
    pub rows: u32,
    pub columns: u32,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub format: Option<String>,
}

/// The legacy `pipette` instruction: groups of transfers, distributions, consolidations, mixes.
#[derive(Clone, Debug, Deserialize)]
pub struct Pipette {
    pub groups: Vec<PipetteGroup>,
}

#[derive(Clone, Debug, Deserialize)]
pub struct PipetteGroup {
    #[serde(default)]
    pub transfer: Vec<Transfer>,
    #[serde(default)]
    pub distribute: Option<Distribute>,
    #[serde(default)]
    pub consolidate: Option<Consolidate>,
    #[serde(default)]
    pub mix: Vec<serde_json::Value>,
}

#[derive(Clone, Debug, Deserialize)]
pub struct Transfer {
    pub from: String,
    pub to: String,
    pub volume: String,
}

#[derive(Clone, Debug, Deserialize)]
pub struct Distribute {
    pub from: String,
    pub to: Vec<WellVolume>,
}

#[derive(Clone, Debug, Deserialize)]
pub struct Consolidate {
    pub from: Vec<WellVolume>,
    pub to: String,
}

#[derive(Clone, Debug, Deserialize, Serialize)]
pub struct WellVolume {
    pub well: String,
    pub volume: String,
}

/// `provision`: a resource (a reagent from the lab's stock) put into wells.
#[derive(Clone, Debug, Deserialize, Serialize)]
pub struct Provision {
    pub resource_id: String,
    pub to: Vec<WellVolume>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub measurement_mode: Option<String>,
}

/// `thermocycle`: a container's profile, as groups of steps each repeated `cycles` times.
#[derive(Clone, Debug, Deserialize, Serialize)]
pub struct Thermocycle {
    pub object: String,
    pub groups: Vec<CycleGroup>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub volume: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lid_temperature: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dataref: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dyes: Option<serde_json::Value>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub melting: Option<serde_json::Value>,
}

#[derive(Clone, Debug, Deserialize, Serialize)]
pub struct CycleGroup {
    pub cycles: u32,
    pub steps: Vec<CycleStep>,
}

#[derive(Clone, Debug, Deserialize, Serialize)]
pub struct CycleStep {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub temperature: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gradient: Option<serde_json::Value>,
    pub duration: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub read: Option<bool>,
}

/// `spin`.
#[derive(Clone, Debug, Deserialize, Serialize)]
pub struct Spin {
    pub object: String,
    pub acceleration: String,
    pub duration: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub flow_direction: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub spin_direction: Option<Vec<String>>,
}

/// `incubate`.
#[derive(Clone, Debug, Deserialize, Serialize)]
pub struct Incubate {
    pub object: String,
    #[serde(rename = "where")]
    pub where_: String,
    pub duration: String,
    #[serde(default)]
    pub shaking: bool,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub co2_percent: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub target_temperature: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shaking_params: Option<serde_json::Value>,
}

/// An instruction that names only its container (`seal`, `cover` and their undoing).
#[derive(Clone, Debug, Deserialize)]
pub struct OnObject {
    pub object: String,
}

/// A point in time a constraint names: exactly one of these.
#[derive(Clone, Debug, Default, Deserialize, Serialize, PartialEq)]
pub struct TimePoint {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub instruction_start: Option<usize>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub instruction_end: Option<usize>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ref_start: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ref_end: Option<String>,
}

#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
pub struct TimeConstraint {
    pub from: TimePoint,
    pub to: TimePoint,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub less_than: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub more_than: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ideal: Option<serde_json::Value>,
}
