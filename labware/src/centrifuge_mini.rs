//! The mini centrifuge (Tiangen TGear mini proportions, `../shared/reference/upstream-autobio.md`
//! §11): a small round-shouldered body with a front panel, a tinted lid on a hinge along the
//! back of its top, a six-place rotor seen through the lid, and a tab on the lid's front edge to
//! lift it by. The lid has no latch: it stays open past upright and closed under its own weight.
//!
//! Frame of the instrument: origin at the centre of the footprint, +y the front (the tab's side),
//! +z up. Joint conventions: lid 0 = open (98° up, past upright), -1.712 rad = closed.

use crate::frame::{Pose, Vec3, pose, translation};
use crate::lid::{HasLid, JOINT, Lid, LidBody, LidNames};
use crate::mjcf::{Fragment, v3};
use crate::model::Lidded;
use crate::model::{Affordance, Instrument, LabwareState, Logic, Measure, Part, Reset};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// Every dimension of the instrument (metres, radians, kilograms, SI gains).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Params {
    /// Half extents of the body below the lid.
    pub base_half: Vec3,
    /// Lid hinge point (axis +x through it), on the back edge of the body's top.
    pub hinge: Vec3,
    /// The lid's extents, mass and damping.
    #[serde(flatten)]
    pub lid_body: LidBody,
    pub lid_open: f64,
    pub lid_closed: f64,
    /// The tab on the lid's front edge: how far it stands out, half width, half thickness.
    pub tab_depth: f64,
    pub tab_half_width: f64,
    pub tab_half_thickness: f64,
    /// Named tolerances of the success predicates (rad).
    pub closed_tolerance: f64,
    pub open_tolerance: f64,
}

impl Default for Params {
    fn default() -> Self {
        Params {
            base_half: [0.072, 0.0795, 0.042],
            hinge: [0.0, -0.0745, 0.084],
            lid_body: LidBody {
                depth: 0.152,
                half_width: 0.068,
                half_thickness: 0.012,
                mass: 0.093,
                damping: 0.01,
            },
            lid_open: 0.0,
            lid_closed: -1.712,
            tab_depth: 0.03,
            tab_half_width: 0.02,
            tab_half_thickness: 0.005,
            closed_tolerance: 0.01,
            open_tolerance: 0.01,
        }
    }
}

/// The lid: open and closed by its angle, with no latch.
impl HasLid for Params {
    fn lid(&self) -> Lid {
        self.lid_body.hinged(
            [self.lid_open, self.lid_closed],
            [self.open_tolerance, self.closed_tolerance],
        )
    }
}

impl Part for Params {
    fn state(&self, state: &str, tolerance: Option<f64>, s: &LabwareState) -> Option<Measure> {
        self.lid().measure(state, s.joint(JOINT), tolerance)
    }
}

impl Params {
    /// The tab's centre in the lid's frame.
    fn tab_centre(&self) -> Vec3 {
        let lid = &self.lid_body;
        [0.0, lid.depth + self.tab_depth / 2.0, lid.half_thickness]
    }

    /// The tab's centre for a lid angle, in the frame `placement` is given in. Axes: x along the
    /// hinge, y away from the hinge, z the lid's outward normal.
    pub fn tab_pose(&self, placement: &Pose, lid: f64) -> Pose {
        placement * self.lid().frame(self.hinge, lid) * translation(self.tab_centre())
    }

    /// TCP frame pinching the tab: approach along the tab towards the hinge (z = -tab y), the
    /// fingers closing across its thickness (x = the lid's normal).
    fn grip_affordance(&self, placement: &Pose, lid: f64) -> Pose {
        let tool = crate::frame::from_axes([0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]);
        self.tab_pose(placement, lid) * pose([0.0; 3], tool)
    }
}

impl Instrument for Params {
    fn footprint_radius(&self) -> f64 {
        self.base_half[0].hypot(self.base_half[1])
    }

