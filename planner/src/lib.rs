//! Collision-free joint-space paths for the scripted expert: OMPL 1.5's RRTConnect ([`plan`],
//! through a one-function C-ABI shim, `cpp/shim.cpp`) finds a path, then seeded random
//! shortcutting ([`shortcut()`]) straightens it. Validity is the caller's closure (the runtime's
//! MuJoCo collision check), so this crate knows no robot, scene or simulator. Timing the path
//! (TOPP) is `primitives::topp`'s job, not this crate's.
//!
//! Determinism: every call is seeded by the caller and budgeted in validity checks, never in
//! wall-clock time, so the same problem and seed give the same path, byte for byte.
//!
//! Its tests are in planner/tests/.

mod rrt;
mod shortcut;

pub use rrt::{PlanError, Problem, plan};
pub use shortcut::{segment_is_clear, shortcut};

/// A planner seed from a base seed and a counter (SplitMix64's finaliser): every bit of both
/// reaches the seed OMPL's 32-bit generator gets, so seeds that differ anywhere plan apart.
pub fn mix(base: u64, n: u64) -> u64 {
    let mut z = base ^ n.wrapping_mul(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Euclidean distance between two joint vectors (rad).
pub fn distance(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).powi(2))
        .sum::<f64>()
        .sqrt()
}

/// The point a fraction `t` of the way from `a` to `b`.
pub fn lerp(a: &[f64], b: &[f64], t: f64) -> Vec<f64> {
    a.iter().zip(b).map(|(x, y)| x + (y - x) * t).collect()
}
