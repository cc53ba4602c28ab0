//! A pipette worked in open tubes on real MuJoCo at the task timestep. The pipette is moved as a
//! hand would carry it (its free joint set each step, upright) and its button is pressed with a
//! thumb's force, ramped; the plunger's two springs, its stops and everything the liquid does
//! follow from the simulation and the item's logic: released with the tip under the surface the
//! tip draws its set volume and the tube's level falls; released above the surface it draws air;
//! withdrawn before the release ends it holds a short volume; pressed under the surface it
//! bubbles and draws nothing; pressed over another tube it dispenses there. Across every run the
//! tubes, the tip and the bench hold the starting volume to the nanolitre at every step. Then the
//! pipetting hand (`ur5e_inspire`) holding the pipette from the start works the plunger with its
//! thumb, and the shipped tasks' expert aspirates and transfers.

use crate::common;

use labware::process::{AIR_UL, BUBBLED_UL, SPILT_UL, VOLUME_UL};
use mujoco_rs::prelude::*;
use physics::liquid::{Liquid, Nanolitres};
use std::sync::Arc;

const PROTOCOL: &str = r#"format = 1
[protocol]
id = "test.pipette_in_tubes"
level = "medium"
instruction = "aspirate 500 µL"
time_limit = "30 s"

[robots.arm]
model = "ur5e_2f85"
base = { pos_m = [-0.6, 0.0, 0.824] }

[labware.rack]
kind = "tube_rack"
pose = { pos_m = [0.3, 0.0, 0.854], yaw_deg = 90 }

[labware.a]
kind = "tube_50ml"
at = "rack.A1"
state = { cap = "off", volume = "20 mL" }

[labware.b]
kind = "tube_50ml"
at = "rack.A3"
state = { cap = "off" }

[labware.pipette]
kind = "pipette"
pose = { pos_m = [0.3, 0.3, 0.9] }
state = { set_volume = "500 µL" }

[[steps]]
do = "pick"
on = "pipette"
with = "arm"

[[steps]]
do = "aspirate"
on = "a"
volume = "500 µL"
with = "arm"

[success]
all = ["pipette.volume = 500 µL"]
"#;

struct Bench {
    ep: runtime::Episode,
    task: compiler::Task,
    free: (usize, usize),
    button: usize,
    /// Tube `a`'s and `b`'s bases (world) and `a`'s liquid surface height above its base (m).
    a: [f64; 3],
    b: [f64; 3],
    level: f64,
}

const START_NL: u64 = 20_000_000;

impl Bench {
    fn new() -> Bench {
        let (task, diags) = compiler::compile_source(PROTOCOL, "pipette.toml");
        let task = task.unwrap_or_else(|| panic!("{diags:#?}"));
        let instance = task.sample(0);
        let scene = Arc::new(runtime::Scene::build(&task, &instance).unwrap());
        assert_eq!(scene.model.opt().timestep, 0.002);
        let ep = runtime::Episode::new(scene.clone(), &task, &instance);
        let pipette = task.labware_index("pipette").unwrap();
        let free = &scene.labware[pipette].free[0];
        let button = scene
            .model
            .name_to_id(MjtObjBase::mjOBJ_BODY, "pipette/button")
            .unwrap();
        let states = ep.labware_state();
        let at = |n: &str| {
            states[task.labware_index(n).unwrap()]
                .pose
                .translation
                .vector
                .into()
        };
        let (a, b) = (at("a"), at("b"));
        let labware::Model::Tube(tube) = &task.labware[task.labware_index("a").unwrap()].params
        else {
            panic!("a is a tube")
        };
        assert!(tube.open, "a tube whose cap starts off is made open");
        let bore = labware::Liquid::interior(tube).unwrap();
        let level = Liquid::new(bore, Nanolitres::from_microlitres(20_000.0), 0.0).offset();
        let (free_qpos, free_dof) = (free.qpos, free.dof);
        Bench {
            ep,
            task,
            free: (free_qpos, free_dof),
            button,
            a,
            b,
            level,
        }
    }

