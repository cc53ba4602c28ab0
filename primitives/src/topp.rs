//! Time-optimal path parametrisation (TOPP) of a joint-space spline under symmetric per-joint
//! velocity and acceleration limits, by the reachability recursion on a uniform grid in s:
//! a backward pass computes the largest path speed from which the end can still be reached at
//! rest, a forward pass accelerates greedily within it. Starts and ends at rest.

use crate::spline::JointSpline;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Limits {
    /// rad/s
    pub vmax: f64,
    /// rad/s^2
    pub amax: f64,
}

#[derive(Clone, Debug)]
pub struct Trajectory {
    spline: JointSpline,
    /// Path parameter and squared path speed (x = sdot^2) at grid points, and their times.
    s: Vec<f64>,
    x: Vec<f64>,
    t: Vec<f64>,
}

const BIG: f64 = 1e8;

fn accel_bounds(dq: &[f64], ddq: &[f64], x: f64, amax: f64) -> (f64, f64) {
    let (mut lo, mut hi) = (-BIG, BIG);
    for j in 0..dq.len() {
        let (a, b) = (dq[j], ddq[j]);
        if a.abs() < 1e-9 {
            continue;
        }
        let (l, h) = ((-amax - b * x) / a, (amax - b * x) / a);
        let (l, h) = if a > 0.0 { (l, h) } else { (h, l) };
        lo = lo.max(l);
        hi = hi.min(h);
    }
    (lo, hi)
}

fn speed_cap(dq: &[f64], ddq: &[f64], lim: &Limits) -> f64 {
    let mut cap = BIG;
    for j in 0..dq.len() {
        if dq[j].abs() > 1e-9 {
            cap = cap.min((lim.vmax / dq[j]).powi(2));
        } else if ddq[j].abs() > 1e-9 {
            cap = cap.min(lim.amax / ddq[j].abs());
        }
    }
    cap
}

/// Fits a spline through `waypoints` (at uniform s) and times it. `grid` intervals in s.
pub fn plan_trajectory(waypoints: Vec<Vec<f64>>, lim: &Limits, grid: usize) -> Trajectory {
    let waypoints = if waypoints.len() == 1 {
        vec![waypoints[0].clone(), waypoints[0].clone()]
    } else {
        waypoints
    };
    let spline = JointSpline::new(waypoints);
    let n = grid.max(2);
    let ds = 1.0 / n as f64;
    let s: Vec<f64> = (0..=n).map(|i| i as f64 * ds).collect();
    let derivs: Vec<(Vec<f64>, Vec<f64>)> = s
        .iter()
        .map(|&si| {
            let (_, d, dd) = spline.eval(si);
            (d, dd)
        })
        .collect();
    let length: f64 = derivs
        .iter()
        .map(|(d, _)| d.iter().map(|v| v.abs()).fold(0.0, f64::max))
        .fold(0.0, f64::max);
    if length < 1e-9 {
        return Trajectory {
            spline,
            s: vec![0.0, 1.0],
            x: vec![0.0, 0.0],
            t: vec![0.0, 0.0],
        };
    }
    // Backward pass: largest x_i from which the rest can be followed and the end reached at rest.
    let mut xmax = vec![0.0; n + 1];
    for i in (0..n).rev() {
        let (d, dd) = &derivs[i];
        let cap = speed_cap(d, dd, lim);
        let feasible = |x: f64| {
            let (lo, hi) = accel_bounds(d, dd, x, lim.amax);
            lo <= hi + 1e-9 && x + 2.0 * ds * lo <= xmax[i + 1] + 1e-12
        };
        let (mut a, mut b) = (0.0, cap.min(BIG));
        if feasible(b) {
            a = b;
        } else {
            for _ in 0..60 {
                let m = 0.5 * (a + b);
                if feasible(m) { a = m } else { b = m }
            }
        }
        xmax[i] = if i == 0 { 0.0 } else { a };
    }
    // Forward pass: accelerate as hard as allowed while staying under the backward bound.
    let mut x = vec![0.0; n + 1];
    for i in 0..n {
        let (d, dd) = &derivs[i];
        let (lo, hi) = accel_bounds(d, dd, x[i], lim.amax);
        let mut u = hi.min((xmax[i + 1] - x[i]) / (2.0 * ds));
        u = u.max(lo.min(hi));
        x[i + 1] = (x[i] + 2.0 * ds * u).clamp(0.0, xmax[i + 1]);
    }
    let mut t = vec![0.0; n + 1];
    for i in 0..n {
        let denom = x[i].sqrt() + x[i + 1].sqrt();
        let dt = if denom > 1e-12 {
            2.0 * ds / denom
        } else {
            (2.0 * ds / lim.amax.max(1e-6)).sqrt()
        };
        t[i + 1] = t[i] + dt;
    }
    Trajectory { spline, s, x, t }
}

