//! The event-driven clock: when a control step may jump lab time, and how far. Lab protocols
//! hold for minutes and hours (a 30-cycle profile, a 10-minute spin) while nothing moves but an
//! instrument's timers; stepping MuJoCo through them at 500 Hz would cost minutes of wall time
//! per episode for nothing. So once every robot has held the same action for [`IDLE_STEPS`]
//! control steps, its arm joints move slower than [`REST_SPEED`] and no coordinate of the scene
//! has moved more than [`REST_DRIFT`] over the last [`IDLE_STEPS`] (small items in contact, a tube
//! in a rotor's sleeve, chatter in place forever in MuJoCo's soft contacts: their velocities never
//! settle, their positions do), a step jumps the clock to the earliest of the instruments' next
//! event (a run's phase ending), the stage's deadline and the task's time limit. A policy that
//! never moves (the hold control) may jump such a scene to its deadline with no timer running
//! ([`IdleClock::never_moves`]): a lid settling or a tube toppling moves more than the drift, so
//! nothing that would happen by itself is skipped.
//!
//! The decision reads only the state and the actions, so a re-run of the same actions jumps the
//! same way; a recording keeps each step's time, so a re-simulation jumps where the recording did
//! ([`crate::episode::Episode::skip_to`]). It moves nothing itself: the episode skips.

use crate::episode::Episode;

/// Control steps of one unchanged action after which an idle scene may jump (0.5 s at 50 Hz),
/// and the window over which the scene's stillness is measured.
pub const IDLE_STEPS: u32 = 25;
/// The speed under which an arm joint counts as at rest (rad/s).
pub const REST_SPEED: f64 = 0.01;
/// How far any coordinate of the scene (m or rad; a loose item's position, not its orientation,
/// which chatters) may have moved over the last window and the scene still count as at rest.
pub const REST_DRIFT: f64 = 1e-3;

/// How long the robots have been idle, where the scene stood a window ago, and whether the
/// policy ever moves.
#[derive(Clone, Debug, Default)]
pub struct IdleClock {
    last_action: Vec<f64>,
    same: u32,
    /// The scene's coordinates at the start of the current stillness window, and the step count
    /// (of the unchanged action) they were taken at.
    window: Option<(u32, Vec<f64>)>,
    /// The policy never moves (the hold control): an idle scene at rest may jump to its deadline
    /// with no instrument running, since nothing will ever change it.
    pub never_moves: bool,
}

impl IdleClock {
    /// Counts the control steps the action has stayed the same, bit for bit, and keeps the
    /// scene's coordinates (after the step: [`Episode::still_coordinates`]) at the start of each
    /// stillness window.
    pub fn note(&mut self, action: &[f64], ep: &Episode) {
        let qpos = ep.still_coordinates();
        let qpos = qpos.as_slice();
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
            self.window = None;
        }
        let drifted = self.window.as_ref().is_some_and(|(_, then)| {
            then.iter()
                .zip(qpos)
                .any(|(a, b)| (a - b).abs() > REST_DRIFT)
        });
        if self.window.is_none() || drifted {
            self.window = Some((self.same, qpos.to_vec()));
        }
    }

    /// The time the clock may jump to now (absolute, s), before `deadline` (the stage's or the
    /// task's, whichever is first): `None` while a robot moved lately, the scene has not been
    /// still for a whole window, no timer runs (unless the policy never moves), or the jump would
    /// be shorter than a control period.
    pub fn jump_to(&self, ep: &Episode, deadline: f64) -> Option<f64> {
        let still_since = self.window.as_ref().map(|(at, _)| *at)?;
        if self.same < IDLE_STEPS || self.same - still_since < IDLE_STEPS {
            return None;
        }
        let next = match ep.next_event() {
            Some(next) => next,
            None if self.never_moves => f64::INFINITY,
            None => return None,
        };
        if !ep.arms_at_rest(REST_SPEED) {
            return None;
        }
        let now = ep.time();
        let target = (now + next).min(deadline);
        (target - now > ep.control_period()).then_some(target)
    }
}
