//! Distractor items: unused racks and blocks stood on the bench where they block nothing. A
//! place is free when it is on the bench top (clear of its edge), clear of every item standing on
//! its own place, clear of every robot's base and clear of the straight way from each base to
//! each item, by the margins below; distractors stand apart from each other too. The places are
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

/// How far a distractor stands from an item's place, a robot's base and the way between them,
/// from another distractor and from the bench's edge (m); the grid the places are chosen on.
const FROM_ITEM: f64 = 0.2;
const FROM_BASE: f64 = 0.3;
const FROM_WAY: f64 = 0.15;
const APART: f64 = 0.2;
const FROM_EDGE: f64 = 0.08;
const GRID: f64 = 0.04;

/// The free places for the items' and bases' positions given (x, y).
fn free_places(items: &[[f64; 2]], bases: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let dist = |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).hypot(a[1] - b[1]);
    let to_segment = |p: [f64; 2], a: [f64; 2], b: [f64; 2]| {
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        let len2 = dx * dx + dy * dy;
        let t = if len2 > 0.0 {
            (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / len2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        dist(p, [a[0] + t * dx, a[1] + t * dy])
    };
    let steps = |half: f64| ((half - FROM_EDGE) / GRID).floor() as i64;
    let (nx, ny) = (steps(BENCH_HALF[0]), steps(BENCH_HALF[1]));
    let mut out = Vec::new();
    for i in -nx..=nx {
        for j in -ny..=ny {
            let p = [i as f64 * GRID, j as f64 * GRID];
            let clear = items.iter().all(|&q| dist(p, q) >= FROM_ITEM)
                && bases.iter().all(|&b| dist(p, b) >= FROM_BASE)
                && bases
                    .iter()
                    .all(|&b| items.iter().all(|&q| to_segment(p, b, q) >= FROM_WAY));
            if clear {
                out.push(p);
            }
        }
    }
    out
}

/// The items standing on their own places (in a slot or a hand, their holder stands for them),
/// and the robots' bases, at `placements`.
fn obstacles(task: &Task, placements: &[labware::Pose]) -> (Vec<[f64; 2]>, Vec<[f64; 2]>) {
    let xy = |p: &labware::Pose| [p.translation.x, p.translation.y];
    let items = task
        .labware
        .iter()
        .zip(placements)
        .filter(|(l, _)| l.at.is_none() && l.held_by.is_none())
        .map(|(_, p)| xy(p))
        .collect();
    let bases = task.robots.iter().map(|r| xy(&r.base)).collect();
    (items, bases)
}

/// How many free places the task's own layout (its items where the file puts them) leaves.
pub(crate) fn room(task: &Task) -> usize {
    let placements: Vec<labware::Pose> = task.labware.iter().map(|l| l.placement).collect();
    let (items, bases) = obstacles(task, &placements);
    free_places(&items, &bases).len()
}

/// Draws the episode's distractors among the places its layout leaves free.
pub(super) fn draw(
    d: &Distractors,
    task: &Task,
    instance: &SceneInstance,
    rng: &mut ChaCha8Rng,
) -> Vec<Distractor> {
    let kinds: Vec<String> = if d.kinds.is_empty() {
        labware::distractor_kinds()
            .into_iter()
            .map(str::to_string)
            .collect()
    } else {
        d.kinds.clone()
    };
    let (items, bases) = obstacles(task, &instance.labware_placement);
    let mut free = free_places(&items, &bases);
    let span = f64::from(d.count[1] - d.count[0] + 1);
    let count = (d.count[0] + uniform(rng, 0.0, span) as u32).min(d.count[1]);
    let mut out = Vec::new();
    for _ in 0..count {
        if free.is_empty() || kinds.is_empty() {
            break;
        }
        let at = free[(uniform(rng, 0.0, free.len() as f64) as usize).min(free.len() - 1)];
        let kind =
            kinds[(uniform(rng, 0.0, kinds.len() as f64) as usize).min(kinds.len() - 1)].clone();
        let yaw = uniform(rng, 0.0, std::f64::consts::TAU);
        free.retain(|p| (p[0] - at[0]).hypot(p[1] - at[1]) >= APART);
        out.push(Distractor {
            kind,
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
        let items = [[0.3, 0.0]];
        let bases = [[-0.3, 0.0]];
        let free = free_places(&items, &bases);
        assert!(!free.is_empty());
        for p in &free {
            assert!((p[0] - 0.3).hypot(p[1]) >= FROM_ITEM);
            assert!((p[0] + 0.3).hypot(p[1]) >= FROM_BASE);
            // The way from the base to the item runs along y = 0 between them.
            assert!(!(p[0].abs() <= 0.3 && p[1].abs() < FROM_WAY), "{p:?}");
            assert!(p[0].abs() <= BENCH_HALF[0] - FROM_EDGE + 1e-9);
        }
        // A bench covered by items has no room.
        let crowded: Vec<[f64; 2]> = (-9..=9)
            .flat_map(|i| (-6..=6).map(move |j| [i as f64 * 0.1, j as f64 * 0.1]))
            .collect();
        assert!(free_places(&crowded, &bases).is_empty());
    }
}
