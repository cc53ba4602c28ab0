//! The Aloha (ViperX 300s) on real MuJoCo: its layouts name its joints and its gripper in metres;
//! the expert picks the tube up (the closed-form IK end to end); and a tube that is lifted and
//! then let go fails the pick-up check, from the state MuJoCo produces; two arms unscrew a cap,
//! screw it back on, and screw on a cap picked up from the bench; and a cap turned part way off
//! (or part way on), or raised off its thread and let go, fails its check. (Its no-motion runs
//! are in tests/hold_control.rs; its IK round trip in tests/kinematics.rs.)

use crate::common;

use common::{compile, predicate, run, run_with};
use expert::ExpertPolicy;
use policy::Observation;
use policy::Policy;
use policy::PolicyError;

#[test]
fn the_aloha_layout_names_its_joints_and_its_gripper_in_metres() {
    let m = robots::model("aloha_vx300s").unwrap();
    assert_eq!(
        m.state_names(),
        [
            "waist",
            "shoulder",
            "elbow",
            "forearm_roll",
            "wrist_angle",
            "wrist_rotate",
            "gripper:left_finger"
        ]
    );
    assert_eq!(m.action_len(), 7);
    assert_eq!((m.gripper.state_unit, m.gripper.action_unit), ("m", "m"));
    assert!(m.gripper.open > m.gripper.closed, "larger is more open");
}

#[test]
fn the_expert_picks_the_tube_up() {
    let t = compile("protocols/tube/pick_up.toml");
    let r = run(&t, 11, "expert");
    assert!(r.success, "{:#?}", r.verdict);
    let lifted = predicate(&r, "tube lifted 9.5 cm");
    assert!(lifted.value >= 0.095, "{lifted:?}");
}

/// The expert, except that once the tube stands `drop_at` metres above its start, the gripper
/// opens and stays open.
struct LetGo {
    expert: ExpertPolicy,
    tube: usize,
    start_z: Option<f64>,
    open: f64,
    dropped: bool,
}

impl Policy for LetGo {
    fn name(&self) -> String {
        "let-go".into()
    }

    fn act(&mut self, obs: &Observation) -> Result<Vec<Vec<f64>>, PolicyError> {
        let mut a = self.expert.act(obs)?;
        let z = obs.privileged.labware[self.tube].pose.translation.vector.z;
        let start = *self.start_z.get_or_insert(z);
        self.dropped |= z - start > 0.06;
        if self.dropped {
            *a[0].last_mut().unwrap() = self.open;
        }
        Ok(a)
    }
}

#[test]
fn a_tube_lifted_and_then_let_go_fails_the_pick_up() {
    let t = compile("protocols/tube/pick_up.toml");
    let tube = t.labware_index("tube").unwrap();
    let open = robots::model("aloha_vx300s").unwrap().gripper.open;
    let r = run_with(&t, 11, &Default::default(), |t, s, i| {
        Box::new(LetGo {
            expert: ExpertPolicy::new(t, s, i).unwrap(),
            tube,
            start_z: None,
            open,
            dropped: false,
        })
    });
    assert!(!r.success && r.error.is_none(), "{r:?}");
    // The tube fell back (to the rack or the bench): well under the lift, and no finger on it.
    let lifted = predicate(&r, "tube lifted 9.5 cm");
    assert!(!lifted.holds && lifted.value < 0.05, "{lifted:?}");
    assert!(!predicate(&r, "arm holds tube.cap").holds);
}

/// The expert until `stop` says so of the cap's rise on its thread (m; and whether it has been
/// off, risen past 10 mm), then no motion (the hands keep their grips: the held targets and
/// gripper commands stay).
struct StopAt {
    expert: ExpertPolicy,
    tube: usize,
    model: labware::Model,
    stop: fn(f64, bool) -> bool,
    was_off: bool,
    stopped: Option<Vec<Vec<f64>>>,
}

impl Policy for StopAt {
    fn name(&self) -> String {
        "stop-at".into()
    }

    fn act(&mut self, obs: &Observation) -> Result<Vec<Vec<f64>>, PolicyError> {
        if let Some(a) = &self.stopped {
            return Ok(a.clone());
        }
        let a = self.expert.act(obs)?;
        let tube = &obs.privileged.labware[self.tube];
        let labware::Model::Tube(p) = &self.model else {
            panic!("a tube model")
        };
        let (risen, _) = labware::tube::cap_rise_and_aside(p, tube).unwrap();
        self.was_off |= risen > 0.01;
        if (self.stop)(risen, self.was_off) {
            self.stopped = Some(a.clone());
        }
        Ok(a)
    }
}

