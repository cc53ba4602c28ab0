//! Statistics over episodes: the success rate with its SEM and Wilson 95% interval, the mean
//! score, counts per outcome, per-run figures and, over several runs, their mean ± SEM (as the
//! paper reports over training seeds).
//!
//! It reads finished episodes only; it does not run or store anything.

use crate::episode::{EpisodeResult, Outcome};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EvalSummary {
    pub episodes: usize,
    pub successes: usize,
    pub success_rate: f64,
    /// Standard error of the mean success rate.
    pub sem: f64,
    /// Wilson score interval of the success rate at 95% (z = 1.96): honest at 0 and 100%,
    /// where the SEM is 0.
    pub wilson_95: [f64; 2],
    /// Mean episode score (binary or progress, averaged over stages).
    pub mean_score: f64,
    /// Episodes per outcome; all of them are in the denominator.
    pub outcomes: BTreeMap<Outcome, usize>,
    /// The run's wall time (for merged shards: the sum of the shards' episode times).
    pub wall_time_s: f64,
    /// Each run's figures (`--runs`; one run otherwise).
    #[serde(default)]
    pub runs: Vec<RunSummary>,
    /// Over two or more runs: the mean of the runs' figures ± their SEM.
    #[serde(default)]
    pub across_runs: Option<AcrossRuns>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunSummary {
    pub run: u32,
    pub episodes: usize,
    pub success_rate: f64,
    pub mean_score: f64,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AcrossRuns {
    pub runs: usize,
    pub success_rate_mean: f64,
    /// Sample standard deviation of the runs' success rates over √runs.
    pub success_rate_sem: f64,
    pub mean_score_mean: f64,
    pub mean_score_sem: f64,
}

/// Tasks grouped (by level, or all of them): the mean over tasks of each task's success rate and
/// mean score, as benchmark tables report them.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Aggregate {
    /// `level <name>` or `overall`.
    pub group: String,
    pub tasks: usize,
    pub episodes: usize,
    pub success_rate: f64,
    pub mean_score: f64,
}

/// Per level (in order of first appearance) and overall, over `(level, summary)` per task.
pub fn aggregate<'a>(
    tasks: impl IntoIterator<Item = (&'a str, &'a EvalSummary)>,
) -> Vec<Aggregate> {
    let tasks: Vec<(&str, &EvalSummary)> = tasks.into_iter().collect();
    let group = |name: String, members: Vec<&EvalSummary>| {
        let n = members.len().max(1) as f64;
        Aggregate {
            group: name,
            tasks: members.len(),
            episodes: members.iter().map(|s| s.episodes).sum(),
            success_rate: members.iter().map(|s| s.success_rate).sum::<f64>() / n,
            mean_score: members.iter().map(|s| s.mean_score).sum::<f64>() / n,
        }
    };
    let mut levels: Vec<&str> = Vec::new();
    for (level, _) in &tasks {
        if !levels.contains(level) {
            levels.push(level);
        }
    }
    let mut out: Vec<Aggregate> = levels
        .iter()
        .map(|l| {
            let members = tasks
                .iter()
                .filter(|(tl, _)| tl == l)
                .map(|(_, s)| *s)
                .collect();
            group(format!("level {l}"), members)
        })
        .collect();
    out.push(group(
        "overall".into(),
        tasks.iter().map(|(_, s)| *s).collect(),
    ));
    out
}

/// The Wilson score interval for `k` successes in `n` trials at normal quantile `z`.
pub fn wilson(k: usize, n: usize, z: f64) -> [f64; 2] {
    if n == 0 {
        return [0.0, 1.0];
    }
    let (n, p) = (n as f64, k as f64 / n as f64);
    let z2 = z * z;
    let centre = (p + z2 / (2.0 * n)) / (1.0 + z2 / n);
    let half = z * (p * (1.0 - p) / n + z2 / (4.0 * n * n)).sqrt() / (1.0 + z2 / n);
    [(centre - half).max(0.0), (centre + half).min(1.0)]
}

/// Mean and standard error of the mean (sample standard deviation / √n; 0 below two values).
pub fn mean_sem(xs: &[f64]) -> (f64, f64) {
    let n = xs.len() as f64;
    if xs.is_empty() {
        return (0.0, 0.0);
    }
    let mean = xs.iter().sum::<f64>() / n;
    if xs.len() < 2 {
        return (mean, 0.0);
    }
    let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt())
}

