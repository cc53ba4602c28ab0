//! Opentrons commands by what becomes of them here: realised as a step or a start state, dropped
//! (what a gantry does that a hand-held pipette has no step for: tips, homing, moves between
//! wells, blow-out and touch-tip, which our dispense already does), or refused (what has no robot
//! realisation on our bench: magnets, plate readers, stackers, the temperature module and the
//! heater-shaker, moving labware with a gripper). The typed parameters of every realised command
//! are read from its `params` with serde, so a missing or ill-typed field is named.

use serde::Deserialize;
use std::collections::BTreeMap;

/// What becomes of a command type.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Fate {
    Realised,
    /// Dropped, with why (said once per type, as a W0011 warning at its first command).
    Dropped(&'static str),
    /// Refused, with why and what to do instead.
    Refused(&'static str, &'static str),
}

const GANTRY: &str = "a gantry's own motion: the hand-held pipette's step moves there itself";
const TIPS: &str =
    "the hand-held pipette's tip is part of it here: tips are not picked up or dropped";
/// Why a module's command is refused (kept as an instrument-only step on request).
pub const NO_MODULE: &str = "the instrument has no model on our bench";
const ASK: &str = "remove the command (or the module's steps) from the protocol, or write the step in our language by hand";

/// The fate of a command type.
pub fn fate(command_type: &str) -> Fate {
    match command_type {
        "loadLabware"
        | "loadPipette"
        | "loadModule"
        | "loadLiquid"
        | "aspirate"
        | "dispense"
        | "waitForDuration"
        | "thermocycler/openLid"
        | "thermocycler/closeLid"
        | "thermocycler/runProfile"
        | "thermocycler/runExtendedProfile" => Fate::Realised,
        "home"
        | "moveToWell"
        | "moveToAddressableArea"
        | "moveToAddressableAreaForDropTip"
        | "moveToCoordinates"
        | "moveRelative"
        | "savePosition"
        | "retractAxis"
        | "prepareToAspirate"
        | "configureForVolume"
        | "configureNozzleLayout" => Fate::Dropped(GANTRY),
        "pickUpTip" | "dropTip" | "dropTipInPlace" | "verifyTipPresence" | "getTipPresence" => {
            Fate::Dropped(TIPS)
        }
        "airGapInPlace" => Fate::Refused(
            "an air gap: the hand-held pipette draws liquid only, and its dispense would push out more than it drew",
            ASK,
        ),
        "touchTip" | "blowout" | "blowOutInPlace" => Fate::Dropped(
            "done by our dispense: the tip is pressed to blow-out and drawn out along the tube's wall",
        ),
        "comment" => Fate::Dropped("a comment for the operator"),
        "waitForResume" | "pause" => {
            Fate::Dropped("a pause for a person: nobody resumes a simulation")
        }
        "thermocycler/setTargetLidTemperature"
        | "thermocycler/waitForLidTemperature"
        | "thermocycler/deactivateLid" => {
            Fate::Dropped("the cycler's lid is heated to 105 °C whenever it runs")
        }
        "thermocycler/deactivateBlock" => {
            Fate::Dropped("the cycler's block idles once its profile is done")
        }
        "thermocycler/setTargetBlockTemperature" | "thermocycler/waitForBlockTemperature" => {
            Fate::Dropped(
                "a block held at a temperature outside a profile: the cycler runs profiles only (a hold of its own is a one-step profile)",
            )
        }
        "moveLabware" => Fate::Refused(
            "moving labware between deck slots has no step here: the 2F-85 does not open across a plate's 85.5 mm",
            ASK,
        ),
        "aspirateInPlace" | "dispenseInPlace" | "liquidProbe" | "tryLiquidProbe" => Fate::Refused(
            "a pipetting command without a well: the hand-held pipette's steps name the container",
            "give the command its labware and well (`aspirate`, `dispense`)",
        ),
        "custom" => Fate::Refused(
            "a legacy command known only by its text (an analysis of an API level below 2.14)",
            "analyse the protocol at API level 2.14 or above",
        ),
        t if t.starts_with("magneticModule/")
            || t.starts_with("temperatureModule/")
            || t.starts_with("heaterShaker/")
            || t.starts_with("absorbanceReader/")
            || t.starts_with("flexStacker/")
            || t.starts_with("vacuumModule/") =>
        {
            Fate::Refused(NO_MODULE, ASK)
        }
        _ => Fate::Refused(
            "a command type the importer does not know",
            "check the command type's spelling, or remove the command",
        ),
    }
}

/// `loadLabware`.
#[derive(Clone, Debug, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct LoadLabware {
    /// Absent in some analyses, which give it in the result.
    pub labware_id: Option<String>,
    pub load_name: String,
    pub namespace: String,
    pub version: u32,
    pub location: Location,
    pub display_name: Option<String>,
}

impl LoadLabware {
    pub fn uri(&self) -> String {
        format!("{}/{}/{}", self.namespace, self.load_name, self.version)
    }
}

/// Where labware or a module is loaded.
#[derive(Clone, Debug, Deserialize)]
#[serde(untagged)]
pub enum Location {
    Slot {
        #[serde(rename = "slotName")]
        slot_name: String,
    },
    Module {
        #[serde(rename = "moduleId")]
        module_id: String,
    },
    OnLabware {
        #[serde(rename = "labwareId")]
        labware_id: String,
    },
    Area {
        #[serde(rename = "addressableAreaName")]
        area: String,
    },
    /// `"offDeck"`.
    Named(String),
}

