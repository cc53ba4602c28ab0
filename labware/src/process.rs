//! Processes between items: what moves a quantity from one item to another while the scene runs
//! (liquid drawn from a tube into a pipette tip while the tip's opening is under the surface). An
//! item's model declares its processes ([`crate::Instrument::processes`]) in its own file; the
//! runtime runs every process after every physics step, after each item's own logic, with every
//! item's root pose, and the process writes the quantities it moves into the items' logic state
//! (so recordings carry them per control step and the judge can read them).
//!
//! [`Pipetting`] is the one there is: an air-displacement pipette's tip takes in or pushes out the
//! volume its plunger displaces. It moves liquid through `physics::liquid`, whose bookkeeping in
//! whole nanolitres conserves the total exactly: every vessel's volume, the tip's and what was
//! spilt on the bench always add up to what the scene started with; each named liquid
//! ([`LIQUID_UL`]) moves with it in proportion and is conserved the same way. The items' logic holds the
//! volumes between steps (so a replay that restores the logic restores them); what a process keeps
//! of its own (each liquid's surface) follows from them. Pure: no MuJoCo here.

use crate::frame::Pose;
use crate::model::{Logic, set};
pub use crate::model::{Process, Vessel};
use physics::liquid::{Container, Liquid, Nanolitres, transfer};

/// The logic key an item's liquid volume is kept under (µL): a vessel's contents, a pipette tip's.
pub const VOLUME_UL: &str = "volume_ul";

/// The pipette's logic: the volume its plunger displaces from rest now (µL), kept by the
/// pipette's own logic from the plunger's travel.
pub const STROKE_UL: &str = "stroke_ul";

/// An item's logic: how much of a named liquid (`state = { liquid = "water" }`) its liquid holds,
/// under `liquid_ul.<name>` (µL, whole nanolitres; the rest of `volume_ul` is unnamed). Each
/// move takes the named liquids in proportion to what the giver holds, in whole nanolitres, so
/// every liquid is conserved exactly, as the volume is.
pub const LIQUID_UL: &str = "liquid_ul.";

/// The pipette's logic: a named liquid pushed out over no vessel, under `spilt_ul.<name>`.
pub const SPILT_LIQUID_UL: &str = "spilt_ul.";

/// The logic key of a named liquid's share of an item's volume.
pub fn liquid_key(liquid: &str) -> String {
    format!("{LIQUID_UL}{liquid}")
}

/// The pipette's logic: volume the tip has still to take in (positive) or push out (negative),
/// µL. The pipette's logic adds each change of the stroke; [`Pipetting`] moves it.
pub const PENDING_UL: &str = "pending_ul";

/// The pipette's logic: liquid pushed out of the tip over no vessel, lost on the bench (µL).
pub const SPILT_UL: &str = "spilt_ul";

/// The pipette's logic: air the tip has taken in, drawn over or above no liquid (µL).
pub const AIR_UL: &str = "air_ul";

/// The pipette's logic: air pushed out of the tip under a liquid's surface (bubbles, µL).
pub const BUBBLED_UL: &str = "bubbled_ul";

/// The pipette's logic: where the tip's opening is, as [`TipPlace::value`] (the logic holds
/// numbers, as recordings store them; code reads it as a [`TipPlace`]).
pub const TIP_IN: &str = "tip_in";

/// Where a pipette's tip opening is, ordered from farthest to deepest.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum TipPlace {
    /// Out of every vessel.
    Out,
    /// In one: inside it, or over its mouth close enough that a drop falls in.
    In,
    /// Under a vessel's liquid surface.
    Immersed,
}

impl TipPlace {
    /// Its value in the logic (0, 1, 2).
    pub fn value(self) -> f64 {
        match self {
            TipPlace::Out => 0.0,
            TipPlace::In => 1.0,
            TipPlace::Immersed => 2.0,
        }
    }

    /// Where the pipette whose logic this is has its tip (out where the process has not said).
    pub fn of(logic: &Logic) -> TipPlace {
        match logic.get(TIP_IN).copied().unwrap_or(0.0) {
            v if v >= 2.0 => TipPlace::Immersed,
            v if v >= 1.0 => TipPlace::In,
            _ => TipPlace::Out,
        }
    }

