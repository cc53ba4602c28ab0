//! Processes between items: what moves a quantity from one item to another while the scene runs
//! (liquid drawn from a tube into a pipette tip while the tip's opening is under the surface). An
//! item's model declares its processes ([`crate::Instrument::processes`]) in its own file; the
//! runtime runs every process after every physics step, after each item's own logic, with every
//! item's live state, and the process writes the quantities it moves into the items' logic state
//! (so recordings carry them and the judge can read them).
//!
//! [`LiquidDraw`] is the first: it moves liquid through `physics::liquid`, whose bookkeeping in
//! whole nanolitres conserves the total exactly. The items' logic holds the volumes between steps
//! (so a replay that restores the logic restores them, and processes sharing an item agree);
//! what a process keeps of its own (a liquid's surface) follows from them. Pure: no MuJoCo here.

use crate::frame::Pose;
pub use crate::model::Process;
use crate::model::{LabwareState, Logic, set};
use physics::liquid::{Container, Liquid, Nanolitres, transfer};

/// The logic key an item's liquid volume is kept under (µL).
pub const VOLUME_UL: &str = "volume_ul";

/// The logic key a tip's draw command is kept under (µL/s; 0 or absent: not drawing). The
/// pipette's logic sets it from its plunger; a process only reads it.
pub const DRAW_UL_S: &str = "draw_ul_s";

/// Liquid drawn from a container into a tip: while the tip asks to draw ([`DRAW_UL_S`] in its
/// logic) and its opening is below the source's liquid surface, the asked rate flows from the
/// source into the tip; with the opening above the surface, nothing does (a real tip draws air).
/// The surface is the quasi-static liquid's plane for the source's volume and tilt.
#[derive(Debug)]
pub struct LiquidDraw {
    /// Items, by index in task order.
    pub source: usize,
    pub tip: usize,
    /// The tip's opening in the tip's root frame (m).
    pub opening: [f64; 3],
    source_liquid: Liquid,
    tip_liquid: Liquid,
    /// Volume asked for and not yet moved (nL, fractional): whole nanolitres move.
    owed: f64,
}

impl LiquidDraw {
    /// A draw from `source` (its container and starting volume) into `tip` (its container,
    /// empty at the start).
    pub fn new(
        source: usize,
        source_container: Container,
        source_ul: f64,
        tip: usize,
        tip_container: Container,
        opening: [f64; 3],
    ) -> LiquidDraw {
        LiquidDraw {
            source,
            tip,
            opening,
            source_liquid: Liquid::new(
                source_container,
                Nanolitres::from_microlitres(source_ul),
                0.0,
            ),
            tip_liquid: Liquid::new(tip_container, Nanolitres(0), 0.0),
            owed: 0.0,
        }
    }

    /// Whether the tip's opening (world frame `opening`) is below the source's surface, with the
    /// source's root at `source`: the surface plane is level (normal along world z) in the world,
    /// expressed in the container's frame.
    fn submerged(&mut self, source: &Pose, opening: nalgebra::Point3<f64>) -> bool {
        if self.source_liquid.volume.0 == 0 {
            return false;
        }
        let up = source.rotation.inverse() * nalgebra::Vector3::z();
        self.source_liquid.surface = physics::liquid::Surface::new([up.x, up.y, up.z], 0.0);
        let local = source.inverse_transform_point(&opening);
        let d = self.source_liquid.offset();
        up.x * local.x + up.y * local.y + up.z * local.z < d
    }

    /// Volumes now (µL): in the source, in the tip.
    pub fn volumes_ul(&self) -> (f64, f64) {
        (
            self.source_liquid.volume.microlitres(),
            self.tip_liquid.volume.microlitres(),
        )
    }
}

