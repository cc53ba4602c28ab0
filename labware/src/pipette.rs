//! A single-channel air-displacement pipette (a P1000 with its tip on): a handle, a nose cone with
//! the tip, a plunger button on two springs in series and a tip ejector on its own spring. The
//! plunger's first spring is soft and stops at the first stop (3.25 N there); the second is stiff
//! and already pushes 8 N at rest, so the button holds at the first stop until a thumb presses
//! more than twice as hard, then gives the blow-out travel (13 N at its end). The set volume
//! is the panel value `set_volume` (µL), set for the episode (our pipette has no volume knob to
//! turn: the task's parameter sets it, as a person sets it before starting).
//!
//! Liquid: the plunger's travel to the first stop displaces the set volume, the blow-out travel a
//! fifth more. The logic turns each change of that stroke into volume the tip must take in or
//! push out ([`crate::process::PENDING_UL`]); [`crate::process::Pipetting`], this model's process,
//! moves it between the tip and the vessels around it. The tip's interior is the model's
//! [`Instrument::interior`]: its liquid is the pipette's `volume_ul`, what a `pipette.volume`
//! predicate measures. The ejector slides and reads out; it does not let the tip go (no task
//! changes tips yet).
//!
//! Frame: origin at the tip's opening, +z up the pipette's axis to the plunger button.
//! Dimensions: a 1000 µL tip 71 mm long, 8 mm across at its top; the handle 27 mm across and
//! 140 mm long; plunger travel 7.5 mm to the first stop and 2.5 mm more to blow-out (upstream's
//! pipette: 8 mm in all, §11.5).

use crate::frame::{Pose, pose};
use crate::mjcf::{Fragment, cylinder_inertia, pose_attrs};
use crate::model::{
    Affordance, Effects, Instrument, Joints, LabwareState, Logic, Measure, Part, Symmetry, set,
};
use crate::model::{Liquid, Panel};
use crate::process::{PENDING_UL, Pipetting, Process, STROKE_UL, TipPlace, VOLUME_UL, Vessel};
use physics::liquid::Container;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// The logic key (and panel value) of the set volume, µL.
pub const SET_VOLUME: &str = "set_volume";

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Params {
    /// The tip: length, outer radius at its top and at its opening (m).
    pub tip_length: f64,
    pub tip_radius: f64,
    pub opening_radius: f64,
    /// The nose cone the tip sits on: length and radius (m).
    pub nose_length: f64,
    pub nose_radius: f64,
    /// The handle: radius and length (m), mass of the whole pipette without plunger (kg).
    pub handle_radius: f64,
    pub handle_length: f64,
    pub mass: f64,
    /// Plunger button: radius, height (m); how far it stands above the handle at rest (m).
    pub button_radius: f64,
    pub button_height: f64,
    pub button_rise: f64,
    /// Travel to the first stop and then to blow-out (m); each spring's stiffness (N/m) and the
    /// force it already pushes with at rest (N).
    pub first_stop: f64,
    pub blow_out: f64,
    pub first_stiffness: f64,
    pub first_preload: f64,
    pub blow_out_stiffness: f64,
    pub blow_out_preload: f64,
    /// The ejector's travel (m).
    pub ejector_travel: f64,
    /// The set volume's range and its value when a task sets none (µL).
    pub min_ul: f64,
    pub max_ul: f64,
    /// Volume the blow-out travel pushes, as a share of the set volume.
    pub blow_out_share: f64,
}

impl Params {
    pub fn p1000() -> Params {
        Params {
            tip_length: 0.071,
            tip_radius: 0.004,
            opening_radius: 0.0006,
            nose_length: 0.06,
            nose_radius: 0.0042,
            handle_radius: 0.0135,
            handle_length: 0.14,
            mass: 0.1,
            button_radius: 0.0065,
            button_height: 0.012,
            button_rise: 0.014,
            first_stop: 0.0075,
            blow_out: 0.0025,
            first_stiffness: 300.0,
            first_preload: 1.0,
            blow_out_stiffness: 2000.0,
            blow_out_preload: 8.0,
            ejector_travel: 0.008,
            min_ul: 100.0,
            max_ul: 1000.0,
            blow_out_share: 0.2,
        }
    }