/// Episode `seed` of `t` under the expert stopped where `stop` says (see [`StopAt`]).
fn run_stopped(
    t: &compiler::Task,
    seed: u64,
    stop: fn(f64, bool) -> bool,
) -> results::episode::EpisodeResult {
    let tube = t.labware_index("tube").unwrap();
    let model = t.labware[tube].params.clone();
    run_with(t, seed, &Default::default(), |t, s, i| {
        Box::new(StopAt {
            expert: ExpertPolicy::new(t, s, i).unwrap(),
            tube,
            model,
            stop,
            was_off: false,
            stopped: None,
        })
    })
}

#[test]
fn a_cap_turned_half_way_off_is_not_lifted() {
    let mut t = compile("protocols/tube/unscrew_cap.toml");
    t.time_limit_s = 25.0;
    let r = run_stopped(&t, 3, |risen, _| risen >= 0.002);
    assert!(!r.success && r.error.is_none(), "{r:?}");
    let lifted = predicate(&r, "tube.cap lifted 3 cm");
    // Two thirds of a turn up the thread, still on it: risen 2 to 4 mm of the 30 mm it needs,
    // though the opener's fingers are on it.
    assert!(
        !lifted.holds && lifted.value > 0.0015 && lifted.value < 0.005,
        "{lifted:?}"
    );
    assert!(predicate(&r, "opener holds tube.cap").holds);
}

/// The expert until the cap has risen 15 mm off its seat (off the thread), then the opener's
/// fingers open and every arm keeps still: the cap drops back onto the tube's mouth and nobody
/// holds it. Upstream's rule (3 cm up and in the opener's fingers) fails it; our former one
/// (10 mm up and the opener touching the tube) would have passed it while it was let go.
struct LetCapGo {
    expert: ExpertPolicy,
    tube: usize,
    model: labware::Model,
    open: f64,
    /// The opener's gripper in an action (the last of its block).
    gripper: usize,
    let_go: Option<Vec<Vec<f64>>>,
}

impl Policy for LetCapGo {
    fn name(&self) -> String {
        "let-cap-go".into()
    }

    fn act(&mut self, obs: &Observation) -> Result<Vec<Vec<f64>>, PolicyError> {
        if let Some(a) = &self.let_go {
            return Ok(a.clone());
        }
        let mut a = self.expert.act(obs)?;
        let labware::Model::Tube(p) = &self.model else {
            panic!("a tube model")
        };
        let (risen, _) =
            labware::tube::cap_rise_and_aside(p, &obs.privileged.labware[self.tube]).unwrap();
        if risen >= 0.015 {
            // The opener is the task's first robot: its gripper is its block's last value.
            a[0][self.gripper] = self.open;
            self.let_go = Some(a.clone());
        }
        Ok(a)
    }
}

#[test]
fn a_cap_raised_15_mm_and_let_go_fails_the_unscrewing() {
    let t = compile("protocols/tube/unscrew_cap.toml");
    assert_eq!(t.robots[0].name, "opener");
    let tube = t.labware_index("tube").unwrap();
    let model = t.labware[tube].params.clone();
    let aloha = robots::model("aloha_vx300s").unwrap();
    let (open, gripper) = (aloha.gripper.open, aloha.action_len() - 1);
    let r = run_with(&t, 5, &Default::default(), |t, s, i| {
        Box::new(LetCapGo {
            expert: ExpertPolicy::new(t, s, i).unwrap(),
            tube,
            model,
            open,
            gripper,
            let_go: None,
        })
    });
    assert!(!r.success && r.error.is_none(), "{r:?}");
    let held = predicate(&r, "opener holds tube.cap");
    assert!(!held.holds && held.value == 0.0, "{held:?}");
    // Off its thread, fallen back under the 3 cm: no longer where the fingers left it.
    let lifted = predicate(&r, "tube.cap lifted 3 cm");
    assert!(!lifted.holds && lifted.value < 0.015, "{lifted:?}");
}

#[test]
fn the_expert_unscrews_the_cap_with_two_arms() {
    let t = compile("protocols/tube/unscrew_cap.toml");
    let r = run(&t, 5, "expert");
    assert!(r.success, "{:#?}", r.verdict);
    // Upstream's rule, measured: 3 cm up, in the opener's fingers.
    assert!(predicate(&r, "tube.cap lifted 3 cm").value >= 0.03);
    assert!(predicate(&r, "opener holds tube.cap").holds);
}

