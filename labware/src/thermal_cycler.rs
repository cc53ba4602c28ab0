//! The thermal cycler (modelled on a Bio-Rad C1000's proportions): a static base, a lid on a hinge
//! at its top, and on the lid's front edge a lock lever with a grip bar that snaps between two
//! notches (raised, pressed). The latch locks the lid only when the lever is pressed *after* the
//! lid is closed; pressing it while the lid is open jams it until it is raised again.
//!
//! Frame of the instrument: origin at the centre of the base's footprint, +y is the front (the side
//! the lid opens from), +z up. Joint conventions follow the upstream task: lid 0 = open,
//! -1.9 rad = closed; lever 0 = raised, -0.94 rad = pressed.

use crate::frame::{Pose, Vec3, pose, translation, x_turn};
use crate::lid::{HasLid, JOINT, LOCK_SWITCH, LOCKED, Lid, LidBody, LidNames};
use crate::mjcf::{Fragment, v3};
use crate::model::Lidded;
use crate::model::{
    Affordance, Effects, Instrument, Joints, LabwareState, Logic, Measure, Mechanism, Part, Reset,
    flag, set_flag,
};
use crate::run::{Programme, RunState};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// Every dimension of the instrument (metres, radians, kilograms, SI gains).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Params {
    /// Half extents of the main body box.
    pub base_half: Vec3,
    /// Lid hinge point (the hinge axis is +x through it).
    pub hinge: Vec3,
    /// The lid's extents, mass and damping.
    #[serde(flatten)]
    pub lid_body: LidBody,
    pub lid_open: f64,
    pub lid_closed: f64,
    /// Lever: pivot on the lid's front edge; grip bar at `lever_arm` from the pivot.
    pub lever_arm: f64,
    pub grip_radius: f64,
    pub grip_half_length: f64,
    pub lever_mass: f64,
    pub lever_raised: f64,
    pub lever_pressed: f64,
    /// Detent spring toward the nearest notch (N·m/rad) and its damping (N·m·s/rad).
    pub detent_stiffness: f64,
    pub detent_damping: f64,
    /// Named tolerances of the success predicates (rad).
    pub closed_tolerance: f64,
    pub locked_tolerance: f64,
    pub open_tolerance: f64,
    pub unlocked_tolerance: f64,
    /// The profile the protocol runs ([`crate::run`]): it starts as the lid locks (the cycler's
    /// software starts it, as a lab automation deck starts its cycler module); none: the cycler
    /// only opens and closes.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub programmes: Vec<Programme>,
    /// The 96-well block 0.2 mL tubes stand in (`thermal_cycler_96`), sunk into the base's top
    /// under where the lid closes, so that capped tubes clear the shut lid; none: the paper's
    /// cycler, whose block is a plate drawn on the base and holds nothing.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub wells: Option<Wells>,
}

/// A block of wells sunk into the base: the block (a rack's plates and bars) in a pocket cut into
/// the base's top, the pocket's floor as deep as the tallest tube the block takes stands.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Wells {
    pub block: crate::rack::Params,
    /// The block's centre along y in the instrument's frame (m): under the closed lid.
    pub centre_y: f64,
    /// The tallest item the block holds, from its bottom to its top (a capped PCR tube, m).
    pub tallest: f64,
}

/// Room between the block and the pocket's walls, and below the base's top over the tallest
/// item (m).
const POCKET_CLEARANCE: f64 = 0.001;

impl Default for Params {
    fn default() -> Self {
        Params {
            base_half: [0.1655, 0.177, 0.0915],
            hinge: [0.0, 0.01, 0.205],
            lid_body: LidBody {
                depth: 0.18,
                half_width: 0.10,
                half_thickness: 0.02,
                mass: 0.87,
                damping: 0.05,
            },
            lid_open: 0.0,
            lid_closed: -1.9,
            lever_arm: 0.06,
            grip_radius: 0.009,
            grip_half_length: 0.056,
            lever_mass: 0.164,
            lever_raised: 0.0,
            lever_pressed: -0.94,
            detent_stiffness: 0.3631,
            detent_damping: 0.0363,
            closed_tolerance: 0.01,
            locked_tolerance: 0.01,
            open_tolerance: 0.003,
            unlocked_tolerance: 0.003,
            programmes: Vec::new(),
            wells: None,
        }
    }
}

/// The lever's MuJoCo names (the lid's are [`LidNames`]), prefixed by the protocol's name.
fn lever_names(prefix: &str) -> (String, String) {
    (format!("{prefix}/lever"), format!("{prefix}/lever_hinge"))
}

