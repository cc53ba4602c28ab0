//! Vortex mixing with two Aloha arms on real MuJoCo: the expert holds the tube in the cup, turns
//! the speed knob through its detent to the drawn speed and switches the mixer on, and the check
//! holds only for what it claims. A mixer switched on whose cup has not reached its speed is not
//! on (the drive's speed is measured, not the switch read), one switched on with its knob at 0
//! never runs, and a tube lifted off the cup while the mixer runs fails, from the states MuJoCo
//! produces.
//! (The no-motion run is in tests/hold_control.rs.)

use crate::common;

use common::{compile, compile_edited, predicate, run, run_with};
use expert::ExpertPolicy;
use labware::{Instrument, Panel};
use policy::Observation;
use policy::Policy;
use policy::PolicyError;
use std::sync::{Arc, Mutex};

const PROTOCOL: &str = "protocols/vortex_mixer/mix_tube.toml";

#[test]
fn the_expert_turns_the_knob_to_the_drawn_speed_and_switches_the_mixer_on() {
    let t = compile(PROTOCOL);
    let r = run(&t, 3, "expert");
    assert!(r.success, "{:#?}", r.verdict);
    // Seed 3 draws 2,000 rpm: the knob's sixth notch (2,044 rpm) is the nearest, 2.76 rad
    // from where it starts, turned in three grips.
    let speed = predicate(&r, "vortex.speed = 2000 rpm");
    assert!(
        speed.holds && (speed.value - 2044.4).abs() < 0.1,
        "{speed:?}"
    );
    // The drive's measured speed, as a fraction of the knob's, within 10%.
    let on = predicate(&r, "vortex.power is on");
    assert!(on.holds && (on.value - 1.0).abs() <= 0.1, "{on:?}");
}

/// What the mixer was at one control step: the time, whether it is switched on, the speed its
/// knob sets (rpm), the drive's measured speed (rad/s), and what the judge's "power on" measures.
#[derive(Clone, Debug)]
struct Seen {
    time: f64,
    switched: bool,
    knob_rpm: f64,
    drive_rad_s: f64,
    on: labware::Measure,
}

/// The expert, noting the mixer at every control step.
struct Watch {
    expert: ExpertPolicy,
    mixer: usize,
    model: labware::vortex_mixer::Params,
    seen: Arc<Mutex<Vec<Seen>>>,
}

impl Policy for Watch {
    fn name(&self) -> String {
        "watch".into()
    }

    fn act(&mut self, obs: &Observation) -> Result<Vec<Vec<f64>>, PolicyError> {
        let state = &obs.privileged.labware[self.mixer];
        let seen = Seen {
            time: obs.time,
            switched: state.flag("power"),
            knob_rpm: self.model.panel_value("speed", state).unwrap(),
            drive_rad_s: state.logic["drive_rad_s"],
            on: self.model.measure("power", "on", None, state).unwrap(),
        };
        self.seen.lock().unwrap().push(seen);
        self.expert.act(obs)
    }
}

/// Runs the expert on `task` (seed 3), watching the mixer.
fn watched(task: &compiler::Task) -> (results::episode::EpisodeResult, Vec<Seen>) {
    let mixer = task.labware_index("vortex").unwrap();
    let labware::Model::VortexMixer(model) = &task.labware[mixer].params else {
        panic!("a vortex mixer")
    };
    let seen = Arc::new(Mutex::new(Vec::new()));
    let log = seen.clone();
    let model = model.clone();
    let r = run_with(task, 3, &Default::default(), move |t, s, i| {
        Box::new(Watch {
            expert: ExpertPolicy::new(t, s, i).unwrap(),
            mixer,
            model,
            seen: log,
        })
    });
    let seen = seen.lock().unwrap().clone();
    (r, seen)
}

