//! What the run primitives (`spin`, `thermocycle`, `incubate`) share: the programme a step
//! carries ([`programme`], the one reading of a run step's arguments, for the proof and for the
//! task's models), the instrument shut and latched (E0038), tubes capped, the rotor balanced
//! (E0037), and the run left done with its least duration on the world's clock. Not a primitive
//! itself.

use super::prelude::*;
use crate::motion::{Motion, MotionStep};
use labware::run::{Programme, RUN};
use std::collections::BTreeMap;

/// How long a centrifuge takes to come up to speed and back down (s): the 5430's ramps, and the
/// range a spin's `ramp` may set (a soft ramp for pellets that must not stir up is minutes).
pub const SPIN_RAMP_S: f64 = 10.0;
pub const SPIN_RAMP_MIN_S: f64 = 1.0;
pub const SPIN_RAMP_MAX_S: f64 = 120.0;
/// The 5430's fastest spin with its 30-place rotor (rpm), and the slowest it offers.
pub const SPIN_MAX_RPM: f64 = 17_500.0;
pub const SPIN_MIN_RPM: f64 = 100.0;
/// The thermal mixer's shaking range (rpm) and its timer's longest run (s, 99:30 h).
pub const SHAKE_MIN_RPM: f64 = 300.0;
pub const SHAKE_MAX_RPM: f64 = 3000.0;
pub const INCUBATE_MAX_S: f64 = 99.5 * 3600.0;
/// A heated lid's temperature (°C), as cyclers default it.
pub const LID_C: f64 = 105.0;
/// The mass (g) a tube adds to a rotor besides its liquid, and the imbalance a rotor tolerates
/// (g, the tubes' masses times their slots' unit directions summed).
const TUBE_G: f64 = 1.0;
const IMBALANCE_G: f64 = 0.1;

/// Standard gravity (m/s²): a relative centrifugal force is the rotor's r ω² in these.
const STANDARD_G: f64 = 9.806_65;

/// The programme a run step carries, from its arguments (rendered) and the kind of the item it
/// runs on (`kind`: what a spin's `× g` converts with): `None` for a step that runs nothing.
pub fn programme(
    primitive: &str,
    args: &BTreeMap<String, String>,
    kind: Option<&str>,
) -> Option<Result<Programme, Violation>> {
    let q = |name: &'static str, dim: Dimension| quantity(args, name, dim);
    Some(match primitive {
        "spin" => (|| {
            let rpm = spin_rpm(args, kind)?;
            let seconds = q("duration", Dimension::Time)?;
            in_range("duration", seconds, 1.0, INCUBATE_MAX_S, "s")?;
            let ramp_s = match args.contains_key("ramp") {
                true => q("ramp", Dimension::Time)?,
                false => SPIN_RAMP_S,
            };
            in_range("ramp", ramp_s, SPIN_RAMP_MIN_S, SPIN_RAMP_MAX_S, "s")?;
            Ok(Programme::Spin {
                rpm,
                seconds,
                ramp_s,
            })
        })(),
        "thermocycle" => (|| {
            let text = args.get("profile").map(String::as_str).unwrap_or_default();
            let holds = crate::profile::parse_profile(text)
                .map_err(|e| violation(Code::E0021, Some("profile"), e.to_string()))?;
            Ok(Programme::Thermocycle {
                holds,
                lid_c: LID_C,
            })
        })(),
        "incubate" => (|| {
            let celsius = q("temperature", Dimension::Temperature)?;
            let rpm = q("speed", Dimension::Speed)?;
            let seconds = q("duration", Dimension::Time)?;
            in_range(
                "temperature",
                celsius,
                crate::profile::BLOCK_MIN_C,
                crate::profile::BLOCK_MAX_C,
                "°C",
            )?;
            in_range("speed", rpm, SHAKE_MIN_RPM, SHAKE_MAX_RPM, "rpm")?;
            in_range("duration", seconds, 1.0, INCUBATE_MAX_S, "s")?;
            Ok(Programme::Incubate {
                celsius,
                rpm,
                seconds,
            })
        })(),
        _ => return None,
    })
}