/// The lid, latched by the lever.
impl HasLid for Params {
    fn lid(&self) -> Lid {
        self.lid_body.hinged(
            [self.lid_open, self.lid_closed],
            [self.open_tolerance, self.closed_tolerance],
        )
    }
}

/// Open and closed are the lid's; the latch is read on the lever. Locked: the lever in its
/// pressed notch and the latch holding; unlocked: raised and not.
impl Part for Params {
    fn state(&self, state: &str, tolerance: Option<f64>, s: &LabwareState) -> Option<Measure> {
        let locked = s.flag(LOCKED);
        let (target, latched, default) = match state {
            "locked" => (self.lever_pressed, locked, self.locked_tolerance),
            "unlocked" => (self.lever_raised, !locked, self.unlocked_tolerance),
            _ => return self.lid().measure(state, s.joint(JOINT), tolerance),
        };
        let m = Measure::near(s.joint("lever"), target, tolerance.unwrap_or(default));
        Some(Measure {
            holds: m.holds && latched,
            ..m
        })
    }
}

impl Params {
    /// The cycler with a 96-well block for 0.2 mL tubes (`thermal_cycler_96`): the wells of the
    /// catalogue kind's published definition (a 96-well block's 9 mm grid), centred under the
    /// closed lid, deep enough that a capped PCR tube clears it.
    pub fn with_96_wells() -> Params {
        let tube = crate::tube::Params::pcr_tube();
        Params {
            wells: Some(Wells {
                block: crate::rack::Params::defined("thermal_cycler_96"),
                centre_y: 0.1,
                tallest: tube.height + tube.cap_height,
            }),
            ..Params::default()
        }
    }

    /// The pocket's floor (m, instrument frame): the tallest item's top
    /// [`POCKET_CLEARANCE`] under the base's top.
    fn pocket_floor(&self, w: &Wells) -> f64 {
        2.0 * self.base_half[2] - POCKET_CLEARANCE - w.tallest - w.block.seat_z_from_bottom()
    }

    /// The block's centre in the instrument's frame.
    fn block_centre(&self, w: &Wells) -> Vec3 {
        [0.0, w.centre_y, self.pocket_floor(w) + w.block.size[2] / 2.0]
    }

    /// The base's collision boxes (centre, half size): one box, or with a block of wells, a
    /// slab under the pocket and four walls around it.
    fn base_boxes(&self) -> Vec<(Vec3, Vec3)> {
        let b = self.base_half;
        let Some(w) = &self.wells else {
            return vec![([0.0, 0.0, b[2]], b)];
        };
        let floor = self.pocket_floor(w);
        let top = 2.0 * b[2];
        let px = w.block.size[0] / 2.0 + POCKET_CLEARANCE;
        let (y0, y1) = (
            w.centre_y - w.block.size[1] / 2.0 - POCKET_CLEARANCE,
            w.centre_y + w.block.size[1] / 2.0 + POCKET_CLEARANCE,
        );
        let (hz, cz) = ((top - floor) / 2.0, (top + floor) / 2.0);
        let side = (b[0] - px) / 2.0;
        vec![
            ([0.0, 0.0, floor / 2.0], [b[0], b[1], floor / 2.0]),
            ([-(px + side), 0.0, cz], [side, b[1], hz]),
            ([px + side, 0.0, cz], [side, b[1], hz]),
            ([0.0, (y0 - b[1]) / 2.0, cz], [px, (y0 + b[1]) / 2.0, hz]),
            ([0.0, (y1 + b[1]) / 2.0, cz], [px, (b[1] - y1) / 2.0, hz]),
        ]
    }

    /// Pose of the grip bar's centre for given joint angles, in the frame `placement` is given in.
    /// Axes: x along the bar, y pointing away from the lever pivot, z = x × y.
    pub fn grip_pose(&self, placement: &Pose, lid: f64, lever: f64) -> Pose {
        let lid_frame = self.lid().frame(self.hinge, lid);
        let lever_frame = pose([0.0, self.lid_body.depth, 0.0], x_turn(lever));
        placement * lid_frame * lever_frame * translation([0.0, self.lever_arm, 0.0])
    }

    /// The notch nearest to a lever angle.
    pub fn nearest_notch(&self, lever: f64) -> f64 {
        if (lever - self.lever_pressed).abs() < (lever - self.lever_raised).abs() {
            self.lever_pressed
        } else {
            self.lever_raised
        }
    }