impl Trajectory {
    pub fn duration(&self) -> f64 {
        *self.t.last().unwrap_or(&0.0)
    }

    pub fn end(&self) -> Vec<f64> {
        self.spline.eval(1.0).0
    }

    fn s_at(&self, t: f64) -> f64 {
        if t <= 0.0 {
            return 0.0;
        }
        if t >= self.duration() {
            return 1.0;
        }
        let i = self
            .t
            .partition_point(|&ti| ti <= t)
            .saturating_sub(1)
            .min(self.t.len() - 2);
        let ds = self.s[i + 1] - self.s[i];
        let u = (self.x[i + 1] - self.x[i]) / (2.0 * ds);
        let tau = t - self.t[i];
        (self.s[i] + self.x[i].sqrt() * tau + 0.5 * u * tau * tau).clamp(self.s[i], self.s[i + 1])
    }

    /// Joint angles at time t (clamped to the ends).
    pub fn sample(&self, t: f64) -> Vec<f64> {
        self.spline.eval(self.s_at(t)).0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn respects_limits_and_ends_at_rest() {
        let lim = Limits {
            vmax: 1.0,
            amax: 2.0,
        };
        let traj = plan_trajectory(
            vec![vec![0.0, 0.0], vec![0.5, -0.2], vec![2.0, 0.3]],
            &lim,
            400,
        );
        let d = traj.duration();
        // A 2 rad move at 1 rad/s and 2 rad/s^2 needs at least 2.5 s.
        assert!(d >= 2.5 - 1e-6, "{d}");
        assert!(d < 5.0, "{d}");
        let dt = 1e-3;
        let mut prev = traj.sample(0.0);
        let mut t = dt;
        while t <= d {
            let q = traj.sample(t);
            for j in 0..2 {
                assert!(
                    ((q[j] - prev[j]) / dt).abs() <= lim.vmax * 1.05,
                    "velocity at {t}"
                );
            }
            prev = q;
            t += dt;
        }
        // Accelerations, by second differences over 10 ms (the finest the grid resolves).
        let h = 1e-2;
        let mut worst = 0.0f64;
        let mut t = h;
        while t + h <= d {
            let (a, b, c) = (traj.sample(t - h), traj.sample(t), traj.sample(t + h));
            for j in 0..2 {
                worst = worst.max(((a[j] - 2.0 * b[j] + c[j]) / (h * h)).abs());
            }
            t += h / 2.0;
        }
        assert!(
            worst <= lim.amax * 1.05,
            "acceleration up to {worst} rad/s^2"
        );
        assert!(
            worst >= lim.amax * 0.5,
            "the limit is used, not avoided: {worst}"
        );
        let end = traj.sample(d + 1.0);
        assert!((end[0] - 2.0).abs() < 1e-9 && (end[1] - 0.3).abs() < 1e-9);
        // At rest at both ends.
        let (q0, q1) = (traj.sample(0.0), traj.sample(dt));
        let (qe, qf) = (traj.sample(d - dt), traj.sample(d));
        for j in 0..2 {
            assert!((q1[j] - q0[j]).abs() / dt < 0.01 && (qf[j] - qe[j]).abs() / dt < 0.01);
        }
    }

    #[test]
    fn zero_length_path_takes_no_time() {
        let traj = plan_trajectory(
            vec![vec![1.0], vec![1.0]],
            &Limits {
                vmax: 1.0,
                amax: 1.0,
            },
            50,
        );
        assert_eq!(traj.duration(), 0.0);
        assert_eq!(traj.sample(3.0), vec![1.0]);
    }
}