    /// A P200 with its 200 µL tip: the P1000's body on a tip 52 mm long below the nose (59.3 mm
    /// of Opentrons' 200 µL tip less its 7.5 mm overlap), 5.2 mm across at its top; set 20-200 µL.
    pub fn p200() -> Params {
        Params {
            tip_length: 0.052,
            tip_radius: 0.0026,
            opening_radius: 0.0004,
            min_ul: 20.0,
            max_ul: 200.0,
            ..Params::p1000()
        }
    }

    /// Where the nose cone starts (the tip's top sits 5 mm up it) and the handle's bottom (m).
    fn nose_z(&self) -> f64 {
        self.tip_length - 0.005
    }
    fn handle_z(&self) -> f64 {
        self.nose_z() + self.nose_length
    }
    fn handle_top(&self) -> f64 {
        self.handle_z() + self.handle_length
    }

    /// Where the plunger button's top stands at rest (m, pipette frame).
    pub fn button_top(&self) -> f64 {
        self.handle_top() + self.button_rise + self.button_height
    }

    /// Where a hand grips the handle (m up the axis): 30 mm below its top, the thumb over the
    /// button (56 mm above the grip point, which the pipetting hand's TCP is placed for).
    pub fn grip_z(&self) -> f64 {
        self.handle_top() - 0.03
    }

    /// The volume the plunger displaces from rest at travels `first` and `blow` (m, negative
    /// when pressed) for a set volume (µL).
    pub fn stroke_ul(&self, set_ul: f64, first: f64, blow: f64) -> f64 {
        let f = (-first / self.first_stop).clamp(0.0, 1.0);
        let b = (-blow / self.blow_out).clamp(0.0, 1.0);
        set_ul * (f + self.blow_out_share * b)
    }

    fn set_ul(&self, logic: &Logic) -> f64 {
        logic
            .get(SET_VOLUME)
            .copied()
            .unwrap_or(self.max_ul)
            .clamp(self.min_ul, self.max_ul)
    }

    /// The tip's interior: a cone from the opening and a short bore above it, 0.4 mm inside the
    /// tip's wall (1.36 mL to the brim).
    fn tip_interior(&self) -> Container {
        let r = self.tip_radius - 0.0004;
        Container::tube(r, self.tip_length - 0.003, 0.75 * self.tip_length, 24)
    }
}

/// The tip: `out` of every vessel, `in` one (inside it, or over its mouth where a drop falls
/// in), or `immersed` under a liquid's surface; the value is where it is
/// ([`TipPlace::value`]), from what the pipetting process found after the last physics step.
impl Part for Params {
    fn state(&self, state: &str, _tolerance: Option<f64>, s: &LabwareState) -> Option<Measure> {
        let place = TipPlace::of(&s.logic);
        let wanted = TipPlace::named(state)?;
        // `in` holds deeper too: a tip under the surface is in its vessel.
        let holds = match wanted {
            TipPlace::In => place >= TipPlace::In,
            _ => place == wanted,
        };
        Some(Measure {
            value: place.value(),
            target: wanted.value(),
            tolerance: 0.0,
            holds,
        })
    }
}