/// `loadPipette`.
#[derive(Clone, Debug, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct LoadPipette {
    pub pipette_id: Option<String>,
    pub pipette_name: String,
    #[serde(default)]
    pub mount: String,
}

/// `loadModule`.
#[derive(Clone, Debug, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct LoadModule {
    pub module_id: Option<String>,
    pub model: String,
    pub location: Location,
}

/// `loadLiquid`.
#[derive(Clone, Debug, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct LoadLiquid {
    pub liquid_id: String,
    pub labware_id: String,
    pub volume_by_well: BTreeMap<String, f64>,
}

/// `aspirate` and `dispense`.
#[derive(Clone, Debug, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct Pipetting {
    pub pipette_id: String,
    pub labware_id: String,
    pub well_name: String,
    pub volume: f64,
}

/// `waitForDuration`.
#[derive(Clone, Debug, Deserialize)]
pub struct WaitForDuration {
    pub seconds: f64,
}

/// A module command that names only its module.
#[derive(Clone, Debug, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct ModuleRef {
    pub module_id: String,
}

/// A profile's hold.
#[derive(Clone, Debug, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct ProfileStep {
    pub celsius: f64,
    pub hold_seconds: f64,
}

/// `thermocycler/runProfile`.
#[derive(Clone, Debug, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct RunProfile {
    pub module_id: String,
    pub profile: Vec<ProfileStep>,
}

/// An element of an extended profile: a hold, or a cycle of holds.
#[derive(Clone, Debug, Deserialize)]
#[serde(untagged)]
pub enum ProfileElement {
    Cycle {
        steps: Vec<ProfileStep>,
        repetitions: u32,
    },
    Step(ProfileStep),
}

/// `thermocycler/runExtendedProfile`.
#[derive(Clone, Debug, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct RunExtendedProfile {
    pub module_id: String,
    pub profile_elements: Vec<ProfileElement>,
}

/// A flat profile (`runProfile`, which an analysis writes with a cycle's holds repeated) as
/// elements: the whole list as one cycle when it is a block of holds repeated, else its holds.
pub fn as_cycles(holds: Vec<ProfileStep>) -> Vec<ProfileElement> {
    let n = holds.len();
    let same = |a: &ProfileStep, b: &ProfileStep| {
        a.celsius == b.celsius && a.hold_seconds == b.hold_seconds
    };
    for period in 1..=n / 2 {
        if n.is_multiple_of(period) && (period..n).all(|i| same(&holds[i], &holds[i - period])) {
            let repetitions = u32::try_from(n / period).unwrap_or(u32::MAX);
            let mut steps = holds;
            steps.truncate(period);
            return vec![ProfileElement::Cycle { steps, repetitions }];
        }
    }
    holds.into_iter().map(ProfileElement::Step).collect()
}

/// A profile in our language's words: `95 °C 30 s, 30 x [95 °C 15 s, ...]`.
pub fn profile_text(elements: &[ProfileElement]) -> String {
    let hold = |s: &ProfileStep| {
        format!(
            "{} °C {} s",
            crate::draft::number(s.celsius),
            crate::draft::number(s.hold_seconds)
        )
    };
    elements
        .iter()
        .map(|e| match e {
            ProfileElement::Step(s) => hold(s),
            ProfileElement::Cycle { steps, repetitions } => format!(
                "{repetitions} x [{}]",
                steps.iter().map(hold).collect::<Vec<_>>().join(", ")
            ),
        })
        .collect::<Vec<_>>()
        .join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_command_type_has_a_fate_and_profiles_read_as_ours() {
        assert_eq!(fate("aspirate"), Fate::Realised);
        assert!(matches!(fate("pickUpTip"), Fate::Dropped(_)));
        assert!(matches!(fate("magneticModule/engage"), Fate::Refused(..)));
        assert!(matches!(
            fate("heaterShaker/openLabwareLatch"),
            Fate::Refused(..)
        ));
        assert!(matches!(fate("frobnicate"), Fate::Refused(..)));
        let elements: Vec<ProfileElement> = serde_json::from_str(
            r#"[{"celsius": 95, "holdSeconds": 30},
                {"repetitions": 30, "steps": [{"celsius": 95, "holdSeconds": 15}, {"celsius": 55.5, "holdSeconds": 30}]},
                {"celsius": 4, "holdSeconds": 60}]"#,
        )
        .unwrap();
        assert_eq!(
            profile_text(&elements),
            "95 °C 30 s, 30 x [95 °C 15 s, 55.5 °C 30 s], 4 °C 60 s"
        );
        let hold = |celsius, hold_seconds| ProfileStep {
            celsius,
            hold_seconds,
        };
        let flat: Vec<ProfileStep> = (0..3)
            .flat_map(|_| [hold(95.0, 15.0), hold(55.0, 30.0)])
            .collect();
        assert_eq!(
            profile_text(&as_cycles(flat)),
            "3 x [95 °C 15 s, 55 °C 30 s]"
        );
        assert_eq!(
            profile_text(&as_cycles(vec![hold(95.0, 30.0), hold(68.0, 60.0)])),
            "95 °C 30 s, 68 °C 60 s"
        );
    }
}