    fn logic(&self, item: &str, key: &str) -> f64 {
        let i = self.task.labware_index(item).unwrap();
        self.ep.labware_state()[i]
            .logic
            .get(key)
            .copied()
            .unwrap_or(0.0)
    }

    /// The liquid in both tubes, the tip and on the bench (nL).
    fn total_nl(&self) -> u64 {
        [
            ("a", VOLUME_UL),
            ("b", VOLUME_UL),
            ("pipette", VOLUME_UL),
            ("pipette", SPILT_UL),
        ]
        .iter()
        .map(|(i, k)| Nanolitres::from_microlitres(self.logic(i, k)).0)
        .sum()
    }

    /// Runs `script` for `seconds`: where the tip's opening is (world) and how hard the thumb
    /// presses the button (N) at each time since the start of the call, checking conservation after every control step (10
    /// physics steps); returns the plunger's deepest travel (m, both springs).
    fn run(&mut self, seconds: f64, script: &dyn Fn(f64) -> ([f64; 3], f64)) -> f64 {
        let (qpos, dof) = self.free;
        let mut deepest: f64 = 0.0;
        let steps = (seconds / 0.002).round() as usize;
        for k in 0..steps {
            let t = k as f64 * 0.002;
            let (opening, force) = script(t);
            let d = &mut self.ep.data;
            d.qpos_mut()[qpos..qpos + 7]
                .copy_from_slice(&[opening[0], opening[1], opening[2], 1.0, 0.0, 0.0, 0.0]);
            d.qvel_mut()[dof..dof + 6].fill(0.0);
            d.xfrc_applied_mut()[self.button] = [0.0, 0.0, -force, 0.0, 0.0, 0.0];
            self.ep.physics_step().unwrap();
            let s = &self.ep.labware_state()[self.task.labware_index("pipette").unwrap()];
            deepest = deepest.min(s.joint("plunger") + s.joint("blow_out"));
            if k % 10 == 9 {
                assert_eq!(self.total_nl(), START_NL, "at t = {t:.3} s");
            }
        }
        deepest
    }

    /// Over tube `base`'s mouth, `above` metres over its rim (negative: inside).
    fn over(&self, base: [f64; 3], above: f64) -> [f64; 3] {
        [base[0], base[1], base[2] + 0.1147 + above]
    }

    /// `depth` under tube `a`'s surface at the start.
    fn under(&self, depth: f64) -> [f64; 3] {
        [self.a[0], self.a[1], self.a[2] + self.level - depth]
    }
}

fn lerp(a: [f64; 3], b: [f64; 3], t: f64) -> [f64; 3] {
    let t = t.clamp(0.0, 1.0);
    [
        a[0] + (b[0] - a[0]) * t,
        a[1] + (b[1] - a[1]) * t,
        a[2] + (b[2] - a[2]) * t,
    ]
}

/// A thumb that presses to the first stop and not past it (the first spring gives 3.25 N
/// there, the second holds until 8 N).
const FIRST_STOP_N: f64 = 3.6;