impl Instrument for Params {
    fn fragment(&self, name: &str, placement: &Pose) -> Fragment {
        let hz = self.handle_length / 2.0;
        let body_i = cylinder_inertia(self.mass, self.handle_radius, hz);
        let tip_hz = (self.tip_length - 0.012) / 2.0;
        let nose_hz = self.nose_length / 2.0;
        let button_hz = self.button_height / 2.0;
        let rod_len = self.button_rise + 0.01;
        let button_z = self.handle_top() + self.button_rise + button_hz;
        // Springs pushing up at rest with their preload: a reference beyond the top stop.
        let first_ref = self.first_preload / self.first_stiffness;
        let blow_ref = self.blow_out_preload / self.blow_out_stiffness;
        let worldbody = format!(
            r#"<body name="{name}/base" {place}>
  <freejoint name="{name}/free"/>
  <inertial pos="0 0 {hc}" mass="{m}" diaginertia="{bi0} {bi0} {bi2}"/>
  <geom name="{name}/handle" type="cylinder" size="{hr} {hz}" pos="0 0 {hc}" rgba="0.93 0.93 0.9 1"/>
  <geom name="{name}/nose" type="cylinder" size="{nr} {nose_hz}" pos="0 0 {nc}" rgba="0.75 0.75 0.72 1"/>
  <geom name="{name}/tip" type="cylinder" size="{tr} {tip_hz}" pos="0 0 {tc}" rgba="0.85 0.9 0.95 0.5"/>
  <geom name="{name}/tip_end" type="cylinder" size="{or} 0.006" pos="0 0 0.006" rgba="0.85 0.9 0.95 0.5"/>
  <site name="{name}/opening" pos="0 0 0" size="0.001" group="4"/>
  <body name="{name}/plunger" pos="0 0 0">
    <joint name="{name}/plunger" type="slide" axis="0 0 1" range="{fs} 0" stiffness="{k1}" springref="{first_ref}" damping="5" armature="0.01" solreflimit="0.004 1" solimplimit="0.95 0.99 0.0005"/>
    <inertial pos="0 0 {button_z}" mass="0.005" diaginertia="1e-6 1e-6 1e-6"/>
    <body name="{name}/button" pos="0 0 0">
      <joint name="{name}/blow_out" type="slide" axis="0 0 1" range="{bs} 0" stiffness="{k2}" springref="{blow_ref}" damping="5" armature="0.01" solreflimit="0.004 1" solimplimit="0.95 0.99 0.0005"/>
      <inertial pos="0 0 {button_z}" mass="0.005" diaginertia="1e-6 1e-6 1e-6"/>
      <geom name="{name}/rod" type="cylinder" size="0.0035 {rod_hz}" pos="0 0 {rod_c}" contype="0" conaffinity="0" rgba="0.8 0.8 0.8 1"/>
      <geom name="{name}/button" type="cylinder" size="{br} {button_hz}" pos="0 0 {button_z}" rgba="0.2 0.45 0.85 1" friction="1.5 0.01 0.0001"/>
    </body>
  </body>
  <body name="{name}/ejector" pos="0 0 0">
    <joint name="{name}/ejector" type="slide" axis="0 0 1" range="-{et} 0" stiffness="500" springref="0.004" damping="2" armature="0.01" solreflimit="0.004 1" solimplimit="0.95 0.99 0.0005"/>
    <inertial pos="{ex} 0 {ez}" mass="0.003" diaginertia="1e-7 1e-7 1e-7"/>
    <geom name="{name}/ejector" type="box" size="0.004 0.006 0.004" pos="{ex} 0 {ez}" rgba="0.6 0.6 0.6 1"/>
  </body>
</body>
"#,
            place = pose_attrs(placement),
            m = self.mass,
            bi0 = body_i[0],
            bi2 = body_i[2],
            hr = self.handle_radius,
            hc = self.handle_z() + hz,
            nr = self.nose_radius,
            nc = self.nose_z() + nose_hz,
            tr = self.tip_radius,
            tc = 0.012 + tip_hz,
            or = self.opening_radius.max(0.0012),
            fs = -self.first_stop,
            k1 = self.first_stiffness,
            bs = -self.blow_out,
            k2 = self.blow_out_stiffness,
            br = self.button_radius,
            rod_hz = rod_len / 2.0,
            rod_c = self.handle_top() - 0.01 + rod_len / 2.0,
            et = self.ejector_travel,
            ex = self.handle_radius + 0.002,
            ez = self.handle_top() + 0.004,
        );
        let discs = crate::liquid_view::fragment(name, &self.tip_interior());
        Fragment {
            worldbody: worldbody + &discs.worldbody,
            contact: format!(
                r#"<exclude body1="{name}/base" body2="{name}/button"/>
<exclude body1="{name}/base" body2="{name}/ejector"/>
<exclude body1="{name}/base" body2="{name}/plunger"/>
"#
            ),
            ..Default::default()
        }
    }

