//! The vortex mixer (Scientific Industries Vortex-Genie 2: its housing's extent, its cup's radius
//! and height, its 2 mm orbit, its speed knob's 11 notches): a weighted housing, a cup on the
//! eccentric drive of `physics::eccentric` (the cup orbits at the throw without turning), a sprung
//! power switch and a speed knob on the front. The knob turns on a hinge held in its notches by
//! `autobio.detent` (0 stops the motor; 1..10 run it at 600..3,200 rpm, linear, as upstream); the
//! speed it sets is the panel value `speed`. The instrument acts: its logic drives its own motor,
//! at the knob's speed while the power is on and at rest while it is off. A press of the switch
//! (spring force over the threshold, held for the repeat time, as the thermal mixer's buttons)
//! toggles the power once; the switch must be let go before it toggles again. The logic also
//! measures how fast the drive really turns, and the judge's "power on" asks for that: switched
//! on, and the cup orbiting within 10% of the knob's speed ("off" is the switch's alone: a cup
//! still coasting down is off). The readout shows the switch, the knob's setting and the measured
//! speed. It does not model the real switch's touch mode (run only while the cup is pressed): our
//! switch is a push toggle, not upstream's three-way rocker.
//!
//! Frame: origin at the centre of the footprint, +y the front (the switch's side), +z up.

use crate::frame::{Pose, Vec3, pose, translation};
use crate::mjcf::{Fragment, pose_attrs, v3};
use crate::model::Panel;
use crate::model::{
    Affordance, Effects, Instrument, Joints, LabwareState, Logic, Measure, Mechanism, Part, Reset,
    flag, set, set_flag,
};
use physics::detent::Detent;
use physics::eccentric::{Eccentric, rpm_to_rad_s};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Params {
    /// Half extents of the housing.
    pub housing_half: Vec3,
    /// The switch: its face's centre on the front, travel (m), spring stiffness (N/m).
    pub switch_at: Vec3,
    pub switch_travel: f64,
    pub switch_stiffness: f64,
    /// The force (N) a press must exceed, held this long (s).
    pub press_force: f64,
    pub repeat_s: f64,
    /// The speed knob: its face's centre on the front, radius and length (m); its hinge turns
    /// it into the housing (+angle right-handed about -y) over `[0, knob_range]` rad with
    /// `knob_notches` detent notches of the given stiffness (N·m/rad) and damping (N·m·s/rad).
    pub knob_at: Vec3,
    pub knob_radius: f64,
    pub knob_length: f64,
    pub knob_range: f64,
    pub knob_notches: u32,
    pub knob_stiffness: f64,
    pub knob_damping: f64,
    /// The motor's speed at the knob's first and last running notch (rpm); notch 0 stops it.
    pub speed_min_rpm: f64,
    pub speed_max_rpm: f64,
    /// The drive's throw (m) and the cup's radius and half height (m).
    pub throw: f64,
    pub cup_radius: f64,
    pub cup_half_height: f64,
    /// Where the drive's axis stands behind the footprint's centre (m, along -y).
    pub cup_back: f64,
}

impl Default for Params {
    fn default() -> Self {
        Params {
            // 122 x 163 x 132 mm; the switch at mid-height on the front, 32 mm left of centre
            // seen from the front; the cup's axis 44 mm behind the centre and its top 161 mm up
            // (upstream-autobio.md, 11; upstream's front faces -y, ours +y).
            housing_half: [0.061, 0.0815, 0.066],
            switch_at: [0.032, 0.0815, 0.063],
            switch_travel: 0.004,
            switch_stiffness: 400.0,
            press_force: 0.5,
            repeat_s: 0.25,
            // Upstream's knob: 11 notches over 4.6 rad (k 0.0401, d 0.0040); 600..3,200 rpm.
            // It stands on the front 24 mm right of centre seen from the front, as upstream's;
            // upstream's front panel slopes 27.5 degrees, ours is upright, so its axis is level.
            knob_at: [-0.0244, 0.0815, 0.0615],
            knob_radius: 0.010,
            knob_length: 0.035,
            knob_range: 4.6,
            knob_notches: 11,
            knob_stiffness: 0.0401,
            knob_damping: 0.004,
            speed_min_rpm: 600.0,
            speed_max_rpm: 3200.0,
            throw: 0.002,
            cup_radius: 0.0282,
            cup_half_height: 0.0135,
            cup_back: 0.0439,
        }
    }
}

