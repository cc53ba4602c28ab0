//! Lidded centrifuges with a latch (Eppendorf 5430 and 5910 Ri proportions and lid dynamics,
//! `../shared/reference/upstream-autobio.md` §5.3 and §11), one parametric model: a grey body
//! with a control panel in front of the lid (display, start and stop marks, the lid key), a heavy lid on a hinge along
//! the back of its top, sprung towards open and heavily damped, with a grip bar on posts near its
//! front edge and a window over the rotor. The 5430 has a fixed-angle rotor with 30 tube slots
//! (its seats are what a tube is judged against), the 5910 a swing-bucket rotor. The latch
//! catches a lid pushed within `latch_catch` of shut (an equality then holds it), as upstream's;
//! unlike upstream's, it can be released: the panel's sprung `open` key, held past its press
//! force for its hold time, lets the lid go, and the latch re-arms once the lid has been lifted
//! twice the catch clear. The lid is heavily damped: released, its spring raises it slowly a few
//! degrees ajar (the 5910's: 0.13 rad), where it rests until lifted by its grip bar.
//!
//! Frame of the instrument: origin at the centre of the footprint, +y the front (the panel's
//! side), +z up. Joint conventions: lid 0 = open, `lid_closed` (negative) = closed; rotor angle
//! about +z.

use crate::frame::{Pose, Vec3, axis_angle, pose, translation, x_turn};
use crate::lid::{HasLid, JOINT, LOCK_SWITCH, LOCKED, Lid, LidBody, LidNames};
use crate::mjcf::{Fragment, pose_attrs, rgba, v3};
use crate::model::Lidded;
use crate::run::{Programme, RunState};
use crate::model::{
    Affordance, Effects, Instrument, Joints, LabwareState, Logic, Measure, Part, Reset, Symmetry,
    flag, set, set_flag,
};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// What turns under the lid.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Rotor {
    /// A disc with `slots` tube slots evenly around it: slot mouths at `radius` from the axis,
    /// tilted `tilt` from vertical (tube tops toward the axis), a tube's base `depth` down the
    /// slot from its mouth.
    FixedAngle {
        slots: u32,
        radius: f64,
        tilt: f64,
        depth: f64,
        disc_radius: f64,
    },
    /// Two crossed arms with a bucket at each end, `arm_radius` from the axis.
    SwingBucket { arm_radius: f64, bucket_radius: f64 },
}

/// Every dimension of the instrument (metres, radians, kilograms, SI gains).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Params {
    /// Half extents of the body below the lid.
    pub base_half: Vec3,
    /// Lid hinge (axis +x through it): y and z, on the back edge of the body's top.
    pub hinge: [f64; 2],
    /// The lid's extents, mass and damping.
    #[serde(flatten)]
    pub lid_body: LidBody,
    /// Spring towards open (N·m/rad).
    pub lid_stiffness: f64,
    pub lid_open: f64,
    pub lid_closed: f64,
    /// The latch catches the lid within this of closed (rad).
    pub latch_catch: f64,
    /// The grip bar near the lid's front edge, standing on two posts: its centre's distance in
    /// from the edge and up from the lid's top, radius, half length.
    pub bar_inset: f64,
    pub bar_height: f64,
    pub grip_radius: f64,
    pub grip_half_length: f64,
    /// The rotor: its axis (x, y), the height of its top, the bowl around it, and its kind.
    pub rotor_axis: [f64; 2],
    pub rotor_top: f64,
    pub bowl_radius: f64,
    pub rotor: Rotor,
    /// Where the expert pushes the lid: across from the centre line, and a fraction of its depth
    /// from the hinge.
    pub push_x: f64,
    pub push_at: f64,
    /// Named tolerances of the success predicates (rad).
    pub closed_tolerance: f64,
    pub open_tolerance: f64,
    /// The key on the panel that releases the lid.
    pub key: Key,
    /// The spins the protocol runs ([`crate::run`]), each started by the panel's start key
    /// (built only for a centrifuge that spins: the green mark becomes a key). The lid stays
    /// latched while the rotor turns.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub programmes: Vec<Programme>,
}

/// Half the inside width of a rotor slot's sleeve: a 1.5 mL tube (5.35 mm radius) with room to
/// slide in at its lean.
const SLEEVE_HALF: f64 = 0.0062;

/// The thickness of the lid's top plate over the rotor chamber (m); below it the lid is hollow.
const LID_PLATE: f64 = 0.006;

/// How far past the shut lid's face the expert's push goes (m).
const PRESS_PAST: f64 = 0.02;

/// A sprung key on the control panel (metres, N/m, newtons, seconds).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Key {
    /// Across the panel from its centre, towards the instrument's +x.
    pub x: f64,
    pub radius: f64,
    /// How far it stands out of the panel, and how far it can be pushed in.
    pub height: f64,
    pub travel: f64,
    pub stiffness: f64,
    pub damping: f64,
    /// A press counts once the spring pushes back with this force for `hold_s`.
    pub force: f64,
    pub hold_s: f64,
}

impl Key {
    /// The thermal mixer's button feel (0.5 N held 0.25 s, upstream's threshold), at `x`.
    fn at(x: f64) -> Key {
        Key {
            x,
            radius: 0.009,
            height: 0.004,
            travel: 0.003,
            stiffness: 250.0,
            damping: 0.5,
            force: 0.5,
            hold_s: 0.25,
        }
    }
}