#[test]
fn a_plunger_pressed_to_the_first_stop_and_released_under_the_surface_draws_the_set_volume() {
    let mut b = Bench::new();
    let (above, under) = (b.over(b.a, 0.02), b.under(0.01));
    // Pressed to the first stop over the tube: air out, nothing else.
    let deepest = b.run(0.6, &|t| (above, FIRST_STOP_N * (t / 0.2).min(1.0)));
    assert!(
        (deepest + 0.0075).abs() < 0.0004,
        "at the first stop, not past it: {deepest} m"
    );
    assert_eq!(b.logic("pipette", VOLUME_UL), 0.0);
    // In, 1 cm under the surface, still pressed; released over a second, as a thumb lets go.
    b.run(0.6, &|t| (lerp(above, under, t / 0.5), FIRST_STOP_N));
    let tube_before = b.logic("a", VOLUME_UL);
    b.run(0.5, &|t| (under, FIRST_STOP_N * (1.0 - t / 1.0)));
    let half_way = b.logic("pipette", VOLUME_UL);
    b.run(1.5, &|t| (under, FIRST_STOP_N * (0.5 - t).max(0.0)));
    b.run(0.6, &|t| (lerp(under, above, t / 0.5), 0.0));
    let tip = b.logic("pipette", VOLUME_UL);
    assert!((tip - 500.0).abs() <= 1.0, "the tip holds {tip} µL");
    assert!(
        half_way > 50.0 && half_way < 450.0,
        "drawn as the thumb let go, not at once: {half_way} µL half way"
    );
    assert!((tube_before - b.logic("a", VOLUME_UL) - tip).abs() < 1e-6);
    assert!(b.logic("pipette", AIR_UL) < 1.0);
    // The open tube stood in its rack through it all.
    let a = b.ep.labware_state()[b.task.labware_index("a").unwrap()].pose;
    let moved = (a.translation.vector - nalgebra::Vector3::from(b.a)).norm();
    assert!(moved < 0.002, "tube a moved {moved} m");
}

#[test]
fn released_above_the_surface_the_tip_draws_air() {
    let mut b = Bench::new();
    let above = b.over(b.a, 0.02);
    // Held at the first stop until the air is out (the flow's time constant is 0.15 s).
    b.run(1.2, &|t| (above, FIRST_STOP_N * (t / 0.2).min(1.0)));
    b.run(2.0, &|t| (above, FIRST_STOP_N * (1.0 - t).max(0.0)));
    assert_eq!(b.logic("pipette", VOLUME_UL), 0.0);
    assert_eq!(b.logic("a", VOLUME_UL), 20_000.0);
    let air = b.logic("pipette", AIR_UL);
    assert!((air - 500.0).abs() < 1.0, "{air} µL of air");
}

#[test]
fn withdrawn_before_the_release_ends_the_tip_holds_a_short_volume() {
    let mut b = Bench::new();
    let (above, under) = (b.over(b.a, 0.02), b.under(0.01));
    b.run(0.6, &|t| (above, FIRST_STOP_N * (t / 0.2).min(1.0)));
    b.run(1.2, &|t| (lerp(above, under, t / 0.5), FIRST_STOP_N));
    // Out of the liquid 0.4 s into a 1 s release.
    b.run(0.4, &|t| (under, FIRST_STOP_N * (1.0 - t)));
    b.run(2.0, &|t| {
        (
            lerp(under, above, t / 0.2),
            FIRST_STOP_N * (0.6 - t).max(0.0),
        )
    });
    let tip = b.logic("pipette", VOLUME_UL);
    assert!(tip > 20.0 && tip < 400.0, "{tip} µL");
    assert!((tip + b.logic("pipette", AIR_UL) - 500.0).abs() < 1.0);
}

#[test]
fn pressed_under_the_surface_the_tip_bubbles_and_draws_nothing() {
    let mut b = Bench::new();
    let (above, under) = (b.over(b.a, 0.02), b.under(0.01));
    b.run(0.6, &|t| (lerp(above, under, t / 0.5), 0.0));
    b.run(1.6, &|t| (under, FIRST_STOP_N * (t / 0.2).min(1.0)));
    b.run(0.6, &|t| (lerp(under, above, t / 0.5), FIRST_STOP_N));
    assert_eq!(b.logic("pipette", VOLUME_UL), 0.0);
    assert_eq!(b.logic("a", VOLUME_UL), 20_000.0);
    let bubbled = b.logic("pipette", BUBBLED_UL);
    assert!((bubbled - 500.0).abs() < 1.0, "{bubbled} µL bubbled");
}

