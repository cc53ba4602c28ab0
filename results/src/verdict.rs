//! Verdicts: every success predicate of the current stage evaluated on measured labware state,
//! each with its value, target, tolerance and progress; stages advanced as their predicates hold.
//! Part states are read out by each item's instrument model (nothing here re-derives "closed" from
//! angles); slots by the holder's model. Pure functions of recorded state and the episode's drawn
//! parameters, so a recording can be re-scored offline ([`Judge::replay`]).

use compiler::params::Bindings;
use compiler::predicates::Check;
use compiler::quantities::ResolvedPredicate;
use compiler::{Predicate, Scoring, Task};
use labware::LabwareState;
use labware::Measure;
use serde::{Deserialize, Serialize};

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PredicateValue {
    pub text: String,
    pub holds: bool,
    /// The measured quantity the predicate looks at (rad or m), its target and the tolerance;
    /// NaN (JSON null) when it cannot be measured.
    #[serde(with = "maybe_measured")]
    pub value: f64,
    #[serde(with = "maybe_measured")]
    pub target: f64,
    #[serde(with = "maybe_measured")]
    pub tolerance: f64,
    /// 0..1: how far the value has come from where the stage started toward the target.
    pub progress: f64,
    /// A predicate that measures several things (an item seated in a slot: in-plane distance,
    /// height, tilt), each against its own tolerance, so that a failure says which part failed
    /// and by how much; empty for one-number predicates.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub parts: Vec<PartValue>,
}

/// One measured part of a predicate, in its own unit (`unit`: "m" or "rad").
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PartValue {
    pub name: String,
    pub value: f64,
    pub tolerance: f64,
    pub unit: String,
    pub holds: bool,
}

/// A measurement in JSON: a number, or null for NaN (which JSON cannot hold), read back as NaN.
mod maybe_measured {
    use serde::{Deserialize, Deserializer, Serializer};

    pub(super) fn serialize<S: Serializer>(v: &f64, s: S) -> Result<S::Ok, S::Error> {
        if v.is_finite() {
            s.serialize_f64(*v)
        } else {
            s.serialize_none()
        }
    }