impl Params {
    /// The Eppendorf 5430: 0.341 x 0.432 x 0.221 m body, 2.95 kg lid over 99°, 30-slot rotor.
    pub fn eppendorf_5430() -> Params {
        Params {
            base_half: [0.1705, 0.216, 0.1105],
            hinge: [-0.198, 0.221],
            lid_body: LidBody {
                depth: 0.352,
                half_width: 0.17,
                half_thickness: 0.0135,
                mass: 2.95,
                damping: 20.0,
            },
            lid_stiffness: 3.2,
            lid_open: 0.0,
            lid_closed: -1.723,
            latch_catch: 0.01,
            bar_inset: 0.025,
            bar_height: 0.028,
            grip_radius: 0.011,
            grip_half_length: 0.07,
            rotor_axis: [0.0, 0.036],
            rotor_top: 0.213,
            bowl_radius: 0.108,
            rotor: Rotor::FixedAngle {
                slots: 30,
                radius: 0.0749,
                tilt: 50.4f64.to_radians(),
                depth: 0.03,
                disc_radius: 0.095,
            },
            push_x: 0.12,
            push_at: 0.62,
            closed_tolerance: 0.01,
            open_tolerance: 0.01,
            key: Key::at(0.06),
            programmes: Vec::new(),
        }
    }

    /// The Eppendorf 5910 Ri: 0.726 x 0.698 x 0.311 m body, 17.5 kg lid over 111°, swing-bucket
    /// rotor.
    pub fn eppendorf_5910() -> Params {
        Params {
            base_half: [0.363, 0.349, 0.1555],
            hinge: [-0.29, 0.311],
            lid_body: LidBody {
                depth: 0.59,
                half_width: 0.36,
                half_thickness: 0.021,
                mass: 17.5,
                damping: 20.0,
            },
            lid_stiffness: 27.5,
            lid_open: 0.0,
            lid_closed: -1.94,
            latch_catch: 0.01,
            bar_inset: 0.03,
            bar_height: 0.028,
            grip_radius: 0.012,
            grip_half_length: 0.12,
            rotor_axis: [0.0, 0.01],
            rotor_top: 0.29,
            bowl_radius: 0.27,
            rotor: Rotor::SwingBucket {
                arm_radius: 0.157,
                bucket_radius: 0.045,
            },
            push_x: 0.2,
            push_at: 0.45,
            closed_tolerance: 0.01,
            open_tolerance: 0.01,
            key: Key::at(0.14),
            programmes: Vec::new(),
        }
    }

    fn hinge_point(&self) -> Vec3 {
        [0.0, self.hinge[0], self.hinge[1]]
    }

    /// The lid's frame at a lid angle (at the hinge; x along it, y towards the front edge, z the
    /// lid's outward normal), in the frame `placement` is given in.
    fn lid_frame(&self, placement: &Pose, lid: f64) -> Pose {
        placement * self.lid().frame(self.hinge_point(), lid)
    }

    /// The grip bar's centre for a lid angle, in the frame `placement` is given in.
    pub fn bar_pose(&self, placement: &Pose, lid: f64) -> Pose {
        self.lid_frame(placement, lid) * translation(self.bar_centre())
    }

    /// The bar's centre in the lid's frame.
    fn bar_centre(&self) -> Vec3 {
        let lid = &self.lid_body;
        [
            0.0,
            lid.depth - self.bar_inset,
            2.0 * lid.half_thickness + self.bar_height,
        ]
    }

    /// The rotor's frame at rotor angle `rotor`: on its axis at its top, z up.
    fn rotor_frame(&self, rotor: f64) -> Pose {
        let [x, y] = self.rotor_axis;
        pose([x, y, self.rotor_top], axis_angle([0.0, 0.0, 1.0], rotor))
    }

    /// The number of tube slots (0 for a swing-bucket rotor).
    pub fn slots(&self) -> u32 {
        match self.rotor {
            Rotor::FixedAngle { slots, .. } => slots,
            Rotor::SwingBucket { .. } => 0,
        }
    }

    /// A tube's base frame in slot `k` (1-based, evenly spaced) of the rotor's frame: down the
    /// slot from its mouth, z along the slot towards the axis and up.
    fn slot_in_rotor(&self, k: u32) -> Option<Pose> {
        let Rotor::FixedAngle {
            slots,
            radius,
            tilt,
            depth,
            ..
        } = self.rotor
        else {
            return None;
        };
        let a = f64::from(k - 1) * std::f64::consts::TAU / f64::from(slots);
        Some(
            pose([0.0; 3], axis_angle([0.0, 0.0, 1.0], a))
                * translation([radius, 0.0, 0.0])
                * pose([0.0; 3], axis_angle([0.0, 1.0, 0.0], -tilt))
                * translation([0.0, 0.0, -depth]),
        )
    }

    /// The control panel: a plate on the strip of the body's top in front of the closed lid,
    /// its face tilted 20° towards the front. Its centre frame (z the face's outward normal, on
    /// the face) and half extents across and along the face.
    fn panel(&self) -> (Pose, f64, f64) {
        let b = self.base_half;
        let front = self.hinge[0] + self.lid_body.depth;
        let half_depth = (b[1] - front) / 2.0 - 0.002;
        let frame = pose(
            [0.0, (b[1] + front) / 2.0, 2.0 * b[2] + 0.012],
            x_turn(-20f64.to_radians()),
        );
        (frame, 0.45 * b[0], half_depth)
    }

    /// A frame on the control panel's face, `x` across it from its centre: z the outward normal.
    fn on_panel(&self, x: f64) -> Pose {
        self.panel().0 * translation([x, 0.0, 0.0])
    }