    fn joints(&self, name: &str) -> Vec<(&'static str, String)> {
        ["plunger", "blow_out", "ejector"]
            .into_iter()
            .map(|role| (role, format!("{name}/{role}")))
            .collect()
    }

    /// All but the button, which the thumb presses.
    fn held_bodies(&self, name: &str) -> Vec<String> {
        ["base", "plunger", "ejector"]
            .iter()
            .map(|b| format!("{name}/{b}"))
            .collect()
    }

    fn place(&self, name: &str, root: &Pose) -> Vec<(String, Pose)> {
        vec![(format!("{name}/free"), *root)]
    }

    /// The plunger's stroke as volume: each change is volume the tip must move. The first call
    /// (at reset) only notes where the plunger stands.
    fn step(&self, _dt: f64, joints: &Joints, logic: &mut Logic, _: &mut Effects) {
        let first = joints.get("plunger").copied().unwrap_or(0.0);
        let blow = joints.get("blow_out").copied().unwrap_or(0.0);
        let stroke = self.stroke_ul(self.set_ul(logic), first, blow);
        if let Some(last) = logic.get(STROKE_UL).copied() {
            let pending = logic.get(PENDING_UL).copied().unwrap_or(0.0);
            if stroke != last {
                set(logic, PENDING_UL, pending - (stroke - last));
            }
        }
        set(logic, STROKE_UL, stroke);
    }

    /// `plunger`: `rest`, `first_stop`; `blow_out`: `rest`, `blow_out` (its stop).
    fn joint_goal(&self, role: &str, goal: &str) -> Option<f64> {
        match (role, goal) {
            ("plunger" | "blow_out", "rest") => Some(0.0),
            ("plunger", "first_stop") => Some(-self.first_stop),
            ("blow_out", "blow_out") => Some(-self.blow_out),
            _ => None,
        }
    }

    fn part(&self) -> Option<(&'static str, &dyn Part)> {
        Some(("tip", self))
    }

    fn readout(&self, s: &LabwareState) -> BTreeMap<String, String> {
        let first = s.joint("plunger");
        let blow = s.joint("blow_out");
        let plunger = if blow < -0.2 * self.blow_out {
            "blow-out"
        } else if first < -0.95 * self.first_stop {
            "first stop"
        } else if first < -0.05 * self.first_stop {
            "pressed"
        } else {
            "rest"
        };
        let held = s.logic.get(VOLUME_UL).copied().unwrap_or(0.0);
        let tip = TipPlace::of(&s.logic).name();
        BTreeMap::from([
            ("plunger".into(), plunger.into()),
            ("tip".into(), tip.into()),
            (
                SET_VOLUME.into(),
                format!("{:.0} µL", self.set_ul(&s.logic)),
            ),
            ("volume".into(), format!("{held:.1} µL")),
        ])
    }

    /// `grasp`: the handle where a fist holds it, the approach (z) down the axis toward the tip.
    /// `opening`: the tip's opening, z down the axis (where it goes in first).
    /// `plunger`: the top of the button, pressed down the axis (a touch).
    fn affordance(&self, name: &str, s: &LabwareState) -> Option<Affordance> {
        let down = crate::frame::from_axes([1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]);
        let (z, touch) = match name {
            "grasp" => (self.grip_z(), false),
            "opening" => (0.0, false),
            "plunger" => (self.button_top(), true),
            _ => return None,
        };
        Some(Affordance {
            pose: s.pose * pose([0.0, 0.0, z], down),
            symmetry: Symmetry::Axial,
            touch,
            lead: 0.0,
        })
    }

