//! The latched centrifuges' lid tasks (issue 9): the expert pushes the 5430's and the 5910's lids
//! shut until the latch catches, and presses each one's lid key and lifts its lid open (the
//! 5910's from an arm on a riser); `hold` scores nothing on any; "locked" fails a lid left a
//! little open or shut without the latch,
//! "open" a lid released but left shut or lifted part way; a latched lid stays shut against its
//! spring; the fixed camera sees each centrifuge, and an open and a latched lid give different
//! frames. Loading the 5430's rotor: the expert puts the tube into the slot across from the loaded
//! one, down the slot's 50.4° lean, and hold scores nothing; the check fails the tube in a
//! neighbouring slot, in the loaded slot's own neighbour, or sitting up out of the right one; the
//! loaded slot shows in the protocol's camera.

use crate::common;

use common::{compile, run, scene, spread};
use mujoco_rs::prelude::*;
use results::verdict::Judge;
use runtime::render::Cameras;

const C5430: &str = "protocols/centrifuge_5430/close_lid.toml";
const C5910: &str = "protocols/centrifuge_5910/close_lid.toml";
const O5430: &str = "protocols/centrifuge_5430/open_lid.toml";
const O5910: &str = "protocols/centrifuge_5910/open_lid.toml";
const ROTOR: &str = "protocols/centrifuge/insert_symmetric.toml";

#[test]
fn the_expert_latches_both_lids_and_hold_scores_nothing() {
    for (path, seed) in [(C5430, 31), (C5430, 32), (C5910, 33), (C5910, 34)] {
        let task = compile(path);
        let r = run(&task, seed, "expert");
        assert!(
            r.success,
            "{path} seed {seed}: {:?} {:#?}",
            r.error, r.verdict
        );
        let hold = run(&task, seed, "hold");
        assert!(
            !hold.success && hold.verdict.score == 0.0,
            "{path}: {:#?}",
            hold.verdict
        );
    }
}

#[test]
fn the_expert_releases_each_latch_with_its_key_and_lifts_the_lid_open() {
    for (path, seeds) in [(O5430, [41, 42]), (O5910, [43, 44])] {
        let task = compile(path);
        for seed in seeds {
            let r = run(&task, seed, "expert");
            assert!(
                r.success,
                "{path} seed {seed}: {:?} {:#?}",
                r.error, r.verdict
            );
        }
        // Without a press the latch holds the lid shut.
        let hold = run(&task, seeds[0], "hold");
        assert!(
            !hold.success && hold.verdict.score == 0.0,
            "{path}: {:#?}",
            hold.verdict
        );
    }
}

#[test]
fn open_needs_the_lid_standing_open_and_the_latch_released() {
    for (path, closed) in [(O5430, -1.723), (O5910, -1.94)] {
        // Open and released.
        assert_eq!(judged(path, 0.0, false), (true, vec![true, true]), "{path}");
        // Released but left shut, resting ajar on its spring, lifted part way, or just short of
        // open: not open.
        for lid in [closed, closed + 0.13, -0.5, -0.02] {
            assert_eq!(
                judged(path, lid, false),
                (false, vec![false, true]),
                "{path} at {lid}"
            );
        }
        // Still latched.
        assert_eq!(
            judged(path, closed, true),
            (false, vec![false, false]),
            "{path}"
        );
    }
}

/// The task's verdict on its first state with the lid at `lid` (rad) and the latch as given.
fn judged(path: &str, lid: f64, locked: bool) -> (bool, Vec<bool>) {
    let task = compile(path);
    let (instance, scene) = scene(&task, 0);
    let ep = runtime::Episode::new(scene, &task, &instance);
    let start = ep.labware_state();
    let mut now = start.clone();
    now[0].joints.insert("lid".into(), lid);
    now[0]
        .logic
        .insert("locked".into(), f64::from(u8::from(locked)));
    let mut judge = Judge::new(&task, &instance.params, &start);
    // Held there for the stage's settle time: success is a state, not a moment.
    judge.update(0.02, &now);
    judge.update(0.02 + task.stages[0].settle_s, &now);
    let v = judge.verdict();
    (v.success, v.predicates().iter().map(|p| p.holds).collect())
}

