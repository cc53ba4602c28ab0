//! Screw-cap tubes (50 mL and 15 mL conical tubes, 1.5 mL microtubes, cryovials): a free body
//! with a free cap held on by the `autobio.thread` mechanism (a bolt thread on the tube's neck, a
//! nut thread in the cap, and a hidden core cylinder that keeps the nut centred). Collision is one
//! cylinder for the tube and one for the cap, so a tube in a rack costs a few primitive contacts
//! plus the thread's SDF contact.
//!
//! Frame: origin at the centre of the tube's bottom, +z along the tube to the cap. Dimensions and
//! masses from `upstream-autobio.md` §11.4; thread as upstream's (pitch 3 mm, bolt turns [-1, 1.2]
//! with gauge 0.9 mm, nut turns [-1.2, 1] with gauge 0.6 mm).

use crate::frame::{Pose, translation};
use crate::mjcf::{Fragment, cylinder_inertia, pose_attrs};
use crate::model::Liquid;
use crate::model::{
    Affordance, Instrument, LabwareState, Measure, Mechanism, Opening, Part, Symmetry,
};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// How far under the liquid's surface a pipette's tip draws from (m): deep enough that the
/// surface, falling as the tip fills (1.9 mm per mL in a 50 mL tube), stays above it.
const DRAW_DEPTH: f64 = 0.008;

/// How far off the bore's bottom a tip stays (m).
const DRAW_CLEARANCE: f64 = 0.005;

/// A bore shallower than this is a narrow opening ([`Instrument::opening`]): twice the 20 mm a
/// pipette's tip dispenses from under a mouth (m).
const NARROW_BORE: f64 = 0.04;

/// How opaque an open tube's walls are drawn.
const OPEN_ALPHA: f64 = 0.3;

/// Boxes in an open tube's wall.
const OPEN_WALLS: usize = 16;

/// Balls in a cap's centring bearing (two rings of four).
const BEARING_BALLS: usize = 8;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Params {
    /// Tube body: outer radius and height (m), mass (kg).
    pub radius: f64,
    pub height: f64,
    pub mass: f64,
    /// Cap: outer radius and height (m), mass (kg).
    pub cap_radius: f64,
    pub cap_height: f64,
    pub cap_mass: f64,
    /// Helix radius of the thread (m).
    pub thread_radius: f64,
    pub pitch: f64,
    /// How far the cap has to rise off its seat to count as off (m).
    pub cap_off_rise: f64,
    pub rgba: [f64; 4],
    pub cap_rgba: [f64; 4],
    /// Made without its cap, open (a tube whose cap starts off): its body is a hollow of walls
    /// on a base, so that a pipette's tip goes in; no cap, no thread.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub open: bool,
}

impl Params {
    pub fn conical_50ml() -> Params {
        Params {
            radius: 0.01395,
            height: 0.1147,
            mass: 0.0144,
            cap_radius: 0.01775,
            cap_height: 0.0123,
            cap_mass: 0.0193,
            thread_radius: 0.014,
            pitch: 0.003,
            cap_off_rise: 0.01,
            rgba: [0.92, 0.93, 0.95, 0.7],
            cap_rgba: [0.2, 0.45, 0.85, 1.0],
            open: false,
        }
    }

    pub fn conical_15ml() -> Params {
        Params {
            radius: 0.0078,
            height: 0.119,
            mass: 0.0247,
            cap_radius: 0.012,
            cap_height: 0.0102,
            cap_mass: 0.0069,
            thread_radius: 0.00784,
            cap_rgba: [0.95, 0.55, 0.15, 1.0],
            ..Params::conical_50ml()
        }
    }

    pub fn microtube() -> Params {
        Params {
            radius: 0.00535,
            height: 0.0426,
            mass: 0.002,
            cap_radius: 0.0075,
            cap_height: 0.0086,
            cap_mass: 0.0011,
            thread_radius: 0.00599,
            cap_off_rise: 0.005,
            cap_rgba: [0.85, 0.2, 0.25, 1.0],
            ..Params::conical_50ml()
        }
    }