    /// The state's name in the catalogue and the readout.
    pub fn name(self) -> &'static str {
        match self {
            TipPlace::Out => "out",
            TipPlace::In => "in",
            TipPlace::Immersed => "immersed",
        }
    }

    /// The place a state name means.
    pub fn named(name: &str) -> Option<TipPlace> {
        [TipPlace::Out, TipPlace::In, TipPlace::Immersed]
            .into_iter()
            .find(|p| p.name() == name)
    }
}

/// How far above a vessel's mouth a drop from a tip still falls into it (m).
const DROP_HEIGHT: f64 = 0.03;

/// A level's rounded volume (nL) and up direction (thousandths).
type LevelKey = (u64, [i32; 3]);

/// A vessel's liquid and the mouth a drop falls in through.
#[derive(Debug)]
struct VesselLiquid {
    item: usize,
    liquid: Liquid,
    /// The interior's top (m, item frame) and its radius there.
    mouth_z: f64,
    mouth_radius: f64,
    /// The surface's offset as last solved, for the rounded volume and up direction it was
    /// solved for ([`VesselLiquid::level_key`]).
    level: Option<(LevelKey, f64)>,
    /// The step the volume is rounded down to for the level (nL): 1e-4 of the capacity, a level
    /// change of about 10 µm in a 50 mL tube.
    resolve_nl: u64,
}

impl VesselLiquid {
    fn new(v: &Vessel) -> VesselLiquid {
        let (_, top) = v.interior.range([0.0, 0.0, 1.0]);
        let mouth_radius = v
            .interior
            .vertices
            .iter()
            .filter(|p| p[2] > top - 1e-9)
            .map(|p| p[0].hypot(p[1]))
            .fold(0.0, f64::max);
        VesselLiquid {
            item: v.item,
            resolve_nl: (v.interior.capacity() * 1e8) as u64,
            liquid: Liquid::new(v.interior.clone(), Nanolitres(0), 0.0),
            mouth_z: top,
            mouth_radius,
            level: None,
        }
    }

    /// Whether the point (world) is inside the interior, under the liquid's surface (a level
    /// plane: the liquid is quasi-static and settles while a pipette works in it).
    fn under_surface(&mut self, at: &Pose, point: nalgebra::Point3<f64>) -> bool {
        let local = at.inverse_transform_point(&point);
        if self.liquid.volume.0 == 0 || !self.liquid.container.contains(local.coords.into()) {
            return false;
        }
        let up = at.rotation.inverse() * nalgebra::Vector3::z();
        let key = self.level_key(up);
        let offset = match self.level {
            // A draw changes the volume every step by a little: the level is solved again only
            // when the rounded volume or direction changes.
            Some((k, d)) if k == key => d,
            _ => {
                let volume = self.liquid.volume;
                self.liquid.volume = Nanolitres(key.0);
                let n = [
                    key.1[0] as f64 * 1e-3,
                    key.1[1] as f64 * 1e-3,
                    key.1[2] as f64 * 1e-3,
                ];
                let norm = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
                self.liquid.surface =
                    physics::liquid::Surface::new([n[0] / norm, n[1] / norm, n[2] / norm], 0.0);
                let d = self.liquid.offset();
                self.liquid.volume = volume;
                self.level = Some((key, d));
                d
            }
        };
        up.dot(&local.coords) < offset
    }

    /// What the level is solved for: the volume rounded down to [`VesselLiquid::resolve_nl`] and
    /// the up direction rounded to a thousandth. The level is then a function of the items' logic
    /// and poses alone (a replay restored from them decides as the run did), and the solve is
    /// skipped while neither moves past its rounding.
    fn level_key(&self, up: nalgebra::Vector3<f64>) -> LevelKey {
        let v = self.liquid.volume.0;
        let round = |x: f64| (x * 1e3).round() as i32;
        (
            v - v % self.resolve_nl.max(1),
            [round(up.x), round(up.y), round(up.z)],
        )
    }

