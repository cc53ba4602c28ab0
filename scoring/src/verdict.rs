//! Verdicts: every success predicate evaluated on labware state, each with its measured value,
//! target and tolerance. Pure functions of recorded state, so a recording can be re-scored offline.

use compiler::{LabwareParams, Predicate, Task};
use runtime::LabwareState;
use serde::{Deserialize, Serialize};

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PredicateValue {
    pub text: String,
    pub holds: bool,
    /// The measured joint angle (rad) the predicate looks at, its target and the tolerance.
    pub value: f64,
    pub target: f64,
    pub tolerance: f64,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Verdict {
    pub success: bool,
    pub predicates: Vec<PredicateValue>,
}

fn evaluate(task: &Task, pred: &Predicate, states: &[LabwareState]) -> PredicateValue {
    let spec = task.labware.iter().find(|l| l.name == pred.labware);
    let state = states.iter().find(|s| s.name == pred.labware);
    let (Some(spec), Some(state)) = (spec, state) else {
        return PredicateValue {
            text: pred.text.clone(),
            holds: false,
            value: f64::NAN,
            target: f64::NAN,
            tolerance: pred.tolerance,
        };
    };
    let LabwareParams::ThermalCycler(p) = &spec.params;
    let lid = state.joints.get("lid").copied().unwrap_or(f64::NAN);
    let lever = state.joints.get("lever").copied().unwrap_or(f64::NAN);
    let (value, target, extra) = match pred.state.as_str() {
        "closed" => (lid, p.lid_closed, true),
        "locked" => (lever, p.lever_pressed, state.locked),
        "open" => (lid, p.lid_open, true),
        _ => (lever, p.lever_raised, !state.locked),
    };
    let holds = (value - target).abs() < pred.tolerance && extra;
    PredicateValue {
        text: pred.text.clone(),
        holds,
        value,
        target,
        tolerance: pred.tolerance,
    }
}

/// Evaluates every success predicate of the task.
pub fn judge(task: &Task, states: &[LabwareState]) -> Verdict {
    let predicates: Vec<PredicateValue> = task
        .success
        .iter()
        .map(|p| evaluate(task, p, states))
        .collect();
    Verdict {
        success: !predicates.is_empty() && predicates.iter().all(|p| p.holds),
        predicates,
    }
}