    /// A 0.2 mL PCR tube, one of a strip's: 6 mm across, 21.2 mm tall (its bore 5 mm across,
    /// close to the 5.46 mm wells of Opentrons' aluminium block definition). Its mass is five
    /// times a real tube's 0.2 g: lighter bodies chatter in their holes at our 2 ms step. Its
    /// cap is a screw cap like the others' (a strip's hinged caps are not modelled).
    pub fn pcr_tube() -> Params {
        Params {
            radius: 0.003,
            height: 0.0212,
            mass: 0.001,
            cap_radius: 0.0035,
            cap_height: 0.004,
            cap_mass: 0.0002,
            thread_radius: 0.0031,
            cap_off_rise: 0.003,
            cap_rgba: [0.95, 0.95, 0.9, 1.0],
            ..Params::conical_50ml()
        }
    }

    pub fn cryovial() -> Params {
        Params {
            radius: 0.00495,
            height: 0.0349,
            mass: 0.0036,
            cap_radius: 0.0065,
            cap_height: 0.0115,
            cap_mass: 0.0007,
            thread_radius: 0.00511,
            cap_off_rise: 0.005,
            cap_rgba: [0.55, 0.3, 0.75, 1.0],
            ..Params::conical_50ml()
        }
    }

    /// The bore's radius, the base's thickness and the depth of the conical bottom (m), from the
    /// outer size: a moulded wall of 7% of the radius (at least 0.5 mm), a base twice as thick,
    /// and a cone 1.5 radii deep (a 50 mL tube's is about 20 mm). The 50 mL tube's bore then
    /// holds 52.7 mL to the brim (upstream's mesh: 55.65 mL).
    pub fn bore(&self) -> (f64, f64, f64) {
        let wall = (0.07 * self.radius).max(0.0005);
        let radius = self.radius - wall;
        (radius, 2.0 * wall, 1.5 * radius)
    }

    /// An open tube's MJCF: walls of [`OPEN_WALLS`] boxes around the bore on a solid base, no
    /// cap and no thread.
    fn open_fragment(&self, name: &str, placement: &Pose) -> Fragment {
        let (bore, base, _) = self.bore();
        let (r, h) = (self.radius, self.height);
        let body_i = cylinder_inertia(self.mass, r, h / 2.0);
        let half_thick = (r - bore) / 2.0;
        let mid = (r + bore) / 2.0;
        let half_side = r * (std::f64::consts::PI / OPEN_WALLS as f64).tan() + 0.0002;
        let wall_hz = (h - base) / 2.0;
        // Clearer than a capped tube's body, so that cameras see the liquid inside.
        let c = crate::mjcf::rgba([self.rgba[0], self.rgba[1], self.rgba[2], OPEN_ALPHA]);
        let walls: String = (0..OPEN_WALLS)
            .map(|i| {
                let a = std::f64::consts::TAU * i as f64 / OPEN_WALLS as f64;
                format!(
                    "  <geom name=\"{name}/wall{i}\" type=\"box\" size=\"{half_thick} {half_side} {wall_hz}\" pos=\"{} {} {}\" euler=\"0 0 {a}\" rgba=\"{c}\" friction=\"1 0.01 0.0001\"/>\n",
                    mid * a.cos(),
                    mid * a.sin(),
                    base + wall_hz,
                )
            })
            .collect();
        let worldbody = format!(
            r#"<body name="{name}/base" {place}>
  <freejoint name="{name}/free"/>
  <inertial pos="0 0 {hz}" mass="{m}" diaginertia="{bi0} {bi0} {bi2}"/>
  <geom name="{name}/bottom" type="cylinder" size="{r} {bhz}" pos="0 0 {bhz}" rgba="{c}" friction="1 0.01 0.0001"/>
{walls}</body>
"#,
            place = pose_attrs(placement),
            hz = h / 2.0,
            m = self.mass,
            bi0 = body_i[0],
            bi2 = body_i[2],
            bhz = base / 2.0,
        );
        let mut fragment = Fragment {
            worldbody,
            ..Default::default()
        };
        if let Some(bore) = self.interior() {
            fragment.append(crate::liquid_view::fragment(name, &bore));
        }
        fragment
    }

    /// Height of the bolt thread's axis origin on the tube (tube frame).
    fn bolt_z(&self) -> f64 {
        self.height - 0.005
    }

    /// The cap body's origin when fully screwed on (tube frame): half a pitch above the bolt and
    /// 5 mm above the nut, as upstream's tubes.
    fn cap_seat_z(&self) -> f64 {
        self.bolt_z() + self.pitch / 2.0 + 0.005
    }

