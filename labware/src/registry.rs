//! The one place labware kinds meet their simulation models: each line of [`registry!`] names a
//! model type and the catalogue kinds it simulates, with the parameters each kind starts from.
//! [`Model`] is the closed, serialisable result (the compiled task carries it, so a task is
//! self-contained); "has a simulation model" is [`Model::for_kind`] returning one.

use crate::model::Instrument;
use crate::{rack, thermal_cycler, tube};
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
        }
    };
}

registry! {
    ThermalCycler(thermal_cycler::Params) { "thermal_cycler" => thermal_cycler::Params::default() },
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
        assert!(!simulated.contains(&"centrifuge_5430"));
        for k in simulated {
            let m = Model::for_kind(k).unwrap();
            let back: Model = serde_json::from_value(serde_json::to_value(&m).unwrap()).unwrap();
            assert_eq!(back, m);
            assert!(m.instrument().is_some());
        }
        assert!(Model::Unmodelled.instrument().is_none());
    }
}
