//! Per-feature statistics in LeRobot's shapes: vectors per dimension (`min`, `max`, `mean`,
//! `std`, `count`, quantiles `q01`..`q99`), images per channel as `(3, 1, 1)` over values
//! divided by 255 (from every frame, through 256-bin histograms, so quantiles are exact), and
//! the count-weighted aggregation over episodes LeRobot uses for `meta/stats.json`.
//!
//! It computes numbers only; it writes nothing.

use serde_json::{Value, json};
use std::collections::BTreeMap;

pub const QUANTILES: [(f64, &str); 5] = [
    (0.01, "q01"),
    (0.10, "q10"),
    (0.50, "q50"),
    (0.90, "q90"),
    (0.99, "q99"),
];

/// Statistics of one feature: each stat's values (per dimension or per channel) and shape.
#[derive(Clone, Debug, PartialEq)]
pub struct FeatureStats {
    pub stats: BTreeMap<&'static str, Vec<f64>>,
    pub count: u64,
    /// Image stats are `(3, 1, 1)`.
    pub image: bool,
}

impl FeatureStats {
    /// As LeRobot's JSON: each stat a list (images `[[[r]], [[g]], [[b]]]`), `count` `[n]`.
    pub fn to_json(&self, quantiles: bool) -> Value {
        let mut m = serde_json::Map::new();
        for (k, v) in &self.stats {
            if !quantiles && k.starts_with('q') {
                continue;
            }
            let value = if self.image {
                Value::Array(v.iter().map(|x| json!([[x]])).collect())
            } else {
                json!(v)
            };
            m.insert(k.to_string(), value);
        }
        m.insert("count".into(), json!([self.count]));
        Value::Object(m)
    }
}

/// Stats of vectors (one row per frame).
pub fn vectors(rows: &[Vec<f64>]) -> FeatureStats {
    let n = rows.len();
    let dims = rows.first().map_or(0, Vec::len);
    let mut stats: BTreeMap<&'static str, Vec<f64>> = BTreeMap::new();
    for d in 0..dims {
        let mut col: Vec<f64> = rows.iter().map(|r| r[d]).collect();
        let mean = col.iter().sum::<f64>() / n as f64;
        let var = col.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n as f64;
        col.sort_by(f64::total_cmp);
        stats.entry("min").or_default().push(col[0]);
        stats.entry("max").or_default().push(col[n - 1]);
        stats.entry("mean").or_default().push(mean);
        stats.entry("std").or_default().push(var.sqrt());
        for (q, name) in QUANTILES {
            stats.entry(name).or_default().push(quantile(&col, q));
        }
    }
    FeatureStats {
        stats,
        count: n as u64,
        image: false,
    }
}

/// The `q` quantile of sorted values, interpolated linearly (numpy's default).
fn quantile(sorted: &[f64], q: f64) -> f64 {
    let pos = q * (sorted.len() - 1) as f64;
    let (lo, hi) = (pos.floor() as usize, pos.ceil() as usize);
    sorted[lo] + (sorted[hi] - sorted[lo]) * (pos - lo as f64)
}

/// Running image statistics: per-channel histograms of 8-bit values over frames.
#[derive(Clone, Debug)]
pub struct ImageStats {
    hist: [[u64; 256]; 3],
    frames: u64,
}

impl Default for ImageStats {
    fn default() -> ImageStats {
        ImageStats {
            hist: [[0; 256]; 3],
            frames: 0,
        }
    }
}

impl ImageStats {
    pub fn add(&mut self, rgb: &[u8]) {
        for px in rgb.chunks_exact(3) {
            for (h, &v) in self.hist.iter_mut().zip(px) {
                h[v as usize] += 1;
            }
        }
        self.frames += 1;
    }