    /// Whether a drop let go at the point (world) lands in the vessel: the point is inside it,
    /// or over its mouth and at most [`DROP_HEIGHT`] above it.
    fn catches(&self, at: &Pose, point: nalgebra::Point3<f64>) -> bool {
        let local = at.inverse_transform_point(&point);
        self.liquid.container.contains(local.coords.into())
            || (local.x.hypot(local.y) <= self.mouth_radius
                && (self.mouth_z..=self.mouth_z + DROP_HEIGHT).contains(&local.z))
    }
}

/// An air-displacement pipette working among vessels. Each physics step a share of the pending
/// volume ([`PENDING_UL`]) moves, so the tip fills over about [`Pipetting::flow_time`] after the
/// plunger moves (liquid through a tip's narrow opening does not follow a thumb at once):
/// - taking in: from the vessel whose liquid the tip's opening is under; with the opening in no
///   liquid the tip takes in air instead, so a tip withdrawn before it has filled holds what was
///   drawn while it was under, and a release above the surface draws nothing.
/// - pushing out: the tip's liquid first, then its air, into the vessel that catches a drop
///   there; over no vessel the liquid is spilt on the bench ([`SPILT_UL`]). Air pushed out under
///   a surface bubbles ([`BUBBLED_UL`]).
#[derive(Debug)]
pub struct Pipetting {
    pipette: usize,
    /// The tip's opening in the pipette's root frame (m).
    opening: [f64; 3],
    tip: Liquid,
    vessels: Vec<VesselLiquid>,
    /// Time constant of the flow (s).
    pub flow_time: f64,
}

impl Pipetting {
    /// The pipette at index `pipette` with its tip's interior and opening (pipette frame), among
    /// `vessels` (the pipette itself is not one of them).
    pub fn new(pipette: usize, tip: Container, opening: [f64; 3], vessels: &[Vessel]) -> Pipetting {
        Pipetting {
            pipette,
            opening,
            tip: Liquid::new(tip, Nanolitres(0), 0.0),
            vessels: vessels
                .iter()
                .filter(|v| v.item != pipette)
                .map(VesselLiquid::new)
                .collect(),
            flow_time: 0.15,
        }
    }

    /// Takes `nl` into the tip at `opening`: liquid from the vessel it is under, else air.
    fn take_in(&mut self, under: Option<usize>, nl: u64, logic: &mut [Logic]) {
        let room = self.tip.room().0;
        let mut air = nl;
        if let Some(v) = under.map(|i| &mut self.vessels[i]) {
            let liquid = nl.min(v.liquid.volume.0).min(room);
            let had = v.liquid.volume.0;
            if liquid > 0 && transfer(&mut v.liquid, &mut self.tip, Nanolitres(liquid)).is_ok() {
                air -= liquid;
                move_named(logic, v.item, (self.pipette, LIQUID_UL), had, liquid);
            }
        }
        add(
            &mut logic[self.pipette],
            AIR_UL,
            Nanolitres(air).microlitres(),
        );
    }

    /// Pushes `nl` out of the tip at `opening`: its liquid first, then air.
    fn push_out(&mut self, at: Place, nl: u64, logic: &mut [Logic]) {
        let liquid = nl.min(self.tip.volume.0);
        let air = nl - liquid;
        let mut spilt = liquid;
        if let Some(v) = at.catching.map(|i| &mut self.vessels[i]) {
            let fits = liquid.min(v.liquid.room().0);
            let had = self.tip.volume.0;
            if fits > 0 && transfer(&mut self.tip, &mut v.liquid, Nanolitres(fits)).is_ok() {
                spilt -= fits;
                move_named(logic, self.pipette, (v.item, LIQUID_UL), had, fits);
            }
            if air > 0 && at.under.is_some() {
                add(
                    &mut logic[self.pipette],
                    BUBBLED_UL,
                    Nanolitres(air).microlitres(),
                );
            }
        }
        if spilt > 0 {
            let had = self.tip.volume.0;
            move_named(
                logic,
                self.pipette,
                (self.pipette, SPILT_LIQUID_UL),
                had,
                spilt,
            );
            self.tip.volume = Nanolitres(self.tip.volume.0 - spilt);
            add(
                &mut logic[self.pipette],
                SPILT_UL,
                Nanolitres(spilt).microlitres(),
            );
        }
        let had =
            Nanolitres::from_microlitres(logic[self.pipette].get(AIR_UL).copied().unwrap_or(0.0));
        set(
            &mut logic[self.pipette],
            AIR_UL,
            Nanolitres(had.0.saturating_sub(air)).microlitres(),
        );
    }
}

