//! The detent plugin and the eccentric drive on real MuJoCo: a released knob settles at the nearest
//! click position from any start; the vortex cup orbits a circle of the throw's radius without
//! turning, stable at 2,500 rpm for 10 simulated seconds.
// Tests print the figures they measure (shown with --nocapture).
#![allow(clippy::print_stdout)]

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
fn every_detent_misconfiguration_is_reported_with_its_reason() {
    physics::register().unwrap();
    let hinge = r#"<joint name="j" type="hinge" range="0 1"/>"#;
    let cases = [
        (
            hinge,
            r#"<config key="n" value="3"/>"#,
            "no `joint` in the config",
        ),
        (
            r#"<joint name="j" type="ball"/>"#,
            r#"<config key="joint" value="j"/><config key="n" value="3"/>"#,
            "joint `j` is not a hinge or slide",
        ),
        (
            r#"<joint name="j" type="hinge"/>"#,
            r#"<config key="joint" value="j"/><config key="n" value="3"/>"#,
            "joint `j` has no range",
        ),
        (
            hinge,
            r#"<config key="joint" value="j"/><config key="n" value="1"/>"#,
            "`n` must be an integer >= 2",
        ),
        (
            hinge,
            r#"<config key="joint" value="j"/>"#,
            "`n` must be an integer >= 2",
        ),
        (
            hinge,
            r#"<config key="joint" value="j"/><config key="n" value="3"/><config key="stiffness" value="-1"/>"#,
            "`stiffness` must be a non-negative number",
        ),
        (
            hinge,
            r#"<config key="joint" value="j"/><config key="n" value="3"/><config key="damping" value="-0.1"/>"#,
            "`damping` must be a non-negative number",
        ),
    ];
    for (joint, config, why) in cases {
        let xml = format!(
            r#"<mujoco>
  <compiler angle="radian"/>
  <extension><plugin plugin="autobio.detent"><instance name="d">{config}</instance></plugin></extension>
  <worldbody><body>{joint}<geom size="0.1"/></body></worldbody>
</mujoco>"#
        );
        let model = MjModel::from_xml_string(&xml).unwrap();
        let data = MjData::new(&model);
        let errors = physics::instance_errors(model.ffi(), data.ffi());
        assert_eq!(errors.len(), 1, "{config}: {errors:?}");
        assert!(errors[0].contains(why), "{config}: {errors:?}");
    }
    // And a well-formed one reports nothing.
    let xml = format!(
        r#"<mujoco>
  <extension><plugin plugin="autobio.detent"><instance name="d"><config key="joint" value="j"/><config key="n" value="3"/></instance></plugin></extension>
  <worldbody><body>{hinge}<geom size="0.1"/></body></worldbody>
</mujoco>"#
    );
    let model = MjModel::from_xml_string(&xml).unwrap();
    let data = MjData::new(&model);
    assert!(physics::instance_errors(model.ffi(), data.ffi()).is_empty());
}

/// What the vortex scene's cup does over 8 s at 2,500 rpm after 2 s of spin-up.
struct Orbit {
    /// Drive speed at the end (rad/s) and pivot turns.
    speed: f64,
    turns: f64,
    /// Distance of the cup from the drive axis (m).
    r_min: f64,
    r_max: f64,
    /// Largest difference between the cup's angle about the axis and the pivot's angle (rad).
    phase_error: f64,
    /// Largest height change (m) and largest turn of the cup's own heading (rad).
    dz: f64,
    max_turn: f64,
    /// Diameter of the path a point on the cup's rim travels (m): what a tube held at the rim
    /// feels. The coupling decides it: a translating cup moves every point on a circle of the
    /// throw's radius (2t); a cup carried round by the pivot sweeps its rim about the axis.
    rim_stroke: f64,
}

