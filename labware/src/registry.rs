//! The one place labware kinds meet their simulation models: each line of [`registry!`] names a
//! model type and the catalogue kinds it simulates, with the parameters each kind starts from.
//! [`Model`] is the closed, serialisable result (the compiled task carries it, so a task is
//! self-contained); "has a simulation model" is [`Model::for_kind`] returning one.

use crate::model::Instrument;
use crate::{
    centrifuge, centrifuge_mini, pipette, rack, thermal_cycler, thermal_mixer, tube, vortex_mixer,
};
use serde::{Deserialize, Serialize};

macro_rules! registry {
    ($($variant:ident($ty:ty) { $($kind:literal => $make:expr),+ $(,)? }),+ $(,)?) => {
        /// A labware item's simulation model with its parameters, tagged by model in JSON.
        #[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
        #[serde(tag = "kind", rename_all = "snake_case")]
        pub enum Model {
            $($variant($ty),)+
            /// A catalogue kind without a simulation model yet: it compiles and is checked, and
            /// the runtime refuses to build it.
            Unmodelled,
        }

        /// Every kind with a model, in registry order.
        pub const MODELLED: &[&str] = &[$($($kind,)+)+];

        impl Model {
            /// The model of a catalogue kind, with the kind's parameters; `None`: not simulated.
            pub fn for_kind(kind: &str) -> Option<Model> {
                match kind {
                    $($($kind => Some(Model::$variant($make)),)+)+
                    _ => None,
                }
            }

            /// The model as the trait the runtime, judge and expert use.
            pub fn instrument(&self) -> Option<&dyn Instrument> {
                match self {
                    $(Model::$variant(p) => Some(p),)+
                    Model::Unmodelled => None,
                }
            }

            /// The model made for the item's declared start (see [`Instrument::start_from`]).
            pub fn for_start(mut self, initial: &std::collections::BTreeMap<String, String>) -> Model {
                match &mut self {
                    $(Model::$variant(p) => p.start_from(initial),)+
                    Model::Unmodelled => {}
                }
                self
            }
        }
    };
}

registry! {
    ThermalCycler(thermal_cycler::Params) { "thermal_cycler" => thermal_cycler::Params::default() },
    CentrifugeMini(centrifuge_mini::Params) { "centrifuge_mini" => centrifuge_mini::Params::default() },
    Centrifuge(centrifuge::Params) {
        "centrifuge_5430" => centrifuge::Params::eppendorf_5430(),
        "centrifuge_5910" => centrifuge::Params::eppendorf_5910(),
    },
    ThermalMixer(thermal_mixer::Params) { "thermal_mixer" => thermal_mixer::Params::default() },
    VortexMixer(vortex_mixer::Params) { "vortex_mixer" => vortex_mixer::Params::default() },
    Rack(rack::Params) {
        "tube_rack" => rack::Params::tube_rack(),
        "microtube_rack" => rack::Params::microtube_rack(),
    },
    Tube(tube::Params) {
        "tube_50ml" => tube::Params::conical_50ml(),
        "tube_15ml" => tube::Params::conical_15ml(),
        "tube_1_5ml" => tube::Params::microtube(),
        "cryovial" => tube::Params::cryovial(),
    },
    Pipette(pipette::Params) { "pipette" => pipette::Params::p1000() },
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_model_is_for_a_catalogue_kind_and_round_trips() {
        let simulated: Vec<&str> = crate::KINDS
            .iter()
            .filter(|k| k.simulated())
            .map(|k| k.name)
            .collect();
        assert!(simulated.contains(&"thermal_cycler") && simulated.contains(&"tube_50ml"));
        assert!(simulated.contains(&"vortex_mixer"));
        for k in simulated {
            let m = Model::for_kind(k).unwrap();
            let back: Model = serde_json::from_value(serde_json::to_value(&m).unwrap()).unwrap();
            assert_eq!(back, m);
            assert!(m.instrument().is_some());
        }
        assert!(Model::Unmodelled.instrument().is_none());
        // And the other way: every registry line names a catalogue kind.
        for k in MODELLED {
            assert!(crate::kind(k).is_some_and(|k| k.simulated()), "{k}");
        }
    }

    /// A model measures the one part its kind's states are about (`Instrument::part`), the
    /// catalogue's, and a kind without parts has nothing to measure.
    #[test]
    fn every_model_measures_its_kinds_part() {
        for k in crate::KINDS.iter().filter(|k| k.simulated()) {
            let model = Model::for_kind(k.name).unwrap();
            let part = model.instrument().unwrap().part().map(|(name, _)| name);
            let declared: Vec<&str> = k.parts.iter().map(|p| p.part).collect();
            assert_eq!(part.into_iter().collect::<Vec<_>>(), declared, "{}", k.name);
        }
    }

    /// Every slot the catalogue names has a seat in the holder's model, and no item a holder
    /// takes may count as standing in a neighbouring slot: its `slot_xy` is under half the
    /// distance between the two closest seats.
    #[test]
    fn holders_seat_every_catalogue_slot_and_slots_are_told_apart() {
        use crate::frame::position;
        for k in crate::KINDS.iter().filter(|k| k.simulated()) {
            let Some(slots) = k.slots else { continue };
            let model = Model::for_kind(k.name).unwrap();
            let state = crate::LabwareState {
                name: "holder".into(),
                pose: crate::frame::Pose::identity(),
                joints: Default::default(),
                parts: Default::default(),
                logic: Default::default(),
                touched_by: Vec::new(),
            };
            let seats: Vec<[f64; 3]> = slots
                .layout
                .names()
                .iter()
                .map(|s| {
                    let seat = model.instrument().unwrap().slot_seat(s, &state);
                    position(&seat.unwrap_or_else(|| panic!("{}: no seat for {s}", k.name)))
                })
                .collect();
            let mut closest = f64::INFINITY;
            for (i, a) in seats.iter().enumerate() {
                for b in &seats[i + 1..] {
                    closest = closest.min((a[0] - b[0]).hypot(a[1] - b[1]));
                }
            }
            for item in slots.accepts {
                let xy = crate::kind(item).unwrap().tolerance("slot_xy").unwrap();
                assert!(
                    xy < closest / 2.0,
                    "{item} in {}: slot_xy {xy} m, seats {closest} m apart",
                    k.name
                );
            }
        }
    }
}