    /// Where the closed fingertips press a key at `x` across the panel: on its cap, pointing
    /// into the panel.
    fn key_affordance(&self, placement: &Pose, x: f64) -> Pose {
        let tool = crate::frame::from_axes([0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]);
        placement * self.on_panel(x) * pose([0.0, 0.0, self.key.height], tool)
    }

    /// Across the panel from its centre: the start mark, or the start key of a centrifuge that
    /// spins.
    fn start_x(&self) -> f64 {
        0.15 * self.panel().1
    }

    /// The start key's body: the lid key's feel, a green cap.
    fn start_key_xml(&self, prefix: &str) -> String {
        format!(
            r#"  <body name="{key}" {kat}>
    <joint name="{key}/press" type="slide" axis="0 0 -1" range="0 {travel}" stiffness="{k}" damping="{d}" springref="0" solreflimit="0.004 1"/>
    <geom name="{key}/cap" type="cylinder" size="{kr} {kh}" pos="0 0 {kh}" mass="0.004" rgba="0.2 0.65 0.3 1" friction="1.2 0.01 0.001"/>
  </body>
"#,
            key = start_key_name(prefix),
            kat = pose_attrs(&self.on_panel(self.start_x())),
            travel = self.key.travel,
            k = self.key.stiffness,
            d = self.key.damping,
            kr = self.key.radius,
            kh = self.key.height / 2.0,
        )
    }

    /// Whether a key pushed in `travel` (m) counts as pressed.
    fn key_pressed(&self, travel: Option<&f64>) -> bool {
        travel.is_some_and(|x| *x * self.key.stiffness > self.key.force)
    }

    /// Where the gripper holds the grip bar to lift the lid: closing across the bar, pointing
    /// into the lid.
    fn bar_affordance(&self, placement: &Pose, lid: f64) -> Pose {
        let tool = crate::frame::from_axes([0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]);
        self.lid_frame(placement, lid) * pose(self.bar_centre(), tool)
    }

    /// Where the hand pushes the lid shut: on its outer face, `push_x` off the centre line,
    /// `push_at` of the way from the hinge to the front edge (clear of the grip bar), the tool
    /// pointing into the lid (a touch: the closed fingertips go there). The frame turns with the lid, so following it while the lid closes pushes the lid
    /// shut; the damper keeps the lid against the fingers. (Held by its bar instead, the 5430's
    /// open lid is out of the arm's reach for a third of the arm's start poses.)
    fn push_affordance(&self, placement: &Pose, lid: f64) -> Pose {
        let body = &self.lid_body;
        let at = [
            self.push_x,
            body.depth * self.push_at,
            2.0 * body.half_thickness,
        ];
        let tool = crate::frame::from_axes([1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]);
        self.lid_frame(placement, lid) * pose(at, tool)
    }