#[test]
fn pressed_through_to_blow_out_over_another_tube_the_tip_empties_into_it() {
    let mut b = Bench::new();
    let (above, under) = (b.over(b.a, 0.02), b.under(0.01));
    b.run(0.6, &|t| (above, FIRST_STOP_N * (t / 0.2).min(1.0)));
    b.run(0.6, &|t| (lerp(above, under, t / 0.5), FIRST_STOP_N));
    b.run(2.0, &|t| (under, FIRST_STOP_N * (1.0 - t).max(0.0)));
    b.run(0.6, &|t| (lerp(under, above, t / 0.5), 0.0));
    let drawn = b.logic("pipette", VOLUME_UL);
    // Over the second tube, 2 cm into it, pressed through the first stop to blow-out.
    let into = b.over(b.b, -0.02);
    b.run(1.0, &|t| (lerp(above, into, t / 0.8), 0.0));
    let deepest = b.run(1.5, &|t| (into, 14.0 * (t / 0.3).min(1.0)));
    assert!(deepest < -0.0085, "past the first stop: {deepest} m");
    assert_eq!(b.logic("pipette", VOLUME_UL), 0.0);
    assert!((b.logic("b", VOLUME_UL) - drawn).abs() < 1e-6);
    assert_eq!(b.logic("pipette", SPILT_UL), 0.0);
    // The judge reads it: tube `a` lost what `b` holds.
    assert!((20_000.0 - b.logic("a", VOLUME_UL) - drawn).abs() < 1e-6);
}

/// [`PROTOCOL`] with its arm a `robot` that holds the pipette from the start (no pick).
fn held_by_the_arm(robot: &str) -> String {
    PROTOCOL
        .replace("model = \"ur5e_2f85\"", &format!("model = \"{robot}\""))
        .replace(
            "pose = { pos_m = [0.3, 0.3, 0.9] }\nstate",
            "held_by = \"arm\"\nstate",
        )
        .replace(
            "[[steps]]\ndo = \"pick\"\non = \"pipette\"\nwith = \"arm\"\n\n",
            "",
        )
}

/// An item a hand holds from the start (`held_by`) is welded where its grasp meets the TCP: at
/// reset and still after two seconds of a motionless arm (and the proof knows the hand is full).
#[test]
fn a_pipette_held_from_the_start_stays_at_the_hands_tcp() {
    let source = held_by_the_arm("ur5e_2f85");
    let (task, diags) = compiler::compile_source(&source, "held.toml");
    let task = task.unwrap_or_else(|| panic!("{diags:#?}"));
    let instance = task.sample(0);
    let scene = Arc::new(runtime::Scene::build(&task, &instance).unwrap());
    let mut ep = runtime::Episode::new(scene.clone(), &task, &instance);
    let pipette = task.labware_index("pipette").unwrap();
    let model = task.labware[pipette].params.instrument().unwrap();
    let grasp_off_tcp = |ep: &runtime::Episode| {
        let s = &ep.labware_state()[pipette];
        let grasp = model.affordance("grasp", s).unwrap().pose;
        let tcp = ep.data.site_xpos()[scene.robots[0].tcp_site];
        let z = grasp.rotation * nalgebra::Vector3::z();
        let tcp_z =
            nalgebra::Matrix3::from_row_slice(&ep.data.site_xmat()[scene.robots[0].tcp_site])
                * nalgebra::Vector3::z();
        (
            (grasp.translation.vector - nalgebra::Vector3::from(tcp)).norm(),
            z.angle(&tcp_z),
        )
    };
    let (d, angle) = grasp_off_tcp(&ep);
    assert!(d < 1e-6 && angle < 1e-6, "at reset: {d} m, {angle} rad");
    for _ in 0..100 {
        ep.control_step().unwrap();
    }
    let (d, angle) = grasp_off_tcp(&ep);
    assert!(d < 0.002 && angle < 0.02, "after 2 s: {d} m, {angle} rad");
    // Another item in the same hand is refused by the proof.
    let two = source.replace(
        "[labware.pipette]",
        "[labware.spare]\nkind = \"pipette\"\nheld_by = \"arm\"\n\n[labware.pipette]",
    );
    let (task, diags) = compiler::compile_source(&two, "two.toml");
    assert!(task.is_none());
    assert!(
        diags
            .iter()
            .any(|d| d.message.contains("both start in `arm`'s hand")),
        "{diags:#?}"
    );
}