#[test]
fn a_mixer_switched_on_is_not_on_until_its_cup_orbits_at_speed() {
    let (r, seen) = watched(&compile(PROTOCOL));
    assert!(r.success, "{:#?}", r.verdict);
    let switched = seen.iter().position(|s| s.switched).expect("switched on");
    // The knob was in its notch (2,044 rpm for seed 3's 2,000) before the switch was pressed;
    // at the switch the drive is far below that speed, and not on.
    let first = &seen[switched];
    assert!((first.knob_rpm - 2044.4).abs() < 0.1, "{first:?}");
    assert!(!first.on.holds && first.on.value < 0.5, "{first:?}");
    // 1.5 s later it turns at the knob's speed.
    let later = seen.iter().find(|s| s.time >= first.time + 1.5).unwrap();
    assert!(
        later.on.holds && (later.on.value - 1.0).abs() <= 0.1,
        "{later:?}"
    );
}

#[test]
fn a_mixer_switched_on_with_its_knob_at_zero_does_not_run() {
    // Nobody turns the knob: it stays at its stop, and the press switches the mixer on. The
    // speed is not asked for, so the plan proves "on".
    let t = compile_edited(PROTOCOL, |s| {
        let knob = s.find("[[steps]]\ndo = \"set_parameter\"").unwrap();
        let press = s.find("[[steps]]\ndo = \"press\"").unwrap();
        format!("{}{}", &s[..knob], &s[press..]).replace(r#""vortex.speed = {rpm} rpm", "#, "")
    });
    let (r, seen) = watched(&t);
    assert!(!r.success && r.error.is_none(), "{r:?}");
    let switched = seen.iter().position(|s| s.switched).expect("switched on");
    // Switched on for the rest of the episode, the cup still: never on.
    assert!(seen[switched..].len() > 500, "on for over 10 s");
    assert!(
        seen[switched..]
            .iter()
            .all(|s| s.switched && s.knob_rpm == 0.0)
    );
    assert!(
        seen.iter()
            .all(|s| !s.on.holds && s.drive_rad_s.abs() < 1.0)
    );
    assert!(!predicate(&r, "vortex.power is on").holds);
}

/// The expert, until the mixer is switched on; from then on the holder's shoulder is raised
/// (0.3 rad over a second) with its grip kept: the tube goes up with the hand.
struct LiftWhenOn {
    expert: ExpertPolicy,
    mixer: usize,
    holder_shoulder: usize,
    since: Option<f64>,
}

impl Policy for LiftWhenOn {
    fn name(&self) -> String {
        "lift-when-on".into()
    }

    fn act(&mut self, obs: &Observation) -> Result<Vec<Vec<f64>>, PolicyError> {
        let mut chunk = self.expert.act(obs)?;
        if self.since.is_none() && obs.privileged.labware[self.mixer].flag("power") {
            self.since = Some(obs.time);
        }
        if let Some(t0) = self.since {
            let raise = 0.3 * ((obs.time - t0) / 1.0).min(1.0);
            for a in &mut chunk {
                a[self.holder_shoulder] -= raise;
            }
        }
        Ok(chunk)
    }
}

#[test]
fn a_tube_lifted_off_the_cup_while_the_mixer_runs_fails() {
    let t = compile(PROTOCOL);
    let mixer = t.labware_index("vortex").unwrap();
    // The holder is the second robot: its block starts after the operator's; its shoulder is
    // its second joint.
    assert_eq!(t.robots[1].name, "holder");
    let operator = robots::model(&t.robots[0].model)
        .unwrap()
        .action_names()
        .len();
    let r = run_with(&t, 3, &Default::default(), |t, s, i| {
        Box::new(LiftWhenOn {
            expert: ExpertPolicy::new(t, s, i).unwrap(),
            mixer,
            holder_shoulder: operator + 1,
            since: None,
        })
    });
    assert!(!r.success && r.error.is_none(), "{r:?}");
    // The mixer ran at its speed, but the tube is no longer standing in the cup.
    assert!(predicate(&r, "vortex.power is on").holds);
    let cup = predicate(&r, "tube in vortex.cup");
    let height = cup.parts.iter().find(|q| q.name == "height").unwrap();
    assert!(!cup.holds && height.value > 0.005, "{cup:?}");
}
