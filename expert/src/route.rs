//! Free-space routes for the scripted expert: a motion that moves between affordances (an
//! approach, a transit) keeps its straight IK path when that path is clear of the scene, and
//! otherwise goes around: RRTConnect from the start to the path's last configuration, checked
//! by MuJoCo collision ([`runtime::clearance`]), shortcut, then resampled at equal joint-space
//! spacing: TOPP's spline puts its knots at equal path parameter, so equal spacing keeps it from
//! overshooting; at a corner it still cuts inside the checked polyline by a fraction of the
//! spacing (0.05 rad). Motions that end in contact (reach, press, follow) are not routed here:
//! touching is their purpose.

use crate::PlanFailure;
use planner::{Problem, distance, lerp, shortcut};
use runtime::clearance::Clearance;

/// RRTConnect gives up after this many collision checks (about a second of checks).
const MAX_CHECKS: u64 = 40_000;
/// Random shortcuts tried on a planned path.
const SHORTCUTS: usize = 100;
/// A planned path is handed to TOPP resampled at this spacing or a little less (rad).
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

/// The first collision along `waypoints` (joint configurations, as straight joint motions), as
/// "moving body against obstacle" names.
fn first_hit(clearance: &mut Clearance, waypoints: &[Vec<f64>], step: f64) -> Option<String> {
    for w in waypoints.windows(2) {
        let n = (distance(&w[0], &w[1]) / step).ceil().max(1.0) as usize;
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

/// A collision-free joint path from `waypoints[0]` to its last configuration, within `limits`,
/// checked at least every `step` of joint travel (the arm's `ExpertLimits::check_step`).
/// `clearance` must be synced to the scene as it is now; its allowances for a motion's ends are
/// set to this path's ([`Clearance::ends_at`]), replacing an earlier route's.
pub fn route(
    clearance: &mut Clearance,
    limits: &[(f64, f64)],
    step: f64,
    waypoints: Vec<Vec<f64>>,
    seed: u64,
) -> Result<Route, PlanFailure> {
    clearance.ends_at(&waypoints[0], waypoints.last().expect("a path has a start"));
    let Some(hits) = first_hit(clearance, &waypoints, step) else {
        return Ok(Route::Straight(waypoints));
    };
    // Already overlapping where the motion starts (the commanded start differs from where the
    // arm sags to, another arm leans in): no planner can start there; the straight path is
    // followed and physics has the last word, as before planning existed.
    if !clearance.is_clear(&waypoints[0]) {
        return Ok(Route::Straight(waypoints));
    }
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
        step,
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
    // Counted before anything else checks: the count is part of the recorded event.
    let short = shortcut(&raw, SHORTCUTS, step, seed, |q| clearance.is_clear(q));
    let checks = clearance.checks - before;
    Ok(Route::Planned {
        path: resample(&short),
        hits,
        checks,
    })
}

/// `path` resampled at equal arc length, at most [`DENSE`] apart, ends kept.
fn resample(path: &[Vec<f64>]) -> Vec<Vec<f64>> {
    let lengths: Vec<f64> = path.windows(2).map(|w| distance(&w[0], &w[1])).collect();
    let total: f64 = lengths.iter().sum();
    let n = (total / DENSE).ceil().max(1.0) as usize;
    let mut out = Vec::with_capacity(n + 1);
    let (mut segment, mut before) = (0, 0.0);
    for k in 0..=n {
        let s = total * k as f64 / n as f64;
        while segment + 1 < lengths.len() && before + lengths[segment] < s {
            before += lengths[segment];
            segment += 1;
        }
        let t = if lengths[segment] > 0.0 {
            ((s - before) / lengths[segment]).clamp(0.0, 1.0)
        } else {
            0.0
        };
        out.push(lerp(&path[segment], &path[segment + 1], t));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resampling_spaces_points_evenly_along_the_path_and_keeps_its_ends() {
        let path = vec![
            vec![0.0, 0.0],
            vec![1.0, 0.0],
            vec![1.0, 0.02],
            vec![1.0, 0.5],
        ];
        let out = resample(&path);
        assert_eq!(out.first(), path.first());
        assert_eq!(out.last().unwrap(), path.last().unwrap());
        let gaps: Vec<f64> = out.windows(2).map(|w| distance(&w[0], &w[1])).collect();
        // Equal arc length: equal chords except where a chord cuts the corner.
        let straight: Vec<&f64> = gaps
            .iter()
            .filter(|g| (**g - gaps[0]).abs() > 1e-9)
            .collect();
        assert!(straight.len() <= 1, "{gaps:?}");
        assert!(gaps.iter().all(|g| *g <= DENSE + 1e-12), "{gaps:?}");
        // Every point lies on the path: on x's leg or on the corner's vertical.
        assert!(
            out.iter()
                .all(|p| p[1].abs() < 1e-12 || (p[0] - 1.0).abs() < 1e-12)
        );
    }
}