fn orbit(drive: &Eccentric, coupled: bool) -> Orbit {
    let xml = physics::scenes::vortex(drive, coupled);
    let model = MjModel::from_xml_string(&xml).unwrap();
    let mut data = MjData::new(&model);
    let cup = model
        .name_to_id(MjtObjBase::mjOBJ_BODY, "vortex/cup")
        .unwrap();
    let omega = rpm_to_rad_s(2500.0);
    data.ctrl_mut()[0] = omega;
    let steps = (10.0 / model.opt().timestep) as usize;
    let mut o = Orbit {
        speed: 0.0,
        turns: 0.0,
        r_min: f64::INFINITY,
        r_max: 0.0,
        phase_error: 0.0,
        dz: 0.0,
        max_turn: 0.0,
        rim_stroke: 0.0,
    };
    let (mut z0, mut phase0, mut rim0) = (None, None, None);
    let wrap = |a: f64| {
        (a + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI
    };
    for k in 0..steps {
        data.step();
        if k * 5 < steps {
            continue; // spin-up: the first two seconds
        }
        // The drive axis is the world z axis through the origin (the scene puts the pivot there);
        // measured in the world, not in the orbit hinge's frame.
        let [x, y, z] = data.xpos()[cup];
        let r = x.hypot(y);
        o.r_min = o.r_min.min(r);
        o.r_max = o.r_max.max(r);
        // The cup sits on the pivot's arm: its angle about the axis keeps a fixed offset from
        // the pivot's angle (where the arm points at zero).
        let phase = wrap(y.atan2(x) - data.qpos()[0]);
        let offset = *phase0.get_or_insert(phase);
        o.phase_error = o.phase_error.max(wrap(phase - offset).abs());
        o.dz = o.dz.max((z - *z0.get_or_insert(z)).abs());
        // The cup's heading: its x axis in the world.
        let xm = data.xmat()[cup];
        o.max_turn = o.max_turn.max(xm[3].atan2(xm[0]).abs());
        // A point on the rim, on the cup's own x axis; its path's diameter is the largest
        // distance from where it was when measuring began.
        let rim = [
            x + xm[0] * drive.cup_radius,
            y + xm[3] * drive.cup_radius,
            z + xm[6] * drive.cup_radius,
        ];
        let start = *rim0.get_or_insert(rim);
        let d = (0..3)
            .map(|i| (rim[i] - start[i]).powi(2))
            .sum::<f64>()
            .sqrt();
        o.rim_stroke = o.rim_stroke.max(d);
        o.turns = data.qpos()[0] / std::f64::consts::TAU;
    }
    assert!(data.qpos().iter().all(|q| q.is_finite()));
    o.speed = data.qvel()[0];
    o
}

#[test]
fn the_vortex_cup_orbits_without_turning_at_2500_rpm() {
    let drive = Eccentric::default();
    let omega = rpm_to_rad_s(2500.0);
    let o = orbit(&drive, true);
    eprintln!(
        "eccentric: {:.1} rad/s, {:.0} turns, orbit radius {:.7}..{:.7} m, phase error {:.2e} rad, \
         height change {:.2e} m, cup turned at most {:.2e} rad, rim stroke {:.7} m",
        o.speed, o.turns, o.r_min, o.r_max, o.phase_error, o.dz, o.max_turn, o.rim_stroke
    );
    assert!(
        (o.speed - omega).abs() / omega < 0.02,
        "drive at {} rad/s",
        o.speed
    );
    assert!(o.turns > 300.0, "{} turns", o.turns);
    // docs/physics.md: a circle of the throw's radius (2.000 mm to 0.001 mm) about the drive axis,
    // in step with the pivot, in one plane, and the cup never turns (measured < 1e-10 rad; the
    // bound allows 1e-8 rad for solver differences, far below the turn an uncoupled cup makes).
    let um = 1e-6;
    assert!(
        (o.r_min - drive.throw).abs() < um && (o.r_max - drive.throw).abs() < um,
        "orbit radius {}..{}, throw {}",
        o.r_min,
        o.r_max,
        drive.throw
    );
    assert!(
        o.phase_error < 1e-6,
        "the cup lags the pivot by {} rad",
        o.phase_error
    );
    assert!(o.dz < um, "the cup moved {} m along the axis", o.dz);
    assert!(o.max_turn < 1e-8, "the cup turned by {} rad", o.max_turn);
    // What the coupling controls (the figures above follow from the joint layout and hold
    // uncoupled too): every point of the cup, its rim included, strokes twice the throw.
    assert!(
        (o.rim_stroke - 2.0 * drive.throw).abs() < um,
        "a rim point's path is {} m across, not twice the throw {}",
        o.rim_stroke,
        drive.throw
    );
}

#[test]
fn without_the_joint_equality_the_cup_turns_with_the_pivot() {
    // The same check fails on the mechanism it guards: uncoupled, the orbit hinge is free and
    // the cup is carried round by the pivot (a spin, not an orbit).
    let drive = Eccentric::default();
    let o = orbit(&drive, false);
    eprintln!(
        "uncoupled: orbit radius {:.7}..{:.7} m, phase error {:.2e} rad, height change {:.2e} m, \
         cup turned at most {:.2e} rad, rim stroke {:.7} m",
        o.r_min, o.r_max, o.phase_error, o.dz, o.max_turn, o.rim_stroke
    );
    assert!(
        o.max_turn > 1.0,
        "the uncoupled cup turned only {} rad",
        o.max_turn
    );
    // Its rim is swept round the drive axis: the path is the rim's circle about the axis, not
    // the throw's.
    assert!(
        o.rim_stroke > 2.0 * (drive.cup_radius - drive.throw),
        "the uncoupled rim's path is only {} m across",
        o.rim_stroke
    );
}
