//! The judge measures `<robot> touches <item>` from MuJoCo's contacts and `<item> near [x, y, z]`
//! from the item's live pose, on real episodes of the tube-transfer scene: the expert's grasp makes
//! the contact hold and a motionless robot never does; a tube carried by the expert is near where
//! it ends up only at the end, not at the start, and a point 10 cm off is never near. Before, both
//! predicates compiled but could never hold, so a task using them could not be won. A volume is
//! measured from the liquid the container holds.

use crate::common;

use common::{compile_edited, run, run_with, scratch};

const TRANSFER: &str = "protocols/tube/transfer.toml";

/// The transfer protocol with other success checks; without its `place` step when `pick_only`
/// (ending with the tube in hand, so that the proof agrees the arm touches it).
fn transfer(success: &str, pick_only: bool) -> compiler::Task {
    compile_edited(TRANSFER, |mut source| {
        if pick_only {
            let place = source.find("[[steps]]\ndo = \"place\"").unwrap();
            let success_at = source.find("[success]").unwrap();
            source.replace_range(place..success_at, "");
        }
        source.replace(
            "all = [\"tube in target.{row}{col}\"]",
            &format!("all = [{success:?}]"),
        )
    })
}

#[test]
fn a_grasp_is_a_contact_and_no_motion_is_none() {
    let task = transfer("arm touches tube", true);
    for seed in [3, 4] {
        let expert = run(&task, seed, "expert");
        assert!(expert.success, "{:?} {:#?}", expert.error, expert.verdict);
        let p = &expert.verdict.predicates()[0];
        assert!(p.holds && p.value == 1.0, "{p:?}");
        // The contact comes with the grasp, not at the start.
        assert!(expert.sim_time_s > 1.0, "{}", expert.sim_time_s);

        let hold = run(&task, seed, "hold");
        assert!(!hold.success, "a motionless arm touched the tube");
        let p = &hold.verdict.predicates()[0];
        assert!(!p.holds && p.value == 0.0, "{p:?}");
        assert!((hold.sim_time_s - task.time_limit_s).abs() < 0.05);
    }
}

#[test]
fn near_measures_the_distance_from_the_live_pose() {
    // The expert carries the tube to the target slot; the recording has its pose at every step.
    let recorded = transfer("tube in target.{row}{col}", false);
    let path = scratch("near").join("carry.mcap");
    let opts = scoring::episode::EpisodeOptions {
        record: Some(path.clone()),
        image_every: 0,
        ..Default::default()
    };
    let r = run_with(&recorded, 5, &opts, |t, s, i| {
        scoring::policies::make("expert", t, s, i).unwrap()
    });
    assert!(r.success, "{:?}", r.error);
    let rec = results::recording::read_recording(&path).unwrap();
    let tube = recorded.labware_index("tube").unwrap();
    let start = rec.labware_series[0].1[tube].pose.translation.vector;
    let end = rec.final_labware[tube].pose.translation.vector;
    assert!(
        (end - start).norm() > 0.2,
        "the tube was carried {} m",
        (end - start).norm()
    );
    let params = recorded.sample(5).params;
    let judge = |point: nalgebra::Vector3<f64>| {
        let mut task = transfer(
            &format!(
                "tube near [{:.5}, {:.5}, {:.5}] m",
                point.x, point.y, point.z
            ),
            false,
        );
        // The moment it is near counts here: the recording ends as soon as the tube has
        // settled in its slot, before it has stood still a settle time near its last pose.
        task.stages[0].settle_s = 0.0;
        results::verdict::Judge::replay(&task, &params, &rec.labware_series)
    };
    // Near where it ends: not at the start, only once carried there.
    let v = judge(end);
    assert!(v.success, "{v:#?}");
    let done = v.stages[0].completed_at_s.unwrap();
    assert!(done > 2.0, "near its final place already at {done} s");
    // Near where it started: at once.
    let v = judge(start);
    assert!(
        v.success && v.stages[0].completed_at_s.unwrap() < 0.05,
        "{v:#?}"
    );
    // 10 cm above where it ends: never, and the measured distance says by how much.
    let v = judge(end + nalgebra::Vector3::new(0.0, 0.0, 0.1));
    assert!(!v.success);
    let p = &v.predicates()[0];
    assert!(!p.holds && (p.value - 0.1).abs() < 2e-3, "{p:?}");
    assert_eq!(p.tolerance, 0.005, "the position tolerance's default");
}

#[test]
fn a_volume_is_measured_from_what_the_container_holds() {
    // The tube starts with the protocol's volume (a parameter's, rendered per episode) in its
    // logic, and the judge reads it there.
    let task = compile_edited(TRANSFER, |source| {
        source
            .replace(
                "at = \"source.{from}\"",
                "at = \"source.{from}\"\nstate = { volume = \"{fill} mL\" }",
            )
            .replace(
                "[params.row]",
                "[params.fill]\nint = [15, 45]\n\n[params.row]",
            )
            .replace(
                "all = [\"tube in target.{row}{col}\"]",
                "all = [\"tube in target.{row}{col}\", \"tube.volume = {fill} mL\"]",
            )
    });
    let seed = 3;
    let fill: f64 = task.sample(seed).params["fill"].parse().unwrap();
    let expert = run(&task, seed, "expert");
    assert!(expert.success, "{:?} {:#?}", expert.error, expert.verdict);
    let p = &expert.verdict.predicates()[1];
    assert!(p.holds && p.value == fill * 1000.0, "{p:?} for {fill} mL");
    // A motionless episode of the task asking for 1 mL more: the volume check fails, by 1000 µL
    // (no process runs in this scene: the judge reads the declared start volume).
    let mut more = task.clone();
    for c in more.stages.iter_mut().flat_map(|s| &mut s.success) {
        if let compiler::predicates::Check::Volume { value, .. } = &mut c.check {
            *value = format!("{} mL", fill + 1.0);
        }
    }
    let hold = run(&more, seed, "hold");
    assert!(!hold.success);
    let p = &hold.verdict.predicates()[1];
    assert!(
        !p.holds && (p.target - p.value - 1000.0).abs() < 1e-9,
        "{p:?}"
    );
}