    /// TCP frame gripping the bar: at the bar's centre, oriented as the bar frame would be with the
    /// lever raised (approach z = -grip y; fingers, x, along grip z). The bar is round, so it turns
    /// inside the closed fingers while the lever moves: the tool follows the lid's rotation but not
    /// the lever's, and never has to come at the pressed lever from below.
    fn grip_affordance(&self, placement: &Pose, lid: f64, lever: f64) -> Pose {
        let mut grip = self.grip_pose(placement, lid, self.lever_raised);
        grip.translation = self.grip_pose(placement, lid, lever).translation;
        let tool = crate::frame::from_axes([0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]);
        grip * pose([0.0; 3], tool)
    }
}

/// The lid latch's state machine, evaluated after every physics step.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Latch {
    /// The lever was pressed while the lid was open; cleared when the lever is raised.
    pub jammed: bool,
    pub locked: bool,
}

impl Latch {
    fn from_logic(l: &Logic) -> Latch {
        Latch {
            jammed: flag(l, "jammed"),
            locked: flag(l, LOCKED),
        }
    }

    fn store(&self, l: &mut Logic) {
        set_flag(l, "jammed", self.jammed);
        set_flag(l, LOCKED, self.locked);
    }

    /// Updates from the current joint angles; returns whether the lock constraint is active.
    pub fn update(&mut self, p: &Params, lid: f64, lever: f64) -> bool {
        let pressed = p.nearest_notch(lever) == p.lever_pressed;
        if !pressed {
            self.jammed = false;
            self.locked = false;
        } else if !self.locked && !p.lid().is_closed(lid) {
            self.jammed = true;
        } else if !self.jammed {
            self.locked = true;
        }
        self.locked
    }
}

impl Instrument for Params {
    fn footprint_radius(&self) -> f64 {
        self.base_half[0].hypot(self.base_half[1])
    }

    fn fragment(&self, name: &str, placement: &Pose) -> Fragment {
        let n = LidNames::new(name);
        let (lever_body, lever_joint) = lever_names(name);
        let b = self.base_half;
        let lid = &self.lid_body;
        let lid_rel_hinge = [0.0, lid.depth / 2.0, 0.0];
        let arm_half = [0.006, self.lever_arm / 2.0, 0.006];
        let side = self.grip_half_length - 0.006;
        let (llo, lhi) = (
            self.lever_pressed.min(self.lever_raised),
            self.lever_pressed.max(self.lever_raised),
        );
        let mut geoms = String::new();
        for (i, (c, h)) in self.base_boxes().into_iter().enumerate() {
            // The paper's cycler keeps its one box's name.
            let suffix = if i == 0 { String::new() } else { i.to_string() };
            geoms += &format!(
                "  <geom name=\"{base}/body{suffix}\" type=\"box\" size=\"{}\" pos=\"{}\" rgba=\"0.82 0.83 0.85 1\"/>\n",
                v3(h),
                v3(c),
                base = n.base,
            );
        }
        match &self.wells {
            // The block's wells, collided with as a rack's plates and bars.
            Some(w) => geoms += &w.block.geoms(&format!("{}/block", n.base), self.block_centre(w)),
            None => {
                geoms += &format!(
                    "  <geom name=\"{}/block\" type=\"box\" size=\"0.075 0.065 0.004\" pos=\"0 0.02 {}\" rgba=\"0.55 0.57 0.6 1\" contype=\"0\" conaffinity=\"0\"/>\n",
                    n.base,
                    2.0 * b[2] + 0.004
                )
            }
        }
        geoms += &format!(
            "  <geom name=\"{}/panel\" type=\"box\" size=\"0.12 0.004 0.04\" pos=\"0 {} 0.1\" rgba=\"0.15 0.2 0.3 1\" contype=\"0\" conaffinity=\"0\"/>\n",
            n.base,
            b[1] + 0.002
        );
        // The lid's shell and badge, and the lever on its front edge.
        let lid_geoms = format!(
            r#"    <geom name="{lid}/shell" type="box" size="{lidh}" pos="{lidc}" rgba="0.86 0.87 0.9 1"/>
    <geom name="{lid}/badge" type="box" size="0.05 0.03 0.001" pos="0 {badgey} {badgez}" rgba="0.2 0.35 0.6 1" contype="0" conaffinity="0"/>
    <body name="{lever}" pos="0 {depth} 0">
      <joint name="{leverj}" type="hinge" axis="1 0 0" range="{llo} {lhi}" armature="0.0005" damping="0.002" solreflimit="0.004 1"/>
      <inertial pos="0 {armc} 0" mass="{leverm}" diaginertia="1.5e-4 6e-5 1.5e-4"/>
      <geom name="{lever}/arm_l" type="box" size="{armh}" pos="{side} {armc} 0" rgba="0.25 0.25 0.27 1"/>
      <geom name="{lever}/arm_r" type="box" size="{armh}" pos="-{side} {armc} 0" rgba="0.25 0.25 0.27 1"/>
      <geom name="{lever}/grip" type="capsule" size="{gr} {gl}" pos="0 {arm} 0" quat="0.7071068 0 0.7071068 0" friction="1.5 0.01 0.001" rgba="0.2 0.2 0.22 1"/>
      <site name="{grip}" pos="0 {arm} 0" size="0.005" rgba="1 0.2 0.2 0.5" group="4"/>
    </body>
"#,
            lid = n.body,
            lidc = v3(lid_rel_hinge),
            lidh = v3(lid.half()),
            badgey = lid.depth * 0.6,
            badgez = lid.half_thickness + 0.001,
            lever = lever_body,
            depth = lid.depth,
            leverj = lever_joint,
            leverm = self.lever_mass,
            armc = self.lever_arm / 2.0,
            armh = v3(arm_half),
            side = side,
            gr = self.grip_radius,
            gl = self.grip_half_length,
            arm = self.lever_arm,
            grip = n.grip,
        );
        let lid_xml = self
            .lid()
            .body_xml(&n, self.hinge, lid_rel_hinge, &lid_geoms);
        Fragment {
            worldbody: n.instrument_xml(placement, &geoms, &lid_xml),
            equality: self.lid().lock_xml(&n),
            contact: format!("<exclude body1=\"{}\" body2=\"{lever_body}\"/>\n", n.base),
            arena_mb: self.wells.as_ref().map_or(0, |w| w.block.arena_mb()),
            ..Default::default()
        }
    }