#[test]
fn locked_needs_the_lid_shut_and_the_latch_engaged() {
    for (path, closed) in [(C5430, -1.723), (C5910, -1.94)] {
        assert_eq!(
            judged(path, closed, true),
            (true, vec![true, true]),
            "{path}"
        );
        // Shut but not latched: closed holds, locked does not.
        assert_eq!(
            judged(path, closed, false),
            (false, vec![true, false]),
            "{path}"
        );
        // A little open, latch flag or not: neither holds.
        assert_eq!(
            judged(path, closed + 0.05, true),
            (false, vec![false, false]),
            "{path}"
        );
        assert_eq!(
            judged(path, 0.0, false),
            (false, vec![false, false]),
            "{path}"
        );
    }
}

/// An episode of the close task with the lid put at `lid` (rad) and the latch flag as given
/// (the logic switches the latch's equality from it at the next step).
fn episode_with_lid(path: &str, lid: f64, locked: bool) -> (runtime::Episode, compiler::Task) {
    let task = compile(path);
    let (instance, scene) = scene(&task, 0);
    let mut ep = runtime::Episode::new(scene.clone(), &task, &instance);
    let (_, adr) = scene.labware[0]
        .joints
        .iter()
        .find(|(r, _)| *r == "lid")
        .copied()
        .unwrap();
    ep.data.qpos_mut()[adr] = lid;
    let state = ep.physics_state();
    let mut logic = ep.logic().to_vec();
    logic[0].insert("locked".into(), f64::from(u8::from(locked)));
    ep.restore(&state, logic).unwrap();
    ep.data.forward();
    (ep, task)
}

#[test]
fn a_latched_lid_stays_shut_and_an_unlatched_one_springs_open() {
    for (path, closed) in [(C5430, -1.723), (C5910, -1.94)] {
        // The lid after 2 s of a motionless arm.
        let lid_after = |lid: f64, locked: bool| {
            let (mut ep, _) = episode_with_lid(path, lid, locked);
            let hold = ep.robot_ctrl(0);
            for _ in 0..100 {
                ep.apply(&hold).unwrap();
                ep.control_step().unwrap();
            }
            let s = &ep.labware_state()[0];
            (s.joints["lid"], s.flag("locked"))
        };
        let (locked, flag) = lid_after(closed, true);
        assert!(
            flag && (locked - closed).abs() < 0.01,
            "{path}: a latched lid moved to {locked}"
        );
        // Left 0.05 rad short of shut, nothing holds it: the spring lifts it further open.
        let (free, flag) = lid_after(closed + 0.05, false);
        assert!(
            !flag && free > closed + 0.055,
            "{path}: an unlatched lid stayed at {free}"
        );
    }
}

#[test]
fn the_fixed_camera_sees_each_centrifuge_open_and_latched() {
    for (path, closed) in [(C5430, -1.723), (C5910, -1.94), (O5910, -1.94)] {
        let frame = |lid: f64| {
            let (ep, task) = episode_with_lid(path, lid, lid == closed);
            let names: Vec<String> = task.cameras.iter().map(|c| c.name.clone()).collect();
            let mut cams = Cameras::new(&ep.scene, 224, 224).unwrap();
            cams.render(&ep.data, ep.logic(), &names)
                .unwrap()
                .remove(0)
                .rgb
        };
        let (open, shut) = (frame(0.0), frame(closed));
        assert!(
            spread(&open) > 10.0 && spread(&shut) > 10.0,
            "{path}: a blank frame"
        );
        let changed = open.iter().zip(&shut).filter(|(a, b)| a != b).count();
        assert!(
            changed > 500,
            "{path}: the lid barely shows: {changed} pixels differ"
        );
    }
}

#[test]
fn the_expert_balances_the_rotor_and_hold_scores_nothing() {
    let task = compile(ROTOR);
    for seed in [51, 52] {
        let r = run(&task, seed, "expert");
        assert!(r.success, "seed {seed}: {:?} {:#?}", r.error, r.verdict);
    }
    let hold = run(&task, 51, "hold");
    assert!(
        !hold.success && hold.verdict.score == 0.0,
        "{:#?}",
        hold.verdict
    );
}

