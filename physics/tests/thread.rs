//! The thread SDF plugin on real MuJoCo, with upstream's 1.5 mL screw-cap geometry.
// Tests print the figures they measure (shown with --nocapture).
#![allow(clippy::print_stdout)]

use mujoco_rs::prelude::*;
use physics::thread::ScrewCap;

use physics::scenes::{SCREW_TIMESTEP as TIMESTEP, cap_mass, cap_torque, screw_cap};

fn scene(cap: &ScrewCap, lift_turns: f64, friction: f64, gravity: bool) -> String {
    screw_cap(cap, lift_turns, friction, gravity, true)
}

struct Run {
    model: MjModel,
}

impl Run {
    fn new(xml: &str) -> Run {
        physics::register().unwrap();
        Run {
            model: MjModel::from_xml_string(xml).unwrap(),
        }
    }
}

/// Cap height (m), unwrapped yaw (rad) and contacts over time, with `torque` about +z and `lift`
/// (N) along +z applied to the cap, until `seconds` pass or `done` says so (a free cap under a
/// constant torque would spin up without bound). Asserts the simulation stayed stable.
fn simulate_until(
    run: &Run,
    seconds: f64,
    torque: f64,
    lift: f64,
    done: impl Fn(&[(f64, f64, usize)]) -> bool,
) -> Vec<(f64, f64, usize)> {
    let mut data = MjData::new(&run.model);
    let cap = run.model.name_to_id(MjtObjBase::mjOBJ_BODY, "cap").unwrap();
    let mut out = Vec::new();
    let mut yaw = 0.0;
    let mut last = None;
    let steps = (seconds / TIMESTEP) as usize;
    for _ in 0..steps {
        data.xfrc_applied_mut()[cap] = [0.0, 0.0, lift, 0.0, 0.0, torque];
        data.step();
        let xm = data.xmat()[cap];
        let a = xm[3].atan2(xm[0]);
        if let Some(prev) = last {
            let mut da: f64 = a - prev;
            da = (da + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
                - std::f64::consts::PI;
            yaw += da;
        }
        last = Some(a);
        out.push((data.xpos()[cap][2], yaw, data.ncon() as usize));
        if done(&out) {
            break;
        }
    }
    let unstable = data.ffi().warning[MjtWarning::mjWARN_BADQACC as usize].number;
    assert_eq!(unstable, 0, "the simulation went unstable");
    out
}

fn simulate(run: &Run, seconds: f64, torque: f64, lift: f64) -> Vec<(f64, f64, usize)> {
    simulate_until(run, seconds, torque, lift, |_| false)
}

fn torque(cap: &ScrewCap) -> f64 {
    cap_torque(cap)
}

#[test]
fn every_tube_size_screws_on_one_pitch_per_turn() {
    for (name, radius) in physics::thread::CONTAINERS {
        let cap = ScrewCap::new(radius);
        screws_on(name, &cap);
    }
}

fn screws_on(name: &str, cap: &ScrewCap) {
    let run = Run::new(&scene(cap, 1.0, 0.3, false));
    // Clockwise seen from above tightens a right-handed thread. Measured over the first turn and
    // a half, while the threads overlap (the model has no shoulder to stop the cap).
    let trace = simulate_until(&run, 2.0, -torque(cap), 0.0, |t| {
        t.last().unwrap().1 - t[0].1 < -1.6 * std::f64::consts::TAU
    });
    let (z0, y0, _) = trace[0];
    let end = trace
        .iter()
        .position(|t| t.1 - y0 < -1.5 * std::f64::consts::TAU)
        .unwrap_or_else(|| panic!("{name}: the cap did not turn 1.5 turns in 2 s"));
    let (z1, y1, _) = trace[end];
    let turns = (y1 - y0) / std::f64::consts::TAU;
    let advance = (z1 - z0) / turns.abs();
    let pitch = cap.bolt.pitch;
    eprintln!("thread {name}: {advance:.6} m per turn over {turns:.2} turns (pitch {pitch})");
    // docs/physics.md measures 3.007 to 3.020 mm on a 3 mm pitch (at most 0.7% off); the bound
    // is 2%, room for solver differences across machines, and fails a pitch mis-set by 5%.
    assert!(
        (advance + pitch).abs() < 0.02 * pitch,
        "{name}: advance {advance} m per turn, pitch {pitch}"
    );
}

#[test]
fn with_friction_a_cap_holds_under_gravity_and_without_it_runs_down() {
    let cap = ScrewCap::new(0.005992);
    // Upstream's friction 1: self-locking, the cap stays put.
    let locked = simulate(&Run::new(&scene(&cap, 1.0, 1.0, true)), 1.0, 0.0, 0.0);
    let (z0, y0, _) = locked[0];
    let (z1, y1, _) = *locked.last().unwrap();
    eprintln!(
        "thread: friction 1 moved {:.2e} m, turned {:.2e} rad in 1 s",
        z1 - z0,
        y1 - y0
    );
    assert!((y1 - y0).abs() < 0.02, "turned {} rad", y1 - y0);
    assert!((z1 - z0).abs() < 1e-4, "moved {} m", z1 - z0);
    // Nearly frictionless: its weight screws it down the thread.
    let free = simulate(&Run::new(&scene(&cap, 1.0, 0.01, true)), 1.0, 0.0, 0.0);
    let (z2, y2, _) = *free.last().unwrap();
    eprintln!(
        "thread: friction 0.01 descended {:.4} m, turned {:.2} rad in 1 s",
        z2 - free[0].0,
        y2 - free[0].1
    );
    assert!(z2 - free[0].0 < -1e-3, "descended {} m", z2 - free[0].0);
    assert!(y2 - free[0].1 < -0.5, "and turned {} rad", y2 - free[0].1);
}

#[test]
fn unscrewing_past_the_last_turn_frees_the_cap() {
    let cap = ScrewCap::new(0.005992);
    let run = Run::new(&scene(&cap, 0.0, 0.3, true));
    let weight = cap_mass(&cap) * 9.81;
    // Engaged, a pull of 1.5 times its weight does not lift it: the thread holds axially.
    let held = simulate(&run, 0.5, 0.0, 1.5 * weight);
    let rise = held.last().unwrap().0 - held[0].0;
    assert!(rise.abs() < 2e-4, "an engaged cap rose {rise} m");
    // Turning it anticlockwise walks it up and off the thread.
    let z_start = held[0].0;
    let unscrew = simulate_until(&run, 3.0, torque(&cap), 0.0, |t| {
        let last = t.last().unwrap();
        last.2 == 0 && last.0 - z_start > 2.0 * cap.bolt.pitch
    });
    let (z0, y0, _) = unscrew[0];
    let off = unscrew
        .iter()
        .position(|t| t.2 == 0 && t.0 - z0 > 2.0 * cap.bolt.pitch)
        .expect("the cap comes off the thread within 3 s");
    let turns = (unscrew[off].1 - y0) / std::f64::consts::TAU;
    eprintln!(
        "thread: engaged cap rose {rise:.2e} m under 1.5x its weight; came off after {turns:.2} turns"
    );
    assert!(turns > 1.5, "came off after {turns} turns");
}
