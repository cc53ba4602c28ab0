//! Detent: a passive force `-k (q - q_j) - λ q̇` toward the nearest of `n` evenly spaced positions
//! `q_j` over a joint's range (the paper's appendix). Pure math here; [`crate::plugin`] registers it
//! with MuJoCo as the passive-force plugin `autobio.detent`.

/// A detent over `[lo, hi]` with `n >= 2` positions, stiffness `k` (N·m/rad or N/m) and damping
/// `lambda` (N·m·s/rad or N·s/m).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Detent {
    pub lo: f64,
    pub hi: f64,
    pub n: u32,
    pub stiffness: f64,
    pub damping: f64,
}

impl Detent {
    /// The detent position nearest `q` (positions outside the range clamp to its ends).
    pub fn nearest(&self, q: f64) -> f64 {
        if self.n < 2 || self.hi <= self.lo {
            return self.lo;
        }
        let step = (self.hi - self.lo) / (self.n - 1) as f64;
        let j = ((q - self.lo) / step)
            .round()
            .clamp(0.0, (self.n - 1) as f64);
        self.lo + j * step
    }

    /// The generalised force at position `q` and velocity `qd`.
    pub fn force(&self, q: f64, qd: f64) -> f64 {
        -self.stiffness * (q - self.nearest(q)) - self.damping * qd
    }

    /// The MJCF `<extension>` instance for a joint (the plugin must be registered, see
    /// [`crate::register`]).
    pub fn mjcf_instance(&self, instance: &str, joint: &str) -> String {
        format!(
            r#"<instance name="{instance}"><config key="joint" value="{joint}"/><config key="n" value="{}"/><config key="stiffness" value="{}"/><config key="damping" value="{}"/></instance>"#,
            self.n, self.stiffness, self.damping
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn snaps_to_the_nearest_notch() {
        let d = Detent {
            lo: 0.0,
            hi: 1.0,
            n: 5,
            stiffness: 2.0,
            damping: 0.0,
        };
        assert_eq!(d.nearest(0.1), 0.0);
        assert_eq!(d.nearest(0.13), 0.25);
        assert_eq!(d.nearest(0.9), 1.0);
        assert_eq!(d.nearest(7.0), 1.0);
        assert!((d.force(0.3, 0.0) - (-0.1)).abs() < 1e-12);
    }
}
