//! The site's statistics: the ranking of comparable submissions (mean success over the suite's
//! tasks, its SEM across runs, per level, mean score) and paired comparisons between two
//! submissions on the same seeds (exact McNemar, per task and pooled over the suite).
//!
//! It computes numbers from loaded submissions; it reads no file and renders nothing.

use super::load::{Spread, Submission, TaskResult};
use results::run::stats::mean_sem;
use serde::Serialize;
use std::collections::BTreeMap;

/// One ranked row.
#[derive(Clone, Debug, Serialize)]
pub struct RankRow {
    pub rank: usize,
    pub model: String,
    pub training: String,
    /// What the policy observes: `vision`, `state` (privileged) or `scripted`.
    pub observation: String,
    pub standing: String,
    pub page: String,
    /// Mean over the suite's tasks of the success rate, and its SEM across runs (percent; 0
    /// for a single run), taken over what `spread` says.
    pub success: f64,
    pub sem: f64,
    pub runs: usize,
    pub spread: Spread,
    pub by_level: BTreeMap<String, f64>,
    pub mean_score: f64,
}

/// Rankings per group of comparable conditions.
pub fn rankings(subs: &[Submission]) -> BTreeMap<String, Vec<RankRow>> {
    let mut groups: BTreeMap<String, Vec<RankRow>> = BTreeMap::new();
    for s in subs {
        if s.standing.is_refused() || s.tasks.is_empty() {
            continue;
        }
        let rates: Vec<f64> = s.tasks.iter().map(|t| t.summary.success_rate).collect();
        let runs = s
            .tasks
            .iter()
            .map(|t| t.summary.runs.len())
            .max()
            .unwrap_or(1);
        let per_run: Vec<f64> = (0..runs)
            .map(|r| {
                let xs: Vec<f64> = s
                    .tasks
                    .iter()
                    .filter_map(|t| t.summary.runs.get(r).map(|x| x.success_rate))
                    .collect();
                xs.iter().sum::<f64>() / xs.len().max(1) as f64
            })
            .collect();
        let (_, sem) = mean_sem(&per_run);
        let mut by_level: BTreeMap<String, Vec<f64>> = BTreeMap::new();
        for t in &s.tasks {
            by_level
                .entry(t.level.clone())
                .or_default()
                .push(t.summary.success_rate);
        }
        groups.entry(s.group.clone()).or_default().push(RankRow {
            rank: 0,
            model: s.index.model.name.clone(),
            training: s.index.model.training.clone().unwrap_or_default(),
            observation: s.observation.clone(),
            standing: s.standing.label().to_string(),
            page: format!("submissions/{}.html", s.slug),
            success: 100.0 * rates.iter().sum::<f64>() / rates.len() as f64,
            sem: 100.0 * if runs > 1 { sem } else { 0.0 },
            runs,
            spread: s.spread(),
            by_level: by_level
                .into_iter()
                .map(|(l, xs)| (l, 100.0 * xs.iter().sum::<f64>() / xs.len() as f64))
                .collect(),
            mean_score: s.tasks.iter().map(|t| t.summary.mean_score).sum::<f64>()
                / s.tasks.len() as f64,
        });
    }
    for rows in groups.values_mut() {
        rows.sort_by(|a, b| b.success.total_cmp(&a.success).then(a.model.cmp(&b.model)));
        for (i, r) in rows.iter_mut().enumerate() {
            r.rank = i + 1;
        }
    }
    groups
}

/// Exact two-sided McNemar test on the discordant pairs: `b` episodes only the first won, `c`
/// only the second.
pub fn mcnemar(b: u64, c: u64) -> f64 {
    let n = b + c;
    if n == 0 {
        return 1.0;
    }
    let k = b.min(c);
    // P(X <= k), X ~ Binomial(n, 1/2), by log-space terms.
    let mut ln_choose = 0.0f64; // ln C(n, 0)
    let mut tail = 0.0;
    for x in 0..=k {
        if x > 0 {
            ln_choose += ((n - x + 1) as f64).ln() - (x as f64).ln();
        }
        tail += (ln_choose - n as f64 * std::f64::consts::LN_2).exp();
    }
    (2.0 * tail).min(1.0)
}

/// One paired comparison on a task.
#[derive(Clone, Debug, Serialize)]
pub struct Paired {
    pub first: String,
    pub second: String,
    pub pairs: usize,
    pub only_first: u64,
    pub only_second: u64,
    pub p_value: f64,
    pub significant: bool,
}

/// One task of two submissions, each episode paired with the other's on the same run and seed;
/// none when they share no episode.
pub(super) fn paired(
    a: &Submission,
    ta: &TaskResult,
    b: &Submission,
    tb: &TaskResult,
) -> Option<Paired> {
    let theirs: BTreeMap<(u32, u64), bool> = tb
        .episodes
        .iter()
        .map(|e| ((e.run, e.seed), e.success))
        .collect();
    let (mut pairs, mut only_a, mut only_b) = (0, 0, 0);
    for e in &ta.episodes {
        if let Some(&other) = theirs.get(&(e.run, e.seed)) {
            pairs += 1;
            match (e.success, other) {
                (true, false) => only_a += 1,
                (false, true) => only_b += 1,
                _ => {}
            }
        }
    }
    (pairs > 0).then(|| {
        let p = mcnemar(only_a, only_b);
        Paired {
            first: a.index.model.name.clone(),
            second: b.index.model.name.clone(),
            pairs,
            only_first: only_a,
            only_second: only_b,
            p_value: p,
            significant: p < 0.05,
        }
    })
}

/// Two submissions compared over every task they share, each episode paired with the other's
/// on the same task, run and seed (McNemar on the pooled discordant episodes).
pub fn paired_over_suite(a: &Submission, b: &Submission) -> Option<Paired> {
    let mut total: Option<Paired> = None;
    for ta in &a.tasks {
        let Some(tb) = b.tasks.iter().find(|t| t.task == ta.task) else {
            continue;
        };
        if let Some(p) = paired(a, ta, b, tb) {
            let t = total.get_or_insert(Paired {
                first: p.first.clone(),
                second: p.second.clone(),
                pairs: 0,
                only_first: 0,
                only_second: 0,
                p_value: 1.0,
                significant: false,
            });
            t.pairs += p.pairs;
            t.only_first += p.only_first;
            t.only_second += p.only_second;
        }
    }
    total.map(|mut t| {
        t.p_value = mcnemar(t.only_first, t.only_second);
        t.significant = t.p_value < 0.05;
        t
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mcnemar_matches_hand_computed_values() {
        // 6 discordant pairs all one way: 2 * (1/2)^6.
        assert!((mcnemar(6, 0) - 2.0 / 64.0).abs() < 1e-12);
        // 3 against 3: no evidence.
        assert_eq!(mcnemar(3, 3), 1.0);
        // 10 against 2: 2 * P(X <= 2), X ~ Bin(12, 1/2) = 2 * (1 + 12 + 66) / 4096.
        assert!((mcnemar(10, 2) - 2.0 * 79.0 / 4096.0).abs() < 1e-12);
        assert_eq!(mcnemar(0, 0), 1.0);
    }
}
