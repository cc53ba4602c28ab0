//! Vortex mixing with two Aloha arms on real MuJoCo: the expert holds the tube in the cup and
//! switches the mixer on, and the check holds only for what it claims. A mixer switched on whose
//! cup has not reached its speed is not on (the drive's speed is measured, not the switch read),
//! and a tube lifted off the cup while the mixer runs fails, from the states MuJoCo produces.
//! (The no-motion run is in tests/hold_control.rs.)

mod common;

use common::{compile, compile_edited, predicate, run, run_with};
use labware::Instrument;
use runtime::{Env, EnvOptions};
use scoring::expert::ExpertPolicy;
use scoring::{Observation, Policy, PolicyError};

const PROTOCOL: &str = "protocols/vortex_mixer/mix_tube.toml";

#[test]
fn the_expert_holds_the_tube_in_the_cup_and_switches_the_mixer_on() {
    let t = compile(PROTOCOL);
    let r = run(&t, 3, "expert");
    assert!(r.success, "{:#?}", r.verdict);
    let on = predicate(&r, "vortex.power is on");
    // The drive's measured speed, as a fraction of the set 2,500 rpm, within 10%.
    assert!(on.holds, "{on:?}");
}

#[test]
fn a_mixer_switched_on_is_not_on_until_its_cup_orbits_at_speed() {
    // Switched on from the start, nobody pressing anything.
    let t = compile_edited(PROTOCOL, |s| {
        let s = s.replace(
            r#"state = { power = "off" }"#,
            r#"state = { power = "on" }"#,
        );
        let press = s.find("[[steps]]\ndo = \"press\"").unwrap();
        let success = s.find("[success]").unwrap();
        format!("{}{}", &s[..press], &s[success..])
    });
    let mut env = Env::make(&t, 0, EnvOptions::default()).unwrap();
    let i = t.labware_index("vortex").unwrap();
    let labware::Model::VortexMixer(mixer) = &t.labware[i].params else {
        panic!("a vortex mixer")
    };
    let hold = env.episode().ctrl();
    let on = |env: &Env| {
        let state = &env.episode().labware_state()[i];
        (
            state.flag("power"),
            mixer.measure("power", "on", None, state).unwrap(),
        )
    };
    env.step(&hold).unwrap();
    let (switched, first) = on(&env);
    // Switched on, but 20 ms into its spin-up the drive is far below its speed.
    assert!(switched && !first.holds && first.value < 0.5, "{first:?}");
    for _ in 0..75 {
        env.step(&hold).unwrap();
    }
    let (_, later) = on(&env);
    assert!(later.holds && (later.value - 1.0).abs() <= 0.1, "{later:?}");
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