impl Process for LiquidDraw {
    fn step(&mut self, dt: f64, states: &[LabwareState], logic: &mut [Logic]) {
        let (Some(source), Some(tip)) = (states.get(self.source), states.get(self.tip)) else {
            return;
        };
        // The items' logic holds the volumes (a restored state, another process's transfer):
        // this process's liquids follow it.
        for (item, liquid) in [
            (self.source, &mut self.source_liquid),
            (self.tip, &mut self.tip_liquid),
        ] {
            if let Some(ul) = logic[item].get(VOLUME_UL) {
                liquid.volume = Nanolitres::from_microlitres(*ul);
            }
        }
        let rate = logic[self.tip].get(DRAW_UL_S).copied().unwrap_or(0.0);
        let opening = tip.pose * nalgebra::Point3::from(self.opening);
        if rate > 0.0 && self.submerged(&source.pose, opening) {
            let limit = self.source_liquid.volume.0.min(self.tip_liquid.room().0);
            if limit == 0 {
                // Nothing left to draw, or no room: a thumb held open draws nothing more.
                self.owed = 0.0;
            } else {
                self.owed += rate * dt * 1e3;
                let movable = (self.owed.floor() as u64).min(limit);
                if movable > 0
                    && transfer(
                        &mut self.source_liquid,
                        &mut self.tip_liquid,
                        Nanolitres(movable),
                    )
                    .is_ok()
                {
                    self.owed -= movable as f64;
                }
            }
        } else {
            self.owed = 0.0;
        }
        let (from, to) = self.volumes_ul();
        set(&mut logic[self.source], VOLUME_UL, from);
        set(&mut logic[self.tip], VOLUME_UL, to);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::pose;
    use nalgebra::UnitQuaternion;

    fn item(name: &str, at: [f64; 3]) -> LabwareState {
        LabwareState {
            name: name.into(),
            pose: pose(at, UnitQuaternion::identity()),
            joints: Default::default(),
            parts: Default::default(),
            logic: Default::default(),
            touched_by: Vec::new(),
        }
    }

    /// A 1.5 mL tube (radius 4.5 mm, 40 mm deep) holding 1000 µL, and a 200 µL tip whose
    /// opening stands `depth` below the tube's rim.
    fn scene(depth: f64) -> (LiquidDraw, Vec<LabwareState>, Vec<Logic>) {
        let tube = Container::tube(0.0045, 0.04, 0.0, 32);
        let tip = Container::tube(0.0025, 0.03, 0.0, 32);
        let draw = LiquidDraw::new(0, tube, 1000.0, 1, tip, [0.0, 0.0, 0.0]);
        let states = vec![
            item("tube", [0.1, 0.2, 0.0]),
            item("tip", [0.1, 0.2, 0.04 - depth]),
        ];
        let mut logic = vec![Logic::new(), Logic::new()];
        logic[1].insert(DRAW_UL_S.into(), 100.0);
        (draw, states, logic)
    }

    fn run(draw: &mut LiquidDraw, states: &[LabwareState], logic: &mut [Logic], seconds: f64) {
        let dt = 0.002;
        for _ in 0..(seconds / dt).round() as usize {
            draw.step(dt, states, logic);
        }
    }

    #[test]
    fn a_submerged_tip_draws_at_its_rate_and_the_total_is_conserved() {
        // 1000 µL in a 4.5 mm tube stands about 15.7 mm deep: 35 mm below the rim is under it.
        let (mut draw, states, mut logic) = scene(0.035);
        run(&mut draw, &states, &mut logic, 0.5);
        let (tube, tip) = draw.volumes_ul();
        assert!((tip - 50.0).abs() < 1e-3, "100 µL/s for 0.5 s: {tip} µL");
        assert_eq!(
            Nanolitres::from_microlitres(tube + tip),
            Nanolitres(1_000_000)
        );
        assert_eq!(logic[0][VOLUME_UL], tube);
        assert_eq!(logic[1][VOLUME_UL], tip);
        // The tube's surface fell as the tip filled.
        let before = Liquid::new(
            Container::tube(0.0045, 0.04, 0.0, 32),
            Nanolitres(1_000_000),
            0.0,
        )
        .offset();
        assert!(draw.source_liquid.offset() < before);
    }

    #[test]
    fn a_tip_above_the_surface_or_not_drawing_moves_nothing() {
        // 10 mm below the rim is 14 mm above the liquid.
        let (mut draw, states, mut logic) = scene(0.010);
        run(&mut draw, &states, &mut logic, 0.5);
        assert_eq!(draw.volumes_ul(), (1000.0, 0.0));
        let (mut draw, states, mut logic) = scene(0.035);
        logic[1].insert(DRAW_UL_S.into(), 0.0);
        run(&mut draw, &states, &mut logic, 0.5);
        assert_eq!(draw.volumes_ul(), (1000.0, 0.0));
    }

    #[test]
    fn a_slow_draw_moves_and_the_items_logic_holds_the_volumes() {
        let (mut draw, states, mut logic) = scene(0.035);
        // 0.1 µL/s: 0.2 nL a step, whole nanolitres as they add up.
        logic[1].insert(DRAW_UL_S.into(), 0.1);
        run(&mut draw, &states, &mut logic, 1.0);
        let (_, tip) = draw.volumes_ul();
        assert!((tip - 0.1).abs() < 0.0015, "{tip} µL");
        // A restored state (a replay) sets the volumes through the logic.
        logic[0].insert(VOLUME_UL.into(), 400.0);
        logic[1].insert(VOLUME_UL.into(), 20.0);
        logic[1].insert(DRAW_UL_S.into(), 0.0);
        run(&mut draw, &states, &mut logic, 0.01);
        assert_eq!(draw.volumes_ul(), (400.0, 20.0));
    }

    #[test]
    fn the_tip_stops_at_its_capacity() {
        let (mut draw, states, mut logic) = scene(0.035);
        logic[1].insert(DRAW_UL_S.into(), 1000.0);
        run(&mut draw, &states, &mut logic, 2.0);
        let (tube, tip) = draw.volumes_ul();
        let capacity = Container::tube(0.0025, 0.03, 0.0, 32).capacity() * 1e9;
        assert!(
            tip <= capacity + 1e-3 && tip > capacity - 1.0,
            "{tip} of {capacity}"
        );
        assert_eq!(
            Nanolitres::from_microlitres(tube + tip),
            Nanolitres(1_000_000)
        );
    }
}