/// Moves the named liquids' share of `nl` nanolitres out of item `from`'s liquid (which held
/// `total` nL before the move) into item `to`'s logic under `prefix` (`liquid_ul.` into a
/// vessel or tip, `spilt_ul.` onto the bench): each liquid, and the unnamed rest, gets its
/// proportion rounded down, and the nanolitres left over go one each to the largest remainders
/// (ties in name order, the unnamed rest last), never more than a liquid has. Exact: what leaves
/// one item arrives in the other, nanolitre for nanolitre.
fn move_named(logic: &mut [Logic], from: usize, (to, prefix): (usize, &str), total: u64, nl: u64) {
    let parts: Vec<(String, u64)> = logic[from]
        .range(LIQUID_UL.to_string()..)
        .take_while(|(k, _)| k.starts_with(LIQUID_UL))
        .map(|(k, v)| {
            (
                k[LIQUID_UL.len()..].to_string(),
                Nanolitres::from_microlitres(*v).0,
            )
        })
        .collect();
    if parts.is_empty() || total == 0 || nl == 0 {
        return;
    }
    let named: u64 = parts.iter().map(|(_, v)| v).sum();
    let held: Vec<u64> = parts
        .iter()
        .map(|(_, v)| *v)
        .chain([total.saturating_sub(named)])
        .collect();
    let (nl, total) = (u128::from(nl.min(total)), u128::from(total));
    let mut share: Vec<u64> = held
        .iter()
        .map(|&h| (u128::from(h) * nl / total) as u64)
        .collect();
    let mut left = nl as u64 - share.iter().sum::<u64>();
    let mut order: Vec<usize> = (0..held.len()).collect();
    order.sort_by_key(|&i| std::cmp::Reverse(u128::from(held[i]) * nl % total));
    for i in order {
        if left == 0 {
            break;
        }
        if share[i] < held[i] {
            share[i] += 1;
            left -= 1;
        }
    }
    for ((liquid, had), moved) in parts.iter().zip(share) {
        if moved == 0 {
            continue;
        }
        let key = liquid_key(liquid);
        set(
            &mut logic[from],
            &key,
            Nanolitres(had - moved).microlitres(),
        );
        add(
            &mut logic[to],
            &format!("{prefix}{liquid}"),
            Nanolitres(moved).microlitres(),
        );
    }
}

/// Adds `ul` (whole nanolitres) to a tally kept in the logic, summed in nanolitres.
fn add(logic: &mut Logic, key: &str, ul: f64) {
    if ul != 0.0 {
        let had = Nanolitres::from_microlitres(logic.get(key).copied().unwrap_or(0.0));
        let more = Nanolitres::from_microlitres(ul);
        set(logic, key, Nanolitres(had.0 + more.0).microlitres());
    }
}

/// Where the tip's opening is: the vessel whose liquid it is under, the vessel a drop from it
/// falls into (by index among the process's vessels).
#[derive(Clone, Copy, Debug, Default)]
struct Place {
    under: Option<usize>,
    catching: Option<usize>,
}

impl Place {
    /// Where the tip is.
    fn tip(self) -> TipPlace {
        match (self.under, self.catching) {
            (Some(_), _) => TipPlace::Immersed,
            (None, Some(_)) => TipPlace::In,
            (None, None) => TipPlace::Out,
        }
    }
}

impl Pipetting {
    /// Where the opening (world) is among the vessels.
    fn place(&mut self, poses: &[Pose], opening: nalgebra::Point3<f64>) -> Place {
        let mut place = Place::default();
        for (i, v) in self.vessels.iter_mut().enumerate() {
            let Some(at) = poses.get(v.item) else {
                continue;
            };
            if v.under_surface(at, opening) {
                return Place {
                    under: Some(i),
                    catching: Some(i),
                };
            }
            if place.catching.is_none() && v.catches(at, opening) {
                place.catching = Some(i);
            }
        }
        place
    }
}