/// The pipetting hand (UR5e + Inspire hand, `ur5e_inspire`) holds the pipette from the start and
/// its one thumb joint works the plunger: the thumb's command is the hand's action, and the
/// plunger's travel follows it through the contact of the thumb's pad on the button.
#[test]
fn the_hands_thumb_works_the_plunger_to_its_stops() {
    let source = held_by_the_arm("ur5e_inspire");
    let (task, diags) = compiler::compile_source(&source, "hand.toml");
    let task = task.unwrap_or_else(|| panic!("{diags:#?}"));
    let instance = task.sample(0);
    let scene = Arc::new(runtime::Scene::build(&task, &instance).unwrap());
    let mut ep = runtime::Episode::new(scene.clone(), &task, &instance);
    let pipette = task.labware_index("pipette").unwrap();
    let arm = ep.arm_q(0);
    let travel = |ep: &mut runtime::Episode, thumb: f64| {
        let mut action = arm.clone();
        action.push(thumb);
        ep.apply(&action).unwrap();
        for _ in 0..50 {
            ep.control_step().unwrap();
        }
        let s = &ep.labware_state()[pipette];
        (
            s.joint("plunger"),
            s.joint("blow_out"),
            ep.robot_state(0)[6],
        )
    };
    // Open: off the button, the plunger at rest.
    let (first, blow, _) = travel(&mut ep, 0.0);
    assert!(first.abs() < 5e-4 && blow.abs() < 5e-4, "{first} {blow}");
    // Part way: the button part way to its first stop.
    let (first, blow, _) = travel(&mut ep, 0.25);
    assert!(
        (-0.006..-0.002).contains(&first) && blow.abs() < 5e-4,
        "{first} {blow}"
    );
    // To the first stop and not past it: the second spring holds.
    let (first, blow, _) = travel(&mut ep, FIRST_STOP_THUMB);
    assert!(
        (first + 0.0075).abs() < 5e-4 && blow > -5e-4,
        "{first} {blow}"
    );
    // Pressed on: through to blow-out, where the thumb stops against the button.
    let (first, blow, thumb) = travel(&mut ep, 0.68);
    assert!(
        (first + 0.0075).abs() < 5e-4 && blow < -0.002,
        "{first} {blow}"
    );
    assert!(thumb < 0.45, "the thumb stalls on the button: {thumb} rad");
    // Let go: the springs push the button and the thumb back.
    let (first, blow, _) = travel(&mut ep, 0.0);
    assert!(first.abs() < 5e-4 && blow.abs() < 5e-4, "{first} {blow}");
}

/// The hand's thumb command that holds the plunger at its first stop (the expert's).
const FIRST_STOP_THUMB: f64 = 0.32;