const POWER: &str = "power";
const HELD: &str = "switch_held_s";
const LATCHED: &str = "switch_latched";
/// The drive's angle at the last step (rad) and the speed measured from it (rad/s).
const DRIVE_ANGLE: &str = "drive_angle";
const DRIVE_SPEED: &str = "drive_rad_s";
/// The knob's angle at the last step (rad), and its joint's and panel value's names.
const KNOB: &str = "knob_angle";
const KNOB_ROLE: &str = "knob";
const SPEED: &str = "speed";
/// The knob's play on its shaft across its axis (m, either way) and the spring that centres it
/// (N/m): a hand turning a knob is not exactly coaxial with it, and a rigid shaft would fight the
/// hand's few millimetres until the fingers slip.
const KNOB_PLAY: f64 = 0.004;
const KNOB_PLAY_STIFFNESS: f64 = 200.0;
/// How far from the set speed (a fraction of it) the drive may turn and count as running.
const SPEED_TOLERANCE: f64 = 0.1;

impl Params {
    fn drive(&self) -> Eccentric {
        Eccentric {
            throw: self.throw,
            cup_radius: self.cup_radius,
            cup_half_height: self.cup_half_height,
            // The Vortex-Genie 2 cup's second ring of bumps (12 of 2.4 mm at 23.4 mm): a 50 mL
            // tube stands inside it with 7 mm to spare, a 15 mL one with 13.
            rim: (0.0234, 0.0024, 12),
            ..Eccentric::default()
        }
    }

    /// The cup's centre at rest, instrument frame.
    fn cup_rest(&self) -> Vec3 {
        [
            self.throw,
            -self.cup_back,
            2.0 * self.housing_half[2] + self.cup_half_height + 0.002,
        ]
    }

    /// The knob's detent over its range.
    fn knob_detent(&self) -> Detent {
        Detent {
            lo: 0.0,
            hi: self.knob_range,
            n: self.knob_notches,
            stiffness: self.knob_stiffness,
            damping: self.knob_damping,
        }
    }

    /// The angle between two notches (rad).
    fn notch_angle(&self) -> f64 {
        self.knob_range / f64::from(self.knob_notches - 1)
    }

    /// The notch a knob angle rests in: 0 stops, 1.. run.
    pub fn notch(&self, angle: f64) -> u32 {
        (angle / self.notch_angle())
            .round()
            .clamp(0.0, f64::from(self.knob_notches - 1)) as u32
    }

    /// The speed a notch sets (rpm): none at 0, then linear from the least to the most.
    pub fn notch_rpm(&self, notch: u32) -> f64 {
        if notch == 0 {
            return 0.0;
        }
        let span = f64::from(self.knob_notches - 2).max(1.0);
        self.speed_min_rpm + (self.speed_max_rpm - self.speed_min_rpm) * f64::from(notch - 1) / span
    }

    /// The speed the knob sets at the logic's last reading (rpm).
    fn set_rpm(&self, logic: &Logic) -> f64 {
        self.notch_rpm(self.notch(logic.get(KNOB).copied().unwrap_or(0.0)))
    }

    /// The motor's command for a logic state (rad/s).
    pub fn motor_speed(&self, logic: &Logic) -> f64 {
        if flag(logic, POWER) {
            rpm_to_rad_s(self.set_rpm(logic))
        } else {
            0.0
        }
    }
}

/// The power: switched on and turning, or off.
impl Part for Params {
    fn state(&self, state: &str, _tolerance: Option<f64>, s: &LabwareState) -> Option<Measure> {
        if !matches!(state, "on" | "off") {
            return None;
        }
        // On: switched on and the drive really turning at the knob's speed (within 10%),
        // measured, as a fraction of that speed; with the knob at its stop nothing may run, and
        // the value is 0.
        let switched = s.flag(POWER);
        if state == "on" {
            let set = rpm_to_rad_s(self.set_rpm(&s.logic));
            let speed = s.logic.get(DRIVE_SPEED).copied().unwrap_or(0.0);
            let running = set > 0.0 && (speed - set).abs() <= SPEED_TOLERANCE * set;
            return Some(Measure {
                value: if set > 0.0 { speed / set } else { 0.0 },
                target: 1.0,
                tolerance: SPEED_TOLERANCE,
                holds: switched && running,
            });
        }
        let value = f64::from(u8::from(switched));
        Some(Measure {
            value,
            target: 0.0,
            tolerance: 0.0,
            holds: !switched,
        })
    }
}

