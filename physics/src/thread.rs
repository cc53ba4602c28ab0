//! Screw threads as signed distance functions: the bounded circular helix of the paper's appendix,
//! thickened by a gauge radius. A thread is configured by `(r1, r2, p, l, h)`: helix radius, gauge
//! radius, pitch (m per turn), and the first and last turn. A bolt and a nut are two instances of
//! the same shape whose helices interleave; [`crate::plugin`] registers it as the SDF plugin
//! `autobio.thread`. Pure math here: no MuJoCo types.

use std::f64::consts::TAU;

/// A helical thread: helix `H(t) = (r1 cos t, r1 sin t, p t / 2π)` for `2π l <= t <= 2π h`,
/// thickened by `r2`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Thread {
    /// Helix radius (m).
    pub radius: f64,
    /// Gauge: the radius of the thread ridge around the helix (m).
    pub gauge: f64,
    /// Axial advance per turn (m).
    pub pitch: f64,
    /// First and last turn (turns from z = 0).
    pub low: f64,
    pub high: f64,
}

/// Attribute names in the order the plugin declares them.
pub const ATTRIBUTES: [&str; 5] = ["radius", "gauge", "pitch", "low", "high"];

impl Thread {
    /// From attribute values in [`ATTRIBUTES`] order.
    pub fn from_attributes(a: &[f64; 5]) -> Thread {
        Thread {
            radius: a[0],
            gauge: a[1],
            pitch: a[2],
            low: a[3],
            high: a[4],
        }
    }

    pub fn attributes(&self) -> [f64; 5] {
        [self.radius, self.gauge, self.pitch, self.low, self.high]
    }

    fn point(&self, t: f64) -> [f64; 3] {
        [
            self.radius * t.cos(),
            self.radius * t.sin(),
            self.pitch * t / TAU,
        ]
    }

    /// The helix parameter of the point the distance is measured to (the paper's case split).
    fn nearest_t(&self, p: [f64; 3]) -> f64 {
        let t0 = p[1].atan2(p[0]);
        let c = self.pitch / TAU;
        let k = ((p[2] - t0 * c) / self.pitch).round();
        let k_lo = (self.low - t0 / TAU).ceil();
        let k_hi = (self.high - t0 / TAU).floor();
        let dist = |t: f64| dist2(self.point(t), p);
        let (t_low, t_high) = (TAU * self.low, TAU * self.high);
        if k_lo <= k && k <= k_hi {
            return TAU * k + t0;
        }
        // Beyond the ends: the end point, or the first/last full winding at this angle.
        let (end, winding) = if k < k_lo {
            (t_low, TAU * k_lo + t0)
        } else {
            (t_high, TAU * k_hi + t0)
        };
        if (t_low..=t_high).contains(&winding) && dist(winding) < dist(end) {
            winding
        } else {
            end
        }
    }

    /// Signed distance (m) from `p` to the thread's surface (negative inside the ridge).
    pub fn distance(&self, p: [f64; 3]) -> f64 {
        dist2(self.point(self.nearest_t(p)), p).sqrt() - self.gauge
    }

    /// Gradient of [`Thread::distance`]. The distance is measured to the helix point at the
    /// query's own polar angle, so besides the unit vector away from that point the gradient has a
    /// circumferential part, `-(p / 2π) u_z / ρ`: the thread's slope, which turns an axial load on a
    /// nut into a torque (without it a cap could never screw itself down).
    pub fn gradient(&self, p: [f64; 3]) -> [f64; 3] {
        let t = self.nearest_t(p);
        let h = self.point(t);
        let v = [p[0] - h[0], p[1] - h[1], p[2] - h[2]];
        let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        let rho = (p[0] * p[0] + p[1] * p[1]).sqrt();
        if n < 1e-12 || rho < 1e-12 {
            // On the helix (or the axis): any direction is as good; take the radial one.
            let r = rho.max(1e-12);
            return [p[0] / r, p[1] / r, 0.0];
        }
        let u = [v[0] / n, v[1] / n, v[2] / n];
        let on_winding = (t - p[1].atan2(p[0])).rem_euclid(TAU) < 1e-9
            || (TAU - (t - p[1].atan2(p[0])).rem_euclid(TAU)) < 1e-9;
        if !on_winding {
            // Measured to an end point of the helix: the plain Euclidean gradient.
            return u;
        }
        let slope = self.pitch / TAU * u[2] / rho;
        let (s0, c0) = (p[1] / rho, p[0] / rho);
        [u[0] + slope * s0, u[1] - slope * c0, u[2]]
    }

