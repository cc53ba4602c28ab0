//! Random shortcutting: pick two points along the path (by arc length, from a seeded ChaCha8),
//! and when the straight motion between them is valid, splice it in. Deterministic per seed.

use crate::{distance, lerp};
use rand_chacha::ChaCha8Rng;
use rand_core::{RngCore, SeedableRng};

/// Whether every point on the straight motion from `a` to `b`, at steps of at most `step`
/// (rad), satisfies `valid` (both ends included).
pub fn segment_is_clear(
    a: &[f64],
    b: &[f64],
    step: f64,
    valid: &mut impl FnMut(&[f64]) -> bool,
) -> bool {
    let n = (distance(a, b) / step).ceil().max(1.0) as usize;
    (0..=n).all(|i| valid(&lerp(a, b, i as f64 / n as f64)))
}

/// The point at arc length `s` along `path`, and the index of the segment it lies on.
fn at_length(path: &[Vec<f64>], s: f64) -> (usize, Vec<f64>) {
    let mut left = s;
    for i in 0..path.len() - 1 {
        let d = distance(&path[i], &path[i + 1]);
        if left <= d || i == path.len() - 2 {
            return (
                i,
                lerp(&path[i], &path[i + 1], (left / d.max(1e-12)).min(1.0)),
            );
        }
        left -= d;
    }
    (0, path[0].clone())
}

fn length(path: &[Vec<f64>]) -> f64 {
    path.windows(2).map(|w| distance(&w[0], &w[1])).sum()
}

/// `path` shortened by `tries` random shortcuts whose straight motions are checked at `step`.
/// The ends stay where they are; the result is never longer than `path`.
pub fn shortcut(
    path: &[Vec<f64>],
    tries: usize,
    step: f64,
    seed: u64,
    mut valid: impl FnMut(&[f64]) -> bool,
) -> Vec<Vec<f64>> {
    let mut path = path.to_vec();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut unit = || (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
    for _ in 0..tries {
        if path.len() < 3 {
            break;
        }
        let total = length(&path);
        let (s1, s2) = {
            let (x, y) = (unit() * total, unit() * total);
            (x.min(y), x.max(y))
        };
        let (i, a) = at_length(&path, s1);
        let (j, b) = at_length(&path, s2);
        // Only a splice that skips at least one vertex shortens the path.
        if j <= i || distance(&a, &b) < 1e-9 || !segment_is_clear(&a, &b, step, &mut valid) {
            continue;
        }
        let mut next = path[..=i].to_vec();
        next.push(a);
        next.push(b);
        next.extend_from_slice(&path[j + 1..]);
        next.dedup_by(|x, y| distance(x, y) < 1e-12);
        path = next;
    }
    path
}