impl Instrument for Params {
    fn footprint_radius(&self) -> f64 {
        self.housing_half[0].hypot(self.housing_half[1])
    }

    fn fragment(&self, name: &str, placement: &Pose) -> Fragment {
        let h = self.housing_half;
        let drive = self
            .drive()
            .mjcf(&format!("{name}/vortex"), [0.0, -self.cup_back, 2.0 * h[2]]);
        let worldbody = format!(
            r#"<body name="{name}/base" {placement}>
  <geom name="{name}/housing" type="box" size="{hh}" pos="0 0 {hz}" mass="3" rgba="0.82 0.84 0.86 1"/>
  <body name="{name}/switch" pos="{sw}">
    <joint name="{name}/switch" type="slide" axis="0 -1 0" range="0 {travel}" stiffness="{k}" damping="2"/>
    <geom name="{name}/switch" type="box" size="0.008 0.004 0.008" pos="0 0.004 0" mass="0.005" rgba="0.2 0.6 0.3 1"/>
  </body>
  <body name="{name}/knob_shaft" pos="{kb}">
    <joint name="{name}/knob_play_x" type="slide" axis="1 0 0" range="-{play} {play}" stiffness="{playk}" damping="5"/>
    <joint name="{name}/knob_play_z" type="slide" axis="0 0 1" range="-{play} {play}" stiffness="{playk}" damping="5"/>
    <geom type="sphere" size="0.002" mass="0.005" contype="0" conaffinity="0" group="3"/>
    <body name="{name}/knob">
      <joint name="{name}/knob" type="hinge" axis="0 -1 0" range="0 {krange}" limited="true" armature="0.0001" damping="0.002"/>
      <geom name="{name}/knob" type="cylinder" size="{kr} {kh}" pos="0 {kh} 0" euler="1.5707963 0 0" mass="0.01" rgba="0.15 0.15 0.17 1"/>
      <geom name="{name}/knob_mark" type="box" size="0.0012 0.0008 {mark}" pos="0 {markp} {marky}" mass="0.0001" contype="0" conaffinity="0" rgba="0.95 0.95 0.95 1"/>
    </body>
  </body>
{drive}
</body>
"#,
            placement = pose_attrs(placement),
            hh = v3(h),
            hz = h[2],
            sw = v3(self.switch_at),
            travel = self.switch_travel,
            k = self.switch_stiffness,
            kb = v3(self.knob_at),
            play = KNOB_PLAY,
            playk = KNOB_PLAY_STIFFNESS,
            krange = self.knob_range,
            kr = self.knob_radius,
            kh = self.knob_length / 2.0,
            mark = 0.35 * self.knob_radius,
            markp = self.knob_length + 0.0008,
            marky = 0.55 * self.knob_radius,
            drive = drive.body,
        );
        Fragment {
            worldbody,
            // The knob turns on its shaft, clear of the housing it stands out of.
            contact: format!(
                "<exclude body1=\"{name}/base\" body2=\"{name}/knob\"/>\n<exclude body1=\"{name}/base\" body2=\"{name}/knob_shaft\"/>\n"
            ),
            equality: format!("{}\n", drive.equality),
            actuator: format!("{}\n", drive.actuator),
            ..Default::default()
        }
    }

    /// The knob's notches.
    fn mechanisms(&self, name: &str) -> Vec<Mechanism> {
        vec![Mechanism::Detent {
            instance: format!("{name}/knob_detent"),
            joint: format!("{name}/knob"),
            detent: self.knob_detent(),
        }]
    }

    fn joints(&self, name: &str) -> Vec<(&'static str, String)> {
        vec![
            ("switch", format!("{name}/switch")),
            (KNOB_ROLE, format!("{name}/knob")),
            ("drive", format!("{name}/vortex/pivot")),
        ]
    }