    /// Where a tube stands in one of the block's wells.
    fn slot_seat(&self, slot: &str, s: &LabwareState) -> Option<Pose> {
        let w = self.wells.as_ref()?;
        let [x, y, z] = w.block.seat_in_rack(slot)?;
        let [cx, cy, cz] = self.block_centre(w);
        Some(s.pose * translation([x + cx, y + cy, z + cz]))
    }

    /// The lever's two notches.
    fn mechanisms(&self, name: &str) -> Vec<Mechanism> {
        vec![Mechanism::Detent {
            instance: format!("{name}/lever_detent"),
            joint: lever_names(name).1,
            detent: physics::detent::Detent {
                lo: self.lever_pressed.min(self.lever_raised),
                hi: self.lever_pressed.max(self.lever_raised),
                n: 2,
                stiffness: self.detent_stiffness,
                damping: self.detent_damping,
            },
        }]
    }

    fn joints(&self, name: &str) -> Vec<(&'static str, String)> {
        vec![
            (JOINT, LidNames::new(name).joint),
            ("lever", lever_names(name).1),
        ]
    }

    fn switches(&self, name: &str) -> Vec<(&'static str, String)> {
        LidNames::new(name).switches()
    }

    /// A lid declared locked starts shut with the lever pressed; open or closed, raised.
    fn reset(&self, initial: &BTreeMap<String, String>) -> Reset {
        let (state, lid) = self.lid().start(initial);
        let lever = match state {
            "open" | "closed" => self.lever_raised,
            _ => self.lever_pressed,
        };
        let mut logic = Logic::new();
        Latch::default().store(&mut logic);
        if !self.programmes.is_empty() {
            self.run().reset(&mut logic);
        }
        Reset {
            joints: vec![(JOINT, lid), ("lever", lever)],
            logic,
        }
    }

    /// The latch; then the profile: it runs on while started and starts once the lid is
    /// locked (one profile per protocol: the compiler refuses a second).
    fn step(&self, dt: f64, joints: &Joints, logic: &mut Logic, effects: &mut Effects) {
        let mut latch = Latch::from_logic(logic);
        let lever = joints.get("lever").copied().unwrap_or(self.lever_raised);
        let locked = latch.update(self, self.lid().angle(joints), lever);
        latch.store(logic);
        effects.switch(LOCK_SWITCH, locked);
        if !self.programmes.is_empty() {
            let run = self.run();
            run.advance(logic, dt);
            if locked && run.state(logic) == RunState::Idle {
                run.start(logic);
            }
        }
    }

    fn programmes(&self) -> &[Programme] {
        &self.programmes
    }

    fn set_programmes(&mut self, programmes: Vec<Programme>) {
        self.programmes = programmes;
    }

    fn lidded(&self) -> Option<&dyn Lidded> {
        Some(self)
    }