/// The rotor task's verdict with the tube's base put on the seat of `slot`, raised `above`
/// metres along the seat's axis.
fn tube_judged(slot: &str, above: f64) -> bool {
    let task = compile(ROTOR);
    let (instance, scene) = scene(&task, 3);
    let ep = runtime::Episode::new(scene, &task, &instance);
    let start = ep.labware_state();
    let centrifuge = task
        .labware
        .iter()
        .position(|l| l.name == "centrifuge")
        .unwrap();
    let tube = task.labware.iter().position(|l| l.name == "tube").unwrap();
    let model = task.labware[centrifuge].params.instrument().unwrap();
    let seat = model.slot_seat(slot, &start[centrifuge]).unwrap();
    let mut now = start.clone();
    now[tube].pose = labware::frame::translated_local(&seat, [0.0, 0.0, above]);
    let mut judge = Judge::new(&task, &instance.params, &start);
    // Held there for the stage's settle time: success is a state, not a moment.
    judge.update(0.02, &now);
    judge.update(0.02 + task.stages[0].settle_s, &now);
    judge.verdict().success
}

#[test]
fn balanced_needs_the_tube_down_in_the_slot_across_from_the_loaded_one() {
    let task = compile(ROTOR);
    let (instance, _) = scene(&task, 3);
    let balance: u32 = instance.params["balance"].parse().unwrap();
    let first: u32 = instance.params["first"].parse().unwrap();
    assert_eq!((first + 14) % 30 + 1, balance, "across the rotor");
    let neighbour = |k: u32, d: u32| ((k - 1 + d) % 30 + 1).to_string();
    assert!(tube_judged(&balance.to_string(), 0.0));
    assert!(!tube_judged(&neighbour(balance, 1), 0.0), "the next slot");
    assert!(
        !tube_judged(&neighbour(balance, 29), 0.0),
        "the slot before"
    );
    assert!(
        !tube_judged(&neighbour(first, 1), 0.0),
        "beside the loaded one"
    );
    assert!(
        !tube_judged(&balance.to_string(), 0.01),
        "sitting 1 cm up the slot"
    );
}

#[test]
fn the_rotor_camera_shows_where_the_loaded_tube_is() {
    // The variant whose fixed camera looks into the rotor (the paper task's, upstream's front
    // camera, sees the open lid).
    let task = compile("protocols/centrifuge/insert_symmetric_rotor_view.toml");
    let arm = task.sample(0).robot_q;
    let rotor = task.sample(0).labware_joints;
    // The first frame of a draw, with the arm and the rotor where draw 0 has them: only the
    // loaded slot differs.
    let frame_turned = |seed: u64, turn: f64| {
        let mut instance = task.sample(seed);
        instance.robot_q = arm.clone();
        instance.labware_joints = rotor.clone();
        *instance
            .labware_joints
            .get_mut("centrifuge")
            .unwrap()
            .get_mut("rotor")
            .unwrap() += turn;
        let scene = std::sync::Arc::new(runtime::Scene::build(&task, &instance).unwrap());
        let ep = runtime::Episode::new(scene, &task, &instance);
        let names: Vec<String> = task.cameras.iter().map(|c| c.name.clone()).collect();
        let mut cams = Cameras::new(&ep.scene, 224, 224).unwrap();
        let rgb = cams
            .render(&ep.data, ep.logic(), &names)
            .unwrap()
            .remove(0)
            .rgb;
        (instance.params["first"].clone(), rgb)
    };
    let frame = |seed: u64| frame_turned(seed, 0.0);
    let (a, fa) = frame(0);
    let (same, fs) = (1..30)
        .map(frame)
        .find(|(slot, _)| *slot == a)
        .expect("a second draw with the same loaded slot");
    let (b, fb) = (1..20)
        .map(frame)
        .find(|(slot, _)| *slot != a)
        .expect("two draws with different loaded slots");
    assert!(spread(&fa) > 10.0 && spread(&fb) > 10.0, "a blank frame");
    assert_eq!(
        fa, fs,
        "slot {same} twice: the frames differ by something else"
    );
    let changed = fa.iter().zip(&fb).filter(|(x, y)| x != y).count();
    assert!(
        changed > 30,
        "slots {a} and {b}: the loaded tube does not show ({changed} values differ)"
    );
    // The same slot with the rotor turned by the draw's full range: the tube moves with it.
    let (_, turned) = frame_turned(0, 0.2);
    let changed = fa.iter().zip(&turned).filter(|(x, y)| x != y).count();
    assert!(
        changed > 30,
        "the rotor turned 0.2 rad does not show ({changed} values differ)"
    );
}

