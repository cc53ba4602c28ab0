//! Distractor items: unused racks and blocks stood on the bench where they block nothing. A
//! place is free when the widest distractor that may be drawn, stood there, lies on the bench
//! top, clear of every item's footprint (`labware::Instrument::footprint_radius`) and every loose
//! part lying apart, clear of every robot's base and of the straight way from each base to each
//! of them, by the margins below; distractors keep clear of each other too. The places are
//! a grid over the bench, so the draw is a choice among them. It builds nothing: the runtime puts
//! each [`Distractor`] into the scene as an inert item that no step, check or state names.

use super::Distractors;
use crate::bench::{BENCH_HALF, BENCH_TOP};
use crate::params::uniform;
use crate::{SceneInstance, Task};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

/// One distractor: its kind and where it stands (x, y on the bench top, m; yaw, rad).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Distractor {
    pub kind: String,
    pub at: [f64; 3],
}

impl Distractor {
    /// Its pose in the world.
    pub fn pose(&self) -> labware::Pose {
        labware::frame::pose(
            [self.at[0], self.at[1], BENCH_TOP],
            labware::frame::axis_angle([0.0, 0.0, 1.0], self.at[2]),
        )
    }
}

/// How far a distractor's footprint keeps from an item's, from a robot's base (its centre),
/// from the straight way between a base and an item or a loose part, from another distractor's
/// footprint (m); the footprint a loose part lying apart (a cap) is given; the grid of places.
const MARGIN: f64 = 0.05;
const FROM_BASE: f64 = 0.25;
const FROM_WAY: f64 = 0.08;
const APART: f64 = 0.03;
const PART_RADIUS: f64 = 0.03;
const GRID: f64 = 0.04;

/// What a distractor keeps clear of: footprints (centre, radius), robot bases, and the ways from
/// each base to each footprint.
struct Obstacles {
    footprints: Vec<([f64; 2], f64)>,
    bases: Vec<[f64; 2]>,
}

fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

