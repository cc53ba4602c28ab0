//! Free-space routes for the scripted expert: a motion that moves between affordances (an
//! approach, a transit) keeps its straight IK path when that path is clear of the scene, and
//! otherwise goes around: RRTConnect from the start to the path's last configuration, checked
//! by MuJoCo collision ([`runtime::clearance`]), shortcut, then densified so that the spline TOPP
//! fits through it stays on the checked segments. Motions that end in contact (reach, press,
//! follow) are not routed here: touching is their purpose.

use crate::policy::PlanFailure;
use planner::{Problem, distance, lerp, segment_is_clear, shortcut};
use runtime::clearance::Clearance;

/// Collision checks along a motion at least every this much joint travel (rad, Euclidean): at
/// the UR5e's 0.9 m reach about 2 cm of tool travel at worst, less than a rotor slot's width.
pub const STEP: f64 = 0.02;
/// RRTConnect gives up after this many collision checks (about a second of checks).
const MAX_CHECKS: u64 = 40_000;
/// Random shortcuts tried on a planned path.
const SHORTCUTS: usize = 100;
/// A planned path is handed to TOPP with a vertex at least every this much (rad).
const DENSE: f64 = 0.05;
/// The planner searches at most this far outside the span of start and goal per joint (rad).
const SLACK: f64 = 1.5;

/// How a route came about.
#[derive(Debug, Clone, PartialEq)]
pub enum Route {
    /// The straight path was clear.
    Straight(Vec<Vec<f64>>),
    /// It hit `hits`; RRTConnect went around (`checks` collision checks in all).
    Planned {
        path: Vec<Vec<f64>>,
        hits: String,
        checks: u64,
    },
}

impl Route {
    pub fn path(self) -> Vec<Vec<f64>> {
        match self {
            Route::Straight(p) | Route::Planned { path: p, .. } => p,
        }
    }
}

/// The first collision along `waypoints` (joint configurations, as straight joint motions), as
/// "moving body against obstacle" names.
fn first_hit(clearance: &mut Clearance, waypoints: &[Vec<f64>]) -> Option<String> {
    for w in waypoints.windows(2) {
        let n = (distance(&w[0], &w[1]) / STEP).ceil().max(1.0) as usize;
        for i in 0..=n {
            let hits = clearance.collisions(&lerp(&w[0], &w[1], i as f64 / n as f64));
            if let Some(&(a, b)) = hits.first() {
                return Some(format!(
                    "`{}` against `{}`",
                    clearance.body_name(a),
                    clearance.body_name(b)
                ));
            }
        }
    }
    None
}

/// A collision-free joint path from `waypoints[0]` to its last configuration, within `limits`.
/// `clearance` must be synced to the scene as it is now.
pub fn route(
    clearance: &mut Clearance,
    limits: &[(f64, f64)],
    waypoints: Vec<Vec<f64>>,
    seed: u64,
) -> Result<Route, PlanFailure> {
    let Some(hits) = first_hit(clearance, &waypoints) else {
        return Ok(Route::Straight(waypoints));
    };
    let start = waypoints[0].clone();
    let goal = waypoints.last().expect("a path has a start").clone();
    let bounds = limits
        .iter()
        .zip(start.iter().zip(&goal))
        .map(|(&(lo, hi), (s, g))| (lo.max(s.min(*g) - SLACK), hi.min(s.max(*g) + SLACK)))
        .collect();
    let problem = Problem {
        bounds,
        start,
        goal,
        step: STEP,
        range: 0.0,
        max_checks: MAX_CHECKS,
        seed,
    };
    let before = clearance.checks;
    let raw = planner::plan(&problem, |q| clearance.is_clear(q)).map_err(|error| {
        PlanFailure::Blocked {
            hits: hits.clone(),
            error,
        }
    })?;
    let short = shortcut(&raw, SHORTCUTS, STEP, seed, |q| clearance.is_clear(q));
    debug_assert!(
        short
            .windows(2)
            .all(|w| segment_is_clear(&w[0], &w[1], STEP, &mut |q| clearance.is_clear(q)))
    );
    Ok(Route::Planned {
        path: densify(&short),
        hits,
        checks: clearance.checks - before,
    })
}

/// `path` with vertices added so that none is more than [`DENSE`] from the next.
fn densify(path: &[Vec<f64>]) -> Vec<Vec<f64>> {
    let mut out = vec![path[0].clone()];
    for w in path.windows(2) {
        let n = (distance(&w[0], &w[1]) / DENSE).ceil().max(1.0) as usize;
        out.extend((1..=n).map(|i| lerp(&w[0], &w[1], i as f64 / n as f64)));
    }
    out
}