    fn panel(&self) -> Option<&dyn Panel> {
        Some(self)
    }

    fn liquid(&self) -> Option<&dyn Liquid> {
        Some(self)
    }
}

impl Panel for Params {
    fn panel_value(&self, param: &str, s: &LabwareState) -> Option<f64> {
        (param == SET_VOLUME).then(|| self.set_ul(&s.logic))
    }
}

impl Liquid for Params {
    fn liquid_bodies(&self, name: &str) -> Vec<String> {
        crate::liquid_view::bodies(name)
    }

    fn interior(&self) -> Option<Container> {
        Some(self.tip_interior())
    }

    /// The tip is not a vessel another tip works in.
    fn open_vessel(&self) -> bool {
        false
    }

    fn processes(&self, _name: &str, me: usize, vessels: &[Vessel]) -> Vec<Box<dyn Process>> {
        vec![Box::new(Pipetting::new(
            me,
            self.tip_interior(),
            [0.0, 0.0, 0.0],
            vessels,
        ))]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_stroke_gives_the_set_volume_at_the_first_stop_and_a_fifth_more_at_blow_out() {
        let p = Params::p1000();
        assert_eq!(p.stroke_ul(200.0, 0.0, 0.0), 0.0);
        assert!((p.stroke_ul(200.0, -p.first_stop, 0.0) - 200.0).abs() < 1e-9);
        assert!((p.stroke_ul(200.0, -p.first_stop / 2.0, 0.0) - 100.0).abs() < 1e-9);
        assert!((p.stroke_ul(200.0, -p.first_stop, -p.blow_out) - 240.0).abs() < 1e-9);
        // Past its stop (a joint's soft limit) it displaces no more.
        assert!((p.stroke_ul(200.0, -0.01, 0.0) - 200.0).abs() < 1e-9);
    }

    #[test]
    fn pressing_and_releasing_asks_the_tip_to_push_out_then_take_in() {
        let p = Params::p1000();
        let mut logic = Logic::new();
        logic.insert(SET_VOLUME.into(), 500.0);
        let mut fx = Effects::default();
        let at = |first: f64| BTreeMap::from([("plunger".to_string(), first)]);
        p.step(0.0, &at(0.0), &mut logic, &mut fx);
        assert_eq!(logic.get(PENDING_UL), None, "reset moves nothing");
        p.step(0.002, &at(-p.first_stop), &mut logic, &mut fx);
        assert!((logic[PENDING_UL] + 500.0).abs() < 1e-9);
        // Pushed out (by the process), then released half way: a quarter of the tip's volume.
        logic.insert(PENDING_UL.into(), 0.0);
        p.step(0.002, &at(-p.first_stop / 2.0), &mut logic, &mut fx);
        assert!((logic[PENDING_UL] - 250.0).abs() < 1e-9);
        // Set volumes outside the pipette's range are held to it.
        logic.insert(SET_VOLUME.into(), 5000.0);
        assert_eq!(p.set_ul(&logic), 1000.0);
    }

    #[test]
    fn the_tip_holds_a_thousand_microlitres_below_its_brim_and_opens_at_the_origin() {
        let p = Params::p1000();
        let tip = p.tip_interior();
        let capacity = tip.capacity() * 1e9;
        assert!((1000.0..1600.0).contains(&capacity), "{capacity} µL");
        let (lo, hi) = tip.range([0.0, 0.0, 1.0]);
        assert!(lo.abs() < 1e-12 && hi < p.tip_length, "{lo} {hi}");
        assert!(p.button_top() > p.handle_top() + p.first_stop + p.blow_out);
    }
}
