//! Collision-free transit (issue 9): the expert's collision check runs MuJoCo's collision
//! detection on the real scene, and can fail (a hand pushed into the bench, a carried tube
//! pushed into it while the hand stays clear); the straight transit into the 5430's rotor hits
//! the housing, so the expert goes around with OMPL's RRTConnect and still seats the tube; the
//! same seed gives the same planned episode, byte for byte.

mod common;

use common::{compile, run_with, scene};
use labware::frame::{axis_angle, pose};
use primitives::Kinematics;
use primitives::ik::solve_ik;
use runtime::clearance::Clearance;
use runtime::kinematics::ArmKinematics;
use scoring::{Observation, Policy, PolicyError, StageEvent};
use std::sync::{Arc, Mutex};

const ROTOR: &str = "protocols/centrifuge/insert_symmetric.toml";

/// A tool pointing straight down with its centre point at `at`.
fn down(at: [f64; 3]) -> labware::Pose {
    pose(at, axis_angle([1.0, 0.0, 0.0], std::f64::consts::PI))
}

#[test]
fn the_check_fails_a_hand_or_a_carried_tube_pushed_into_the_bench() {
    let task = compile("protocols/tube/transfer.toml");
    let (instance, scene) = scene(&task, 0);
    let ep = runtime::Episode::new(scene.clone(), &task, &instance);
    let start = instance.robot_q[0].clone();
    let mut kin = ArmKinematics::new(&scene, 0);
    // The bench top: where the rack stands.
    let rack = task
        .labware
        .iter()
        .position(|l| l.name == "source")
        .unwrap();
    let bench = instance.labware_placement[rack].translation.vector.z;
    let tcp = kin.tcp(&start);
    let (x, y) = (tcp.translation.vector.x, tcp.translation.vector.y - 0.1);
    let ik = |kin: &mut ArmKinematics, z: f64| {
        solve_ik(kin, &down([x, y, z]), &start, &Default::default()).unwrap()
    };
    let above = ik(&mut kin, bench + 0.05);
    let into = ik(&mut kin, bench - 0.03);

    let mut clear = Clearance::new(&scene, 0);
    clear.sync(&ep.qpos(), None);
    assert!(clear.is_clear(&start), "{:?}", clear.collisions(&start));
    assert!(clear.is_clear(&above), "{:?}", clear.collisions(&above));
    let hits = clear.collisions(&into);
    assert!(!hits.is_empty(), "the fingers 3 cm into the bench");
    assert!(
        hits.iter()
            .any(|&(a, b)| clear.body_name(a).starts_with("arm/")
                || clear.body_name(b).starts_with("arm/")),
        "{hits:?}"
    );

    // The tube held 6 cm past the tool's centre point, the hand 15 cm up: clear. Carried, it
    // follows the hand down to 5 cm up and goes 1 cm into the bench; not carried, it stays
    // behind and the hand alone is clear there.
    let high = ik(&mut kin, bench + 0.15);
    let mut qpos = ep.qpos();
    for (k, &adr) in scene.robots[0].qpos.iter().enumerate() {
        qpos[adr] = high[k];
    }
    let tube = task.labware.iter().position(|l| l.name == "tube").unwrap();
    let held = kin.tcp(&high) * labware::frame::translation([0.0, 0.0, 0.06]);
    let adr = scene.labware[tube].free[0].qpos;
    let p = held.translation.vector;
    let r = labware::frame::wxyz(&held.rotation);
    qpos[adr..adr + 7].copy_from_slice(&[p.x, p.y, p.z, r[0], r[1], r[2], r[3]]);
    clear.sync(&qpos, Some(tube));
    assert!(clear.is_clear(&high), "{:?}", clear.collisions(&high));
    let hits = clear.collisions(&above);
    let names: Vec<(String, String)> = hits
        .iter()
        .map(|&(a, b)| (clear.body_name(a), clear.body_name(b)))
        .collect();
    assert!(
        names
            .iter()
            .any(|(a, b)| a.starts_with("tube") || b.starts_with("tube")),
        "{names:?}"
    );
    clear.sync(&qpos, None);
    assert!(clear.is_clear(&above), "{:?}", clear.collisions(&above));
}

/// The expert, keeping a copy of the events it reports.
struct Watched {
    expert: Box<dyn Policy>,
    seen: Arc<Mutex<Vec<StageEvent>>>,
}

impl Policy for Watched {
    fn name(&self) -> String {
        self.expert.name()
    }
    fn act(&mut self, obs: &Observation) -> Result<Vec<Vec<f64>>, PolicyError> {
        self.expert.act(obs)
    }
    fn drain_events(&mut self) -> Vec<StageEvent> {
        let events = self.expert.drain_events();
        self.seen.lock().unwrap().extend(events.iter().cloned());
        events
    }
}

#[test]
fn the_expert_goes_around_the_housing_into_the_rotor_with_rrt_connect() {
    let task = compile(ROTOR);
    let seen = Arc::new(Mutex::new(Vec::new()));
    let watched = seen.clone();
    // The expert reports its events to the recorder.
    let opts = scoring::EpisodeOptions {
        record: Some(common::scratch("planning").join("rotor.mcap")),
        image_every: 0,
        ..Default::default()
    };
    let r = run_with(&task, 53, &opts, |t, s, i| {
        Box::new(Watched {
            expert: scoring::policies::make("expert", t, s, i).unwrap(),
            seen: watched,
        })
    });
    assert!(r.success, "{:?} {:#?}", r.error, r.verdict);
    let events = seen.lock().unwrap();
    let planned: Vec<&str> = events
        .iter()
        .map(|e| e.label.as_str())
        .filter(|l| l.starts_with("planned around"))
        .collect();
    // Only the transit into the rotor is planned: the straight line from the lifted tube to
    // above the slot hits the centrifuge's housing.
    assert_eq!(planned.len(), 1, "{events:#?}");
    assert!(planned[0].contains("`centrifuge/"), "{}", planned[0]);
    // Planning is seeded: the same episode again, byte for byte.
    assert_eq!(
        common::run(&task, 53, "expert").trajectory_hash,
        r.trajectory_hash
    );
}