    /// How far the cap's top stands above its body's origin (the cap shell reaches this far up).
    const CAP_TOP_ABOVE_ORIGIN: f64 = 0.004;

    /// The capped tube's height: from its base to the top of its screwed-on cap (m).
    pub fn capped_height(&self) -> f64 {
        self.cap_seat_z() + Self::CAP_TOP_ABOVE_ORIGIN
    }

    /// Radius of the hidden core on the tube's neck that keeps the cap centred.
    fn core_radius(&self) -> f64 {
        self.thread_radius - 0.0012
    }

    /// Small hidden balls in the cap, two rings around the core at the nut's top and bottom:
    /// they keep the nut centred on the bolt (a thread has no shoulder) with cheap sphere
    /// contacts instead of a second SDF contact.
    fn bearing(&self, name: &str) -> String {
        let r = 0.001;
        let ring = self.core_radius() + r;
        (0..BEARING_BALLS)
            .map(|i| {
                let a = std::f64::consts::TAU * (i % 4) as f64 / 4.0;
                let z = -0.005 + if i < 4 { 0.004 } else { -0.004 };
                format!(
                    "  <geom name=\"{name}/bearing{i}\" type=\"sphere\" size=\"{r}\" pos=\"{} {} {z}\" contype=\"0\" conaffinity=\"0\" group=\"5\"/>\n",
                    ring * a.cos(),
                    ring * a.sin()
                )
            })
            .collect()
    }

    fn threads(&self, name: &str) -> [Mechanism; 2] {
        let thread = |part: &str, gauge: f64, low: f64, high: f64| Mechanism::Thread {
            instance: format!("{name}/{part}"),
            thread: physics::thread::Thread {
                radius: self.thread_radius,
                gauge,
                pitch: self.pitch,
                low,
                high,
            },
        };
        [
            thread("bolt", 0.0009, -1.0, 1.2),
            thread("nut", 0.0006, -1.2, 1.0),
        ]
    }
}

/// The cap: on its seat or off it.
impl Part for Params {
    fn state(&self, state: &str, tolerance: Option<f64>, s: &LabwareState) -> Option<Measure> {
        let tolerance = tolerance.unwrap_or(0.002);
        if self.open {
            // No cap: off, as far as a cap can be (and apart from nothing).
            let off = state == "off";
            // Its value: as far as a cap can be from the seat, the tube's height.
            return matches!(state, "on" | "off" | "apart").then_some(Measure {
                value: self.height,
                target: if off { self.cap_off_rise } else { 0.0 },
                tolerance,
                holds: off,
            });
        }
        let (_, tilt) = cap_offset(self, s)?;
        Some(match state {
            // On: screwed to its seat, measured along the thread's travel (the tube's axis),
            // coaxial within the thread's play and not crossed (tilted).
            "on" => {
                // Its value: how far from seated, up or down the thread, and how far beyond
                // the play aside (so that a cap at its seat's height but off the axis does not
                // read as nearly on).
                let (rise, aside) = cap_rise_and_aside(self, s)?;
                Measure {
                    value: rise.abs() + (aside - CAP_PLAY).max(0.0),
                    target: 0.0,
                    tolerance,
                    holds: rise.abs() <= tolerance && aside <= CAP_PLAY && tilt <= CAP_TILT,
                }
            }
            // Off: risen off the thread along the tube's axis, or put down clear of the neck
            // (its skirt no longer around it). A cap forced down onto its tube, or torn sideways
            // into the neck (which a thread does not allow; a simulated one may let go), is not.
            "off" => {
                let (rise, aside) = cap_rise_and_aside(self, s)?;
                Measure {
                    value: rise.max(aside - self.radius - self.cap_radius + self.cap_off_rise),
                    target: self.cap_off_rise,
                    tolerance,
                    holds: rise >= self.cap_off_rise || aside >= self.radius + self.cap_radius,
                }
            }
            // Apart: clear of the tube's neck, its skirt no longer around it, wherever it is (a
            // cap lying on the bench); its value how far aside it is.
            "apart" => {
                let (_, aside) = cap_rise_and_aside(self, s)?;
                let clear = self.radius + self.cap_radius;
                Measure {
                    value: aside,
                    target: clear,
                    tolerance,
                    holds: aside >= clear,
                }
            }
            _ => return None,
        })
    }

    fn rise(&self, s: &LabwareState) -> Option<f64> {
        if self.open {
            return None;
        }
        cap_rise_and_aside(self, s).map(|(rise, _)| rise)
    }

