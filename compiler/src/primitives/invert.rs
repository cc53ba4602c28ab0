//! `invert`: turn a carried, capped tube upside down and back, a number of times (mixing by
//! inversion: BioCoder's `invert`, a kit's "invert the tube 4-6 times").

use super::prelude::*;
use crate::motion::{Motion, MotionStep};

/// The most inversions one step asks for.
const MAX_TIMES: u32 = 20;

/// How high the hand lifts the tube before it turns it (m): turned about the fingers, the hand's
/// own wrist swings down past them (the 2F-85's tool centre is 16 cm out), so it rises clear of
/// the rack it took the tube from by more than that.
const LIFT_M: f64 = 0.25;

pub(super) const PRIMITIVE: LabPrimitive = LabPrimitive {
    name: "invert",
    description: "turn a carried, capped tube upside down and back, a number of times, to mix it",
    args: &[
        ON,
        Arg {
            name: "times",
            kind: ArgKind::Count,
            doc: "how many times to turn it over and back, 1 to 20",
            optional: false,
        },
    ],
    requires: "the robot carries `on`; its cap is on",
    leaves: "`on` carried upright again, inverted that many more times in the stage (`<on> inverted <n> times`)",
    phrase: "mix the {on} by inverting it {times} times",
    // Not timed by `within`: the judge's count of turns is a stage's memory, not a state a
    // moment shows (what an outcome must be).
    outcome: None,
    effect,
    motions: Some(motions),
};

/// The count a `times` argument gives (E0020 not a whole number, E0021 out of range).
fn times(text: &str) -> Result<u32, Violation> {
    let n: u32 = text.trim().parse().map_err(|_| {
        violation(
            Code::E0020,
            Some("times"),
            format!("`{text}` is not a whole number of times"),
        )
    })?;
    if !(1..=MAX_TIMES).contains(&n) {
        return Err(violation(
            Code::E0021,
            Some("times"),
            format!("`invert` turns a tube over 1 to {MAX_TIMES} times, found {n}"),
        ));
    }
    Ok(n)
}

fn effect(w: &mut World, env: &Env, step: &BoundStep) -> Result<(), Violation> {
    let robot = step.robot;
    let (lw, _) = step.on(env)?;
    let n = times(step.text("times")?)?;
    require_carrying(w, robot, &lw, PRIMITIVE.name)?;
    if w.part(&lw, "cap") != Some("on") {
        return Err(precondition(
            format!("`invert` needs `{lw}` capped, but its cap is not on"),
            "add a `screw_cap` step before this one: an open tube turned over spills",
        ));
    }
    *w.inversions.entry(lw).or_default() += n;
    Ok(())
}

/// Lift clear, then turn the tube over about the fingers and back, `times` times.
fn motions(step: &MotionStep) -> Vec<Motion> {
    let n = times(&step.arg("times")).unwrap_or(1);
    let mut m = vec![Motion::Lift { height: LIFT_M }];
    for _ in 0..n {
        m.push(Motion::Tilt {
            angle: std::f64::consts::PI,
        });
        m.push(Motion::Tilt {
            angle: -std::f64::consts::PI,
        });
    }
    m
}