    fn actuators(&self, name: &str) -> Vec<(&'static str, String)> {
        vec![("motor", format!("{name}/vortex/motor"))]
    }

    fn reset(&self, initial: &BTreeMap<String, String>) -> Reset {
        let on = initial.get(POWER).is_some_and(|s| s == "on");
        let mut logic = Logic::new();
        set_flag(&mut logic, POWER, on);
        set(&mut logic, DRIVE_SPEED, 0.0);
        set(&mut logic, KNOB, 0.0);
        Reset {
            joints: Vec::new(),
            logic,
        }
    }

    fn step(&self, dt: f64, joints: &Joints, logic: &mut Logic, out: &mut Effects) {
        let depth = joints.get("switch").copied().unwrap_or(0.0);
        let pressed = self.switch_stiffness * depth > self.press_force;
        let held = if pressed {
            logic.get(HELD).copied().unwrap_or(0.0) + dt
        } else {
            0.0
        };
        let latched = flag(logic, LATCHED);
        if held >= self.repeat_s && !latched {
            let on = flag(logic, POWER);
            set_flag(logic, POWER, !on);
            set(logic, LATCHED, 1.0);
        } else if !pressed {
            set(logic, LATCHED, 0.0);
        }
        set(logic, HELD, held);
        set(logic, KNOB, joints.get(KNOB_ROLE).copied().unwrap_or(0.0));
        out.drive("motor", self.motor_speed(logic));
        let angle = joints.get("drive").copied().unwrap_or(0.0);
        if dt > 0.0
            && let Some(last) = logic.get(DRIVE_ANGLE).copied()
        {
            set(logic, DRIVE_SPEED, (angle - last) / dt);
        }
        set(logic, DRIVE_ANGLE, angle);
    }

    fn part(&self) -> Option<(&'static str, &dyn Part)> {
        Some((POWER, self))
    }

    /// The switch's position, the knob's notch and speed, and the drive's measured speed:
    /// switched on during spin-up (or with the drive held back) reads "on" at under the set
    /// speed, which the judge's "on" is not.
    fn readout(&self, s: &LabwareState) -> BTreeMap<String, String> {
        let state = if s.flag(POWER) { "on" } else { "off" };
        let rad_s = s.logic.get(DRIVE_SPEED).copied().unwrap_or(0.0);
        let rpm = rad_s * 60.0 / std::f64::consts::TAU;
        let notch = self.notch(s.logic.get(KNOB).copied().unwrap_or(0.0));
        BTreeMap::from([
            (POWER.to_string(), state.to_string()),
            (
                "knob".to_string(),
                format!("{notch} ({:.0} rpm)", self.notch_rpm(notch)),
            ),
            ("speed".to_string(), format!("{rpm:.0} rpm")),
        ])
    }

    fn affordance(&self, name: &str, s: &LabwareState) -> Option<Affordance> {
        if name == KNOB_ROLE {
            // Gripped round its outer half from the front, the tool's approach along the hinge
            // axis (-y, into the housing): a right-handed turn of the tool turns the knob up.
            // Round: the fingers take it at any heading, and it turns with them.
            let at = [
                self.knob_at[0],
                self.knob_at[1] + self.knob_length - 0.012,
                self.knob_at[2],
            ];
            let tool = crate::frame::from_axes([1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]);
            return Some(Affordance {
                pose: s.pose * pose(at, tool),
                symmetry: crate::model::Symmetry::Axial,
                touch: false,
                lead: 0.0,
            });
        }
        // The switch's face, pushed along -y by a fingertip coming from the front.
        (name == "switch").then(|| {
            let face = [
                self.switch_at[0],
                self.switch_at[1] + 0.008,
                self.switch_at[2],
            ];
            let tool = crate::frame::from_axes([1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]);
            Affordance {
                pose: s.pose * pose(face, tool),
                symmetry: crate::model::Symmetry::HalfTurn,
                touch: true,
                lead: 0.0,
            }
        })
    }

    fn slot_seat(&self, slot: &str, s: &LabwareState) -> Option<Pose> {
        (slot == "cup").then(|| {
            let c = self.cup_rest();
            s.pose * translation([c[0], c[1], c[2] + self.cup_half_height])
        })
    }