pub fn summarise(episodes: &[EpisodeResult], wall: f64) -> EvalSummary {
    let n = episodes.len();
    let k = episodes.iter().filter(|e| e.success).count();
    let p = if n > 0 { k as f64 / n as f64 } else { 0.0 };
    let sem = if n > 1 {
        (p * (1.0 - p) / (n as f64 - 1.0)).sqrt()
    } else {
        0.0
    };
    let mean_score = |eps: &[&EpisodeResult]| {
        if eps.is_empty() {
            0.0
        } else {
            eps.iter().map(|e| e.verdict.score).sum::<f64>() / eps.len() as f64
        }
    };
    let mut by_run: BTreeMap<u32, Vec<&EpisodeResult>> = BTreeMap::new();
    for e in episodes {
        by_run.entry(e.run).or_default().push(e);
    }
    let runs: Vec<RunSummary> = by_run
        .iter()
        .map(|(&run, eps)| RunSummary {
            run,
            episodes: eps.len(),
            success_rate: eps.iter().filter(|e| e.success).count() as f64 / eps.len() as f64,
            mean_score: mean_score(eps),
        })
        .collect();
    let across_runs = (runs.len() > 1).then(|| {
        let rates: Vec<f64> = runs.iter().map(|r| r.success_rate).collect();
        let scores: Vec<f64> = runs.iter().map(|r| r.mean_score).collect();
        let ((rm, rs), (sm, ss)) = (mean_sem(&rates), mean_sem(&scores));
        AcrossRuns {
            runs: runs.len(),
            success_rate_mean: rm,
            success_rate_sem: rs,
            mean_score_mean: sm,
            mean_score_sem: ss,
        }
    });
    EvalSummary {
        episodes: n,
        successes: k,
        success_rate: p,
        sem,
        wilson_95: wilson(k, n, 1.96),
        mean_score: mean_score(&episodes.iter().collect::<Vec<_>>()),
        outcomes: episodes.iter().fold(Default::default(), |mut m, e| {
            *m.entry(e.outcome).or_insert(0) += 1;
            m
        }),
        wall_time_s: wall,
        runs,
        across_runs,
    }
}

#[cfg(test)]
mod tests {
    use super::{mean_sem, wilson};

    #[test]
    fn wilson_intervals_match_the_formula_at_the_edges_and_the_middle() {
        // Reference values at z = 1.96 (e.g. Newcombe 1998, method 3).
        for (k, n, want) in [
            (0, 20, [0.0, 0.1611]),
            (20, 20, [0.8389, 1.0]),
            (10, 20, [0.2993, 0.7007]),
            (81, 263, [0.2553, 0.3662]),
        ] {
            let got = wilson(k, n, 1.96);
            assert!(
                (got[0] - want[0]).abs() < 5e-4 && (got[1] - want[1]).abs() < 5e-4,
                "{k}/{n}: {got:?}"
            );
        }
        assert_eq!(wilson(0, 0, 1.96), [0.0, 1.0]);
    }

    #[test]
    fn levels_and_overall_are_means_over_tasks() {
        let s = |rate: f64, episodes: usize| super::EvalSummary {
            episodes,
            successes: (rate * episodes as f64) as usize,
            success_rate: rate,
            sem: 0.0,
            wilson_95: [0.0, 1.0],
            mean_score: rate,
            outcomes: Default::default(),
            wall_time_s: 0.0,
            runs: vec![],
            across_runs: None,
        };
        let (a, b, c) = (s(1.0, 10), s(0.5, 20), s(0.0, 4));
        let g = super::aggregate([("easy", &a), ("hard", &b), ("easy", &c)]);
        let got: Vec<(&str, usize, usize, f64)> = g
            .iter()
            .map(|g| (g.group.as_str(), g.tasks, g.episodes, g.success_rate))
            .collect();
        assert_eq!(
            got,
            [
                ("level easy", 2, 14, 0.5),
                ("level hard", 1, 20, 0.5),
                ("overall", 3, 34, 0.5)
            ]
        );
    }

    #[test]
    fn mean_and_sem_of_run_rates() {
        // 0.9, 0.8, 1.0: mean 0.9, sample sd 0.1, SEM 0.1/√3.
        let (m, s) = mean_sem(&[0.9, 0.8, 1.0]);
        assert!(
            (m - 0.9).abs() < 1e-12 && (s - 0.1 / 3f64.sqrt()).abs() < 1e-12,
            "{m} {s}"
        );
        assert_eq!(mean_sem(&[0.5]), (0.5, 0.0));
        assert_eq!(mean_sem(&[]), (0.0, 0.0));
    }
}