    /// A cap lies on its rim, top up: its frame a cap's height less its top's offset above.
    fn lying(&self) -> Pose {
        translation([0.0, 0.0, self.cap_height - Self::CAP_TOP_ABOVE_ORIGIN])
    }
}

impl Instrument for Params {
    fn fragment(&self, name: &str, placement: &Pose) -> Fragment {
        if self.open {
            return self.open_fragment(name, placement);
        }
        let (r, h) = (self.radius, self.height);
        let body_i = cylinder_inertia(self.mass, r, h / 2.0);
        let cap_i = cylinder_inertia(self.cap_mass, self.cap_radius, self.cap_height / 2.0);
        let cap_pose = placement * translation([0.0, 0.0, self.cap_seat_z()]);
        let cap_z = -self.cap_height / 2.0 + Self::CAP_TOP_ABOVE_ORIGIN;
        let (tube_c, cap_c) = (
            crate::mjcf::rgba(self.rgba),
            crate::mjcf::rgba(self.cap_rgba),
        );
        let worldbody = format!(
            r#"<body name="{name}/base" {place}>
  <freejoint name="{name}/free"/>
  <inertial pos="0 0 {hz}" mass="{m}" diaginertia="{bi0} {bi0} {bi2}"/>
  <geom name="{name}/body" type="cylinder" size="{r} {hz}" pos="0 0 {hz}" rgba="{tube_c}" friction="1 0.01 0.0001"/>
  <geom name="{name}/bolt" type="sdf" mesh="{name}/bolt" pos="0 0 {bolt_z}" contype="0" conaffinity="0" group="5">
    <plugin instance="{name}/bolt"/>
  </geom>
  <geom name="{name}/core" type="cylinder" size="{core} 0.01" pos="0 0 {bolt_z}" contype="0" conaffinity="0" group="5"/>
</body>
<body name="{name}/cap" {cap_place}>
  <freejoint name="{name}/cap_free"/>
  <inertial pos="0 0 {cap_z}" mass="{cm}" diaginertia="{ci0} {ci0} {ci2}"/>
  <geom name="{name}/cap_shell" type="cylinder" size="{cr} {chz}" pos="0 0 {cap_z}" rgba="{cap_c}" friction="1.5 0.01 0.0001"/>
{bearing}  <body name="{name}/nut_frame" euler="3.141592653589793 0 0">
    <geom name="{name}/nut" type="sdf" mesh="{name}/nut" pos="0 0 0.005" contype="0" conaffinity="0" group="5">
      <plugin instance="{name}/nut"/>
    </geom>
  </body>
</body>
"#,
            place = pose_attrs(placement),
            cap_place = pose_attrs(&cap_pose),
            hz = h / 2.0,
            m = self.mass,
            bi0 = body_i[0],
            bi2 = body_i[2],
            bolt_z = self.bolt_z(),
            core = self.core_radius(),
            cm = self.cap_mass,
            ci0 = cap_i[0],
            ci2 = cap_i[2],
            cr = self.cap_radius,
            chz = self.cap_height / 2.0,
            bearing = self.bearing(name),
        );
        let asset = format!(
            r#"<mesh name="{name}/bolt"><plugin instance="{name}/bolt"/></mesh>
<mesh name="{name}/nut"><plugin instance="{name}/nut"/></mesh>
"#
        );
        let mut contact = format!(
            r#"<exclude body1="{name}/base" body2="{name}/cap"/>
<pair geom1="{name}/nut" geom2="{name}/bolt" friction="1 1 0.001 0.0001 0.0001" solref="0.004 1" margin="0.0005"/>
"#
        );
        for i in 0..BEARING_BALLS {
            contact += &format!(
                r#"<pair geom1="{name}/bearing{i}" geom2="{name}/core" friction="0.01 0.01 0.001 0.0001 0.0001" solref="0.004 1" solimp="0.9 0.95 0.001"/>
"#
            );
        }
        Fragment {
            asset,
            worldbody,
            equality: String::new(),
            contact,
            ..Default::default()
        }
    }

    fn mechanisms(&self, name: &str) -> Vec<Mechanism> {
        if self.open {
            return Vec::new();
        }
        self.threads(name).to_vec()
    }

