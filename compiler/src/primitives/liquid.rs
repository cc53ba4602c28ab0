//! What `aspirate` and `dispense` share: moving a volume between an open container and the pipette
//! the robot carries.

use super::prelude::*;

/// The tool pose that brings `tool`'s opening onto `on`'s affordance `to`, `above` metres back
/// along it: what `aspirate` and `dispense` aim with.
pub(super) fn tip_onto(tool: &str, on: &str, to: &str, above: f64) -> crate::motion::Target {
    crate::motion::Target::Bring {
        carried: tool.into(),
        from: "opening".into(),
        labware: on.into(),
        to: to.into(),
        above,
    }
}

/// Where the tip waits over a container's mouth before it goes in (m above the mouth).
pub(super) const OVER_MOUTH: f64 = 0.03;
/// How far into a container's mouth a tip dispenses from (m).
pub(super) const INTO_MOUTH: f64 = 0.02;
/// Where a tip comes up to when it is done (m above the mouth: clear of the container).
pub(super) const WITHDRAW: f64 = 0.06;
/// The longest a press to a plunger's stop may take (s).
pub(super) const PRESS_TIMEOUT_S: f64 = 6.0;
/// How long the thumb takes to ease off the plunger (s): upstream's 3.2 s release.
pub(super) const EASE_S: f64 = 3.2;
/// How long after the plunger stops the tip waits for the liquid to finish flowing (s): five of
/// the flow's time constants (`labware::process::Pipetting`).
pub(super) const FLOW_S: f64 = 0.75;

pub(super) fn effect(w: &mut World, env: &Env, step: &BoundStep) -> Result<(), Violation> {
    let robot = step.robot;
    let name = step.primitive.name;
    let (lw, _) = step.on(env)?;
    let volume = step.quantity("volume", Dimension::Volume)?;
    if volume <= 0.0 {
        return Err(violation(
            Code::E0021,
            Some("volume"),
            format!("`{name}` needs a positive volume, found {volume} µL"),
        ));
    }
    let pipette = match w.hand(robot) {
        Hand::Item(p) if env.kinds.get(p).is_some_and(|k| k.liquid_tool) => p.clone(),
        h => {
            return Err(precondition(
                format!("`{name}` needs `{robot}` to carry a pipette, but its hand is {h}"),
                "add a `pick` of the pipette before this step",
            ));
        }
    };
    if w.part(&lw, "cap") == Some("on") {
        return Err(precondition(
            format!("`{name}` needs `{lw}` open, but its cap is on"),
            "add an `unscrew_cap` step before this one",
        ));
    }
    let (from, to) = if name == "aspirate" {
        (lw.clone(), pipette)
    } else {
        (pipette, lw.clone())
    };
    let have = w.volumes.get(&from).copied().unwrap_or(0.0);
    let room =
        env.kinds[&to].capacity_ul.unwrap_or(0.0) - w.volumes.get(&to).copied().unwrap_or(0.0);
    if have < volume {
        return Err(precondition(
            format!("`{name}` of {volume} µL needs that much in `{from}`, but it holds {have} µL"),
            "lower the volume or fill the container first",
        ));
    }
    if room < volume {
        return Err(precondition(
            format!("`{name}` of {volume} µL needs that much room in `{to}`, but it has {room} µL"),
            "lower the volume or empty it first",
        ));
    }
    w.move_contents(&from, &to, volume);
    *w.volumes.entry(from).or_default() -= volume;
    *w.volumes.entry(to).or_default() += volume;
    Ok(())
}