    fn fragment(&self, name: &str, placement: &Pose) -> Fragment {
        let n = LidNames::new(name);
        let b = self.base_half;
        let lid = &self.lid_body;
        let lid_c = [0.0, lid.depth / 2.0, lid.half_thickness];
        let tab_half = [
            self.tab_half_width,
            self.tab_depth / 2.0,
            self.tab_half_thickness,
        ];
        // The rotor under the lid: a hub and six tube wells, in the lid's closed frame's space.
        let rotor_z = 2.0 * b[2] - 0.012;
        let wells: String = (0..6)
            .map(|k| {
                let a = k as f64 * std::f64::consts::PI / 3.0;
                format!(
                    "  <geom name=\"{base}/well{k}\" type=\"cylinder\" size=\"0.0065 0.004\" pos=\"{:.4} {:.4} {rotor_z}\" rgba=\"0.12 0.12 0.14 1\" contype=\"0\" conaffinity=\"0\"/>\n",
                    0.03 * a.cos(),
                    0.005 + 0.03 * a.sin(),
                    base = n.base,
                )
            })
            .collect();
        let geoms = format!(
            r#"  <geom name="{base}/body" type="box" size="{bh}" pos="0 0 {bz}" rgba="0.93 0.93 0.91 1"/>
  <geom name="{base}/shoulder" type="cylinder" size="{sr} {sh}" pos="0 0.005 {shz}" rgba="0.93 0.93 0.91 1" contype="0" conaffinity="0"/>
  <geom name="{base}/rotor" type="cylinder" size="0.045 0.006" pos="0 0.005 {rz}" rgba="0.55 0.57 0.6 1" contype="0" conaffinity="0"/>
{wells}  <geom name="{base}/panel" type="box" size="0.05 0.002 0.022" pos="0 {py} {pz}" rgba="0.25 0.45 0.75 1" contype="0" conaffinity="0"/>
  <geom name="{base}/window" type="box" size="0.022 0.001 0.008" pos="-0.015 {wy} {wz}" rgba="0.08 0.1 0.1 1" contype="0" conaffinity="0"/>
  <geom name="{base}/button" type="cylinder" size="0.007 0.002" pos="0.028 {wy} {wz}" quat="0.7071068 0.7071068 0 0" rgba="0.2 0.7 0.35 1" contype="0" conaffinity="0"/>
"#,
            base = n.base,
            bh = v3(b),
            bz = b[2],
            sr = b[0] * 0.97,
            sh = 0.004,
            shz = 2.0 * b[2] - 0.004,
            rz = rotor_z - 0.008,
            wells = wells,
            py = b[1] + 0.002,
            pz = b[2],
            wy = b[1] + 0.004,
            wz = b[2] + 0.004,
        );
        let lid_geoms = format!(
            r#"    <geom name="{lid}/shell" type="box" size="{lidh}" pos="{lidc}" rgba="0.35 0.55 0.85 0.55"/>
    <geom name="{lid}/rim" type="box" size="{rimh}" pos="{rimc}" rgba="0.2 0.35 0.65 1" contype="0" conaffinity="0"/>
    <geom name="{lid}/tab" type="box" size="{tabh}" pos="{tabc}" friction="1.5 0.01 0.001" rgba="0.2 0.35 0.65 1"/>
    <site name="{grip}" pos="{tabc}" size="0.005" rgba="1 0.2 0.2 0.5" group="4"/>
"#,
            lid = n.body,
            lidc = v3(lid_c),
            lidh = v3(lid.half()),
            rimh = v3([lid.half_width, 0.004, lid.half_thickness + 0.001]),
            rimc = v3([0.0, lid.depth - 0.004, lid.half_thickness]),
            tabh = v3(tab_half),
            tabc = v3(self.tab_centre()),
            grip = n.grip,
        );
        let lid_xml = self.lid().body_xml(&n, self.hinge, lid_c, &lid_geoms);
        let worldbody = n.instrument_xml(placement, &geoms, &lid_xml);
        let contact = format!("<exclude body1=\"{}\" body2=\"{}\"/>\n", n.base, n.body);
        Fragment {
            worldbody,
            contact,
            ..Default::default()
        }
    }

    fn joints(&self, name: &str) -> Vec<(&'static str, String)> {
        vec![(JOINT, LidNames::new(name).joint)]
    }

    fn reset(&self, initial: &BTreeMap<String, String>) -> Reset {
        Reset {
            joints: vec![(JOINT, self.lid().start(initial).1)],
            logic: Logic::new(),
        }
    }

    /// Its `lid is …` measures, readout and lid goals are the lid's.
    fn lidded(&self) -> Option<&dyn Lidded> {
        Some(self)
    }

    fn affordance(&self, name: &str, s: &LabwareState) -> Option<Affordance> {
        crate::lid::handle(name, || self.grip_affordance(&s.pose, s.joint(JOINT)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_tab_swings_from_above_the_back_to_the_front_edge() {
        let p = Params::default();
        let at = |lid| p.tab_pose(&Pose::identity(), lid).translation.vector;
        let (open, closed) = (at(p.lid_open), at(p.lid_closed));
        // Closed: at the front, just above the body; open: high above the back.
        assert!(
            closed.y > p.base_half[1] && (closed.z - 0.096).abs() < 0.01,
            "{closed:?}"
        );
        assert!(open.y < 0.0 && open.z > 0.2, "{open:?}");
    }

    #[test]
    fn closed_and_open_are_judged_by_the_lid_angle() {
        let p = Params::default();
        let state = |lid: f64| LabwareState {
            name: "mini".into(),
            pose: Pose::identity(),
            joints: BTreeMap::from([("lid".to_string(), lid)]),
            parts: BTreeMap::new(),
            logic: Logic::new(),
            touched_by: Vec::new(),
            finger_contacts: Vec::new(),
        };
        let closed = |lid| p.measure("lid", "closed", None, &state(lid)).unwrap().holds;
        assert!(closed(p.lid_closed + 0.005));
        assert!(!closed(p.lid_closed + 0.05));
        assert!(!closed(p.lid_open));
        assert!(p.measure("lid", "open", None, &state(0.0)).unwrap().holds);
        assert!(p.measure("lid", "locked", None, &state(0.0)).is_none());
        assert_eq!(p.readout(&state(p.lid_closed))["lid"], "closed");
    }
}