    /// The lid's collision shell as boxes (name, centre, half extents), in the lid body's frame
    /// (closed geometry: x along the hinge, y from the hinge to the front edge, z up). Over a
    /// fixed-angle rotor: a plate `LID_PLATE` thick on top and, below it, a skirt around the
    /// rotor chamber's footprint, so that the shut lid is hollow over the chamber, as a real
    /// centrifuge's lid is, and clears the tubes standing out of the rotor's slots (a flat slab
    /// pressed on their caps and tipped them in their slots once it latched). Over a swing-bucket
    /// rotor, whose buckets hang below the body's top, one slab.
    fn lid_boxes(&self) -> Vec<(&'static str, Vec3, Vec3)> {
        let lid = &self.lid_body;
        let (w, d, t) = (lid.half_width, lid.depth, 2.0 * lid.half_thickness);
        if !matches!(self.rotor, Rotor::FixedAngle { .. }) {
            return vec![("shell", [0.0, d / 2.0, t / 2.0], [w, d / 2.0, t / 2.0])];
        }
        let hollow = t - LID_PLATE;
        let [cx, ay] = self.rotor_axis;
        let (cy, r) = (ay - self.hinge[0], self.bowl_radius);
        let skirt = |name: &'static str, x: [f64; 2], y: [f64; 2]| {
            let c = [(x[0] + x[1]) / 2.0, (y[0] + y[1]) / 2.0, hollow / 2.0];
            let h = [(x[1] - x[0]) / 2.0, (y[1] - y[0]) / 2.0, hollow / 2.0];
            (name, c, h)
        };
        vec![
            (
                "shell",
                [0.0, d / 2.0, hollow + LID_PLATE / 2.0],
                [w, d / 2.0, LID_PLATE / 2.0],
            ),
            skirt("skirt_back", [-w, w], [0.0, cy - r]),
            skirt("skirt_front", [-w, w], [cy + r, d]),
            skirt("skirt_left", [-w, cx - r], [cy - r, cy + r]),
            skirt("skirt_right", [cx + r, w], [cy - r, cy + r]),
        ]
    }

    /// The lid's collision geoms ([`Params::lid_boxes`]) for the body `lid`.
    fn lid_shell(&self, lid: &str) -> String {
        self.lid_boxes()
            .iter()
            .map(|(name, c, h)| {
                format!(
                    "    <geom name=\"{lid}/{name}\" type=\"box\" size=\"{}\" pos=\"{}\" rgba=\"0.84 0.85 0.87 1\"/>\n",
                    v3(*h),
                    v3(*c)
                )
            })
            .collect()
    }

    /// The floor of the rotor chamber: a rotor's tubes hang into it.
    fn bowl_floor(&self) -> f64 {
        self.rotor_top - 0.07
    }

    /// The housing below the lid: a slab under the rotor chamber and four walls around it, so that
    /// the rotor and the tubes in it are seen and touched inside the chamber (collision and look).
    fn housing(&self, base: &str) -> String {
        let b = self.base_half;
        let top = 2.0 * b[2];
        let floor = self.bowl_floor();
        let [ax, ay] = self.rotor_axis;
        let r = self.bowl_radius;
        let wall_h = (top - floor) / 2.0;
        let wall_z = floor + wall_h;
        // (name, centre, half extents)
        let parts: [(&str, Vec3, Vec3); 5] = [
            ("body", [0.0, 0.0, floor / 2.0], [b[0], b[1], floor / 2.0]),
            (
                "wall_left",
                [(-b[0] + ax - r) / 2.0, 0.0, wall_z],
                [(ax - r + b[0]) / 2.0, b[1], wall_h],
            ),
            (
                "wall_right",
                [(b[0] + ax + r) / 2.0, 0.0, wall_z],
                [(b[0] - ax - r) / 2.0, b[1], wall_h],
            ),
            (
                "wall_back",
                [ax, (-b[1] + ay - r) / 2.0, wall_z],
                [r, (ay - r + b[1]) / 2.0, wall_h],
            ),
            (
                "wall_front",
                [ax, (b[1] + ay + r) / 2.0, wall_z],
                [r, (b[1] - ay - r) / 2.0, wall_h],
            ),
        ];
        parts
            .iter()
            .map(|(name, c, h)| {
                format!(
                    "  <geom name=\"{base}/{name}\" type=\"box\" size=\"{}\" pos=\"{}\" rgba=\"0.78 0.80 0.82 1\"/>\n",
                    v3(*h),
                    v3(*c)
                )
            })
            .collect()
    }

    /// A fixed-angle rotor's slot sleeves (in the rotor body's frame): four thin walls and a floor
    /// around each slot's axis, from a tube's base up to the slot's mouth, that hold a tube at the
    /// slot's lean.
    fn sleeves(&self, base: &str) -> String {
        let Rotor::FixedAngle { slots, depth, .. } = self.rotor else {
            return String::new();
        };
        let (half, t) = (SLEEVE_HALF, 0.001);
        let metal = rgba([0.55, 0.57, 0.6, 1.0]);
        let mut out = String::new();
        for k in 1..=slots {
            let seat = self.slot_in_rotor(k).expect("fixed-angle slots");
            let walls: [(&str, Vec3, Vec3); 5] = [
                (
                    "px",
                    [half + t, 0.0, depth / 2.0],
                    [t, half + 2.0 * t, depth / 2.0],
                ),
                (
                    "nx",
                    [-half - t, 0.0, depth / 2.0],
                    [t, half + 2.0 * t, depth / 2.0],
                ),
                ("py", [0.0, half + t, depth / 2.0], [half, t, depth / 2.0]),
                ("ny", [0.0, -half - t, depth / 2.0], [half, t, depth / 2.0]),
                ("floor", [0.0, 0.0, -t], [half + 2.0 * t, half + 2.0 * t, t]),
            ];
            for (name, c, h) in walls {
                out += &format!(
                    "    <geom name=\"{base}/slot{k}_{name}\" type=\"box\" size=\"{}\" {} rgba=\"{metal}\"/>\n",
                    v3(h),
                    pose_attrs(&(seat * translation(c)))
                );
            }
        }
        out
    }

    /// The rotor's visual geoms, in the rotor body's frame.
    fn rotor_geoms(&self, base: &str) -> String {
        let geom = |name: &str, kind: &str, size: String, at: &Pose, colour: [f64; 4]| {
            format!(
                "    <geom name=\"{base}/{name}\" type=\"{kind}\" size=\"{size}\" {} rgba=\"{}\" contype=\"0\" conaffinity=\"0\"/>\n",
                pose_attrs(at),
                rgba(colour)
            )
        };
        let metal = [0.62, 0.64, 0.66, 1.0];
        let dark = [0.1, 0.1, 0.12, 1.0];
        match self.rotor {
            Rotor::FixedAngle {
                slots,
                depth,
                disc_radius,
                ..
            } => {
                let mut g = geom(
                    "rotor_disc",
                    "cylinder",
                    format!("{disc_radius} 0.003"),
                    &translation([0.0, 0.0, -0.004]),
                    metal,
                );
                for k in 1..=slots {
                    let mouth = self.slot_in_rotor(k).expect("fixed-angle slots")
                        * translation([0.0, 0.0, depth]);
                    g += &geom(
                        &format!("hole{k}"),
                        "cylinder",
                        "0.0055 0.002".into(),
                        &mouth,
                        dark,
                    );
                }
                g
            }
            Rotor::SwingBucket {
                arm_radius,
                bucket_radius,
            } => {
                let mut g = geom(
                    "rotor_hub",
                    "cylinder",
                    "0.035 0.02".into(),
                    &translation([0.0, 0.0, -0.02]),
                    metal,
                );
                for (i, turn) in [0.0, std::f64::consts::FRAC_PI_2].iter().enumerate() {
                    let arm = pose([0.0, 0.0, -0.015], axis_angle([0.0, 0.0, 1.0], *turn));
                    g += &geom(
                        &format!("rotor_arm{i}"),
                        "box",
                        format!("{} 0.008 0.012", arm_radius),
                        &arm,
                        metal,
                    );
                }
                for k in 0..4 {
                    let a = f64::from(k) * std::f64::consts::FRAC_PI_2;
                    let at = translation([arm_radius * a.cos(), arm_radius * a.sin(), -0.03]);
                    g += &geom(
                        &format!("bucket{k}"),
                        "cylinder",
                        format!("{bucket_radius} 0.03"),
                        &at,
                        [0.45, 0.47, 0.5, 1.0],
                    );
                }
                g
            }
        }
    }
}