    fn joint_goal(&self, role: &str, goal: &str) -> Option<f64> {
        if role == JOINT {
            return self.lid_goal(goal);
        }
        Some(match (role, goal) {
            ("lever", "raised") => self.lever_raised,
            ("lever", "pressed") => self.lever_pressed,
            // Pushed nine tenths of the way: the detent carries it into the notch.
            ("lever", "press") => self.lever_pressed * 0.9 + self.lever_raised * 0.1,
            _ => return None,
        })
    }

    /// The lid primitives hold the lid by the lever's grip bar to open and to close it.
    fn affordance(&self, name: &str, s: &LabwareState) -> Option<Affordance> {
        crate::lid::handle(name, || {
            self.grip_affordance(&s.pose, s.joint(JOINT), s.joint("lever"))
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn latch_locks_only_when_pressed_after_closing() {
        let p = Params::default();
        let mut l = Latch::default();
        assert!(
            !l.update(&p, 0.0, p.lever_pressed),
            "pressed while open must not lock"
        );
        assert!(
            !l.update(&p, p.lid_closed, p.lever_pressed),
            "jammed until raised"
        );
        assert!(!l.update(&p, p.lid_closed, 0.0));
        assert!(l.update(&p, p.lid_closed, p.lever_pressed));
        assert!(!l.update(&p, p.lid_closed, -0.1), "raising unlocks");
    }

    #[test]
    fn grip_moves_on_the_lid_arc() {
        let p = Params::default();
        let open = p.grip_pose(&Pose::identity(), p.lid_open, 0.0);
        let closed = p.grip_pose(&Pose::identity(), p.lid_closed, 0.0);
        // Closed: the bar lies in front of the hinge at hinge height; open: above and behind the front edge.
        assert!((closed.translation.vector[2] - p.hinge[2]).abs() < 1e-9);
        assert!(
            (closed.translation.vector[1] - (p.hinge[1] + p.lid_body.depth + p.lever_arm)).abs()
                < 1e-9
        );
        assert!(open.translation.vector[2] > closed.translation.vector[2] + 0.2);
        let r = |q: &Pose| {
            ((q.translation.vector[1] - p.hinge[1]).powi(2)
                + (q.translation.vector[2] - p.hinge[2]).powi(2))
            .sqrt()
        };
        assert!((r(&open) - r(&closed)).abs() < 1e-9);
    }

    /// The 96-well block: every well's seat is the block's place moved to the block's centre in
    /// the pocket; a capped PCR tube standing in any well is under the shut lid's underside and
    /// its base on the block's floor, above the pocket's; no box of the base is where a tube
    /// stands; the paper's cycler keeps its one box.
    #[test]
    fn capped_pcr_tubes_in_the_96_well_block_clear_the_shut_lid() {
        let p = Params::with_96_wells();
        let w = p.wells.as_ref().unwrap();
        let tube = crate::tube::Params::pcr_tube();
        let lid_underside = p.hinge[2] - p.lid_body.half_thickness;
        let s = LabwareState::probe("cycler");
        let floor = p.pocket_floor(w);
        let kind = crate::kind("thermal_cycler_96").unwrap();
        for slot in kind.slots.unwrap().layout.names() {
            let seat = crate::frame::position(&p.slot_seat(&slot, &s).unwrap());
            let [x, y, z] = w.block.seat_in_rack(&slot).unwrap();
            let c = p.block_centre(w);
            assert!((seat[0] - x - c[0]).abs() < 1e-12 && (seat[1] - y - c[1]).abs() < 1e-12);
            assert!((seat[2] - z - c[2]).abs() < 1e-12);
            let top = seat[2] + tube.height + tube.cap_height;
            assert!(top < lid_underside && top < 2.0 * p.base_half[2], "{slot}: top at {top}");
            assert!(seat[2] > floor, "{slot}");
            for (centre, half) in p.base_boxes() {
                let inside = (0..3).all(|i| {
                    let mid = [seat[0], seat[1], seat[2] + tube.height / 2.0][i];
                    (mid - centre[i]).abs() < half[i]
                });
                assert!(!inside, "{slot}: a base box at {centre:?} fills the well");
            }
        }
        assert_eq!(Params::default().base_boxes().len(), 1);
        assert_eq!(p.base_boxes().len(), 5);
        assert!(!Params::default().fragment("c", &Pose::identity()).worldbody.contains("c/body1"));
    }

    #[test]
    fn the_lever_reads_as_its_nearest_notch() {
        let p = Params::default();
        assert_eq!(p.nearest_notch(-0.2), p.lever_raised);
        assert_eq!(p.nearest_notch(-0.6), p.lever_pressed);
    }
}