    pub fn finish(&self) -> FeatureStats {
        let mut stats: BTreeMap<&'static str, Vec<f64>> = BTreeMap::new();
        for h in &self.hist {
            let n: u64 = h.iter().sum();
            let value = |v: usize| v as f64 / 255.0;
            let mean = h
                .iter()
                .enumerate()
                .map(|(v, &k)| value(v) * k as f64)
                .sum::<f64>()
                / n as f64;
            let var = h
                .iter()
                .enumerate()
                .map(|(v, &k)| (value(v) - mean).powi(2) * k as f64)
                .sum::<f64>()
                / n as f64;
            let min = h.iter().position(|&k| k > 0).unwrap_or(0);
            let max = h.iter().rposition(|&k| k > 0).unwrap_or(0);
            stats.entry("min").or_default().push(value(min));
            stats.entry("max").or_default().push(value(max));
            stats.entry("mean").or_default().push(mean);
            stats.entry("std").or_default().push(var.sqrt());
            for (q, name) in QUANTILES {
                // The smallest value whose cumulative share reaches q.
                let want = (q * n as f64).ceil().max(1.0) as u64;
                let mut seen = 0;
                let v = h
                    .iter()
                    .position(|&k| {
                        seen += k;
                        seen >= want
                    })
                    .unwrap_or(255);
                stats.entry(name).or_default().push(value(v));
            }
        }
        FeatureStats {
            stats,
            count: self.frames,
            image: true,
        }
    }
}

/// Count-weighted aggregation over episodes: min of mins, max of maxes, the pooled mean and
/// standard deviation, and count-weighted quantiles (as LeRobot aggregates them).
pub fn aggregate(parts: &[&FeatureStats]) -> FeatureStats {
    let total: u64 = parts.iter().map(|p| p.count).sum();
    let dims = parts.first().map_or(0, |p| p.stats["mean"].len());
    let mut stats: BTreeMap<&'static str, Vec<f64>> = BTreeMap::new();
    for d in 0..dims {
        let w = |p: &FeatureStats| p.count as f64 / total as f64;
        let mean: f64 = parts.iter().map(|p| w(p) * p.stats["mean"][d]).sum();
        let second: f64 = parts
            .iter()
            .map(|p| w(p) * (p.stats["std"][d].powi(2) + p.stats["mean"][d].powi(2)))
            .sum();
        stats.entry("mean").or_default().push(mean);
        stats
            .entry("std")
            .or_default()
            .push((second - mean * mean).max(0.0).sqrt());
        stats.entry("min").or_default().push(
            parts
                .iter()
                .map(|p| p.stats["min"][d])
                .fold(f64::INFINITY, f64::min),
        );
        stats.entry("max").or_default().push(
            parts
                .iter()
                .map(|p| p.stats["max"][d])
                .fold(f64::NEG_INFINITY, f64::max),
        );
        for (_, name) in QUANTILES {
            stats
                .entry(name)
                .or_default()
                .push(parts.iter().map(|p| w(p) * p.stats[name][d]).sum());
        }
    }
    FeatureStats {
        stats,
        count: total,
        image: parts.first().is_some_and(|p| p.image),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn vector_and_image_stats_and_their_aggregate() {
        let a = vectors(&[vec![0.0, 1.0], vec![2.0, 1.0], vec![4.0, 1.0]]);
        assert_eq!(a.stats["mean"], [2.0, 1.0]);
        assert_eq!(a.stats["min"], [0.0, 1.0]);
        assert!((a.stats["std"][0] - (8.0f64 / 3.0).sqrt()).abs() < 1e-12);
        assert_eq!(a.stats["q50"], [2.0, 1.0]);
        let b = vectors(&[vec![10.0, 3.0]]);
        let all = aggregate(&[&a, &b]);
        let rows = [[0.0, 1.0], [2.0, 1.0], [4.0, 1.0], [10.0, 3.0]];
        let mean = rows.iter().map(|r| r[0]).sum::<f64>() / 4.0;
        let std = (rows.iter().map(|r| (r[0] - mean).powi(2)).sum::<f64>() / 4.0).sqrt();
        assert_eq!(all.count, 4);
        assert!((all.stats["mean"][0] - mean).abs() < 1e-12);
        assert!((all.stats["std"][0] - std).abs() < 1e-12);
        assert_eq!((all.stats["min"][0], all.stats["max"][0]), (0.0, 10.0));

        let mut img = ImageStats::default();
        img.add(&[0, 255, 51, 255, 255, 51]);
        let s = img.finish();
        assert_eq!(s.stats["mean"], [0.5, 1.0, 0.2]);
        assert_eq!(s.stats["min"], [0.0, 1.0, 0.2]);
        assert_eq!(s.count, 1);
        assert_eq!(s.to_json(false)["mean"], json!([[[0.5]], [[1.0]], [[0.2]]]));
    }
}