/// The lid, sprung towards open, and the latch that catches it shut.
impl HasLid for Params {
    /// Closed is driven past the stop, so that the latch catches it against the spring: the
    /// push point goes `PRESS_PAST` below the shut lid's face, more than the arm sags under
    /// gravity (about 1 cm at the UR5e's reach).
    fn lid(&self) -> Lid {
        let lid = self.lid_body.hinged(
            [self.lid_open, self.lid_closed],
            [self.open_tolerance, self.closed_tolerance],
        );
        Lid {
            spring: Some(self.lid_stiffness),
            closing_to: Some(self.lid_closed - PRESS_PAST / (self.push_at * self.lid_body.depth)),
            ..lid
        }
    }
}

/// Open and closed are the lid's. Locked: shut and held by the latch; unlocked: released,
/// whatever the lid's angle.
impl Part for Params {
    fn state(&self, state: &str, tolerance: Option<f64>, s: &LabwareState) -> Option<Measure> {
        let lid = s.joint(JOINT);
        let locked = s.flag(LOCKED);
        match state {
            "locked" => {
                let m = self.lid().measure("closed", lid, tolerance)?;
                Some(Measure {
                    holds: m.holds && locked,
                    ..m
                })
            }
            "unlocked" => Some(Measure {
                value: f64::from(u8::from(locked)),
                target: 0.0,
                tolerance: 0.5,
                holds: !locked,
            }),
            _ => self.lid().measure(state, lid, tolerance),
        }
    }
}

/// The MuJoCo name of the lid key's body (the lid's are [`LidNames`]).
fn key_name(prefix: &str) -> String {
    format!("{prefix}/key_open")
}

/// The MuJoCo name of the start key's body.
fn start_key_name(prefix: &str) -> String {
    format!("{prefix}/key_start")
}

impl Instrument for Params {
    fn footprint_radius(&self) -> f64 {
        self.base_half[0].hypot(self.base_half[1])
    }