/// The rotor speed (rpm) a spin's `speed` asks for, in the instrument's range: as written in
/// rpm, or from a relative centrifugal force (`× g`, as kits write spins) at the radius the
/// instrument's model gives its rotor's load (RCF = r ω² / g, so ω = √(RCF g / r)).
fn spin_rpm(args: &BTreeMap<String, String>, kind: Option<&str>) -> Result<f64, Violation> {
    let text = args.get("speed").map(String::as_str).unwrap_or_default();
    let rcf = dsl::parse_quantity(text)
        .ok()
        .filter(|q| q.dimension == Dimension::Acceleration);
    let Some(rcf) = rcf else {
        let rpm = quantity(args, "speed", Dimension::Speed)?;
        in_range("speed", rpm, SPIN_MIN_RPM, SPIN_MAX_RPM, "rpm")?;
        return Ok(rpm);
    };
    let model = kind.and_then(labware::Model::for_kind);
    let radius = model
        .as_ref()
        .and_then(labware::Model::instrument)
        .and_then(|m| m.rcf_radius_m())
        .ok_or_else(|| {
            violation(
                Code::E0021,
                Some("speed"),
                format!(
                    "`{text}` is a force, but `{}` has no rotor radius to turn it into a speed",
                    kind.unwrap_or("the item")
                ),
            )
        })?;
    let omega = (rcf.si * STANDARD_G / radius).sqrt();
    let rpm = omega * 60.0 / std::f64::consts::TAU;
    if (SPIN_MIN_RPM..=SPIN_MAX_RPM).contains(&rpm) {
        return Ok(rpm);
    }
    Err(violation(
        Code::E0021,
        Some("speed"),
        format!(
            "`{text}` needs {rpm:.0} rpm at this rotor's {:.1} cm, outside the instrument's {SPIN_MIN_RPM}..{SPIN_MAX_RPM} rpm",
            radius * 100.0
        ),
    ))
}

fn quantity(
    args: &BTreeMap<String, String>,
    name: &'static str,
    dim: Dimension,
) -> Result<f64, Violation> {
    let text = args.get(name).map(String::as_str).unwrap_or_default();
    super::quantity_arg(text, name, dim)
}

fn in_range(name: &'static str, v: f64, lo: f64, hi: f64, unit: &str) -> Result<(), Violation> {
    if (lo..=hi).contains(&v) {
        return Ok(());
    }
    Err(violation(
        Code::E0021,
        Some(name),
        format!("`{name}` is {v} {unit}, outside the instrument's {lo}..{hi} {unit}"),
    ))
}

/// The step's programme on an item of `kind`, its violations as the proof reports them.
pub(super) fn step_programme(step: &BoundStep, kind: &LabwareKind) -> Result<Programme, Violation> {
    programme(step.primitive.name, step.args, Some(kind.name))
        .expect("a run primitive carries a programme")
}

/// The instrument's lid is closed and latched (E0038).
pub(super) fn require_shut(
    w: &World,
    lw: &str,
    kind: &LabwareKind,
    what: &str,
) -> Result<(), Violation> {
    let state = w.part(lw, "lid").unwrap_or("locked");
    let (now, hint) = match state {
        "locked" => return Ok(()),
        "closed" if kind.supports("lock") => (
            "closed but not latched".to_string(),
            format!("add a `lock` step on `{lw}` before this one"),
        ),
        "closed" => (
            "closed but not latched".to_string(),
            format!(
                "`close_lid` latches it as it shuts: open the lid (`open_lid` on `{lw}`) and close it again before this step, or let `{lw}` start `locked`"
            ),
        ),
        other => (
            other.to_string(),
            format!(
                "add a `close_lid` step on `{lw}` before this one (it latches the lid as it shuts)"
            ),
        ),
    };
    Err(Violation {
        code: Code::E0038,
        arg: None,
        message: format!("`{what}` needs `{lw}`'s lid closed and latched, but it is {now}"),
        hint: Some(hint),
    })
}

/// The items standing in `holder`'s slots, with their slots.
fn loaded<'w>(w: &'w World, holder: &str) -> Vec<(&'w str, &'w str)> {
    w.locations
        .iter()
        .filter_map(|(item, loc)| match loc {
            Location::Slot { holder: h, slot } if h == holder => {
                Some((item.as_str(), slot.as_str()))
            }
            _ => None,
        })
        .collect()
}

/// Every tube in `holder`'s slots has its cap on (a run shakes or spins them).
pub(super) fn require_capped(w: &World, holder: &str, what: &str) -> Result<(), Violation> {
    for (item, _) in loaded(w, holder) {
        if let Some(cap) = w.part(item, "cap")
            && cap != "on"
        {
            return Err(precondition(
                format!("`{what}` would run `{item}` in `{holder}` with its cap {cap}"),
                &format!("screw the cap back on `{item}` before this step"),
            ));
        }
    }
    Ok(())
}

/// The tubes in a ring rotor balance (E0037): their masses times their slots' directions sum
/// to under [`IMBALANCE_G`].
pub(super) fn require_balanced(
    w: &World,
    holder: &str,
    kind: &LabwareKind,
) -> Result<(), Violation> {
    let Some(labware::Slots {
        layout: layout @ labware::SlotLayout::Ring { n },
        ..
    }) = kind.slots
    else {
        return Ok(());
    };
    let load = loaded(w, holder);
    let (mut x, mut y) = (0.0, 0.0);
    let mut masses = Vec::new();
    for (item, slot) in &load {
        let Ok(i) = slot.parse::<u32>() else { continue };
        let angle = std::f64::consts::TAU * f64::from(i - 1) / f64::from(n);
        let grams = TUBE_G + w.volumes.get(*item).copied().unwrap_or(0.0) / 1000.0;
        x += grams * angle.cos();
        y += grams * angle.sin();
        masses.push(format!("`{item}` in {slot} ({grams:.2} g)"));
    }
    let off = x.hypot(y);
    if off <= IMBALANCE_G {
        return Ok(());
    }
    let hint = match load.as_slice() {
        [(_, slot)] => format!(
            "add a tube with the same volume in the opposite slot, `{holder}.{}`",
            layout.opposite(slot).unwrap_or_default()
        ),
        _ => "put tubes of equal volume in evenly spaced slots: opposite pairs, or three 120° apart (a slot parameter with `balances` and `tubes` draws them)".to_string(),
    };
    Err(Violation {
        code: Code::E0037,
        arg: Some("on"),
        message: format!(
            "`{holder}`'s rotor is unbalanced by {off:.2} g: {}",
            masses.join(", ")
        ),
        hint: Some(hint),
    })
}