    pub(super) fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
        Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StageVerdict {
    pub id: String,
    pub success: bool,
    /// 0..1: binary stages score 1 or 0; progress stages the weighted mean of progress.
    pub score: f64,
    /// When the stage's predicates all held (simulated seconds), if they did.
    pub completed_at_s: Option<f64>,
    pub predicates: Vec<PredicateValue>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Verdict {
    pub success: bool,
    /// Mean of the stage scores (stages never reached score 0).
    pub score: f64,
    pub stages: Vec<StageVerdict>,
}

impl Verdict {
    /// The verdict of an episode that ended in an error (a policy error, a server fault, an
    /// unstable simulation): a failure that scores 0, whatever its checks said when it stopped.
    /// One rule for the harness that records it and the verifier that re-enacts it.
    pub fn ended_by_error(&mut self) {
        self.success = false;
        self.score = 0.0;
    }

    /// The predicates of the last stage reached.
    pub fn predicates(&self) -> &[PredicateValue] {
        self.stages
            .last()
            .map(|s| s.predicates.as_slice())
            .unwrap_or(&[])
    }
}

/// The measured value of one predicate, where the judge can measure it. Long on purpose: one
/// arm per predicate form, each the few lines that form measures.
fn measure(
    task: &Task,
    resolved: &ResolvedPredicate,
    check: &Check,
    states: &[LabwareState],
) -> Option<Measure> {
    let state_of = |name: &str| states.iter().find(|s| s.name == name);
    let spec_of = |name: &str| task.labware.iter().find(|l| l.name == name);
    match check {
        Check::State {
            labware,
            part,
            state,
            tolerance,
            ..
        } => {
            let model = spec_of(labware)?.params.instrument()?;
            model.measure(
                part,
                state,
                tolerance.as_ref().map(|t| t.value),
                state_of(labware)?,
            )
        }
        Check::JointRange {
            labware,
            joint,
            low,
            high,
        } => {
            let value = state_of(labware)?.joints.get(joint).copied()?;
            let (target, tolerance) = ((low + high) / 2.0, (high - low) / 2.0);
            Some(Measure {
                value,
                target,
                tolerance,
                holds: (value - target).abs() <= tolerance,
            })
        }
        Check::InSlot {
            item,
            location: _,
            tolerance,
            height,
            tilt,
        } => {
            let (holder, slot) = resolved.place.as_ref()?;
            let seat = spec_of(holder)?
                .params
                .instrument()?
                .slot_seat(slot, state_of(holder)?)?;
            Some(labware::model::seated(
                &seat,
                &state_of(item)?.pose,
                tolerance.value,
                *height,
                *tilt,
            ))
        }
        // A contact holds while the robot touches the item (value 1) and not otherwise (0).
        Check::Contact { robot, item } => {
            let touching = state_of(item)?.touched_by.iter().any(|r| r == robot);
            Some(Measure {
                value: f64::from(u8::from(touching)),
                target: 1.0,
                tolerance: 0.0,
                holds: touching,
            })
        }
        // A finger of the robot touches the item, or the part (value 1), or not (0).
        Check::Holds { robot, item, part } => {
            let holding = state_of(item)?
                .finger_contacts
                .iter()
                .any(|f| &f.robot == robot && (part.is_none() || f.part == *part));
            Some(Measure {
                value: f64::from(u8::from(holding)),
                target: 1.0,
                tolerance: 0.0,
                holds: holding,
            })
        }
        // How far the part stands above its seat on the item (m), along the item's axis.
        Check::Lifted {
            item,
            height,
            part: Some(part),
        } => {
            let (role, measured) = spec_of(item)?.params.instrument()?.part()?;
            let value = if role == part {
                measured.rise(state_of(item)?)?
            } else {
                return None;
            };
            Some(Measure {
                value,
                target: *height,
                tolerance: 0.0,
                holds: value >= *height,
            })
        }
        // How far the item is tilted from upright now (rad); it "holds" upside down. What the
        // predicate's verdict shows is the judge's count of turns over and back
        // ([`Judge::update`]).
        Check::Inverted { item, .. } => {
            let up = state_of(item)?.pose.rotation * nalgebra::Vector3::z();
            let tilt = up.z.clamp(-1.0, 1.0).acos();
            Some(Measure {
                value: tilt,
                target: std::f64::consts::PI,
                tolerance: std::f64::consts::PI - compiler::predicates::INVERTED_RAD,
                holds: tilt >= compiler::predicates::INVERTED_RAD,
            })
        }
        // The item's distance from the point (m).
        Check::Position {
            item,
            pos,
            tolerance,
        } => {
            let at = state_of(item)?.pose.translation.vector;
            let distance = (at - nalgebra::Vector3::from(*pos)).norm();
            Some(Measure {
                value: distance,
                target: 0.0,
                tolerance: tolerance.value,
                holds: distance <= tolerance.value,
            })
        }
        // How far the item stands above where it started: its start slot's seat (the holder
        // as it is now), else its placement.
        Check::Lifted {
            item,
            height,
            part: None,
        } => {
            let spec = spec_of(item)?;
            let start = match &spec.at {
                Some(_) => {
                    let (holder, slot) = resolved.place.as_ref()?;
                    spec_of(holder)?
                        .params
                        .instrument()?
                        .slot_seat(slot, state_of(holder)?)?
                        .translation
                        .vector
                        .z
                }
                None => spec.placement.translation.vector.z,
            };
            let value = state_of(item)?.pose.translation.vector.z - start;
            Some(Measure {
                value,
                target: *height,
                tolerance: 0.0,
                holds: value >= *height,
            })
        }
        // The value the instrument's panel shows against the target.
        Check::Panel {
            instrument,
            param,
            unit: _,
            value: _,
            tolerance,
            ..
        } => {
            let target = resolved.target.clone().ok()??;
            let shown = spec_of(instrument)?
                .params
                .instrument()?
                .panel()?
                .panel_value(param, state_of(instrument)?)?;
            Some(Measure {
                value: shown,
                target,
                tolerance: tolerance.value,
                holds: (shown - target).abs() <= tolerance.value,
            })
        }
        // The liquid the container holds now (its logic's volume, or a named liquid's share of
        // it; none kept: empty) against the target, compared as the predicate says.
        Check::Volume {
            container,
            liquid,
            cmp,
            value: _,
            tolerance,
        } => {
            let target = resolved.target.clone().ok()??;
            spec_of(container)?
                .params
                .instrument()?
                .liquid()?
                .interior()?;
            let key = match liquid {
                Some(liquid) => labware::process::liquid_key(liquid),
                None => labware::process::VOLUME_UL.to_string(),
            };
            let held = state_of(container)?.logic.get(&key).copied().unwrap_or(0.0);
            Some(Measure {
                value: held,
                target,
                tolerance: tolerance.value,
                holds: compiler::predicates::compare(held, *cmp, target, tolerance.value),
            })
        }
    }
}

/// The parts of an `in` predicate: in-plane distance, height and tilt against their tolerances.
fn parts(
    task: &Task,
    resolved: &ResolvedPredicate,
    check: &Check,
    states: &[LabwareState],
) -> Vec<PartValue> {
    let Check::InSlot {
        item,
        location: _,
        tolerance,
        height,
        tilt,
    } = check
    else {
        return Vec::new();
    };
    let state_of = |name: &str| states.iter().find(|s| s.name == name);
    let seat = (|| {
        let (holder, slot) = resolved.place.as_ref()?;
        let spec = task.labware.iter().find(|l| &l.name == holder)?;
        let seat = spec
            .params
            .instrument()?
            .slot_seat(slot, state_of(holder)?)?;
        Some(labware::model::seat_offsets(&seat, &state_of(item)?.pose))
    })();
    let Some((planar, dz, tilted)) = seat else {
        return Vec::new();
    };
    let part = |name: &str, value: f64, tolerance: f64, unit: &str| PartValue {
        name: name.into(),
        holds: value.abs() <= tolerance,
        value,
        tolerance,
        unit: unit.into(),
    };
    vec![
        part("in-plane distance", planar, tolerance.value, "m"),
        part("height", dz, *height, "m"),
        part("tilt", tilted, *tilt, "rad"),
    ]
}

fn evaluate(
    task: &Task,
    resolved: &ResolvedPredicate,
    pred: &Predicate,
    states: &[LabwareState],
    start: &[LabwareState],
) -> PredicateValue {
    // The predicate as the author wrote it, with this episode's parameters filled in.
    let text = resolved.text.clone();
    let Some(Measure {
        value,
        target,
        tolerance,
        holds,
    }) = measure(task, resolved, &pred.check, states)
    else {
        return PredicateValue {
            text,
            holds: false,
            value: f64::NAN,
            target: f64::NAN,
            tolerance: f64::NAN,
            progress: 0.0,
            parts: Vec::new(),
        };
    };
    let from = measure(task, resolved, &pred.check, start)
        .map(|m| m.value)
        .unwrap_or(value);
    let span = (target - from).abs();
    let progress = if holds {
        1.0
    } else if span > tolerance {
        // Short of holding never scores full marks, even when the value is on target.
        (1.0 - (value - target).abs() / span).clamp(0.0, 0.99)
    } else {
        0.0
    };
    PredicateValue {
        text,
        holds,
        value,
        target,
        tolerance,
        progress,
        parts: if holds {
            Vec::new()
        } else {
            parts(task, resolved, &pred.check, states)
        },
    }
}

/// What the judge remembers of the stage's predicates: which `was` states it has seen, and how
/// long each time-constrained form has held (s).
#[derive(Clone, Copy)]
struct Memory<'a> {
    seen: &'a [bool],
    held_s: &'a [f64],
    starts: &'a [u32],
    /// Per timed step's predicate: when the earlier step's outcome first held, and when its own
    /// first held after that.
    timing: &'a [Timing],
    /// Per `inverted` predicate: the turns over and back counted so far.
    inversions: &'a [Inversions],
}

/// An `inverted` predicate's count: turns upside down and back upright seen so far, and whether
/// the item is upside down now (past [`compiler::predicates::INVERTED_RAD`], until it is back
/// within [`compiler::predicates::UPRIGHT_RAD`] of upright).
#[derive(Clone, Copy, Debug, Default)]
struct Inversions {
    count: u32,
    upside_down: bool,
}

/// A timed step's two times on the episode's clock (s), as the judge saw them: the first update
/// at which the earlier outcome held, and the first at or after it at which the later outcome
/// came about (held, not having held at the update before: a tube still in the gripper as it is
/// set down is not yet picked up again); and whether the later outcome held at the last update.
#[derive(Clone, Copy, Debug, Default)]
struct Timing {
    since: Option<f64>,
    reached: Option<f64>,
    held: bool,
}

/// Stage `index`'s verdict; `resolved` is its predicates with the parameters filled in.
fn stage_verdict(
    task: &Task,
    resolved: &[ResolvedPredicate],
    index: usize,
    states: &[LabwareState],
    start: &[LabwareState],
    completed_at_s: Option<f64>,
    memory: Memory,
) -> StageVerdict {
    let Memory {
        seen,
        held_s,
        starts,
        timing,
        inversions,
    } = memory;
    let stage = &task.stages[index];
    let predicates: Vec<PredicateValue> = stage
        .success
        .iter()
        .enumerate()
        .map(|(k, p)| {
            let mut v = evaluate(task, &resolved[k], p, states, start);
            // A `was` check holds once its state has been seen in this stage.
            if p.check.is_history() && seen.get(k).copied().unwrap_or(false) {
                v.holds = true;
                v.progress = 1.0;
                v.parts.clear();
            }
            // A time constraint holds when its form has held for the time it bounds: its value
            // is that time (s), its target the least (else the most) time.
            if let Some(dwell) = &p.dwell {
                let held = held_s.get(k).copied().unwrap_or(0.0);
                let step = task.physics.timestep_s * task.physics.substeps as f64;
                let started = starts.get(k).copied().unwrap_or(0).max(1);
                v.holds = dwell.kept(held, step * f64::from(started));
                v.value = held;
                v.target = dwell.at_least_s.or(dwell.at_most_s).unwrap_or(0.0);
                v.tolerance = 0.0;
                v.progress = f64::from(u8::from(v.holds));
                if v.holds {
                    v.parts.clear();
                }
            }
            // An inversion count holds once the judge has counted enough turns over and back:
            // its value is the count, its target the number asked for.
            if let Check::Inverted { times, .. } = &p.check {
                let count = inversions.get(k).map_or(0, |i| i.count);
                v.holds = count >= *times;
                v.value = f64::from(count);
                v.target = f64::from(*times);
                v.tolerance = 0.0;
                v.progress = (f64::from(count) / f64::from(*times)).min(1.0);
                v.parts.clear();
            }
            // A timed step holds once its outcome came within its time of the earlier step's:
            // its value is the time between them (so far, while it has not come), its target
            // the time allowed.
            if let Some(since) = &p.since {
                let t = timing.get(k).copied().unwrap_or_default();
                let step = task.physics.timestep_s * task.physics.substeps as f64;
                let now = completed_at_s.unwrap_or(0.0);
                let gap = match (t.since, t.reached) {
                    (Some(a), Some(b)) => b - a,
                    (Some(a), None) => now - a,
                    (None, _) => 0.0,
                };
                v.holds = t.reached.is_some() && gap <= since.within_s + step + 1e-9;
                v.value = gap;
                v.target = since.within_s;
                v.tolerance = 0.0;
                v.progress = f64::from(u8::from(v.holds));
                if v.holds {
                    v.parts.clear();
                }
            }
            v
        })
        .collect();
    let success = !predicates.is_empty() && predicates.iter().all(|p| p.holds);
    let score = match stage.scoring {
        Scoring::Binary => f64::from(u8::from(success)),
        Scoring::Progress => {
            let total: f64 = stage.success.iter().map(|p| p.weight).sum();
            let got: f64 = stage
                .success
                .iter()
                .zip(&predicates)
                .map(|(p, v)| p.weight * v.progress)
                .sum();
            if total > 0.0 { got / total } else { 0.0 }
        }
    };
    StageVerdict {
        id: stage.id.clone(),
        success,
        score,
        completed_at_s: completed_at_s.filter(|_| success),
        predicates,
    }
}

/// A stage verdict whose predicates may hold but have not held for the settle time yet: not a
/// success, and under binary scoring worth nothing yet.
fn unsettled(mut v: StageVerdict, scoring: Scoring) -> StageVerdict {
    if v.success {
        v.success = false;
        v.completed_at_s = None;
        if scoring == Scoring::Binary {
            v.score = 0.0;
        }
    }
    v
}

/// Follows an episode through its stages: the current stage advances when all its predicates hold;
/// the episode is over when the last stage completes or the current one runs out of time.
///
/// It keeps its own copy of the task and the drawn parameters, so an environment can own it.
pub struct Judge {
    task: Task,
    /// Each stage's predicates with the episode's parameters filled in, resolved once.
    resolved: Vec<Vec<ResolvedPredicate>>,
    stage: usize,
    stage_start_s: f64,
    stage_start: Vec<LabwareState>,
    /// Since when every predicate of the current stage has held, while it settles.
    holding_since: Option<f64>,
    /// Per predicate of the current stage: a `was` check's state has been seen.
    seen: Vec<bool>,
    /// Per predicate of the current stage with a time constraint: the seconds its form has
    /// held, and whether it held at the last update. An update's interval counts when the form
    /// held at its start: what holds at a step holds until the next (a jump of the clock ends
    /// where a run's phase ends, and the run was running all through it).
    held_s: Vec<f64>,
    held_then: Vec<bool>,
    /// How many times each form started holding (each start is seen up to a step late).
    starts: Vec<u32>,
    /// Per predicate of the current stage that times a step: its two times so far.
    timing: Vec<Timing>,
    /// Per `inverted` predicate of the current stage: its count so far.
    inversions: Vec<Inversions>,
    /// Each stage's timed steps' earlier outcomes, resolved once (by predicate index).
    resolved_since: Vec<Vec<Option<ResolvedPredicate>>>,
    /// The time of the last update (s).
    last_s: f64,
    done: Vec<StageVerdict>,
    last: Option<StageVerdict>,
}

impl Judge {
    /// A judge for one episode of `task` with its drawn parameters.
    pub fn new(task: &Task, params: &Bindings, initial: &[LabwareState]) -> Self {
        Judge {
            task: task.clone(),
            resolved: task
                .stages
                .iter()
                .map(|s| {
                    s.success
                        .iter()
                        .map(|p| ResolvedPredicate::of(task, p, params))
                        .collect()
                })
                .collect(),
            resolved_since: task
                .stages
                .iter()
                .map(|s| {
                    s.success
                        .iter()
                        .map(|p| {
                            p.since
                                .as_ref()
                                .map(|x| ResolvedPredicate::of(task, &x.predicate(), params))
                        })
                        .collect()
                })
                .collect(),
            timing: Vec::new(),
            inversions: Vec::new(),
            stage: 0,
            stage_start_s: 0.0,
            stage_start: initial.to_vec(),
            holding_since: None,
            seen: Vec::new(),
            held_s: Vec::new(),
            held_then: Vec::new(),
            starts: Vec::new(),
            last_s: 0.0,
            done: Vec::new(),
            last: None,
        }
    }