    fn fragment(&self, name: &str, placement: &Pose) -> Fragment {
        let n = LidNames::new(name);
        let key = key_name(name);
        let b = self.base_half;
        let lid = &self.lid_body;
        let lid_c = [0.0, lid.depth / 2.0, lid.half_thickness];
        let bar_c = self.bar_centre();
        let rotor = format!(
            "  <body name=\"{base}/rotor\" {frame}>\n    <joint name=\"{base}/rotor_hinge\" type=\"hinge\" axis=\"0 0 1\" damping=\"0.0001\" frictionloss=\"0.05\"/>\n    <inertial pos=\"0 0 -0.02\" mass=\"0.59\" diaginertia=\"0.0017 0.0017 0.0033\"/>\n{geoms}  </body>\n",
            base = n.base,
            frame = pose_attrs(&self.rotor_frame(0.0)),
            geoms = self.rotor_geoms(&n.base) + &self.sleeves(&n.base),
        );
        // The control panel: a dark plate in front of the closed lid, its face tilted towards the
        // front, with a display, start (green) and stop (red) marks and the sprung lid key (grey,
        // a white bar across it).
        let (face, pw, pd) = self.panel();
        let plate = face * translation([0.0, 0.0, -0.008]);
        let on_panel = |x: f64| self.on_panel(x);
        let panel = format!(
            r#"  <geom name="{base}/panel" type="box" size="{pw} {pd} 0.008" {at} rgba="0.2 0.22 0.25 1" contype="0" conaffinity="0"/>
  <geom name="{base}/display" type="box" size="{dw} {dd} 0.0005" {dat} rgba="0.35 0.75 0.9 1" contype="0" conaffinity="0"/>
{start}  <geom name="{base}/stop" type="box" size="0.008 0.006 0.0005" {tat} rgba="0.8 0.2 0.2 1" contype="0" conaffinity="0"/>
  <body name="{key}" {kat}>
    <joint name="{key}/press" type="slide" axis="0 0 -1" range="0 {travel}" stiffness="{k}" damping="{d}" springref="0" solreflimit="0.004 1"/>
    <geom name="{key}/cap" type="cylinder" size="{kr} {kh}" pos="0 0 {kh}" mass="0.004" rgba="0.55 0.57 0.6 1" friction="1.2 0.01 0.001"/>
    <geom name="{key}/mark" type="box" size="0.005 0.0012 0.0003" pos="0 0 {mz}" rgba="0.95 0.95 0.95 1" contype="0" conaffinity="0"/>
  </body>
"#,
            base = n.base,
            at = pose_attrs(&plate),
            dw = 0.4 * pw,
            dd = 0.7 * pd,
            dat = pose_attrs(&on_panel(-0.4 * pw)),
            start = if self.programmes.is_empty() {
                format!(
                    "  <geom name=\"{}/start\" type=\"box\" size=\"0.008 0.006 0.0005\" {} rgba=\"0.2 0.65 0.3 1\" contype=\"0\" conaffinity=\"0\"/>\n",
                    n.base,
                    pose_attrs(&on_panel(0.15 * pw))
                )
            } else {
                self.start_key_xml(name)
            },
            tat = pose_attrs(&on_panel(0.4 * pw)),
            key = key,
            kat = pose_attrs(&on_panel(self.key.x)),
            travel = self.key.travel,
            k = self.key.stiffness,
            d = self.key.damping,
            kr = self.key.radius,
            kh = self.key.height / 2.0,
            mz = self.key.height + 0.0003,
        );
        let [rx, ry] = self.rotor_axis;
        let geoms = format!(
            r#"{housing}  <geom name="{base}/bowl" type="cylinder" size="{bowl} 0.002" pos="{rx} {ry} {bowlz}" rgba="0.3 0.31 0.33 1" contype="0" conaffinity="0"/>
{rotor}{panel}  <geom name="{base}/stripe" type="box" size="{sx} 0.001 0.006" pos="0 {sy} {stz}" rgba="0.15 0.3 0.6 1" contype="0" conaffinity="0"/>
"#,
            base = n.base,
            housing = self.housing(&n.base),
            bowl = self.bowl_radius,
            bowlz = self.bowl_floor() + 0.002,
            sx = b[0] - 0.01,
            sy = b[1] + 0.001,
            stz = 0.03,
        );
        // The lid's shell, the window over the rotor, the label and the grip bar on its posts.
        let lid_geoms = format!(
            r#"{shell}    <geom name="{lid}/window" type="cylinder" size="{win} 0.001" pos="{rx} {winy} {winz}" rgba="0.15 0.2 0.28 0.85" contype="0" conaffinity="0"/>
    <geom name="{lid}/label" type="box" size="{labw} 0.012 0.001" pos="0 {laby} {winz}" rgba="0.15 0.3 0.6 1" contype="0" conaffinity="0"/>
    <geom name="{lid}/post_l" type="cylinder" size="0.007 {posth}" pos="{postx} {posty} {postz}" rgba="0.3 0.31 0.33 1"/>
    <geom name="{lid}/post_r" type="cylinder" size="0.007 {posth}" pos="-{postx} {posty} {postz}" rgba="0.3 0.31 0.33 1"/>
    <geom name="{lid}/bar" type="capsule" size="{gr} {gl}" pos="{barc}" quat="0.7071068 0 0.7071068 0" friction="1.5 0.01 0.001" rgba="0.3 0.31 0.33 1"/>
    <site name="{grip}" pos="{barc}" size="0.005" rgba="1 0.2 0.2 0.5" group="4"/>
"#,
            lid = n.body,
            shell = self.lid_shell(&n.body),
            win = 0.65 * self.bowl_radius,
            winy = ry - self.hinge[0],
            winz = 2.0 * lid.half_thickness + 0.001,
            labw = 0.3 * lid.half_width,
            laby = lid.depth * 0.85,
            posth = self.bar_height / 2.0,
            postx = self.grip_half_length - 0.005,
            posty = bar_c[1],
            postz = 2.0 * lid.half_thickness + self.bar_height / 2.0,
            gr = self.grip_radius,
            gl = self.grip_half_length,
            barc = v3(bar_c),
            grip = n.grip,
        );
        let lid_xml = self
            .lid()
            .body_xml(&n, self.hinge_point(), lid_c, &lid_geoms);
        let mut contact = format!(
            "<exclude body1=\"{base}\" body2=\"{}\"/>\n<exclude body1=\"{base}\" body2=\"{key}\"/>\n",
            n.body,
            base = n.base
        );
        if !self.programmes.is_empty() {
            contact += &format!(
                "<exclude body1=\"{}\" body2=\"{}\"/>\n",
                n.base,
                start_key_name(name)
            );
        }
        Fragment {
            worldbody: n.instrument_xml(placement, &geoms, &lid_xml),
            equality: self.lid().lock_xml(&n),
            contact,
            ..Default::default()
        }
    }

    fn joints(&self, name: &str) -> Vec<(&'static str, String)> {
        vec![
            (JOINT, LidNames::new(name).joint),
            ("rotor", format!("{name}/base/rotor_hinge")),
            // The role is the catalogue's name of the key.
            ("open", format!("{}/press", key_name(name))),
        ]
        .into_iter()
        .chain(
            (!self.programmes.is_empty())
                .then(|| ("start", format!("{}/press", start_key_name(name)))),
        )
        .collect()
    }

    fn slot_seat(&self, slot: &str, s: &LabwareState) -> Option<Pose> {
        let k: u32 = slot
            .parse()
            .ok()
            .filter(|k| (1..=self.slots()).contains(k))?;
        let rotor = s.joints.get("rotor").copied().unwrap_or(0.0);
        Some(s.pose * self.rotor_frame(rotor) * self.slot_in_rotor(k)?)
    }

    fn switches(&self, name: &str) -> Vec<(&'static str, String)> {
        LidNames::new(name).switches()
    }

    fn reset(&self, initial: &BTreeMap<String, String>) -> Reset {
        let (state, lid) = self.lid().start(initial);
        let mut logic = Logic::new();
        set_flag(&mut logic, LOCKED, state == "locked");
        // A lid that starts shut but unlatched must be lifted clear before the latch can catch.
        set_flag(&mut logic, "armed", state == "open");
        if !self.programmes.is_empty() {
            self.run().reset(&mut logic);
        }
        Reset {
            joints: vec![(JOINT, lid)],
            logic,
        }
    }

