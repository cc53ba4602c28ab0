//! Natural cubic splines through joint waypoints at uniform path parameter s in [0, 1], with first
//! and second derivatives for time parametrisation.

#[derive(Clone, Debug)]
pub struct JointSpline {
    /// Waypoints (each a joint vector).
    points: Vec<Vec<f64>>,
    /// Second derivatives at the knots, per knot per joint.
    m: Vec<Vec<f64>>,
    h: f64,
}

impl JointSpline {
    pub fn new(points: Vec<Vec<f64>>) -> JointSpline {
        let k = points.len();
        let n = points[0].len();
        let h = 1.0 / (k - 1) as f64;
        let mut m = vec![vec![0.0; n]; k];
        if k > 2 {
            for j in 0..n {
                // Tridiagonal system for interior second derivatives (natural ends).
                let size = k - 2;
                let mut diag = vec![4.0; size];
                let mut rhs: Vec<f64> = (1..k - 1)
                    .map(|i| {
                        6.0 * (points[i + 1][j] - 2.0 * points[i][j] + points[i - 1][j]) / (h * h)
                    })
                    .collect();
                for i in 1..size {
                    let f = 1.0 / diag[i - 1];
                    diag[i] -= f;
                    rhs[i] -= f * rhs[i - 1];
                }
                let mut x = vec![0.0; size];
                x[size - 1] = rhs[size - 1] / diag[size - 1];
                for i in (0..size - 1).rev() {
                    x[i] = (rhs[i] - x[i + 1]) / diag[i];
                }
                for i in 0..size {
                    m[i + 1][j] = x[i];
                }
            }
        }
        JointSpline { points, m, h }
    }

    pub fn dof(&self) -> usize {
        self.points[0].len()
    }

    /// (q, dq/ds, d2q/ds2) at s.
    pub fn eval(&self, s: f64) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
        let k = self.points.len();
        let s = s.clamp(0.0, 1.0);
        let i = ((s / self.h).floor() as usize).min(k - 2);
        let t = s - i as f64 * self.h;
        let h = self.h;
        let n = self.dof();
        let (mut q, mut dq, mut ddq) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        for j in 0..n {
            let (y0, y1) = (self.points[i][j], self.points[i + 1][j]);
            let (m0, m1) = (self.m[i][j], self.m[i + 1][j]);
            let a = h - t;
            q[j] = m0 * a.powi(3) / (6.0 * h)
                + m1 * t.powi(3) / (6.0 * h)
                + (y0 / h - m0 * h / 6.0) * a
                + (y1 / h - m1 * h / 6.0) * t;
            dq[j] = -m0 * a * a / (2.0 * h) + m1 * t * t / (2.0 * h) - (y0 / h - m0 * h / 6.0)
                + (y1 / h - m1 * h / 6.0);
            ddq[j] = m0 * a / h + m1 * t / h;
        }
        (q, dq, ddq)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interpolates_knots_and_lines() {
        let s = JointSpline::new(vec![vec![0.0, 1.0], vec![1.0, 1.0], vec![2.0, 1.0]]);
        let (q, dq, ddq) = s.eval(0.25);
        assert!((q[0] - 0.5).abs() < 1e-12 && (q[1] - 1.0).abs() < 1e-12);
        assert!((dq[0] - 2.0).abs() < 1e-12 && ddq[0].abs() < 1e-12);
        let curved = JointSpline::new(vec![vec![0.0], vec![1.0], vec![0.0], vec![1.0]]);
        assert!((curved.eval(1.0 / 3.0).0[0] - 1.0).abs() < 1e-12);
    }
}
