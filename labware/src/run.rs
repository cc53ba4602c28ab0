//! Instrument runs: the programmes an instrument executes on its own once started (a centrifuge's
//! spin, a thermal cycler's profile, a thermal mixer's incubation) and the state machine that
//! runs them, shared by every model that runs ([`crate::model::Instrument::programmes`]).
//!
//! A run is logic, not physics: the rotor's speed and the block's temperature are values in the
//! item's logic state (`rotor_rpm`, `block_c`), advanced in closed form, so that advancing by one
//! physics step or by a whole phase at once ends in the same state. That is what lets the runtime
//! jump the clock while only instrument timers run ([`Run::next_event`], the runtime's clock
//! jump). The instrument's model decides when a run starts (a key held, a lid locked) and calls
//! [`Run::start`]; the protocol's programmes for an item run in order, one per start.
//!
//! The block's temperature follows its target as a first-order lag (time constant
//! [`BLOCK_TAU_S`]); a hold's time counts once the block is within [`AT_TARGET_C`] of its target,
//! as a cycler counts a step's time from reaching its temperature. A spin ramps its rotor up and
//! down linearly over its acceleration time; its duration is the time at speed.
//!
//! It draws nothing and reads no joints: the models do.

use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// An item's logic state (`crate::model::Logic`).
type Logic = BTreeMap<String, f64>;

fn set(logic: &mut Logic, key: &str, value: f64) {
    match logic.get_mut(key) {
        Some(v) => *v = value,
        None => {
            logic.insert(key.to_string(), value);
        }
    }
}

/// The block's time constant (s): a 40 °C step is within [`AT_TARGET_C`] in about 18 s (the
/// C1000's 3-5 °C/s ramp).
pub const BLOCK_TAU_S: f64 = 4.0;

/// How close (°C) the block must be to a hold's target before the hold's time counts.
pub const AT_TARGET_C: f64 = 0.5;

/// The block's temperature before any run (°C): the room's.
pub const ROOM_C: f64 = 25.0;

/// The part a run's states are about (`cycler.run is done`), and its states.
pub const RUN: &str = "run";
pub const STATES: [&str; 3] = ["idle", "running", "done"];

/// Logic keys: the run's state (0 idle, 1 running, 2 done), programmes started so far, the phase
/// now running and the seconds spent in it, the block's temperature at the phase's start.
const STATE: &str = "run";
pub const STARTED: &str = "runs_started";
const PHASE: &str = "run_phase";
const PHASE_T: &str = "run_phase_s";
const PHASE_FROM: &str = "run_phase_from_c";
/// What the run shows: seconds since its start, the block's temperature, the rotor's speed, the
/// mixer's shaking speed.
pub const ELAPSED: &str = "run_elapsed_s";
pub const BLOCK_C: &str = "block_c";
pub const ROTOR_RPM: &str = "rotor_rpm";
pub const SHAKE_RPM: &str = "shake_rpm";

/// One temperature held for a time (a step of a thermal profile).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Hold {
    pub celsius: f64,
    pub seconds: f64,
}

/// What one run does, from the protocol's step (units: °C, seconds, rpm).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "run", rename_all = "snake_case")]
pub enum Programme {
    /// A centrifuge's spin: up to `rpm` in `ramp_s`, `seconds` at speed, down in `ramp_s`.
    Spin { rpm: f64, seconds: f64, ramp_s: f64 },
    /// A thermal cycler's profile, its cycles unrolled into holds in order, under a heated lid.
    Thermocycle { holds: Vec<Hold>, lid_c: f64 },
    /// A thermal mixer's incubation: the block held at `celsius`, shaken at `rpm`, for `seconds`
    /// (counted from the start, as the ThermoMixer's timer counts).
    Incubate {
        celsius: f64,
        rpm: f64,
        seconds: f64,
    },
}

/// One phase of a run: what it drives toward and how long it lasts once it starts from a block
/// at `from_c`.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Phase {
    /// The rotor's speed ramps linearly from `from` to `to` rpm over `seconds`.
    Ramp { from: f64, to: f64, seconds: f64 },
    /// The block heads for `celsius`; the phase lasts until it is there, then `seconds` more.
    Hold { celsius: f64, seconds: f64 },
    /// The block heads for `celsius` while shaking at `rpm`, for `seconds` from the phase's start.
    Timed {
        celsius: f64,
        rpm: f64,
        seconds: f64,
    },
}

