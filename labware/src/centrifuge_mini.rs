//! The mini centrifuge (Tiangen TGear mini proportions, `../shared/reference/upstream-autobio.md`
//! §11): a small round-shouldered body with a front panel, a tinted lid on a hinge along the
//! back of its top, a six-place rotor seen through the lid, and a tab on the lid's front edge to
//! lift it by. The lid has no latch: it stays open past upright and closed under its own weight.
//!
//! Frame of the instrument: origin at the centre of the footprint, +y the front (the tab's side),
//! +z up. Joint conventions: lid 0 = open (98° up, past upright), -1.712 rad = closed.

use crate::frame::{Pose, Vec3, pose, translation, x_turn};
use crate::lid::{Lid, LidNames};
use crate::mjcf::{Fragment, box_inertia, pose_attrs, v3};
use crate::model::{Affordance, Instrument, LabwareState, Logic, Measure, Reset, Symmetry};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// Every dimension of the instrument (metres, radians, kilograms, SI gains).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Params {
    /// Half extents of the body below the lid.
    pub base_half: Vec3,
    /// Lid hinge point (axis +x through it), on the back edge of the body's top.
    pub hinge: Vec3,
    /// Lid extent from the hinge to its front edge, half width, half thickness, mass, damping.
    pub lid_depth: f64,
    pub lid_half_width: f64,
    pub lid_half_thickness: f64,
    pub lid_mass: f64,
    pub lid_damping: f64,
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
            lid_depth: 0.152,
            lid_half_width: 0.068,
            lid_half_thickness: 0.012,
            lid_mass: 0.093,
            lid_damping: 0.01,
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

struct Names {
    base: String,
    lid: LidNames,
}

impl Names {
    fn new(prefix: &str) -> Names {
        Names {
            base: format!("{prefix}/base"),
            lid: LidNames::new(prefix),
        }
    }
}

impl Params {
    /// Orientation of the lid body at joint angle 0: the closed geometry turned open about +x.
    /// The lid this instrument composes ([`crate::lid`]), from its parameters.
    pub fn lid(&self) -> Lid {
        Lid::new(
            self.lid_open,
            self.lid_closed,
            self.open_tolerance,
            self.closed_tolerance,
        )
    }

    /// The tab's centre for a lid angle, in the frame `placement` is given in. Axes: x along the
    /// hinge, y away from the hinge, z the lid's outward normal.
    pub fn tab_pose(&self, placement: &Pose, lid: f64) -> Pose {
        let lid_frame = pose(self.hinge, self.lid().rest() * x_turn(lid));
        placement
            * lid_frame
            * translation([
                0.0,
                self.lid_depth + self.tab_depth / 2.0,
                self.lid_half_thickness,
            ])
    }

    pub fn lid_is_closed(&self, lid: f64) -> bool {
        self.lid().is_closed(lid)
    }

    /// TCP frame pinching the tab: approach along the tab towards the hinge (z = -tab y), the
    /// fingers closing across its thickness (x = the lid's normal).
    fn grip_affordance(&self, placement: &Pose, lid: f64) -> Pose {
        let tool = crate::frame::from_axes([0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]);
        self.tab_pose(placement, lid) * pose([0.0; 3], tool)
    }
}