    /// The latch: it catches a lid within `latch_catch` of shut when armed; the lid key held
    /// past its press force for `hold_s` releases it and disarms it until the lid has been
    /// lifted twice the catch clear.
    ///
    /// A centrifuge that spins: the start key held likewise starts the next spin while the lid
    /// is latched, and the lid key does nothing while the rotor turns.
    fn step(&self, dt: f64, joints: &Joints, logic: &mut Logic, effects: &mut Effects) {
        let lid = self.lid().angle(joints);
        let held_for = |logic: &Logic, key: &str, pressed: bool| {
            if pressed {
                logic.get(key).copied().unwrap_or(0.0) + dt
            } else {
                0.0
            }
        };
        let held = held_for(logic, "key_held_s", self.key_pressed(joints.get("open")));
        let mut locked = flag(logic, LOCKED);
        let spinning = !self.programmes.is_empty() && {
            let run = self.run();
            run.advance(logic, dt);
            let start = held_for(logic, "start_held_s", self.key_pressed(joints.get("start")));
            if start >= self.key.hold_s && locked {
                run.start(logic);
            }
            set(logic, "start_held_s", start);
            run.state(logic) == RunState::Running
        };
        let mut armed = flag(logic, "armed") || lid > self.lid_closed + 2.0 * self.latch_catch;
        if held >= self.key.hold_s && !spinning {
            locked = false;
            armed = false;
        } else if armed && lid <= self.lid_closed + self.latch_catch {
            locked = true;
        }
        set(logic, "key_held_s", held);
        set_flag(logic, LOCKED, locked);
        set_flag(logic, "armed", armed);
        effects.switch(LOCK_SWITCH, locked);
    }

    fn lidded(&self) -> Option<&dyn Lidded> {
        Some(self)
    }

    fn programmes(&self) -> &[Programme] {
        &self.programmes
    }

    fn set_programmes(&mut self, programmes: Vec<Programme>) {
        self.programmes = programmes;
    }

    /// A fixed-angle rotor's tube bottoms (the slot's radius at its mouth plus its depth along
    /// the lean); a swing-bucket rotor's buckets swung out level, at the arm's end.
    fn rcf_radius_m(&self) -> Option<f64> {
        Some(match self.rotor {
            Rotor::FixedAngle {
                radius,
                tilt,
                depth,
                ..
            } => radius + depth * tilt.sin(),
            Rotor::SwingBucket {
                arm_radius,
                bucket_radius,
            } => arm_radius + bucket_radius,
        })
    }