/// Our screw-on variant's expert stopped once the cap, taken off and set back on the mouth, has
/// been turned down to 1.5 mm of its seat: half a turn short, on its thread but not seated.
#[test]
fn a_cap_screwed_half_a_turn_short_is_not_on() {
    let mut t = compile("protocols/tube/recap.toml");
    // The expert seats the cap by 55 s (100 seeds); this one is stopped before.
    t.time_limit_s = 60.0;
    let r = run_stopped(&t, 0, |risen, was_off| was_off && risen <= 0.0015);
    assert!(!r.success && r.error.is_none(), "{r:?}");
    assert!(predicate(&r, "tube.cap was off").holds);
    // Measured on the thread's travel: still over a millimetre up it and under a turn (3 mm;
    // the hand stopped mid-turn, and the cap sits back a little in the thread's play).
    let on = predicate(&r, "tube.cap is on within 0.5 mm");
    assert!(!on.holds && on.value > 0.001 && on.value < 0.003, "{on:?}");
}

#[test]
fn the_expert_screws_the_cap_back_on_with_two_arms() {
    let t = compile("protocols/tube/recap.toml");
    let r = run(&t, 1, "expert");
    assert!(r.success, "{:#?}", r.verdict);
    // It was off, and is seated along the thread within half a millimetre.
    let on = predicate(&r, "tube.cap is on within 0.5 mm");
    assert!(on.holds, "{on:?}");
}

/// The paper's screw-on: the cap starts on the bench, drawn in its disc, and ends seated.
#[test]
fn the_expert_screws_a_cap_from_the_bench_onto_its_tube() {
    let t = compile("protocols/tube/screw_cap.toml");
    let (instance, _) = common::scene(&t, 2);
    let cap = instance.part_placement["tube.cap"].translation.vector;
    assert!(
        ((cap.x - 0.2).powi(2) + (cap.y - 0.2).powi(2)).sqrt() <= 0.01 && cap.z == 0.824,
        "{cap:?}"
    );
    let r = run(&t, 2, "expert");
    assert!(r.success, "{:#?}", r.verdict);
    let on = predicate(&r, "tube.cap is on within 3.35 mm");
    assert!(on.holds && on.value <= 0.00335, "{on:?}");
}

/// The expert on the paper's screw-on, until the cap, set on the mouth, is turned down to 4 mm
/// of its seat; then every arm keeps still with its grip.
struct StopAbove {
    expert: ExpertPolicy,
    tube: usize,
    model: labware::Model,
    stopped: Option<Vec<Vec<f64>>>,
}

impl Policy for StopAbove {
    fn name(&self) -> String {
        "stop-above".into()
    }

    fn act(&mut self, obs: &Observation) -> Result<Vec<Vec<f64>>, PolicyError> {
        if let Some(a) = &self.stopped {
            return Ok(a.clone());
        }
        let a = self.expert.act(obs)?;
        let labware::Model::Tube(p) = &self.model else {
            panic!("a tube model")
        };
        let (risen, aside) =
            labware::tube::cap_rise_and_aside(p, &obs.privileged.labware[self.tube]).unwrap();
        // On the mouth (coaxial, not lying on the bench) and 4 mm up the thread.
        if aside < 0.002 && (0.0..=0.004).contains(&risen) {
            self.stopped = Some(a.clone());
        }
        Ok(a)
    }
}

#[test]
fn a_cap_4_mm_above_its_seat_fails_the_screwing_on() {
    let t = compile("protocols/tube/screw_cap.toml");
    let tube = t.labware_index("tube").unwrap();
    let model = t.labware[tube].params.clone();
    let r = run_with(&t, 2, &Default::default(), |t, s, i| {
        Box::new(StopAbove {
            expert: ExpertPolicy::new(t, s, i).unwrap(),
            tube,
            model,
            stopped: None,
        })
    });
    assert!(!r.success && r.error.is_none(), "{r:?}");
    // Past upstream's 3.35 mm, on the thread: under a turn (3 mm) more and it would count as on.
    let on = predicate(&r, "tube.cap is on within 3.35 mm");
    assert!(
        !on.holds && on.value > 0.00335 && on.value < 0.006,
        "{on:?}"
    );
}