    /// The tube and its cap, the cap screwed on.
    fn place(&self, name: &str, root: &Pose) -> Vec<(String, Pose)> {
        if self.open {
            return vec![(format!("{name}/free"), *root)];
        }
        vec![
            (format!("{name}/free"), *root),
            (
                format!("{name}/cap_free"),
                root * translation([0.0, 0.0, self.cap_seat_z()]),
            ),
        ]
    }

    fn part_bodies(&self, name: &str) -> Vec<(&'static str, String)> {
        if self.open {
            return Vec::new();
        }
        vec![("cap", format!("{name}/cap"))]
    }

    fn part(&self) -> Option<(&'static str, &dyn Part)> {
        Some(("cap", self))
    }

    fn readout(&self, s: &LabwareState) -> BTreeMap<String, String> {
        let on = !self.open
            && cap_rise_and_aside(self, s).is_none_or(|(rise, aside)| {
                rise < self.cap_off_rise && aside < self.radius + self.cap_radius
            });
        BTreeMap::from([("cap".into(), if on { "on" } else { "off" }.into())])
    }

    /// A bore shallower than [`NARROW_BORE`] is a narrow opening: a pipette's tip goes at most
    /// half way down it (the tip's narrow end fits; its wide part would catch on the rim), aimed
    /// over the mouth to within a fifth of the bore's radius. Only the mouth: a draw goes under
    /// the liquid's surface as in any tube.
    fn opening(&self, affordance: &str) -> Option<Opening> {
        let (radius, base, _) = self.bore();
        let depth = self.height - base;
        (affordance == "mouth" && depth < NARROW_BORE).then_some(Opening {
            depth: 0.5 * depth,
            aim: 0.2 * radius,
        })
    }

    /// `grasp`: the cap from above (approach straight down, fingers closing across the cap at its
    /// mid-height); any turn about the tube's axis grasps it the same.
    /// `cap_start`: the grasp of a cap set coaxially on the mouth, ready to be screwed on.
    /// `cap_seated`: the grasp of a cap screwed fully on (where screwing it on stops).
    /// `hold`: the body from the side, below the cap (approach across the tube's axis, fingers
    /// closing across the body at [`HOLD_HEIGHT`] of its height), from any side; an open tube
    /// (no cap to take) is grasped the same way.
    /// `mouth`: the centre of the open mouth, z down the axis (where a tip goes in).
    /// `draw`: where a pipette's tip draws from: on the axis [`DRAW_DEPTH`] under the surface of
    /// the liquid the tube holds now (its logic's volume, the surface level in the tube's frame),
    /// but no lower than [`DRAW_CLEARANCE`] off the bottom; z down the axis.
    fn affordance(&self, name: &str, s: &LabwareState) -> Option<Affordance> {
        if name == "draw" {
            let bore = self.interior()?;
            let (bottom, _) = bore.range([0.0, 0.0, 1.0]);
            let ul = s
                .logic
                .get(crate::process::VOLUME_UL)
                .copied()
                .unwrap_or(0.0);
            let liquid = physics::liquid::Liquid::new(
                bore,
                physics::liquid::Nanolitres::from_microlitres(ul),
                0.0,
            )
            .offset();
            let z = (liquid - DRAW_DEPTH).max(bottom + DRAW_CLEARANCE);
            let down = crate::frame::from_axes([1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]);
            return Some(Affordance {
                pose: s.pose * crate::frame::pose([0.0, 0.0, z], down),
                symmetry: Symmetry::Axial,
                touch: false,
                lead: 0.0,
            });
        }
        if name == "mouth" {
            let down = crate::frame::from_axes([1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]);
            return Some(Affordance {
                pose: s.pose * crate::frame::pose([0.0, 0.0, self.height], down),
                symmetry: Symmetry::Axial,
                touch: false,
                lead: 0.0,
            });
        }
        if name == "hold" || (self.open && name == "grasp") {
            let across = crate::frame::from_axes([0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]);
            let at = [0.0, 0.0, HOLD_HEIGHT * self.height];
            if name == "hold" {
                return Some(Affordance {
                    pose: s.pose * crate::frame::pose(at, across),
                    symmetry: Symmetry::AboutY,
                    touch: false,
                    lead: 0.0,
                });
            }
            // An open tube is picked up at the same height, the approach slanted down (turned
            // about the fingers' closing direction) so that the wrist stays high over the bench.
            let slant = crate::frame::x_turn(PICK_SLANT);
            return Some(Affordance {
                pose: s.pose * crate::frame::pose(at, across * slant),
                symmetry: Symmetry::About([0.0, PICK_SLANT.cos(), -PICK_SLANT.sin()]),
                touch: false,
                lead: 0.0,
            });
        }
        // The cap where it is now (its frame: the seat's, moved with it), else where it sits;
        // for `cap_start`, where it goes to be screwed on: coaxial over the mouth, at the height
        // its heading puts it in the thread (see `start_turns`).
        let cap = match (name, s.parts.get("cap")) {
            ("grasp", Some(c)) => *c,
            ("grasp", None) | ("cap_seated", _) => {
                s.pose * translation([0.0, 0.0, self.cap_seat_z()])
            }
            ("cap_start", cap) => {
                let rel = cap.map_or(Pose::identity(), |c| s.pose.inverse() * c);
                let turns = start_turns(&rel);
                s.pose * translation([0.0, 0.0, self.cap_seat_z() + turns * self.pitch])
            }
            _ => return None,
        };
        let down = crate::frame::from_axes([1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]);
        let mid = translation([0.0, 0.0, -self.cap_height / 2.0 + 0.004]);
        Some(Affordance {
            pose: cap * mid * crate::frame::pose([0.0; 3], down),
            symmetry: Symmetry::Axial,
            touch: false,
            lead: self.pitch / std::f64::consts::TAU,
        })
    }