impl Programme {
    fn phases(&self) -> Vec<Phase> {
        match self {
            Programme::Spin {
                rpm,
                seconds,
                ramp_s,
            } => vec![
                Phase::Ramp {
                    from: 0.0,
                    to: *rpm,
                    seconds: *ramp_s,
                },
                Phase::Ramp {
                    from: *rpm,
                    to: *rpm,
                    seconds: *seconds,
                },
                Phase::Ramp {
                    from: *rpm,
                    to: 0.0,
                    seconds: *ramp_s,
                },
            ],
            Programme::Thermocycle { holds, .. } => holds
                .iter()
                .map(|h| Phase::Hold {
                    celsius: h.celsius,
                    seconds: h.seconds,
                })
                .collect(),
            Programme::Incubate {
                celsius,
                rpm,
                seconds,
            } => vec![Phase::Timed {
                celsius: *celsius,
                rpm: *rpm,
                seconds: *seconds,
            }],
        }
    }

    /// The run's length in seconds when it starts from a block at `block_c`.
    pub fn duration(&self, block_c: f64) -> f64 {
        let mut from = block_c;
        let mut total = 0.0;
        for phase in self.phases() {
            total += phase.length(from);
            from = phase.block_at(from, phase.length(from)).unwrap_or(from);
        }
        total
    }

    /// The run's length as the compiler bounds it: from a block already at its first target
    /// (spins and timed incubations are exact; a profile's ramps come on top).
    pub fn least_duration(&self) -> f64 {
        let first = self.phases().iter().find_map(|p| match p {
            Phase::Hold { celsius, .. } | Phase::Timed { celsius, .. } => Some(*celsius),
            Phase::Ramp { .. } => None,
        });
        self.duration(first.unwrap_or(ROOM_C))
    }
}

impl Phase {
    /// Seconds the phase lasts from a block at `from_c`.
    fn length(&self, from_c: f64) -> f64 {
        match *self {
            Phase::Ramp { seconds, .. } | Phase::Timed { seconds, .. } => seconds,
            Phase::Hold { celsius, seconds } => reach_s(from_c, celsius) + seconds,
        }
    }

    /// The block's temperature `t` seconds into the phase from `from_c` (`None`: the phase
    /// does not drive the block).
    fn block_at(&self, from_c: f64, t: f64) -> Option<f64> {
        match *self {
            Phase::Hold { celsius, .. } | Phase::Timed { celsius, .. } => {
                Some(celsius + (from_c - celsius) * (-t / BLOCK_TAU_S).exp())
            }
            Phase::Ramp { .. } => None,
        }
    }

    fn rotor_at(&self, t: f64) -> Option<f64> {
        match *self {
            Phase::Ramp { from, to, seconds } => {
                let f = if seconds > 0.0 {
                    (t / seconds).clamp(0.0, 1.0)
                } else {
                    1.0
                };
                Some(from + (to - from) * f)
            }
            _ => None,
        }
    }
}

/// Seconds a block at `from` takes to come within [`AT_TARGET_C`] of `to`.
fn reach_s(from: f64, to: f64) -> f64 {
    let gap = (from - to).abs();
    if gap <= AT_TARGET_C {
        0.0
    } else {
        BLOCK_TAU_S * (gap / AT_TARGET_C).ln()
    }
}

/// An item's runs over its logic state: the protocol's programmes for it, in order.
pub struct Run<'a> {
    pub programmes: &'a [Programme],
}

/// A run's state as the judge and the proof name it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RunState {
    Idle,
    Running,
    Done,
}

impl RunState {
    pub fn name(self) -> &'static str {
        match self {
            RunState::Idle => "idle",
            RunState::Running => "running",
            RunState::Done => "done",
        }
    }
}

fn get(logic: &Logic, key: &str) -> f64 {
    logic.get(key).copied().unwrap_or(0.0)
}