impl Process for Pipetting {
    fn step(&mut self, dt: f64, poses: &[Pose], logic: &mut [Logic]) {
        let Some(at) = poses.get(self.pipette) else {
            return;
        };
        let opening = at * nalgebra::Point3::from(self.opening);
        // The items' logic holds the volumes (a restored state, another process's transfer):
        // this process's liquids follow it.
        let volume = |item: usize| logic[item].get(VOLUME_UL).copied().unwrap_or(0.0);
        self.tip.volume = Nanolitres::from_microlitres(volume(self.pipette));
        for v in &mut self.vessels {
            v.liquid.volume = Nanolitres::from_microlitres(volume(v.item));
        }
        let place = self.place(poses, opening);
        set(&mut logic[self.pipette], TIP_IN, place.tip().value());
        let pending = logic[self.pipette].get(PENDING_UL).copied().unwrap_or(0.0);
        if pending == 0.0 {
            return;
        }
        // The share of the pending volume that flows this step, in whole nanolitres (at least
        // one, so the flow ends; never more than is pending).
        let share = pending.abs() * (1.0 - (-dt / self.flow_time).exp());
        let whole = (pending.abs() * 1e3).round() as u64;
        let nl = ((share * 1e3).ceil() as u64).min(whole);
        if pending > 0.0 {
            self.take_in(place.under, nl, logic);
        } else {
            self.push_out(place, nl, logic);
        }
        let left = if nl == whole {
            0.0
        } else {
            pending - pending.signum() * Nanolitres(nl).microlitres()
        };
        set(&mut logic[self.pipette], PENDING_UL, left);
        set(
            &mut logic[self.pipette],
            VOLUME_UL,
            self.tip.volume.microlitres(),
        );
        for v in &self.vessels {
            set(&mut logic[v.item], VOLUME_UL, v.liquid.volume.microlitres());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::translation;

    /// A 50 mL tube's interior (radius 13 mm, 20 mm cone, 2 mm base) holding 20 mL at the origin,
    /// a second, empty tube 10 cm along x, and a pipette (item 2) whose 1 mL tip opens at its root.
    fn scene() -> (Pipetting, Vec<Logic>) {
        let tube = Container::tube(0.013, 0.11, 0.02, 32).shifted([0.0, 0.0, 0.002]);
        let vessels = [
            Vessel {
                item: 0,
                interior: tube.clone(),
            },
            Vessel {
                item: 1,
                interior: tube,
            },
        ];
        let tip = Container::tube(0.0038, 0.072, 0.055, 16);
        let p = Pipetting::new(2, tip, [0.0, 0.0, 0.0], &vessels);
        let mut logic = vec![Logic::new(), Logic::new(), Logic::new()];
        logic[0].insert(VOLUME_UL.into(), 20_000.0);
        (p, logic)
    }

    /// Poses with the pipette's opening at `tip` (world).
    fn poses(tip: [f64; 3]) -> Vec<Pose> {
        vec![
            Pose::identity(),
            translation([0.1, 0.0, 0.0]),
            translation(tip),
        ]
    }

    fn run(p: &mut Pipetting, poses: &[Pose], logic: &mut [Logic], seconds: f64) {
        for _ in 0..(seconds / 0.002).round() as usize {
            p.step(0.002, poses, logic);
        }
    }

    /// The plunger asks `pending_ul` of the tip (drawn in: positive), the tip's opening held at
    /// `tip` for `seconds`.
    fn stroke(
        p: &mut Pipetting,
        logic: &mut [Logic],
        pending_ul: f64,
        tip: [f64; 3],
        seconds: f64,
    ) {
        logic[2].insert(PENDING_UL.into(), pending_ul);
        run(p, &poses(tip), logic, seconds);
    }

    /// No liquid moved: the tip holds none, the full tube still holds 20 mL, and the stroke's
    /// 200 µL went to the tip's `key` (air drawn in, or air bubbled out).
    fn drew_nothing(logic: &[Logic], key: &str, what: &str) {
        assert_eq!(ul(logic, 2, VOLUME_UL), 0.0, "{what}");
        assert_eq!(ul(logic, 0, VOLUME_UL), 20_000.0, "{what}");
        assert!((ul(logic, 2, key) - 200.0).abs() < 1e-9, "{what}");
    }

    fn ul(logic: &[Logic], item: usize, key: &str) -> f64 {
        logic[item].get(key).copied().unwrap_or(0.0)
    }

    fn total_nl(logic: &[Logic]) -> u64 {
        [
            (0, VOLUME_UL),
            (1, VOLUME_UL),
            (2, VOLUME_UL),
            (2, SPILT_UL),
        ]
        .iter()
        .map(|(i, k)| Nanolitres::from_microlitres(ul(logic, *i, k)).0)
        .sum()
    }

    // 20 mL in the 50 mL interior stands about 48 mm above the base: z = 0.03 is under it.
    const UNDER: [f64; 3] = [0.0, 0.0, 0.03];
    const ABOVE: [f64; 3] = [0.0, 0.0, 0.09];

    #[test]
    fn a_release_under_the_surface_draws_the_volume_over_time_and_conserves_it() {
        let (mut p, mut logic) = scene();
        let at = poses(UNDER);
        logic[2].insert(PENDING_UL.into(), 200.0);
        run(&mut p, &at, &mut logic, 0.1);
        let early = ul(&logic, 2, VOLUME_UL);
        assert!(
            early > 50.0 && early < 150.0,
            "not at once: {early} µL after 0.1 s"
        );
        run(&mut p, &at, &mut logic, 2.0);
        assert_eq!(ul(&logic, 2, VOLUME_UL), 200.0);
        assert_eq!(ul(&logic, 0, VOLUME_UL), 19_800.0);
        assert_eq!(ul(&logic, 2, PENDING_UL), 0.0);
        assert_eq!(ul(&logic, 2, AIR_UL), 0.0);
        assert_eq!(total_nl(&logic), 20_000_000);
    }

    #[test]
    fn a_release_above_the_surface_or_outside_the_tube_draws_air() {
        for tip in [ABOVE, [0.05, 0.0, 0.03]] {
            let (mut p, mut logic) = scene();
            stroke(&mut p, &mut logic, 200.0, tip, 2.0);
            drew_nothing(&logic, AIR_UL, &format!("{tip:?}"));
        }
    }

    #[test]
    fn a_tip_withdrawn_before_it_fills_holds_what_it_drew_under_the_surface() {
        let (mut p, mut logic) = scene();
        stroke(&mut p, &mut logic, 200.0, UNDER, 0.1);
        let drawn = ul(&logic, 2, VOLUME_UL);
        run(&mut p, &poses(ABOVE), &mut logic, 2.0);
        assert_eq!(ul(&logic, 2, VOLUME_UL), drawn);
        assert!(drawn < 190.0, "{drawn}");
        assert!((ul(&logic, 2, AIR_UL) + drawn - 200.0).abs() < 1e-6);
        assert_eq!(total_nl(&logic), 20_000_000);
    }

    #[test]
    fn pressing_under_the_surface_bubbles_and_draws_nothing() {
        let (mut p, mut logic) = scene();
        stroke(&mut p, &mut logic, -200.0, UNDER, 2.0);
        drew_nothing(&logic, BUBBLED_UL, "pressed under the surface");
    }

    #[test]
    fn what_is_pushed_out_lands_in_the_vessel_under_the_tip_or_on_the_bench() {
        let (mut p, mut logic) = scene();
        stroke(&mut p, &mut logic, 300.0, UNDER, 2.0);
        // Into the second tube from 2 cm over its mouth.
        stroke(&mut p, &mut logic, -100.0, [0.1, 0.0, 0.132], 2.0);
        assert_eq!(ul(&logic, 1, VOLUME_UL), 100.0);
        // Over the bench between the tubes: spilt.
        stroke(&mut p, &mut logic, -150.0, [0.05, 0.0, 0.05], 2.0);
        assert_eq!(ul(&logic, 2, SPILT_UL), 150.0);
        assert_eq!(ul(&logic, 2, VOLUME_UL), 50.0);
        // More pushed out than the tip holds: the rest is air.
        stroke(&mut p, &mut logic, -120.0, [0.1, 0.0, 0.1], 2.0);
        assert_eq!(ul(&logic, 1, VOLUME_UL), 150.0);
        assert_eq!(ul(&logic, 2, VOLUME_UL), 0.0);
        assert_eq!(total_nl(&logic), 20_000_000);
    }

    fn named_nl(logic: &[Logic], liquid: &str) -> u64 {
        let key = liquid_key(liquid);
        let spilt = format!("{SPILT_LIQUID_UL}{liquid}");
        [(0, &key), (1, &key), (2, &key), (2, &spilt)]
            .iter()
            .map(|(i, k)| Nanolitres::from_microlitres(ul(logic, *i, k)).0)
            .sum()
    }

    /// A source of 15 mL of `buffer` in 20 mL: a draw takes three quarters of it as buffer, the
    /// rest unnamed; what lands in the target and on the bench carries its share along.
    #[test]
    fn named_liquids_move_in_proportion_and_are_conserved() {
        let (mut p, mut logic) = scene();
        logic[0].insert(liquid_key("buffer"), 15_000.0);
        // Each step's share is rounded to whole nanolitres (the flow's last steps move one at a
        // time): proportions hold to within 0.05 µL of 400 µL, totals exactly.
        let near = |a: f64, b: f64| (a - b).abs() < 0.05;
        stroke(&mut p, &mut logic, 400.0, UNDER, 2.0);
        assert_eq!(ul(&logic, 2, VOLUME_UL), 400.0);
        assert!(near(ul(&logic, 2, &liquid_key("buffer")), 300.0));
        assert!(near(ul(&logic, 0, &liquid_key("buffer")), 14_700.0));
        stroke(&mut p, &mut logic, -200.0, [0.1, 0.0, 0.132], 2.0);
        assert!(near(ul(&logic, 1, &liquid_key("buffer")), 150.0));
        stroke(&mut p, &mut logic, -200.0, [0.05, 0.0, 0.05], 2.0);
        assert!(near(
            ul(&logic, 2, &format!("{SPILT_LIQUID_UL}buffer")),
            150.0
        ));
        assert_eq!(ul(&logic, 2, &liquid_key("buffer")), 0.0);
        assert_eq!(named_nl(&logic, "buffer"), 15_000_000);
    }

    /// Random strokes at random places: the vessels, the tip and the bench always hold the
    /// starting volume, to the nanolitre (1e-9 of it is 0.02 nL here), and so does each named
    /// liquid, the target's own included.
    #[test]
    fn the_total_is_conserved_over_random_strokes() {
        use rand_core::{RngCore, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let mut uniform =
            |lo: f64, hi: f64| lo + (hi - lo) * (rng.next_u64() as f64 / u64::MAX as f64);
        let (mut p, mut logic) = scene();
        logic[0].insert(liquid_key("dye"), 7_333.333);
        logic[1].insert(VOLUME_UL.into(), 1_000.0);
        logic[1].insert(liquid_key("water"), 1_000.0);
        for _ in 0..400 {
            if uniform(0.0, 1.0) < 0.2 {
                let ul = uniform(-400.0, 400.0);
                let had = logic[2].get(PENDING_UL).copied().unwrap_or(0.0);
                logic[2].insert(PENDING_UL.into(), had + ul);
            }
            let tip = [
                uniform(-0.02, 0.12),
                uniform(-0.02, 0.02),
                uniform(0.0, 0.15),
            ];
            run(&mut p, &poses(tip), &mut logic, 0.02);
            assert_eq!(total_nl(&logic), 21_000_000);
            assert_eq!(named_nl(&logic, "dye"), 7_333_333);
            assert_eq!(named_nl(&logic, "water"), 1_000_000);
            for i in 0..logic.len() {
                let nl = |key: &str| Nanolitres::from_microlitres(ul(&logic, i, key)).0;
                let named = nl(&liquid_key("dye")) + nl(&liquid_key("water"));
                let here = nl(VOLUME_UL);
                assert!(named <= here, "item {i}: {named} nL named in {here}");
            }
        }
        assert!(ul(&logic, 2, &liquid_key("dye")) > 0.0 || ul(&logic, 1, &liquid_key("dye")) > 0.0);
        assert!(ul(&logic, 1, VOLUME_UL) > 0.0 || ul(&logic, 2, SPILT_UL) > 0.0);
    }
}