    /// `lid_close`: the lid is pushed shut (a touch on its face); `lid_open`: it is lifted by its
    /// grip bar; `open`: the lid key.
    fn affordance(&self, name: &str, s: &LabwareState) -> Option<Affordance> {
        let (pose, touch) = match name {
            "lid_close" => (self.push_affordance(&s.pose, s.joint(JOINT)), true),
            "lid_open" => (self.bar_affordance(&s.pose, s.joint(JOINT)), false),
            "open" => (self.key_affordance(&s.pose, self.key.x), true),
            "start" if !self.programmes.is_empty() => {
                (self.key_affordance(&s.pose, self.start_x()), true)
            }
            _ => return None,
        };
        Some(Affordance {
            pose,
            symmetry: Symmetry::HalfTurn,
            touch,
            lead: 0.0,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn state(lid: f64, locked: bool) -> LabwareState {
        let mut logic = Logic::new();
        set(&mut logic, "locked", f64::from(u8::from(locked)));
        LabwareState {
            name: "c".into(),
            pose: Pose::identity(),
            joints: BTreeMap::from([("lid".to_string(), lid)]),
            parts: BTreeMap::new(),
            logic,
            touched_by: Vec::new(),
            finger_contacts: Vec::new(),
        }
    }

    #[test]
    fn the_latch_catches_a_shut_lid_and_holds_it_without_the_key() {
        let p = Params::eppendorf_5430();
        let mut logic = p.reset(&BTreeMap::new()).logic;
        let mut run = |lid: f64| {
            let mut sw = Effects::default();
            p.step(
                0.002,
                &BTreeMap::from([("lid".to_string(), lid)]),
                &mut logic,
                &mut sw,
            );
            sw.switches[0].1
        };
        assert!(!run(p.lid_open));
        assert!(!run(p.lid_closed + 0.05));
        assert!(run(p.lid_closed + 0.005));
        assert!(run(p.lid_open), "only the key lets go");
    }

    /// The latch after `seconds` of steps with the lid at `lid` and the key pushed in `key` (m).
    fn run_latch(p: &Params, logic: &mut Logic, lid: f64, key: f64, seconds: f64) -> bool {
        let dt = 0.002;
        let mut locked = false;
        for _ in 0..(seconds / dt).round() as usize {
            let mut sw = Effects::default();
            let joints = BTreeMap::from([("lid".to_string(), lid), ("open".to_string(), key)]);
            p.step(dt, &joints, logic, &mut sw);
            locked = sw.switches[0].1;
        }
        locked
    }

    #[test]
    fn the_key_held_releases_the_latch_a_tap_does_not_and_the_latch_rearms_once_lifted() {
        let p = Params::eppendorf_5430();
        let locked = BTreeMap::from([("lid".to_string(), "locked".to_string())]);
        let mut logic = p.reset(&locked).logic;
        let pushed = 0.9 * p.key.travel;
        assert!(
            run_latch(&p, &mut logic, p.lid_closed, 0.0, 0.5),
            "starts latched"
        );
        // Pushed in past its press force, but let go before the hold time: still latched.
        assert!(run_latch(&p, &mut logic, p.lid_closed, pushed, 0.2));
        assert!(run_latch(&p, &mut logic, p.lid_closed, 0.0, 0.1));
        // Pushed in but not to the press force: still latched.
        assert!(run_latch(
            &p,
            &mut logic,
            p.lid_closed,
            0.5 * p.key.force / p.key.stiffness,
            1.0
        ));
        // Held: released, and the shut lid is not caught again while it stays in the catch.
        assert!(!run_latch(&p, &mut logic, p.lid_closed, pushed, 0.3));
        assert!(!run_latch(&p, &mut logic, p.lid_closed, 0.0, 1.0));
        // Lifted clear, then pushed shut again: caught.
        assert!(!run_latch(&p, &mut logic, p.lid_closed + 0.1, 0.0, 0.1));
        assert!(run_latch(&p, &mut logic, p.lid_closed + 0.005, 0.0, 0.1));
    }

    #[test]
    fn locked_needs_the_latch_and_the_lid_shut() {
        let p = Params::eppendorf_5430();
        let holds = |lid, locked, what| {
            p.measure("lid", what, None, &state(lid, locked))
                .unwrap()
                .holds
        };
        assert!(holds(p.lid_closed, true, "locked"));
        assert!(!holds(p.lid_closed, false, "locked"));
        assert!(holds(p.lid_closed, false, "closed"));
        assert!(!holds(p.lid_closed + 0.05, false, "closed"));
        assert!(holds(p.lid_open, false, "open"));
        assert_eq!(p.readout(&state(p.lid_closed, true))["lid"], "locked");
    }

    #[test]
    fn the_shut_lid_is_hollow_over_the_rotor_and_clears_a_seated_tubes_cap() {
        let p = Params::eppendorf_5430();
        let s = state(p.lid_closed, true);
        let tube = crate::tube::Params::microtube();
        // Shut, the lid body's frame is the instrument's moved to the hinge.
        let boxes = p.lid_boxes();
        let [hy, hz] = p.hinge;
        let clearance = |at: nalgebra::Vector3<f64>| -> f64 {
            let q = [at.x, at.y - hy, at.z - hz];
            boxes
                .iter()
                .map(|(_, c, h)| {
                    (0..3)
                        .map(|i| (q[i] - c[i]).abs() - h[i])
                        .fold(f64::MIN, f64::max)
                })
                .fold(f64::MAX, f64::min)
        };
        let mut closest = f64::MAX;
        for k in 1..=30 {
            let seat = p.slot_seat(&k.to_string(), &s).unwrap();
            let axis = seat.rotation * nalgebra::Vector3::z();
            let top = seat.translation.vector + axis * tube.capped_height();
            // The highest point of the cap's top rim: towards the axis's upward tilt.
            let up = (nalgebra::Vector3::z() - axis * axis.z).normalize();
            let rim = top + up * tube.cap_radius;
            // The caps stand above the body's top: a flat lid would press on them.
            assert!(rim.z > hz, "slot {k}: {}", rim.z);
            for point in [top, rim] {
                closest = closest.min(clearance(point));
            }
        }
        assert!(closest > 0.005, "a cap within {closest} m of the lid");
        // The skirt stands on every side of the hollow, inside the lid's outline.
        let (cy, r) = (p.rotor_axis[1] - p.hinge[0], p.bowl_radius);
        let lid = &p.lid_body;
        assert!(cy - r > 0.0 && cy + r < lid.depth && r < lid.half_width);
        let xml = p.fragment("c", &Pose::identity()).worldbody;
        for (part, ..) in &boxes {
            assert!(xml.contains(&format!("c/lid/{part}\"")), "{part}");
        }
        // The 5910's buckets hang below its body's top: its lid is one slab.
        let slab = Params::eppendorf_5910();
        assert_eq!(slab.lid_boxes().len(), 1);
        let xml = slab.fragment("c", &Pose::identity()).worldbody;
        assert!(xml.contains("c/lid/shell\"") && !xml.contains("skirt"));
    }

    #[test]
    fn the_rotor_seats_thirty_tilted_slots_in_opposite_pairs() {
        let p = Params::eppendorf_5430();
        let s = state(p.lid_open, false);
        let seat = |k: u32| p.slot_seat(&k.to_string(), &s).unwrap();
        let [ax, ay] = p.rotor_axis;
        for k in 1..=30 {
            let a = seat(k);
            // Leaning 50.4 degrees from vertical, its top towards the axis.
            let z = a.rotation * nalgebra::Vector3::z();
            assert!((z.z.acos() - 50.4f64.to_radians()).abs() < 1e-9);
            let out = nalgebra::Vector3::new(a.translation.x - ax, a.translation.y - ay, 0.0);
            assert!(z.dot(&out) < 0.0, "slot {k} leans outwards");
            // The slot across the rotor mirrors it through the axis.
            let b = seat((k + 14) % 30 + 1);
            assert!((a.translation.x + b.translation.x - 2.0 * ax).abs() < 1e-9);
            assert!((a.translation.y + b.translation.y - 2.0 * ay).abs() < 1e-9);
        }
        // 12 degrees apart, turning with the rotor.
        let (a, b) = (seat(1).translation.vector, seat(2).translation.vector);
        let (ra, rb) = ((a.x - ax).atan2(a.y - ay), (b.x - ax).atan2(b.y - ay));
        assert!(((ra - rb).abs() - 12f64.to_radians()).abs() < 1e-9);
        let turned = s.with_joints(&[("rotor".into(), 0.3)]);
        let c = p.slot_seat("1", &turned).unwrap().translation.vector;
        assert!((c - a).norm() > 0.01);
        assert!(p.slot_seat("31", &s).is_none() && p.slot_seat("0", &s).is_none());
        // The swing-bucket 5910 has no tube slots.
        assert!(Params::eppendorf_5910().slot_seat("1", &s).is_none());
    }
}