    /// The stage now running (equal to the number of stages once all are done).
    pub fn stage(&self) -> usize {
        self.stage
    }

    /// Feeds the state at `time`; returns true when the episode is over. A stage is done when
    /// every predicate has gone on holding for its settle time (`Stage::settle_s`); until then
    /// it is not a success, and a predicate that stops holding starts the wait again.
    pub fn update(&mut self, time: f64, states: &[LabwareState]) -> bool {
        // Whole microseconds: a recording stores nanosecond timestamps, and a replay must agree.
        let time = (time * 1e6).round() / 1e6;
        while self.stage < self.task.stages.len() {
            let stage = &self.task.stages[self.stage];
            self.seen.resize(stage.success.len(), false);
            self.held_s.resize(stage.success.len(), 0.0);
            self.held_then.resize(stage.success.len(), false);
            self.starts.resize(stage.success.len(), 0);
            self.timing.resize(stage.success.len(), Timing::default());
            self.inversions
                .resize(stage.success.len(), Inversions::default());
            let interval = time - self.last_s;
            for (k, p) in stage.success.iter().enumerate() {
                if p.dwell.is_none() {
                    continue;
                }
                if self.held_then[k] {
                    self.held_s[k] += interval;
                }
                let now = measure(&self.task, &self.resolved[self.stage][k], &p.check, states)
                    .is_some_and(|m| m.holds);
                if now && !self.held_then[k] {
                    self.starts[k] += 1;
                }
                self.held_then[k] = now;
            }
            self.last_s = time;
            for (k, p) in stage.success.iter().enumerate() {
                let (Some(since), Some(from)) = (&p.since, &self.resolved_since[self.stage][k])
                else {
                    continue;
                };
                let holds = |r: &ResolvedPredicate, c: &compiler::predicates::Check| {
                    measure(&self.task, r, c, states).is_some_and(|m| m.holds)
                };
                let t = &mut self.timing[k];
                if t.since.is_none() && holds(from, &since.check) {
                    t.since = Some(time);
                }
                let now = holds(&self.resolved[self.stage][k], &p.check);
                if t.since.is_some() && t.reached.is_none() && now && !t.held {
                    t.reached = Some(time);
                }
                t.held = now;
            }
            for (k, p) in stage.success.iter().enumerate() {
                if !matches!(p.check, Check::Inverted { .. }) {
                    continue;
                }
                let Some(tilt) =
                    measure(&self.task, &self.resolved[self.stage][k], &p.check, states)
                        .map(|m| m.value)
                else {
                    continue;
                };
                let i = &mut self.inversions[k];
                if tilt >= compiler::predicates::INVERTED_RAD {
                    i.upside_down = true;
                } else if i.upside_down && tilt <= compiler::predicates::UPRIGHT_RAD {
                    i.upside_down = false;
                    i.count += 1;
                }
            }
            for (k, p) in stage.success.iter().enumerate() {
                if p.check.is_history()
                    && measure(&self.task, &self.resolved[self.stage][k], &p.check, states)
                        .is_some_and(|m| m.holds)
                {
                    self.seen[k] = true;
                }
            }
            let v = stage_verdict(
                &self.task,
                &self.resolved[self.stage],
                self.stage,
                states,
                &self.stage_start,
                Some(time),
                Memory {
                    seen: &self.seen,
                    held_s: &self.held_s,
                    starts: &self.starts,
                    timing: &self.timing,
                    inversions: &self.inversions,
                },
            );
            let settle = self.task.stages[self.stage].settle_s;
            let settled = v.success && {
                let since = *self.holding_since.get_or_insert(time);
                time - since >= settle - 1e-9
            };
            if !settled {
                if !v.success {
                    self.holding_since = None;
                }
                let limit = self.task.stages[self.stage].time_limit_s;
                self.last = Some(unsettled(v, self.task.stages[self.stage].scoring));
                return time - self.stage_start_s >= limit - 1e-9;
            }
            self.holding_since = None;
            self.seen.clear();
            self.held_s.clear();
            self.held_then.clear();
            self.starts.clear();
            self.timing.clear();
            self.inversions.clear();
            self.done.push(v);
            self.last = None;
            self.stage += 1;
            self.stage_start_s = time;
            self.stage_start = states.to_vec();
        }
        true
    }

    /// When the stage now running runs out of time (s on the episode's clock); `None` once
    /// every stage is done.
    pub fn deadline(&self) -> Option<f64> {
        let stage = self.task.stages.get(self.stage)?;
        Some(self.stage_start_s + stage.time_limit_s)
    }

    /// The verdict so far: completed stages, the current one as last evaluated, the rest unreached.
    pub fn verdict(&self) -> Verdict {
        let mut stages = self.done.clone();
        if let Some(v) = &self.last {
            stages.push(v.clone());
        }
        let n = self.task.stages.len().max(1) as f64;
        Verdict {
            success: self.done.len() == self.task.stages.len(),
            score: stages.iter().map(|s| s.score).sum::<f64>() / n,
            stages,
        }
    }

    /// Re-scores a recorded series of (time, labware state), first entry the initial state.
    pub fn replay(task: &Task, params: &Bindings, series: &[(f64, Vec<LabwareState>)]) -> Verdict {
        let Some((_, first)) = series.first() else {
            return Judge::new(task, params, &[]).verdict();
        };
        let mut j = Judge::new(task, params, first);
        for (t, s) in series {
            if j.update(*t, s) {
                break;
            }
        }
        j.verdict()
    }
}
