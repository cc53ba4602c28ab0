//! Autoprotocol's document as typed values, written from its published specification (the ASC
//! documents' `Specification/`: refs, instructions, time constraints; it has no JSON Schema) and
//! from what autoprotocol-python writes where the specification is silent (`thermocycle`'s
//! groups, `provision`). Quantities stay text here (`"25:microliter"`); `units.rs` reads them.
//! Only the instructions the importer realises are typed (the others are known by their `op` in
//! `lower.rs`). Fields that would change what happens are typed and checked there (a gradient, a
//! multi-channel `shape`, a `mode`); other fields are ignored (a transfer's tip positions and
//! flow rates: the hand-held pipette's own).

use serde::Deserialize;

/// A container the protocol uses: a new one of a type, or an existing one by id.
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
pub struct Ref {
    #[serde(default)]
    pub id: Option<String>,
    /// The container type's short name (`96-pcr`, `micro-1.5`).
    #[serde(default)]
    pub new: Option<String>,
    /// Not in the specification's ref, but in autoprotocol-python's manifests and Strateos'
    /// previews: an existing container's type.
    #[serde(default, rename = "type")]
    pub container_type: Option<String>,
    #[serde(default)]
    pub store: Option<Store>,
    #[serde(default)]
    pub discard: Option<bool>,
    #[serde(default)]
    pub cover: Option<String>,
}

#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
pub struct Store {
    #[serde(rename = "where", default)]
    pub where_: Option<String>,
}

/// `liquid_handle`: locations visited in order, each with the transports done there (a negative
/// volume draws, a positive one expels; a transport without a volume is a move).
#[derive(Clone, Debug, Deserialize)]
pub struct LiquidHandle {
    pub locations: Vec<Location>,
    #[serde(default)]
    pub mode: Option<String>,
    #[serde(default)]
    pub shape: Option<Shape>,
    #[serde(default)]
    pub mode_params: Option<serde_json::Value>,
}

#[derive(Clone, Debug, Deserialize)]
pub struct Location {
    /// An aliquot, `ref/well` (a 0-based index or a well name).
    #[serde(default)]
    pub location: Option<String>,
    #[serde(default)]
    pub transports: Vec<Transport>,
}

#[derive(Clone, Debug, Deserialize)]
pub struct Transport {
    #[serde(default)]
    pub volume: Option<String>,
    #[serde(default)]
    pub mode_params: Option<TransportModeParams>,
}

#[derive(Clone, Debug, Deserialize)]
pub struct TransportModeParams {
    /// `air`, `default`, `viscous`.
    #[serde(default)]
    pub liquid_class: Option<String>,
}

/// Which tips a liquid handling uses at once: 1 x 1 is a single channel.
#[derive(Clone, Debug, Deserialize)]
pub struct Shape {
    pub rows: u32,
    pub columns: u32,
    #[serde(default)]
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

#[derive(Clone, Debug, Deserialize)]
pub struct WellVolume {
    pub well: String,
    pub volume: String,
}

/// `provision`: a resource (a reagent from the lab's stock) put into wells.
#[derive(Clone, Debug, Deserialize)]
pub struct Provision {
    pub resource_id: String,
    pub to: Vec<WellVolume>,
    #[serde(default)]
    pub measurement_mode: Option<String>,
}

/// `thermocycle`: a container's profile, as groups of steps each repeated `cycles` times.
#[derive(Clone, Debug, Deserialize)]
pub struct Thermocycle {
    pub object: String,
    pub groups: Vec<CycleGroup>,
    #[serde(default)]
    pub volume: Option<String>,
    #[serde(default)]
    pub lid_temperature: Option<String>,
    #[serde(default)]
    pub dataref: Option<String>,
    #[serde(default)]
    pub dyes: Option<serde_json::Value>,
    #[serde(default)]
    pub melting: Option<serde_json::Value>,
}

#[derive(Clone, Debug, Deserialize)]
pub struct CycleGroup {
    pub cycles: u32,
    pub steps: Vec<CycleStep>,
}

#[derive(Clone, Debug, Deserialize)]
pub struct CycleStep {
    #[serde(default)]
    pub temperature: Option<String>,
    #[serde(default)]
    pub gradient: Option<serde_json::Value>,
    pub duration: String,
    #[serde(default)]
    pub read: Option<bool>,
}

/// A point in time a constraint names: exactly one of these.
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
pub struct TimePoint {
    #[serde(default)]
    pub instruction_start: Option<usize>,
    #[serde(default)]
    pub instruction_end: Option<usize>,
    #[serde(default)]
    pub ref_start: Option<String>,
    #[serde(default)]
    pub ref_end: Option<String>,
}

#[derive(Clone, Debug, Deserialize, PartialEq)]
pub struct TimeConstraint {
    pub from: TimePoint,
    pub to: TimePoint,
    #[serde(default)]
    pub less_than: Option<String>,
    #[serde(default)]
    pub more_than: Option<String>,
    #[serde(default)]
    pub ideal: Option<serde_json::Value>,
}