/// The shipped pipetting tasks, run by the expert with a recording: they succeed, the judge's
/// volumes are what arrived, and over the whole episode the tubes, the tip and the bench hold the
/// starting volume at every control step (to the nanolitre: 1e-9 of 15 mL is 0.015 nL).
/// Dispensed into the wrong tube, the same episode fails the transfer's check.
#[test]
fn the_expert_transfers_the_set_volume_and_every_step_conserves_it() {
    let task = common::compile("protocols/pipette/transfer.toml");
    let seed = 3;
    let params = task.sample(seed).params;
    let volume: f64 = params["volume"].parse().unwrap();
    let fill: f64 = params["fill"].parse().unwrap();
    let path = common::scratch("pipette").join("transfer.mcap");
    let opts = scoring::episode::EpisodeOptions {
        record: Some(path.clone()),
        image_every: 0,
        ..Default::default()
    };
    let r = common::run_with(&task, seed, &opts, |t, s, i| {
        scoring::policies::make("expert", t, s, i).unwrap()
    });
    assert!(r.success, "{:?} {:#?}", r.error, r.verdict);
    let arrived = common::predicate(&r, &format!("target.volume = {volume} µL"));
    assert!((arrived.value - volume).abs() <= 1.0, "{arrived:?}");
    let rec = results::recording::read_recording(&path).unwrap();
    let at = |name: &str| task.labware_index(name).unwrap();
    let held = |s: &[labware::LabwareState], item: &str, key: &str| {
        Nanolitres::from_microlitres(s[at(item)].logic.get(key).copied().unwrap_or(0.0)).0
    };
    let start = Nanolitres::from_microlitres(fill * 1000.0).0;
    let mut drawn = false;
    for (t, s) in &rec.labware_series {
        let total = held(s, "source", VOLUME_UL)
            + held(s, "target", VOLUME_UL)
            + held(s, "pipette", VOLUME_UL)
            + held(s, "pipette", SPILT_UL);
        assert_eq!(total, start, "at t = {t:.2} s");
        drawn |= held(s, "pipette", VOLUME_UL) > 0;
    }
    assert!(drawn, "the tip held liquid on the way");
    // Replayed from the middle, while the tip holds liquid (a process restored from the items'
    // logic decides as the run did): the same states, the same verdict, the same volume.
    let mid = rec
        .labware_series
        .iter()
        .position(|(_, s)| held(s, "pipette", VOLUME_UL) > 0)
        .unwrap();
    let recording = scoring::replay::Recording::open(&path).unwrap();
    let again = scoring::replay::resimulate(&recording, mid).unwrap();
    assert!(
        again.reproduced(),
        "diverged at {:?}",
        again.first_divergence
    );
    assert!(again.verdict.success);
    let p = again
        .verdict
        .predicates()
        .iter()
        .find(|p| p.text.starts_with("target.volume"))
        .unwrap();
    assert_eq!(p.value, arrived.value);
    // The same liquid put back into the source instead: the transfer's check fails, by all of it.
    let wrong = common::compile_edited("protocols/pipette/transfer.toml", |s| {
        s.replace(
            "do = \"dispense\"\non = \"target\"",
            "do = \"dispense\"\non = \"source\"",
        )
        .replace(
            "all = [\"target.volume = {volume} µL\"",
            "all = [\"source.volume = {fill} mL\"",
        )
    });
    let path = common::scratch("pipette").join("wrong.mcap");
    let opts = scoring::episode::EpisodeOptions {
        record: Some(path.clone()),
        image_every: 0,
        ..Default::default()
    };
    let r = common::run_with(&wrong, seed, &opts, |t, s, i| {
        scoring::policies::make("expert", t, s, i).unwrap()
    });
    assert!(r.error.is_none(), "{:?}", r.error);
    let rec = results::recording::read_recording(&path).unwrap();
    let v = results::verdict::Judge::replay(&task, &params, &rec.labware_series);
    assert!(!v.success);
    let p = v
        .predicates()
        .iter()
        .find(|p| p.text.starts_with("target.volume"))
        .unwrap();
    assert!(!p.holds && p.value == 0.0, "{p:?}");
}

/// The aspirate task's expert draws the set volume from under the surface on seeds that fill
/// the tube from near empty to near full (the tip's depth follows the level), and a motionless
/// hand draws nothing.
#[test]
fn the_expert_aspirates_at_every_fill_and_a_still_hand_draws_nothing() {
    let task = common::compile("protocols/pipette/aspirate.toml");
    let fills: Vec<(u64, f64)> = (0..40)
        .map(|s| (s, task.sample(s).params["fill"].parse::<f64>().unwrap()))
        .collect();
    let low = fills.iter().min_by(|a, b| a.1.total_cmp(&b.1)).unwrap();
    let high = fills.iter().max_by(|a, b| a.1.total_cmp(&b.1)).unwrap();
    assert!(low.1 <= 18.0 && high.1 >= 42.0, "{low:?} {high:?}");
    for (seed, _) in [low, high] {
        let r = common::run(&task, *seed, "expert");
        assert!(r.success, "seed {seed}: {:?} {:#?}", r.error, r.verdict);
    }
    let r = common::run(&task, low.0, "hold");
    assert!(!r.success);
    assert_eq!(r.verdict.predicates()[0].value, 0.0);
}

