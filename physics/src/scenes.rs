//! Small MuJoCo scenes that show each mechanism on its own, shared by the tests, `autobio bench`
//! and the docs' examples. Each comes in the version with the mechanism and the same scene without
//! it, so benchmarks compare like with like.

use crate::detent::Detent;
use crate::eccentric::Eccentric;
use crate::thread::ScrewCap;

/// A knob on a hinge over the detent's range; `with_detent: false` leaves the plugin out.
pub fn knob(detent: &Detent, with_detent: bool) -> String {
    let extension = if with_detent {
        format!(
            r#"<extension><plugin plugin="autobio.detent">{}</plugin></extension>"#,
            detent.mjcf_instance("knob_detent", "knob")
        )
    } else {
        String::new()
    };
    format!(
        r#"<mujoco>
  <compiler angle="radian"/>
  <option timestep="0.002"/>
  {extension}
  <worldbody>
    <body name="knob">
      <joint name="knob" type="hinge" axis="0 0 1" range="{} {}" armature="0.0001"/>
      <geom type="cylinder" size="0.02 0.01" mass="0.05"/>
    </body>
  </worldbody>
</mujoco>"#,
        detent.lo, detent.hi
    )
}

/// Timestep of the screw-cap scene (s).
pub const SCREW_TIMESTEP: f64 = 0.001;

/// A tube body with its bolt thread and a free cap with its nut thread, raised by `lift_turns`
/// turns from fully screwed. The nut sits 5 mm below the (flipped) cap's origin and half a pitch
/// above the bolt, as upstream's tubes. `with_thread: false` leaves out the nut-bolt contact pair.
pub fn screw_cap(
    cap: &ScrewCap,
    lift_turns: f64,
    friction: f64,
    gravity: bool,
    with_thread: bool,
) -> String {
    let bolt_z = 0.038;
    let cap_z = bolt_z + cap.bolt.pitch / 2.0 + 0.005 + lift_turns * cap.bolt.pitch;
    let yaw = -lift_turns * std::f64::consts::TAU;
    // Cap mass and inertia scale with the thread radius (a 1.5 mL cap: about 2 g).
    let r = cap.bolt.radius;
    let mass = cap_mass(cap);
    let iz = 0.5 * mass * (r + 0.002).powi(2);
    let pair = if with_thread {
        format!(
            r#"<pair geom1="nut" geom2="bolt" friction="{friction} {friction} 0.001 0.0001 0.0001" solref="0.002 1"/>"#
        )
    } else {
        String::new()
    };
    format!(
        r#"<mujoco>
  <compiler angle="radian"/>
  <option timestep="{SCREW_TIMESTEP}" gravity="0 0 {g}" sdf_iterations="5" sdf_initpoints="20"/>
  <extension><plugin plugin="autobio.thread">{bolt}{nut}</plugin></extension>
  <asset>
    <mesh name="bolt"><plugin instance="bolt"/></mesh>
    <mesh name="nut"><plugin instance="nut"/></mesh>
  </asset>
  <worldbody>
    <body name="tube">
      <geom name="bolt" type="sdf" mesh="bolt" pos="0 0 {bolt_z}" contype="0" conaffinity="0" rgba="0.9 0.9 0.9 1">
        <plugin instance="bolt"/>
      </geom>
      <geom name="core" type="cylinder" size="{core} 0.01" pos="0 0 {bolt_z}" contype="0" conaffinity="0" group="5"/>
    </body>
    <body name="cap" pos="0 0 {cap_z}" euler="0 0 {yaw}">
      <freejoint/>
      <inertial pos="0 0 0" mass="{mass}" diaginertia="{iz} {iz} {iz}"/>
      <body euler="3.141592653589793 0 0">
        <geom name="nut" type="sdf" mesh="nut" pos="0 0 0.005" contype="0" conaffinity="0" rgba="0.2 0.4 0.9 1">
          <plugin instance="nut"/>
        </geom>
      </body>
    </body>
  </worldbody>
  <contact>
    {pair}
    <pair geom1="nut" geom2="core" friction="0.01 0.01 0.001 0.0001 0.0001" solimp="0.9 0.95 0.001"/>
  </contact>
</mujoco>"#,
        g = if gravity { -9.81 } else { 0.0 },
        bolt = cap.bolt.mjcf_instance("bolt"),
        nut = cap.nut.mjcf_instance("nut"),
        core = cap.bolt.radius - 0.0012,
    )
}

/// The cap's mass in [`screw_cap`] (kg).
pub fn cap_mass(cap: &ScrewCap) -> f64 {
    0.002 * (cap.bolt.radius / 0.006).powi(2)
}

/// A torque (N·m) that turns a cap of this size briskly without tearing it off the thread.
pub fn cap_torque(cap: &ScrewCap) -> f64 {
    2e-4 * (cap.bolt.radius / 0.006).powi(3)
}

/// The vortex mixer's drive at the origin, 500 Hz; `coupled: false` leaves out the equality.
pub fn vortex(drive: &Eccentric, coupled: bool) -> String {
    let m = drive.mjcf("vortex", [0.0, 0.0, 0.1]);
    let equality = if coupled { m.equality } else { String::new() };
    format!(
        r#"<mujoco>
  <compiler angle="radian"/>
  <option timestep="0.002" integrator="implicitfast"/>
  <worldbody>{}</worldbody>
  <equality>{equality}</equality>
  <actuator>{}</actuator>
</mujoco>"#,
        m.body, m.actuator
    )
}

/// Interior of the shaken tube (a 50 mL tube): radius, height, tip depth (m), sides.
pub const TUBE: (f64, f64, f64, usize) = (0.014, 0.1, 0.02, 64);

/// A tube on a carriage (`slide` along y, `tilt` about x, position actuators), an accelerometer
/// `accel` at its bottom centre (site `tube`), and a mocap disk `surface` for the liquid's surface.
pub fn shaken_tube() -> String {
    let (r, h, _, _) = TUBE;
    format!(
        r#"<mujoco>
  <compiler angle="radian"/>
  <option timestep="0.002" integrator="implicitfast"/>
  <worldbody>
    <body name="carriage" pos="0 0 0.1">
      <joint name="slide" type="slide" axis="0 1 0" range="-0.5 0.5"/>
      <geom type="box" size="0.03 0.03 0.005" mass="1" contype="0" conaffinity="0"/>
      <body name="tube" pos="0 0 0.01">
        <joint name="tilt" type="hinge" axis="1 0 0" range="-1.3 1.3"/>
        <geom type="cylinder" size="{r} {hh}" pos="0 0 {hh}" mass="0.05" rgba="0.9 0.9 0.95 0.3" contype="0" conaffinity="0"/>
        <site name="tube" pos="0 0 0"/>
      </body>
    </body>
    <body name="surface" mocap="true">
      <geom type="cylinder" size="{r} 0.0004" rgba="0.2 0.5 1 0.8" contype="0" conaffinity="0"/>
    </body>
  </worldbody>
  <actuator>
    <position name="slide" joint="slide" kp="4000" kv="120"/>
    <position name="tilt" joint="tilt" kp="40" kv="4"/>
  </actuator>
  <sensor><accelerometer name="accel" site="tube"/></sensor>
</mujoco>"#,
        hh = h / 2.0
    )
}