    fn start_from(&mut self, initial: &BTreeMap<String, String>) {
        self.open = initial.get("cap").map(String::as_str) == Some("off");
    }

    fn unsupported_start(&self, initial: &BTreeMap<String, String>) -> Option<String> {
        (!self.open && initial.get("cap").map(String::as_str) == Some("off")).then(|| {
            "a tube whose cap starts off is made open when its protocol compiles; this task was compiled without that: compile it again"
                .into()
        })
    }

    fn liquid(&self) -> Option<&dyn Liquid> {
        Some(self)
    }
}

impl Liquid for Params {
    /// Only a tube built open: a capped one's liquid is out of a tip's reach. (A cap taken off
    /// during an episode does not open the tube to a tip: no task pipettes from one.)
    fn open_vessel(&self) -> bool {
        self.open
    }

    /// An open tube's liquid is drawn (a capped one's cannot be seen into).
    fn liquid_bodies(&self, name: &str) -> Vec<String> {
        if self.open {
            crate::liquid_view::bodies(name)
        } else {
            Vec::new()
        }
    }

    /// The bore: a cylinder on a cone, from above the base up to the mouth (see [`Params::bore`]).
    fn interior(&self) -> Option<physics::liquid::Container> {
        let (radius, base, cone) = self.bore();
        Some(
            physics::liquid::Container::tube(radius, self.height - base, cone, 48)
                .shifted([0.0, 0.0, base]),
        )
    }
}

/// Where a side grip holds a tube's body, as a fraction of its height. Set for the 50 mL tube in
/// its rack and the Aloha's fingers (26 mm tall where they take the tube): they stay above the
/// rack's top plate (the tube stands 54 mm deep in it) and below the fingertips of a hand that
/// grips the cap. Other tubes have no task that holds them yet.
const HOLD_HEIGHT: f64 = 0.79;

/// How far below the horizontal an open tube's pick approaches it (rad): a side grasp of a tube in
/// a rack, approached level, brings a UR5e's wrist down to the bench (upstream's expert slants its
/// pick by 25°).
const PICK_SLANT: f64 = 30.0 * std::f64::consts::PI / 180.0;

/// How far above its seat, in turns of the thread, a cap is set on the mouth to be screwed on, at
/// most: the nut engages the bolt over 2.2 turns (see [`start_turns`]).
const CAP_START_TURNS: f64 = 2.3;

/// Where, in turns above its seat, a cap whose pose relative to its tube is `rel` goes to be
/// screwed on: the highest rise up to [`CAP_START_TURNS`] at which the cap's heading puts its nut
/// in the bolt's groove (a thread's height and heading are bound: each turn anticlockwise, seen
/// from above, raises it one pitch from the seat, where the heading is the tube's). Set there,
/// the nut overlaps the bolt by less than a turn, so it can come straight down onto it, and
/// turning it follows the thread from the first degree. Set at any other height the nut's ridge
/// lands on the bolt's (0.03 mm of play each side) and the cap goes on crossed.
fn start_turns(rel: &Pose) -> f64 {
    let x = rel.rotation * nalgebra::Vector3::x();
    let phase = x.y.atan2(x.x).rem_euclid(std::f64::consts::TAU) / std::f64::consts::TAU;
    phase + (CAP_START_TURNS - phase).floor()
}