/// The aspirate task is two-armed: the same episode with the gripper's pick taken out of the
/// compiled plan (the state proof refuses such a protocol; the hand draws the set volume from
/// the tube where it stands in the rack) fails on the tube that was neither held nor lifted.
#[test]
fn aspirating_from_the_rack_without_the_lift_fails() {
    let mut task = common::compile("protocols/pipette/aspirate.toml");
    let plan = &mut task.stages[0].plan;
    assert_eq!(
        plan[0].primitive, "pick",
        "the shipped task picks the tube first"
    );
    plan.remove(0);
    let r = common::run(&task, 0, "expert");
    assert!(!r.success, "{:#?}", r.verdict);
    let p = r.verdict.predicates();
    let by = |text: &str| p.iter().find(|q| q.text.starts_with(text)).unwrap();
    assert!(by("pipette.volume").holds, "the volume was drawn: {p:#?}");
    assert!(!by("right touches tube").holds, "{p:#?}");
    let lifted = by("tube lifted");
    assert!(!lifted.holds && lifted.value < 0.01, "{lifted:?}");
}

/// Cameras see the liquid: the aspirate scene drawn at 224x224 with the tube's volume and drawn
/// again with it emptied differ where the liquid stands, and more so the fuller the tube.
#[test]
fn cameras_see_the_liquid_and_how_high_it_stands() {
    let task = common::compile_edited("protocols/pipette/aspirate.toml", |s| {
        s.replace("pos_m = [1.2, 0.0, 1.35]", "pos_m = [0.25, 0.15, 1.15]")
            .replace(
                "look_at_m = [0.07, 0.0, 0.94]",
                "look_at_m = [0.0, 0.0, 0.93]",
            )
    });
    let instance = task.sample(0);
    let scene = Arc::new(runtime::Scene::build(&task, &instance).unwrap());
    let ep = runtime::Episode::new(scene.clone(), &task, &instance);
    let mut cams =
        runtime::render::Cameras::with_detail(&scene, 224, 224, robots::Detail::Simplified)
            .unwrap();
    let names = vec![task.cameras[0].name.clone()];
    let tube = task.labware_index("tube").unwrap();
    let mut draw = |ul: f64| {
        let mut logic = ep.logic().to_vec();
        logic[tube].insert(VOLUME_UL.into(), ul);
        cams.render(&ep.data, &logic, &names).unwrap().remove(0).rgb
    };
    let (empty, low, high) = (draw(0.0), draw(10_000.0), draw(40_000.0));
    let changed = |a: &[u8], b: &[u8]| a.chunks(3).zip(b.chunks(3)).filter(|(p, q)| p != q).count();
    let (low, high) = (changed(&empty, &low), changed(&empty, &high));
    assert!(low > 100, "10 mL changes {low} pixels");
    assert!(high > low + 100, "40 mL changes {high} pixels, 10 mL {low}");
}

#[test]
fn a_task_whose_quantities_do_not_resolve_is_refused_before_any_episode() {
    // The compiler proves every template resolves; a task edited by hand may not: its scene is
    // refused with the template named, built afresh or reused for another seed.
    let text = std::fs::read_to_string("protocols/pipette/transfer.toml").unwrap();
    let mut task = compiler::compile_source(&text, "transfer.toml").0.unwrap();
    let ok = task.sample(0);
    let mut slot = Some(std::sync::Arc::new(
        runtime::Scene::build(&task, &ok).unwrap(),
    ));
    let source = task
        .labware
        .iter()
        .position(|l| l.name == "source")
        .unwrap();
    task.labware[source].volume = Some("{nowhere} mL".into());
    let instance = task.sample(0);
    let refused = |e: runtime::SceneError| {
        assert!(matches!(e, runtime::SceneError::Quantity(_)), "{e}");
        assert!(e.to_string().contains("{nowhere} mL"), "{e}");
    };
    refused(runtime::Scene::build(&task, &instance).err().unwrap());
    refused(
        runtime::Scene::reuse_or_build(&mut slot, &task, &instance)
            .err()
            .unwrap(),
    );
}