/// The run done: its state, and its least duration on the world's clock.
pub(super) fn ran(w: &mut World, lw: &str, programme: &Programme) {
    w.set_part(lw, RUN, "done");
    w.clock_s += programme.least_duration();
}

/// How long the expert waits for a run at most beyond its own length (s).
const RUN_SLACK_S: f64 = 120.0;

/// Keep still until the instrument's run (of primitive `primitive`) is done.
pub(super) fn await_run(step: &MotionStep, primitive: &str) -> Motion {
    let timeout_s = programme(primitive, step.args, step.kind.map(|k| k.name))
        .and_then(Result::ok)
        .map_or(RUN_SLACK_S, |p| {
            p.duration(labware::run::ROOM_C) + RUN_SLACK_S
        });
    Motion::AwaitRun {
        labware: step.arg("on"),
        timeout_s,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spin(speed: &str) -> BTreeMap<String, String> {
        BTreeMap::from([
            ("speed".to_string(), speed.to_string()),
            ("duration".to_string(), "1 min".to_string()),
        ])
    }

    fn rpm(p: Programme) -> f64 {
        match p {
            Programme::Spin { rpm, .. } => rpm,
            other => panic!("{other:?}"),
        }
    }

    /// A force converts at the model's rotor radius, both ways round: RCF = r ω² / g.
    #[test]
    fn a_spin_in_x_g_runs_at_the_speed_that_gives_that_force_at_the_rotor() {
        let kind = Some("centrifuge_5430");
        let model = labware::Model::for_kind("centrifuge_5430").unwrap();
        let r = model.instrument().unwrap().rcf_radius_m().unwrap();
        for text in ["16000 x g", "16000 × g", "16000xg"] {
            let v = rpm(programme("spin", &spin(text), kind).unwrap().unwrap());
            let omega = v * std::f64::consts::TAU / 60.0;
            let force = r * omega * omega / STANDARD_G;
            assert!((force - 16000.0).abs() < 1e-6, "{text}: {force}");
        }
        assert_eq!(
            rpm(programme("spin", &spin("12000 rpm"), kind)
                .unwrap()
                .unwrap()),
            12000.0
        );
        // Past the rotor's top speed, with the speed it would need.
        let e = programme("spin", &spin("40000 x g"), kind)
            .unwrap()
            .unwrap_err();
        assert_eq!(e.code, Code::E0021);
        assert!(e.message.contains("rpm at this rotor's"), "{}", e.message);
        // An item with no rotor cannot turn a force into a speed.
        let e = programme("spin", &spin("1000 x g"), Some("thermal_mixer"))
            .unwrap()
            .unwrap_err();
        assert!(e.message.contains("no rotor radius"), "{}", e.message);
        // A force where a speed is asked for elsewhere is the wrong dimension.
        let mut shake = spin("1000 x g");
        shake.insert("temperature".into(), "37 °C".into());
        let e = programme("incubate", &shake, Some("thermal_mixer"))
            .unwrap()
            .unwrap_err();
        assert_eq!(e.code, Code::E0020);
    }

    /// A spin's optional `ramp` sets how long the rotor takes up and down (the default where
    /// left out); out of range or not a time, it is refused.
    #[test]
    fn a_spin_ramps_over_its_ramp_or_the_default() {
        let kind = Some("centrifuge_5430");
        let ramp = |args: &BTreeMap<String, String>| match programme("spin", args, kind) {
            Some(Ok(Programme::Spin { ramp_s, .. })) => Ok(ramp_s),
            Some(Err(e)) => Err(e.code),
            other => panic!("{other:?}"),
        };
        assert_eq!(ramp(&spin("12000 rpm")), Ok(SPIN_RAMP_S));
        let mut soft = spin("12000 rpm");
        soft.insert("ramp".into(), "45 s".into());
        assert_eq!(ramp(&soft), Ok(45.0));
        soft.insert("ramp".into(), "5 min".into());
        assert_eq!(ramp(&soft), Err(Code::E0021));
        soft.insert("ramp".into(), "45 rpm".into());
        assert_eq!(ramp(&soft), Err(Code::E0020));
    }
}