    fn panel(&self) -> Option<&dyn Panel> {
        Some(self)
    }
}

impl Panel for Params {
    /// The speed the knob's notch sets (rpm): what its dial shows, not how fast the drive turns.
    fn panel_value(&self, param: &str, s: &LabwareState) -> Option<f64> {
        (param == SPEED).then(|| self.set_rpm(&s.logic))
    }

    /// The knob angle of the running notch whose speed is nearest `target` (rpm).
    fn dial_toward(&self, param: &str, target: f64) -> Option<(&'static str, f64)> {
        if param != SPEED {
            return None;
        }
        // The running notch nearest the target, half way between two the higher: the
        // catalogue's rule (`PanelParam::set_value`), on the same 600..3,200 rpm.
        let spacing = (self.speed_max_rpm - self.speed_min_rpm) / f64::from(self.knob_notches - 2);
        let nearest = ((target - self.speed_min_rpm) / spacing + 1.0)
            .round()
            .clamp(1.0, f64::from(self.knob_notches - 1));
        Some((KNOB_ROLE, nearest * self.notch_angle()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Steps the logic with the switch at `depth` and the knob in notch 5 for `seconds`; the
    /// last motor command.
    fn hold(p: &Params, logic: &mut Logic, depth: f64, seconds: f64) -> f64 {
        let joints = BTreeMap::from([
            ("switch".to_string(), depth),
            (KNOB_ROLE.to_string(), 5.0 * 0.46),
        ]);
        let mut out = Effects::default();
        for _ in 0..(seconds / 0.002).round() as usize {
            out.clear();
            p.step(0.002, &joints, logic, &mut out);
        }
        out.drives.last().map(|(_, v)| *v).unwrap_or(f64::NAN)
    }

    /// A mixer at the origin whose logic state is `logic`.
    fn at_rest(logic: Logic) -> LabwareState {
        LabwareState {
            name: "vortex".into(),
            pose: Pose::identity(),
            joints: BTreeMap::new(),
            parts: BTreeMap::new(),
            logic,
            touched_by: Vec::new(),
            finger_contacts: Vec::new(),
        }
    }

    /// "On" is switched on and turning at the set speed, measured from the drive's angle: a
    /// drive held back to half speed (or still) with the switch on is not on.
    #[test]
    fn on_is_the_drive_turning_at_its_set_speed() {
        let p = Params::default();
        // The knob in notch 8: 600 + 7/9 of 2,600 rpm.
        let knob = 8.0 * 0.46;
        let rpm = 600.0 + 2600.0 * 7.0 / 9.0;
        let set = rpm_to_rad_s(rpm);
        // The logic after 0.1 s of the drive turning at `rate` (rad/s), started switched on or
        // off, the knob in that notch.
        let spin = |on: bool, rate: f64| {
            let start = BTreeMap::from([(POWER.into(), if on { "on" } else { "off" }.into())]);
            let mut logic = p.reset(&start).logic;
            let mut out = Effects::default();
            for i in 0..50 {
                let joints = BTreeMap::from([
                    ("switch".to_string(), 0.0),
                    (KNOB_ROLE.to_string(), knob),
                    ("drive".to_string(), rate * 0.002 * i as f64),
                ]);
                out.clear();
                p.step(0.002, &joints, &mut logic, &mut out);
            }
            at_rest(logic)
        };
        let run = |rate: f64| p.measure(POWER, "on", None, &spin(true, rate)).unwrap();
        let full = run(set);
        assert!(full.holds && (full.value - 1.0).abs() < 1e-9, "{full:?}");
        assert!(run(0.95 * set).holds);
        assert!(!run(1.15 * set).holds, "over the set speed");
        let half = run(0.5 * set);
        assert!(!half.holds && (half.value - 0.5).abs() < 1e-9, "{half:?}");
        assert!(!run(0.0).holds);
        // Turning at speed with the switch off (coasting) is not on.
        let s = spin(false, set);
        assert!(!p.measure(POWER, "on", None, &s).unwrap().holds);
        assert!(p.measure(POWER, "off", None, &s).unwrap().holds);
        assert_eq!(p.readout(&s)["speed"], "2622 rpm");
        assert_eq!(p.readout(&s)["knob"], "8 (2622 rpm)");
        // Switched on with the knob at 0, nothing runs and nothing is on.
        let mut logic = p
            .reset(&BTreeMap::from([(POWER.into(), "on".into())]))
            .logic;
        let mut out = Effects::default();
        p.step(0.002, &BTreeMap::new(), &mut logic, &mut out);
        assert_eq!(out.drives, vec![("motor", 0.0)]);
        assert!(!p.measure(POWER, "on", None, &at_rest(logic)).unwrap().holds);
    }

    /// The knob's notches set 0, then 600..3,200 rpm in nine equal steps; the dial is turned to
    /// the notch nearest a target, and a knob resting between notches reads the nearer one.
    #[test]
    fn the_knob_sets_the_speed_by_its_notch() {
        let p = Params::default();
        assert_eq!(p.notch_rpm(0), 0.0);
        assert_eq!(p.notch_rpm(1), 600.0);
        assert_eq!(p.notch_rpm(10), 3200.0);
        assert!((p.notch_rpm(6) - (600.0 + 2600.0 * 5.0 / 9.0)).abs() < 1e-9);
        assert_eq!(p.notch(0.2), 0);
        assert_eq!(p.notch(0.25), 1);
        assert_eq!(p.notch(9.0), 10, "past the range: the last notch");
        let (role, angle) = p.dial_toward(SPEED, 2000.0).unwrap();
        assert_eq!(role, KNOB_ROLE);
        assert!(
            (angle - 6.0 * 0.46).abs() < 1e-9,
            "2,044 rpm is nearest: {angle}"
        );
        assert!((p.dial_toward(SPEED, 600.0).unwrap().1 - 0.46).abs() < 1e-9);
        assert_eq!(p.dial_toward("temperature", 1.0), None);
        // The dial's model and the catalogue (what the compiler proves with) agree on every
        // target's notch, midway ones (1,900 rpm: between the fifth and sixth) included.
        let kind = crate::catalogue::KINDS
            .iter()
            .find(|k| k.name == "vortex_mixer")
            .unwrap();
        let speed = kind.panel_param(SPEED).unwrap();
        for target in 600..=3200 {
            let target = f64::from(target);
            let angle = p.dial_toward(SPEED, target).unwrap().1;
            let model = p.notch_rpm(p.notch(angle));
            assert!(
                (model - speed.set_value(target)).abs() < 1e-9,
                "{target} rpm"
            );
        }
        assert!((speed.set_value(1900.0) - p.notch_rpm(6)).abs() < 1e-9);
        let mut logic = p.reset(&BTreeMap::new()).logic;
        let joints = BTreeMap::from([(KNOB_ROLE.to_string(), 6.0 * 0.46 + 0.1)]);
        p.step(0.002, &joints, &mut logic, &mut Effects::default());
        let shown = p.panel_value(SPEED, &at_rest(logic)).unwrap();
        assert!((shown - p.notch_rpm(6)).abs() < 1e-9, "{shown}");
    }

    #[test]
    fn a_held_press_toggles_the_power_once_and_the_motor_follows() {
        let p = Params::default();
        let mut logic = p.reset(&BTreeMap::new()).logic;
        assert_eq!(hold(&p, &mut logic, 0.0, 0.1), 0.0, "off at rest");
        // A tap shorter than the repeat time does nothing.
        assert_eq!(hold(&p, &mut logic, p.switch_travel, 0.1), 0.0);
        hold(&p, &mut logic, 0.0, 0.05);
        let speed = hold(&p, &mut logic, p.switch_travel, 1.0);
        assert_eq!(speed, rpm_to_rad_s(p.notch_rpm(5)), "held: on, once");
        assert_eq!(
            hold(&p, &mut logic, 0.0, 0.1),
            speed,
            "stays on when let go"
        );
        assert_eq!(
            hold(&p, &mut logic, p.switch_travel, 0.5),
            0.0,
            "pressed again: off"
        );
        // A touch too light to pass the force threshold is not a press.
        hold(&p, &mut logic, 0.0, 0.05);
        assert_eq!(
            hold(
                &p,
                &mut logic,
                0.5 * p.press_force / p.switch_stiffness,
                1.0
            ),
            0.0
        );
    }
}