impl Instrument for Params {
    fn fragment(&self, name: &str, placement: &Pose) -> Fragment {
        let n = Names::new(name);
        let b = self.base_half;
        let lid_half = [
            self.lid_half_width,
            self.lid_depth / 2.0,
            self.lid_half_thickness,
        ];
        let lid_c = [0.0, self.lid_depth / 2.0, self.lid_half_thickness];
        let tab_c = [
            0.0,
            self.lid_depth + self.tab_depth / 2.0,
            self.lid_half_thickness,
        ];
        let tab_half = [
            self.tab_half_width,
            self.tab_depth / 2.0,
            self.tab_half_thickness,
        ];
        let (lo, hi) = (
            self.lid_closed.min(self.lid_open),
            self.lid_closed.max(self.lid_open),
        );
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
        let worldbody = format!(
            r#"<body name="{base}" {placement}>
  <geom name="{base}/body" type="box" size="{bh}" pos="0 0 {bz}" rgba="0.93 0.93 0.91 1"/>
  <geom name="{base}/shoulder" type="cylinder" size="{sr} {sh}" pos="0 0.005 {shz}" rgba="0.93 0.93 0.91 1" contype="0" conaffinity="0"/>
  <geom name="{base}/rotor" type="cylinder" size="0.045 0.006" pos="0 0.005 {rz}" rgba="0.55 0.57 0.6 1" contype="0" conaffinity="0"/>
{wells}  <geom name="{base}/panel" type="box" size="0.05 0.002 0.022" pos="0 {py} {pz}" rgba="0.25 0.45 0.75 1" contype="0" conaffinity="0"/>
  <geom name="{base}/window" type="box" size="0.022 0.001 0.008" pos="-0.015 {wy} {wz}" rgba="0.08 0.1 0.1 1" contype="0" conaffinity="0"/>
  <geom name="{base}/button" type="cylinder" size="0.007 0.002" pos="0.028 {wy} {wz}" quat="0.7071068 0.7071068 0 0" rgba="0.2 0.7 0.35 1" contype="0" conaffinity="0"/>
  <body name="{lid}" {lidframe}>
    <joint name="{lidj}" type="hinge" axis="1 0 0" range="{lo} {hi}" damping="{lidd}" solreflimit="0.004 1" solimplimit="0.95 0.99 0.0005"/>
    <inertial pos="{lidc}" mass="{lidm}" diaginertia="{lidi}"/>
    <geom name="{lid}/shell" type="box" size="{lidh}" pos="{lidc}" rgba="0.35 0.55 0.85 0.55"/>
    <geom name="{lid}/rim" type="box" size="{rimh}" pos="{rimc}" rgba="0.2 0.35 0.65 1" contype="0" conaffinity="0"/>
    <geom name="{lid}/tab" type="box" size="{tabh}" pos="{tabc}" friction="1.5 0.01 0.001" rgba="0.2 0.35 0.65 1"/>
    <site name="{grip}" pos="{tabc}" size="0.005" rgba="1 0.2 0.2 0.5" group="4"/>
  </body>
</body>
"#,
            base = n.base,
            placement = pose_attrs(placement),
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
            lid = n.lid.body,
            lidframe = pose_attrs(&pose(self.hinge, self.lid().rest())),
            lidj = n.lid.joint,
            lidd = self.lid_damping,
            lidc = v3(lid_c),
            lidm = self.lid_mass,
            lidi = v3(box_inertia(self.lid_mass, lid_half)),
            lidh = v3(lid_half),
            rimh = v3([self.lid_half_width, 0.004, self.lid_half_thickness + 0.001]),
            rimc = v3([0.0, self.lid_depth - 0.004, self.lid_half_thickness]),
            tabh = v3(tab_half),
            tabc = v3(tab_c),
            grip = n.lid.grip,
        );
        let contact = format!("<exclude body1=\"{}\" body2=\"{}\"/>\n", n.base, n.lid.body);
        Fragment {
            asset: String::new(),
            worldbody,
            equality: String::new(),
            contact,
            ..Default::default()
        }
    }

    fn joints(&self, name: &str) -> Vec<(&'static str, String)> {
        vec![("lid", Names::new(name).lid.joint)]
    }

    fn reset(&self, initial: &BTreeMap<String, String>) -> Reset {
        let lid = match initial.get("lid").map(String::as_str).unwrap_or("open") {
            "open" => self.lid_open,
            _ => self.lid_closed,
        };
        Reset {
            joints: vec![("lid", lid)],
            logic: Logic::new(),
        }
    }

    fn joint_goal(&self, role: &str, goal: &str) -> Option<f64> {
        match role {
            crate::lid::JOINT => self.lid().goal(goal),
            _ => None,
        }
    }

    fn measure(
        &self,
        part: &str,
        state: &str,
        tolerance: Option<f64>,
        s: &LabwareState,
    ) -> Option<Measure> {
        if part != crate::lid::JOINT {
            return None;
        }
        self.lid()
            .measure(state, s.joint(crate::lid::JOINT), tolerance)
    }

    fn readout(&self, s: &LabwareState) -> BTreeMap<String, String> {
        self.lid().readout(s)
    }

    fn affordance(&self, name: &str, s: &LabwareState) -> Option<Affordance> {
        // The lid primitives hold the lid by the same handle to open and to close it.
        matches!(name, "lid_open" | "lid_close").then(|| Affordance {
            pose: self.grip_affordance(&s.pose, s.joint("lid")),
            symmetry: Symmetry::HalfTurn,
            touch: false,
            lead: 0.0,
        })
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