#[test]
fn the_rotor_starts_at_its_drawn_angle_with_the_loaded_tube_in_its_turned_slot() {
    let task = compile(ROTOR);
    let centrifuge = task
        .labware
        .iter()
        .position(|l| l.name == "centrifuge")
        .unwrap();
    let placed = task
        .labware
        .iter()
        .position(|l| l.name == "placed")
        .unwrap();
    let model = task.labware[centrifuge].params.instrument().unwrap();
    // What seeds 0-3 draw, as tests/golden/centrifuge/insert_symmetric.draws.jsonl pins them.
    let drawn = [
        0.07763908959780763,
        -0.07335121751493841,
        0.07056178124014964,
        0.08003895079400733,
    ];
    for (seed, want) in (0..4).zip(drawn) {
        let (instance, scene) = scene(&task, seed);
        let angle = instance.labware_joints["centrifuge"]["rotor"];
        assert_eq!(angle, want, "seed {seed}");
        let ep = runtime::Episode::new(scene, &task, &instance);
        let state = ep.labware_state();
        assert!((state[centrifuge].joint("rotor") - angle).abs() < 1e-9);
        // The loaded tube is on its slot's seat as the rotor stands, not as it would at 0.
        let first = &instance.params["first"];
        let seat = model.slot_seat(first, &state[centrifuge]).unwrap();
        let tube = state[placed].pose.translation.vector;
        assert!(
            (tube - seat.translation.vector).norm() < 1e-3,
            "seed {seed}: {tube:?} vs {seat:?}"
        );
        // And, apart from the seat arithmetic, it stands where the unturned slot's seat does
        // turned by the drawn angle about the rotor's vertical axis (the 5430's axis is 36 mm
        // behind the instrument's origin): the same radius, the azimuth the angle further on.
        let unturned = state[centrifuge].with_joints(&[("rotor".into(), 0.0)]);
        let seat0 = model
            .slot_seat(first, &unturned)
            .unwrap()
            .translation
            .vector;
        let axis = state[centrifuge].pose * nalgebra::Point3::new(0.0, 0.036, 0.0);
        let about = |p: nalgebra::Vector3<f64>| {
            let d = p - axis.coords;
            (d.x.hypot(d.y), d.y.atan2(d.x))
        };
        let ((r, az), (r0, az0)) = (about(tube), about(seat0));
        assert!((r - r0).abs() < 1e-4, "seed {seed}: radius {r} vs {r0}");
        assert!(
            (az - az0 - angle).abs() < 1e-4,
            "seed {seed}: turned {} rad, drawn {angle}",
            az - az0
        );
        assert!((tube.z - seat0.z).abs() < 1e-4, "seed {seed}");
    }
}

/// The pedestal geom under `robot` in the seed-0 scene of `task`: its bottom and top heights.
fn pedestal(task: &compiler::Task, robot: &str) -> Option<(f64, f64)> {
    let (_, scene) = scene(task, 0);
    let m = &scene.model;
    let g = m.name_to_id(MjtObjBase::mjOBJ_GEOM, &format!("{robot}/pedestal"))?;
    assert_ne!(m.geom_contype()[g], 0, "a pedestal the arm passes through");
    let (z, half) = (m.geom_pos()[g][2], m.geom_size()[g][1]);
    Some((z - half, z + half))
}

#[test]
fn a_raised_arm_stands_on_a_pedestal_from_the_surface_below_it() {
    // The 5910 opener's arm stands 0.626 m above the bench top (0.824 m): on a riser that
    // reaches from the bench to its base.
    let (bottom, top) = pedestal(&compile(O5910), "arm").expect("the raised arm's pedestal");
    assert!(
        (bottom - 0.824).abs() < 1e-9 && (top - 1.45).abs() < 1e-9,
        "{bottom} {top}"
    );
    // Off the bench, the riser stands on the floor (the scene file moved, the protocol as is).
    let dir = common::scratch("pedestal-off-bench");
    let riser = std::fs::read_to_string("protocols/centrifuge_5910/riser.toml").unwrap();
    let moved = riser.replace("[0.4, 0.25, 1.45]", "[1.0, 0.25, 1.45]");
    assert_ne!(moved, riser);
    std::fs::write(dir.join("riser.toml"), moved).unwrap();
    std::fs::copy(O5910, dir.join("open_lid.toml")).unwrap();
    let off = compiler::check_file(&dir.join("open_lid.toml"), None)
        .unwrap()
        .task
        .unwrap();
    let (bottom, top) = pedestal(&off, "arm").expect("the off-bench arm's pedestal");
    assert!(
        bottom.abs() < 1e-9 && (top - 1.45).abs() < 1e-9,
        "{bottom} {top}"
    );
    // An arm standing on the bench has none.
    assert_eq!(pedestal(&compile(C5910), "arm"), None);
}
