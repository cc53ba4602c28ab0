//! The one place labware kinds meet their simulation models: the crate root invokes
//! [`registry!`] once, one line per model, and each line declares the model's module and names
//! the catalogue kinds it simulates with the parameters each kind starts from. Adding a model is
//! its file and its line. [`crate::Model`] is the closed, serialisable result (the compiled task
//! carries it, so a task is self-contained); "has a simulation model" is
//! [`crate::Model::for_kind`] returning one.

/// Declares every model module (`module::Variant { "kind" => params, ... }`: the module's
/// `Params` is the model) and generates [`crate::Model`], `MODELLED` (every kind with a model)
/// and `MODEL_MODULES` (every model's module), in registry order.
macro_rules! registry {
    ($($module:ident :: $variant:ident { $($kind:literal => $make:expr),+ $(,)? }),+ $(,)?) => {
        $(pub mod $module;)+

        /// A labware item's simulation model with its parameters, tagged by model in JSON.
        #[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
        #[serde(tag = "kind", rename_all = "snake_case")]
        pub enum Model {
            $($variant($module::Params),)+
            /// A catalogue kind without a simulation model yet: it compiles and is checked, and
            /// the runtime refuses to build it.
            Unmodelled,
        }

        /// Every kind with a model, in registry order.
        pub const MODELLED: &[&str] = &[$($($kind,)+)+];

        /// Every model's module (its file under `labware/src/`), in registry order.
        pub const MODEL_MODULES: &[&str] = &[$(stringify!($module),)+];

        impl Model {
            /// The model of a catalogue kind, with the kind's parameters; `None`: not simulated.
            pub fn for_kind(kind: &str) -> Option<Model> {
                match kind {
                    $($($kind => Some(Model::$variant($make)),)+)+
                    _ => None,
                }
            }

            /// The model as the trait the runtime, judge and expert use.
            pub fn instrument(&self) -> Option<&dyn $crate::model::Instrument> {
                match self {
                    $(Model::$variant(p) => Some(p),)+
                    Model::Unmodelled => None,
                }
            }

            /// The model made for the item's declared start (see
            /// [`Instrument::start_from`](crate::model::Instrument::start_from)).
            pub fn for_start(mut self, initial: &std::collections::BTreeMap<String, String>) -> Model {
                use $crate::model::Instrument as _;
                match &mut self {
                    $(Model::$variant(p) => p.start_from(initial),)+
                    Model::Unmodelled => {}
                }
                self
            }

            /// The model running `programmes` ([`crate::run`]), in order.
            pub fn with_programmes(mut self, programmes: Vec<$crate::run::Programme>) -> Model {
                use $crate::model::Instrument as _;
                match &mut self {
                    $(Model::$variant(p) => p.set_programmes(programmes),)+
                    Model::Unmodelled => {}
                }
                self
            }
        }
    };
}

pub(crate) use registry;

#[cfg(test)]
mod tests {
    use crate::{MODELLED, Model};

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
            // A run is measured by every model that runs ([`crate::run`]), apart from its part.
            let declared: Vec<&str> = k
                .parts
                .iter()
                .map(|p| p.part)
                .filter(|p| *p != crate::run::RUN)
                .collect();
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
                finger_contacts: Vec::new(),
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