/// Farthest a cap on its tube may stand from the tube's axis (m) and count as on: the play of a
/// nut on its bolt (a seated cap wanders up to 0.9 mm in the simulated thread).
const CAP_PLAY: f64 = 0.0015;

/// Largest tilt (rad) of a cap on its tube that still counts as on.
const CAP_TILT: f64 = 0.1;

/// How far the cap is from its seat on the tube (m, in any direction) and how far it is tilted
/// from the tube's axis (rad), from the live poses of tube and cap.
pub fn cap_offset(p: &Params, s: &LabwareState) -> Option<(f64, f64)> {
    let rel = s.pose.inverse() * s.parts.get("cap")?;
    let mut d = rel.translation.vector;
    d.z -= p.cap_seat_z();
    let axis = rel.rotation * nalgebra::Vector3::z();
    Some((d.norm(), axis.z.clamp(-1.0, 1.0).acos()))
}

/// How far the cap has risen from its seat along the tube's axis (m; negative: pushed down onto
/// the neck) and how far it stands from the axis (m), from the live poses of tube and cap.
pub fn cap_rise_and_aside(p: &Params, s: &LabwareState) -> Option<(f64, f64)> {
    let rel = s.pose.inverse() * s.parts.get("cap")?;
    let d = rel.translation.vector;
    Some((d.z - p.cap_seat_z(), (d.x * d.x + d.y * d.y).sqrt()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each tube's bore holds about its nominal volume (the catalogue's capacity) to the brim:
    /// no less than 0.9 of it and under twice it (a 1.5 mL microtube holds about 2 mL to its
    /// brim; ours, 42.6 mm to the rim, 2.7 mL).
    #[test]
    fn each_bore_holds_its_nominal_volume() {
        for kind in ["tube_50ml", "tube_15ml", "tube_1_5ml", "cryovial"] {
            let Some(crate::Model::Tube(p)) = crate::Model::for_kind(kind) else {
                panic!("{kind}")
            };
            let nominal = crate::kind(kind).unwrap().capacity_ul.unwrap();
            let bore = p.interior().unwrap();
            let ratio = bore.capacity() * 1e9 / nominal;
            assert!((0.9..2.0).contains(&ratio), "{kind}: {ratio}");
            // The bore is inside the body: above the base, within the wall, below the mouth.
            let (lo, hi) = bore.range([0.0, 0.0, 1.0]);
            assert!(
                lo > 0.0 && (hi - p.height).abs() < 1e-12,
                "{kind}: {lo} {hi}"
            );
            assert!(!bore.contains([p.radius * 0.99, 0.0, p.height / 2.0]));
        }
    }

    /// A PCR tube's mouth is a narrow opening: a tip goes 10 mm down its 20 mm bore (the narrow
    /// end of a tip, not its wide part) and ends within half a millimetre of its axis; a cryovial's
    /// 34 mm bore is one too; the 1.5 mL tube's and the conical tubes' are not (a dispense goes
    /// the 20 mm it always has).
    #[test]
    fn shallow_bores_are_narrow_openings() {
        let pcr = Params::pcr_tube().opening("mouth").expect("a PCR tube is narrow");
        assert!((pcr.depth - 0.0101).abs() < 1e-9, "{pcr:?}");
        assert!((pcr.aim - 0.0005).abs() < 1e-9, "{pcr:?}");
        assert!(Params::pcr_tube().opening("draw").is_none());
        assert!(Params::cryovial().opening("mouth").is_some());
        for deep in [Params::microtube(), Params::conical_15ml(), Params::conical_50ml()] {
            assert!(deep.opening("mouth").is_none(), "{deep:?}");
        }
    }

    /// Set on the mouth to be screwed on, a cap stands at a height its heading fixes: one pitch
    /// higher per turn anticlockwise from the seat's heading, at most 2.3 turns up and more
    /// than 1.3 (so the nut overlaps the bolt by less than a turn).
    #[test]
    fn a_cap_is_set_on_the_mouth_at_the_height_its_heading_puts_it_in_the_thread() {
        let p = Params::conical_50ml();
        let tube = translation([0.3, 0.1, 0.83]);
        for deg in [0.0, 10.0, 108.0, 179.0, 181.0, 300.0, 359.9, -60.0] {
            let heading = crate::frame::axis_angle([0.0, 0.0, 1.0], f64::to_radians(deg));
            let held = tube * crate::frame::pose([0.0, 0.0, 0.2], heading);
            let s = LabwareState {
                name: "tube".into(),
                pose: tube,
                joints: BTreeMap::new(),
                parts: BTreeMap::from([("cap".into(), held)]),
                logic: Default::default(),
                touched_by: Vec::new(),
                finger_contacts: Vec::new(),
            };
            let start = p.affordance("cap_start", &s).unwrap().pose;
            let seated = p.affordance("cap_seated", &s).unwrap().pose;
            let turns = (position(&start)[2] - position(&seated)[2]) / p.pitch;
            assert!(turns > 1.3 - 1e-9 && turns <= 2.3 + 1e-9, "{deg}: {turns}");
            let phase = f64::to_radians(deg).rem_euclid(std::f64::consts::TAU);
            let off = (turns - phase / std::f64::consts::TAU).rem_euclid(1.0);
            assert!(
                !(1e-9..=1.0 - 1e-9).contains(&off),
                "{deg}: {turns} turns is out of phase"
            );
        }
    }
    use crate::frame::position;

    #[test]
    fn the_cap_sits_on_the_neck_and_is_grasped_from_above() {
        let p = Params::conical_50ml();
        let tube = translation([0.3, 0.1, 0.83]);
        let placed = p.place("tube", &tube);
        assert_eq!(placed.len(), 2);
        // The cap covers the rim: its top above the tube, its skirt below the rim.
        let top = p.cap_seat_z() + 0.004;
        assert!(top > p.height && top - p.cap_height < p.height);
        let s = LabwareState {
            name: "tube".into(),
            pose: tube,
            joints: BTreeMap::new(),
            parts: BTreeMap::from([("cap".into(), placed[1].1)]),
            logic: Default::default(),
            touched_by: Vec::new(),
            finger_contacts: Vec::new(),
        };
        assert!(cap_offset(&p, &s).unwrap().0 < 1e-12);
        let g = p.affordance("grasp", &s).unwrap();
        let z = g.pose.rotation * nalgebra::Vector3::z();
        assert!((z.z + 1.0).abs() < 1e-12, "approach points down");
        assert!(position(&g.pose)[2] > 0.83 + p.height - 0.01);
        assert!(p.measure("cap", "on", None, &s).unwrap().holds);
        assert!(!p.measure("cap", "off", None, &s).unwrap().holds);
        let mut lifted = s.clone();
        lifted
            .parts
            .insert("cap".into(), placed[1].1 * translation([0.0, 0.0, 0.02]));
        assert!(p.measure("cap", "off", None, &lifted).unwrap().holds);
        assert_eq!(p.readout(&lifted)["cap"], "off");
        // A cap put down beside the tube, level with its seat, is off too.
        let mut beside = s.clone();
        beside
            .parts
            .insert("cap".into(), placed[1].1 * translation([0.05, 0.0, 0.0]));
        assert!(!p.measure("cap", "on", None, &beside).unwrap().holds);
        assert!(p.measure("cap", "off", None, &beside).unwrap().holds);
        // A cap forced 14 mm down onto the neck is not on, and not off either.
        let mut forced = s.clone();
        forced
            .parts
            .insert("cap".into(), placed[1].1 * translation([0.0, 0.0, -0.014]));
        assert!(!p.measure("cap", "on", None, &forced).unwrap().holds);
        assert!(!p.measure("cap", "off", None, &forced).unwrap().holds);
        assert_eq!(p.readout(&forced)["cap"], "on");
        // Nor is one torn 20 mm sideways into the neck at its seat's height.
        let mut torn = s.clone();
        torn.parts
            .insert("cap".into(), placed[1].1 * translation([0.02, 0.0, 0.0]));
        assert!(!p.measure("cap", "off", None, &torn).unwrap().holds);
        // Grasped where the cap is now, not where it was seated.
        let g2 = p.affordance("grasp", &lifted).unwrap();
        assert!((position(&g2.pose)[2] - position(&g.pose)[2] - 0.02).abs() < 1e-12);
    }
}
