//! The event-driven clock: when a control step may jump lab time, and how far. Lab protocols
//! hold for minutes and hours (a 30-cycle profile, a 10-minute spin) while nothing moves but an
//! instrument's timers; stepping MuJoCo through them at 500 Hz would cost minutes of wall time
//! per episode for nothing. So once every robot has held the same action for [`IDLE_STEPS`]
//! control steps and no arm joint moves faster than [`REST_SPEED`], a step jumps the
//! clock to the earliest of the instruments' next event (a run's phase ending), the stage's
//! deadline and the task's time limit. A policy that never moves (the hold control) may jump an
//! idle scene at rest to its deadline with no timer running ([`IdleClock::never_moves`]).
//!
//! The decision reads only the state and the actions, so a re-run of the same actions jumps the
//! same way; a recording keeps each step's time, so a re-simulation jumps where the recording did
//! ([`crate::episode::Episode::skip_to`]). It moves nothing itself: the episode skips.

use crate::episode::Episode;

/// Control steps of one unchanged action after which an idle scene may jump (0.5 s at 50 Hz).
pub const IDLE_STEPS: u32 = 25;
/// The speed under which every arm joint counts as at rest (rad/s). Only the robots' arms are
/// asked: small items in contact (a tube in a rotor's sleeve) chatter at a few rad/s forever in
/// MuJoCo's soft contacts, and freezing them mid-chatter changes nothing a check reads.
pub const REST_SPEED: f64 = 0.01;

/// How long the robots have been idle, and whether the policy ever moves.
#[derive(Clone, Debug, Default)]
pub struct IdleClock {
    last_action: Vec<f64>,
    same: u32,
    /// The policy never moves (the hold control): an idle scene at rest may jump to its deadline
    /// with no instrument running, since nothing will ever change it.
    pub never_moves: bool,
}

impl IdleClock {
    /// Counts the control steps the action has stayed the same, bit for bit.
    pub fn note(&mut self, action: &[f64]) {
        let same = self.last_action.len() == action.len()
            && self
                .last_action
                .iter()
                .zip(action)
                .all(|(a, b)| a.to_bits() == b.to_bits());
        if same {
            self.same = self.same.saturating_add(1);
        } else {
            self.last_action.clear();
            self.last_action.extend_from_slice(action);
            self.same = 1;
        }
    }

    /// The time the clock may jump to now (absolute, s), before `deadline` (the stage's or the
    /// task's, whichever is first): `None` while a robot moved lately, something in the scene
    /// moves, no timer runs (unless the policy never moves), or the jump would be shorter than a
    /// control period.
    pub fn jump_to(&self, ep: &Episode, deadline: f64) -> Option<f64> {
        if self.same < IDLE_STEPS {
            return None;
        }
        let next = match ep.next_event() {
            Some(next) => next,
            None if self.never_moves => f64::INFINITY,
            None => return None,
        };
        if !ep.at_rest(REST_SPEED) {
            return None;
        }
        let now = ep.time();
        let target = (now + next).min(deadline);
        (target - now > ep.control_period()).then_some(target)
    }
}
