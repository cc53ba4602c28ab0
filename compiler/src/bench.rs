//! The lab bench every task stands on: its footprint and height, facts the compiler checks poses
//! against (a pose off the bench and out of every robot's reach is a unit mistake) and the
//! runtime builds the scene from. Data only.

/// The bench top's half extents (m): a 1.8 m lab bench, so that the 5910 (0.73 m a side) stands
/// on it wherever its tasks place it (upstream's 0.82 m table left half of it in the air).
pub const BENCH_HALF: [f64; 2] = [0.9, 0.652];
/// The bench top's height (m).
pub const BENCH_TOP: f64 = 0.824;

/// Whether a point (m) is over the bench top, `margin` metres of slack around it.
pub fn over_bench(x: f64, y: f64, margin: f64) -> bool {
    x.abs() <= BENCH_HALF[0] + margin && y.abs() <= BENCH_HALF[1] + margin
}