    /// Bounding box: centre and half sizes, with a margin so a marched mesh closes.
    pub fn aabb(&self) -> [f64; 6] {
        let margin = 2.0 * self.gauge;
        let r = self.radius + self.gauge + margin;
        let (z0, z1) = (self.low * self.pitch, self.high * self.pitch);
        [
            0.0,
            0.0,
            (z0 + z1) / 2.0,
            r,
            r,
            (z1 - z0).abs() / 2.0 + self.gauge + margin,
        ]
    }

    /// MJCF `<extension>` instance of the `autobio.thread` plugin.
    pub fn mjcf_instance(&self, instance: &str) -> String {
        let config: String = ATTRIBUTES
            .iter()
            .zip(self.attributes())
            .map(|(k, v)| format!(r#"<config key="{k}" value="{v}"/>"#))
            .collect();
        format!(r#"<instance name="{instance}">{config}</instance>"#)
    }
}

fn dist2(a: [f64; 3], b: [f64; 3]) -> f64 {
    (a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)
}

/// The bolt and nut threads of a screw-cap container, as upstream configured them: same helix
/// radius, pitch 3 mm, bolt turns [-1, 1.2] with gauge 0.9 mm, nut turns [-1.2, 1] with gauge
/// 0.6 mm (the two gauges sum to half a pitch, so the ridges touch flank to flank).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScrewCap {
    pub bolt: Thread,
    pub nut: Thread,
}

impl ScrewCap {
    pub fn new(radius: f64) -> ScrewCap {
        let pitch = 0.003;
        ScrewCap {
            bolt: Thread {
                radius,
                gauge: 0.0009,
                pitch,
                low: -1.0,
                high: 1.2,
            },
            nut: Thread {
                radius,
                gauge: 0.0006,
                pitch,
                low: -1.2,
                high: 1.0,
            },
        }
    }
}

/// Container sizes with screw caps and their thread radius (m), from upstream's models.
pub const CONTAINERS: [(&str, f64); 4] = [
    ("1.5 mL tube", 0.005992),
    ("15 mL tube", 0.00784),
    ("50 mL tube", 0.014),
    ("1.8 mL vial", 0.005112),
];

#[cfg(test)]
mod tests {
    use super::*;

    fn thread() -> Thread {
        Thread {
            radius: 0.01,
            gauge: 0.001,
            pitch: 0.003,
            low: -1.0,
            high: 1.0,
        }
    }

    #[test]
    fn distance_is_zero_on_the_surface_and_negative_inside() {
        let t = thread();
        // On the helix at t = 0: (r, 0, 0); the ridge surface is a gauge away radially.
        assert!((t.distance([0.011, 0.0, 0.0])).abs() < 1e-12);
        assert!(t.distance([0.01, 0.0, 0.0]) < 0.0);
        // Half a pitch above a winding is the furthest point between windings.
        let mid = t.distance([0.01, 0.0, 0.0015]);
        assert!((mid - (0.0015 - 0.001)).abs() < 1e-9, "{mid}");
        // Beyond the last turn it is the distance to the end point (0.01, 0, 0.003).
        assert!((t.distance([0.01, 0.0, 0.01]) - 0.006).abs() < 1e-12);
    }

    #[test]
    fn gradient_matches_finite_differences() {
        let t = thread();
        for p in [
            [0.012, 0.003, 0.0007],
            [-0.004, 0.011, -0.0011],
            [0.009, -0.002, 0.0013],
        ] {
            let g = t.gradient(p);
            let h = 1e-7;
            for i in 0..3 {
                let (mut a, mut b) = (p, p);
                a[i] += h;
                b[i] -= h;
                let fd = (t.distance(a) - t.distance(b)) / (2.0 * h);
                assert!((fd - g[i]).abs() < 1e-5, "{p:?} axis {i}: {fd} vs {}", g[i]);
            }
        }
    }

    #[test]
    fn the_box_contains_the_thread() {
        let t = thread();
        let b = t.aabb();
        for k in 0..200 {
            let s = TAU * (t.low + (t.high - t.low) * k as f64 / 199.0);
            let p = t.point(s);
            for i in 0..3 {
                assert!((p[i] - b[i]).abs() + t.gauge <= b[i + 3] + 1e-12);
            }
        }
    }
}