fn to_segment(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let len2 = dx * dx + dy * dy;
    let t = if len2 > 0.0 {
        (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    dist(p, [a[0] + t * dx, a[1] + t * dy])
}

/// The grid places on the bench where a distractor of footprint radius `r` is clear of `o`.
fn free_places(o: &Obstacles, r: f64) -> Vec<[f64; 2]> {
    let steps = |half: f64| ((half - r) / GRID).floor().max(-1.0) as i64;
    let (nx, ny) = (steps(BENCH_HALF[0]), steps(BENCH_HALF[1]));
    let mut out = Vec::new();
    for i in -nx..=nx {
        for j in -ny..=ny {
            let p = [i as f64 * GRID, j as f64 * GRID];
            let clear = o
                .footprints
                .iter()
                .all(|&(q, rq)| dist(p, q) >= rq + r + MARGIN)
                && o.bases.iter().all(|&b| dist(p, b) >= FROM_BASE + r)
                && o.bases.iter().all(|&b| {
                    o.footprints
                        .iter()
                        .all(|&(q, _)| to_segment(p, b, q) >= FROM_WAY + r)
                });
            if clear {
                out.push(p);
            }
        }
    }
    out
}

/// The items standing on their own places (in a slot or a hand, their holder stands for them)
/// with their footprints, the loose parts lying apart, and the robots' bases, at `placements`.
fn obstacles(
    task: &Task,
    placements: &[labware::Pose],
    parts: impl Iterator<Item = labware::Pose>,
) -> Obstacles {
    let xy = |p: &labware::Pose| [p.translation.x, p.translation.y];
    let mut footprints: Vec<([f64; 2], f64)> = task
        .labware
        .iter()
        .zip(placements)
        .filter(|(l, _)| l.at.is_none() && l.held_by.is_none())
        .map(|(l, p)| {
            let r = l.params.instrument().map_or(0.1, |i| i.footprint_radius());
            (xy(p), r)
        })
        .collect();
    footprints.extend(parts.map(|p| (xy(&p), PART_RADIUS)));
    let bases = task.robots.iter().map(|r| xy(&r.base)).collect();
    Obstacles { footprints, bases }
}

/// The largest footprint among `kinds`.
fn widest(kinds: &[String]) -> f64 {
    kinds
        .iter()
        .filter_map(|k| labware::Model::for_kind(k))
        .filter_map(|m| m.instrument().map(|i| i.footprint_radius()))
        .fold(0.0, f64::max)
}

/// The kinds a perturbation draws among (all racks and blocks when it names none).
fn kinds_of(d: &Distractors) -> Vec<String> {
    if d.kinds.is_empty() {
        labware::distractor_kinds()
            .into_iter()
            .map(str::to_string)
            .collect()
    } else {
        d.kinds.clone()
    }
}

/// What E0045 says of a bench with no free place.
pub(crate) const NO_ROOM: &str = "no place on the bench keeps a distractor clear of the work (5 cm from every item's footprint, 25 cm from every robot's base, 8 cm from the way between them)";

/// How many free places the task's own layout (its items where the file puts them) leaves for
/// the widest distractor `d` may draw.
pub(crate) fn room(task: &Task, d: &Distractors) -> usize {
    let placements: Vec<labware::Pose> = task.labware.iter().map(|l| l.placement).collect();
    let parts = task.labware.iter().flat_map(|l| l.parts.values().copied());
    free_places(&obstacles(task, &placements, parts), widest(&kinds_of(d))).len()
}

/// Draws the episode's distractors among the places its layout leaves free for the widest kind
/// it may draw.
pub(super) fn draw(
    d: &Distractors,
    task: &Task,
    instance: &SceneInstance,
    rng: &mut ChaCha8Rng,
) -> Vec<Distractor> {
    let kinds = kinds_of(d);
    let r = widest(&kinds);
    let parts = instance.part_placement.values().copied();
    let mut free = free_places(&obstacles(task, &instance.labware_placement, parts), r);
    let (lo, hi) = (d.count[0].min(d.count[1]), d.count[1]);
    let span = f64::from(hi - lo + 1);
    let count = (lo + uniform(rng, 0.0, span) as u32).min(hi);
    let mut out = Vec::new();
    for _ in 0..count {
        if free.is_empty() || kinds.is_empty() {
            break;
        }
        let at = free[(uniform(rng, 0.0, free.len() as f64) as usize).min(free.len() - 1)];
        let k = (uniform(rng, 0.0, kinds.len() as f64) as usize).min(kinds.len() - 1);
        let yaw = uniform(rng, 0.0, std::f64::consts::TAU);
        free.retain(|p| dist(*p, at) >= 2.0 * r + APART);
        out.push(Distractor {
            kind: kinds[k].clone(),
            at: [at[0], at[1], yaw],
        });
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn free_places_keep_clear_of_items_bases_and_the_way_between() {
        let o = Obstacles {
            footprints: vec![([0.3, 0.0], 0.2)],
            bases: vec![[-0.3, 0.0]],
        };
        let r = 0.1;
        let free = free_places(&o, r);
        assert!(!free.is_empty());
        for p in &free {
            assert!(dist(*p, [0.3, 0.0]) >= 0.2 + r + MARGIN);
            assert!(dist(*p, [-0.3, 0.0]) >= FROM_BASE + r);
            // The way from the base to the item runs along y = 0 between them.
            assert!(!(p[0].abs() <= 0.3 && p[1].abs() < FROM_WAY + r), "{p:?}");
            assert!(p[0].abs() + r <= BENCH_HALF[0] + 1e-9);
        }
        // A bench covered by items has no room.
        let crowded = Obstacles {
            footprints: (-9..=9)
                .flat_map(|i| (-6..=6).map(move |j| ([i as f64 * 0.1, j as f64 * 0.1], 0.05)))
                .collect(),
            bases: vec![[-0.3, 0.0]],
        };
        assert!(free_places(&crowded, r).is_empty());
    }
}