impl Run<'_> {
    /// The logic a runnable item starts with: idle, nothing started, the block at room
    /// temperature and the rotor still.
    pub fn reset(&self, logic: &mut Logic) {
        for key in [
            STATE, STARTED, PHASE, PHASE_T, ELAPSED, ROTOR_RPM, SHAKE_RPM,
        ] {
            set(logic, key, 0.0);
        }
        set(logic, BLOCK_C, ROOM_C);
        set(logic, PHASE_FROM, ROOM_C);
    }

    pub fn state(&self, logic: &Logic) -> RunState {
        match get(logic, STATE) as i64 {
            1 => RunState::Running,
            2 => RunState::Done,
            _ => RunState::Idle,
        }
    }

    /// A programme is waiting to be started and none is running.
    pub fn ready(&self, logic: &Logic) -> bool {
        self.state(logic) != RunState::Running
            && (get(logic, STARTED) as usize) < self.programmes.len()
    }

    /// Starts the next programme, if one is [`Run::ready`].
    pub fn start(&self, logic: &mut Logic) {
        if !self.ready(logic) {
            return;
        }
        set(logic, STATE, 1.0);
        set(logic, STARTED, get(logic, STARTED) + 1.0);
        set(logic, PHASE, 0.0);
        set(logic, PHASE_T, 0.0);
        set(logic, ELAPSED, 0.0);
        set(logic, PHASE_FROM, get(logic, BLOCK_C));
    }

    fn current(&self, logic: &Logic) -> Option<(&Programme, Vec<Phase>)> {
        if self.state(logic) != RunState::Running {
            return None;
        }
        let p = self
            .programmes
            .get((get(logic, STARTED) as usize).checked_sub(1)?)?;
        Some((p, p.phases()))
    }

    /// Advances a running programme by `dt` seconds, across as many phases as `dt` spans; exact
    /// for any `dt` (the closed forms above), so one call of a minute and three thousand of 20 ms
    /// end in the same state up to rounding.
    pub fn advance(&self, logic: &mut Logic, dt: f64) {
        let Some((_, phases)) = self.current(logic) else {
            return;
        };
        let mut left = dt;
        let mut index = get(logic, PHASE) as usize;
        let mut t = get(logic, PHASE_T);
        let mut from = get(logic, PHASE_FROM);
        set(logic, ELAPSED, get(logic, ELAPSED) + dt);
        loop {
            let Some(phase) = phases.get(index) else {
                set(logic, STATE, 2.0);
                set(logic, ROTOR_RPM, 0.0);
                set(logic, SHAKE_RPM, 0.0);
                break;
            };
            let length = phase.length(from);
            if t + left < length {
                t += left;
                self.show(logic, phase, from, t);
                break;
            }
            left -= length - t;
            self.show(logic, phase, from, length);
            from = phase.block_at(from, length).unwrap_or(from);
            index += 1;
            t = 0.0;
        }
        set(logic, PHASE, index as f64);
        set(logic, PHASE_T, t);
        set(logic, PHASE_FROM, from);
    }

    fn show(&self, logic: &mut Logic, phase: &Phase, from: f64, t: f64) {
        if let Some(c) = phase.block_at(from, t) {
            set(logic, BLOCK_C, c);
        }
        if let Some(rpm) = phase.rotor_at(t) {
            set(logic, ROTOR_RPM, rpm);
        }
        if let Phase::Timed { rpm, .. } = *phase {
            set(logic, SHAKE_RPM, rpm);
        }
    }

    /// Seconds until the running programme's phase ends (its next event), `None` when nothing
    /// runs: how far the runtime may jump the clock.
    pub fn next_event(&self, logic: &Logic) -> Option<f64> {
        let (_, phases) = self.current(logic)?;
        let phase = phases.get(get(logic, PHASE) as usize)?;
        Some((phase.length(get(logic, PHASE_FROM)) - get(logic, PHASE_T)).max(0.0))
    }

    /// `run is <state>` measured: the run's state and the wanted one as numbers (0 idle, 1
    /// running, 2 done); `None` for a state runs do not have.
    pub fn measure(&self, state: &str, logic: &Logic) -> Option<(f64, f64)> {
        let wanted = STATES.iter().position(|s| *s == state)? as f64;
        Some((get(logic, STATE), wanted))
    }

    /// The run's readout for recordings and reports.
    pub fn readout(&self, logic: &Logic) -> (String, String) {
        let state = self.state(logic).name();
        let text = match self.current(logic) {
            Some((Programme::Spin { .. }, _)) => {
                format!("{state} {:.0} rpm", get(logic, ROTOR_RPM))
            }
            Some(_) => format!("{state} {:.1} °C", get(logic, BLOCK_C)),
            None => state.to_string(),
        };
        (RUN.to_string(), text)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pcr(cycles: usize) -> Programme {
        let mut holds = vec![Hold {
            celsius: 95.0,
            seconds: 180.0,
        }];
        for _ in 0..cycles {
            holds.extend([
                Hold {
                    celsius: 95.0,
                    seconds: 15.0,
                },
                Hold {
                    celsius: 55.0,
                    seconds: 15.0,
                },
                Hold {
                    celsius: 72.0,
                    seconds: 30.0,
                },
            ]);
        }
        Programme::Thermocycle {
            holds,
            lid_c: 105.0,
        }
    }

    fn started(p: &[Programme]) -> Logic {
        let run = Run { programmes: p };
        let mut logic = Logic::new();
        run.reset(&mut logic);
        run.start(&mut logic);
        logic
    }

    #[test]
    fn one_jump_and_many_small_steps_end_in_the_same_state() {
        let p = [pcr(3)];
        let run = Run { programmes: &p };
        let mut small = started(&p);
        let mut jumped = small.clone();
        for _ in 0..(200.0 / 0.02) as usize {
            run.advance(&mut small, 0.02);
        }
        // Jump by events, as the runtime does, then the rest.
        let mut t = 0.0;
        while let Some(next) = run.next_event(&jumped) {
            if t + next >= 200.0 {
                break;
            }
            run.advance(&mut jumped, next);
            t += next;
        }
        run.advance(&mut jumped, 200.0 - t);
        for key in [BLOCK_C, PHASE, ELAPSED] {
            assert!(
                (small[key] - jumped[key]).abs() < 1e-6,
                "{key}: {} vs {}",
                small[key],
                jumped[key]
            );
        }
    }

    #[test]
    fn a_profile_runs_its_holds_after_reaching_each_target_and_ends_done() {
        let p = [pcr(30)];
        let run = Run { programmes: &p };
        let mut logic = started(&p);
        let total = p[0].duration(ROOM_C);
        // 3 min + 30 x 60 s of holds, plus the ramps (about 47 s a cycle at a 4 s lag).
        assert!(total > 180.0 + 30.0 * 60.0 && total < 180.0 + 30.0 * 60.0 + 30.0 * 60.0);
        run.advance(&mut logic, total - 1.0);
        assert_eq!(run.state(&logic), RunState::Running);
        assert!((logic[BLOCK_C] - 72.0).abs() < AT_TARGET_C);
        run.advance(&mut logic, 2.0);
        assert_eq!(run.state(&logic), RunState::Done);
        assert!(run.next_event(&logic).is_none());
        assert_eq!(run.measure("done", &logic), Some((2.0, 2.0)));
        assert_eq!(run.measure("running", &logic), Some((2.0, 1.0)));
    }

    #[test]
    fn a_spin_ramps_holds_and_stops_and_programmes_run_in_order() {
        let p = [
            Programme::Spin {
                rpm: 5000.0,
                seconds: 60.0,
                ramp_s: 10.0,
            },
            Programme::Spin {
                rpm: 14000.0,
                seconds: 30.0,
                ramp_s: 10.0,
            },
        ];
        let run = Run { programmes: &p };
        let mut logic = started(&p);
        run.advance(&mut logic, 5.0);
        assert!((logic[ROTOR_RPM] - 2500.0).abs() < 1e-9);
        run.advance(&mut logic, 30.0);
        assert!((logic[ROTOR_RPM] - 5000.0).abs() < 1e-9);
        // A start while running does nothing.
        run.start(&mut logic);
        assert_eq!(logic[STARTED], 1.0);
        run.advance(&mut logic, 45.0);
        assert_eq!(run.state(&logic), RunState::Done);
        assert_eq!(logic[ROTOR_RPM], 0.0);
        run.start(&mut logic);
        run.advance(&mut logic, 15.0);
        assert!((logic[ROTOR_RPM] - 14000.0).abs() < 1e-9);
        run.advance(&mut logic, 40.0);
        assert!(!run.ready(&logic), "no third programme");
        run.start(&mut logic);
        assert_eq!(run.state(&logic), RunState::Done);
    }
}
