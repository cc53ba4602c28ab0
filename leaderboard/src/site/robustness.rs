//! A robustness suite's table (a suite with `perturb` presets, docs/robustness.md): per
//! submission, its success under each preset, pooled over the suite's tasks, beside its clean
//! success over the same tasks, and the drop from clean with Newcombe's 95% interval for a
//! difference of two proportions (each side's Wilson interval combined). Plain data, as the rest
//! of the view model; it reads the submissions' task results and nothing else.

use super::load::Submission;
use results::run::stats::wilson;
use results::suite::split_variant;
use std::collections::BTreeMap;

/// The table of one group whose suite names presets.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Robustness {
    /// The suite's presets, in its order (`light:1`).
    pub presets: Vec<String>,
    pub rows: Vec<RobustRow>,
}

/// One submission's row.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct RobustRow {
    pub model: String,
    /// The submission's page, without extension.
    pub submission: String,
    /// Success over every clean task (percent) and its Wilson interval.
    pub clean: (f64, [f64; 2]),
    /// Per preset (the table's order): `None` where the submission ran no task under it.
    pub cells: Vec<Option<RobustCell>>,
}

/// One submission under one preset.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct RobustCell {
    /// Success under the preset (percent) and its Wilson interval.
    pub success: f64,
    pub wilson: [f64; 2],
    /// Clean success minus perturbed success over the same tasks (percentage points), and its
    /// 95% interval.
    pub drop: f64,
    pub drop_interval: [f64; 2],
}

/// Successes and episodes.
#[derive(Clone, Copy, Debug, Default)]
struct Count {
    k: usize,
    n: usize,
}

impl Count {
    fn rate(self) -> f64 {
        if self.n == 0 {
            0.0
        } else {
            self.k as f64 / self.n as f64
        }
    }
}

/// Newcombe's hybrid score interval for `a - b` (proportions, 95%).
fn difference(a: Count, b: Count) -> [f64; 2] {
    let (pa, pb) = (a.rate(), b.rate());
    let ([la, ua], [lb, ub]) = (wilson(a.k, a.n, 1.96), wilson(b.k, b.n, 1.96));
    let d = pa - pb;
    [
        d - ((pa - la).powi(2) + (ub - pb).powi(2)).sqrt(),
        d + ((ua - pa).powi(2) + (pb - lb).powi(2)).sqrt(),
    ]
}

/// The table for a group's members, when their suite names presets.
pub(super) fn table(members: &[&Submission]) -> Option<Robustness> {
    // The suite's presets as read (`camera` is `camera:1`), in its order.
    let presets: Vec<String> = members
        .first()?
        .index
        .suite
        .presets()
        .iter()
        .map(ToString::to_string)
        .collect();
    if presets.is_empty() {
        return None;
    }
    let rows = members
        .iter()
        .map(|s| {
            // Each suite task's clean count, and its counts by preset.
            let mut clean: BTreeMap<&str, Count> = BTreeMap::new();
            let mut under: BTreeMap<(String, &str), Count> = BTreeMap::new();
            for t in &s.tasks {
                let c = Count {
                    k: t.summary.successes,
                    n: t.summary.episodes,
                };
                match split_variant(&t.task) {
                    (base, None) => {
                        clean.insert(base, c);
                    }
                    (base, Some(p)) => {
                        under.insert((p.to_string(), base), c);
                    }
                }
            }
            let sum = |v: &mut dyn Iterator<Item = Count>| {
                v.fold(Count::default(), |a, c| Count {
                    k: a.k + c.k,
                    n: a.n + c.n,
                })
            };
            let all_clean = sum(&mut clean.values().copied());
            let cells = presets
                .iter()
                .map(|p| {
                    // Only tasks run both ways: the drop compares the same tasks.
                    let tasks: Vec<(&str, Count)> = under
                        .iter()
                        .filter(|((q, base), _)| q == p && clean.contains_key(base))
                        .map(|((_, base), c)| (*base, *c))
                        .collect();
                    if tasks.is_empty() {
                        return None;
                    }
                    let perturbed = sum(&mut tasks.iter().map(|(_, c)| *c));
                    let same_clean =
                        sum(&mut tasks.iter().filter_map(|(b, _)| clean.get(b).copied()));
                    let w = wilson(perturbed.k, perturbed.n, 1.96);
                    let [lo, hi] = difference(same_clean, perturbed);
                    Some(RobustCell {
                        success: 100.0 * perturbed.rate(),
                        wilson: [100.0 * w[0], 100.0 * w[1]],
                        drop: 100.0 * (same_clean.rate() - perturbed.rate()),
                        drop_interval: [100.0 * lo, 100.0 * hi],
                    })
                })
                .collect();
            let w = wilson(all_clean.k, all_clean.n, 1.96);
            RobustRow {
                model: s.index.model.name.clone(),
                submission: s.slug.clone(),
                clean: (100.0 * all_clean.rate(), [100.0 * w[0], 100.0 * w[1]]),
                cells,
            }
        })
        .collect();
    Some(Robustness { presets, rows })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn newcombes_interval_matches_his_worked_example() {
        // Newcombe (1998), Table II, example (a): 56/70 against 48/80, method 10:
        // difference 0.2000, interval 0.0524 to 0.3339.
        let [lo, hi] = difference(Count { k: 56, n: 70 }, Count { k: 48, n: 80 });
        assert!(
            (lo - 0.0524).abs() < 5e-4 && (hi - 0.3339).abs() < 5e-4,
            "{lo} {hi}"
        );
        // Equal and certain: no drop, an interval about zero.
        let [lo, hi] = difference(Count { k: 20, n: 20 }, Count { k: 20, n: 20 });
        assert!(lo < 0.0 && hi > 0.0 && (lo + hi).abs() < 1e-12);
    }
}
