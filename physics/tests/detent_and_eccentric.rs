//! The detent plugin and the eccentric drive on real MuJoCo: a released knob settles at the nearest
//! click position from any start; the vortex cup orbits a circle of the throw's radius without
//! turning, stable at 2,500 rpm for 10 simulated seconds.

use mujoco_rs::prelude::*;
use physics::detent::Detent;
use physics::eccentric::{Eccentric, rpm_to_rad_s};

fn knob_model(detent: &Detent) -> MjModel {
    physics::register().unwrap();
    MjModel::from_xml_string(&physics::scenes::knob(detent, true)).unwrap()
}

#[test]
fn a_released_knob_settles_at_the_nearest_position() {
    // The vortex mixer's speed knob, as upstream: 11 positions over [0, 4.6] rad.
    let detent = Detent {
        lo: 0.0,
        hi: 4.6,
        n: 11,
        stiffness: 0.0401,
        damping: 0.0040,
    };
    let model = knob_model(&detent);
    let mut data = MjData::new(&model);
    assert!(physics::instance_errors(model.ffi(), data.ffi()).is_empty());
    for start in [0.1, 0.22, 0.24, 1.0, 2.05, 3.5, 4.55] {
        data.reset();
        data.qpos_mut()[0] = start;
        for _ in 0..1500 {
            data.step();
        }
        let q = data.qpos()[0];
        let want = detent.nearest(start);
        eprintln!("detent: from {start} settled at {q:.6} (nearest {want:.2})");
        assert!(
            (q - want).abs() < 1e-3,
            "from {start}: settled at {q}, nearest position {want}"
        );
        assert!(data.qvel()[0].abs() < 1e-3);
    }
}

#[test]
fn a_detent_on_a_missing_joint_reports_instead_of_crashing() {
    physics::register().unwrap();
    let xml = r#"<mujoco>
  <compiler angle="radian"/>
  <extension><plugin plugin="autobio.detent"><instance name="d"><config key="joint" value="nope"/><config key="n" value="3"/></instance></plugin></extension>
  <worldbody><body><joint name="j" type="hinge" range="0 1"/><geom size="0.1"/></body></worldbody>
</mujoco>"#;
    let model = MjModel::from_xml_string(xml).unwrap();
    let data = MjData::new(&model);
    let errors = physics::instance_errors(model.ffi(), data.ffi());
    assert_eq!(errors.len(), 1);
    assert!(errors[0].contains("no joint named `nope`"), "{errors:?}");
}

#[test]
fn the_vortex_cup_orbits_without_turning_at_2500_rpm() {
    let drive = Eccentric::default();
    let xml = physics::scenes::vortex(&drive, true);
    let model = MjModel::from_xml_string(&xml).unwrap();
    let mut data = MjData::new(&model);
    let cup = model
        .name_to_id(MjtObjBase::mjOBJ_BODY, "vortex/cup")
        .unwrap();
    let omega = rpm_to_rad_s(2500.0);
    data.ctrl_mut()[0] = omega;
    let steps = (10.0 / model.opt().timestep) as usize;
    let (mut r_min, mut r_max, mut max_turn) = (f64::INFINITY, 0.0f64, 0.0f64);
    let mut turns = 0.0;
    for k in 0..steps {
        data.step();
        if k * 5 < steps {
            continue; // spin-up: the first two seconds
        }
        let [x, y, _] = data.xpos()[cup];
        let r = x.hypot(y);
        r_min = r_min.min(r);
        r_max = r_max.max(r);
        // The cup's heading: its x axis in the world.
        let xm = data.xmat()[cup];
        max_turn = max_turn.max(xm[3].atan2(xm[0]).abs());
        turns = data.qpos()[0] / std::f64::consts::TAU;
    }
    assert!(data.qpos().iter().all(|q| q.is_finite()));
    let speed = data.qvel()[0];
    eprintln!(
        "eccentric: {speed:.1} rad/s, {turns:.0} turns, orbit radius {r_min:.6}..{r_max:.6} m, cup turned at most {max_turn:.2e} rad"
    );
    assert!(
        (speed - omega).abs() / omega < 0.02,
        "drive at {speed} rad/s"
    );
    assert!(turns > 300.0, "{turns} turns");
    assert!(
        (r_min - drive.throw).abs() < 0.1e-3 && (r_max - drive.throw).abs() < 0.1e-3,
        "orbit radius {r_min}..{r_max}, throw {}",
        drive.throw
    );
    assert!(max_turn < 0.01, "the cup turned by {max_turn} rad");
}
