//! `open_lid`: unlatch a lid and swing it open.

use super::lid;
use super::prelude::*;
use crate::motion::{Motion, MotionStep};

pub(super) const PRIMITIVE: LabPrimitive = LabPrimitive {
    name: "open_lid",
    description: "unlatch a lid if latched and swing it open",
    args: &[ON],
    requires: "the hand is empty; the lid is closed or locked",
    leaves: "the lid open (and unlocked)",
    phrase: "open the lid of the {on}",
    outcome: Some("{on}.lid is open"),
    effect: lid::effect,
    motions: Some(motions),
};

/// A lid with a lever on its handle: grip the pressed lever of the closed lid, raise it out of
/// its notch, swing the lid open. A lid a key has released (see `unlock`): lift it by its
/// handle from where it rests all the way open (a lid let go short of open, even past the balance
/// of its spring, swings on into the hand that let it go), and there stop pushing before letting
/// go and back off 8 cm: the damped lid holds the hand back on the way, so the hand arrives
/// pressing the lid against its open stop (the 5430's wrist lagged 0.17 rad, the hand slid up to
/// 4 cm along the bar), and the 4 cm retreat and the route home from the commanded pose left the
/// fingers on the bar and dragged the lid half shut (`workflows.centrifuge_run`, issue 26).
fn motions(step: &MotionStep) -> Vec<Motion> {
    if lid::release_key(step).is_some() {
        let mut m = lid::handle_motions(step, "lid_open", &[], &[(&[("lid", "open")], 30)], 0.08);
        let release = m.iter().position(|m| matches!(m, Motion::Release));
        m.insert(release.expect("a handle is let go"), Motion::Comply);
        return m;
    }
    lid::handle_motions(
        step,
        "lid_open",
        &[("lid", "closed"), ("lever", "pressed")],
        &[
            (&[("lid", "closed"), ("lever", "raised")], 10),
            (&[("lid", "open"), ("lever", "raised")], 30),
        ],
        0.1,
    )
}
