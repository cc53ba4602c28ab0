//! The online audit's statistics: is a live model server's success rate on fresh seeds
//! consistent with the rate its bundle claims? Re-enacting a bundle proves its episodes are
//! physically real, not that the model produced them (the expert's actions re-enact too); an
//! audit asks the model again on seeds the submitter could not know.
//!
//! Per task, a one-sided Fisher exact test of "the audited rate is below the claimed one"; over
//! the suite, the same test on the pooled counts. The decision rule: inconsistent when the pooled
//! p-value is below [`ALPHA`], or any task's is below `ALPHA / tasks` (Bonferroni). It computes;
//! running the audit's episodes is the caller's.

use serde::Serialize;

/// The audit's significance level.
pub const ALPHA: f64 = 0.01;

/// Successes out of episodes.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Count {
    pub successes: u64,
    pub episodes: u64,
}

impl Count {
    pub fn rate(&self) -> f64 {
        self.successes as f64 / self.episodes.max(1) as f64
    }
}

/// One task's claimed and audited counts and the test's p-value.
#[derive(Clone, Debug, Serialize)]
pub struct TaskAudit {
    pub task: String,
    pub claimed: Count,
    pub audited: Count,
    pub p_value: f64,
}

/// The whole audit.
#[derive(Clone, Debug, Serialize)]
pub struct Audit {
    pub tasks: Vec<TaskAudit>,
    pub pooled_claimed: Count,
    pub pooled_audited: Count,
    pub pooled_p_value: f64,
    pub consistent: bool,
    pub rule: String,
}

/// Compares claimed and audited counts per task (see the module doc).
pub fn audit(tasks: Vec<(String, Count, Count)>) -> Audit {
    let n = tasks.len().max(1) as f64;
    let mut pooled = (
        Count {
            successes: 0,
            episodes: 0,
        },
        Count {
            successes: 0,
            episodes: 0,
        },
    );
    let tasks: Vec<TaskAudit> = tasks
        .into_iter()
        .map(|(task, claimed, audited)| {
            pooled.0.successes += claimed.successes;
            pooled.0.episodes += claimed.episodes;
            pooled.1.successes += audited.successes;
            pooled.1.episodes += audited.episodes;
            TaskAudit {
                task,
                claimed,
                audited,
                p_value: fisher_lower(claimed, audited),
            }
        })
        .collect();
    let pooled_p_value = fisher_lower(pooled.0, pooled.1);
    let consistent = pooled_p_value >= ALPHA && tasks.iter().all(|t| t.p_value >= ALPHA / n);
    Audit {
        rule: format!(
            "one-sided Fisher exact test (audited rate below claimed); inconsistent if the pooled \
             p < {ALPHA} or any task's p < {ALPHA}/{} (Bonferroni)",
            tasks.len()
        ),
        tasks,
        pooled_claimed: pooled.0,
        pooled_audited: pooled.1,
        pooled_p_value,
        consistent,
    }
}

/// What a bundle claims per task: successes out of episodes, over every run folder's journal.
pub fn claimed(
    bundle: &crate::bundle::Unpacked,
) -> Result<std::collections::BTreeMap<String, Count>, results::run::RunError> {
    let mut out: std::collections::BTreeMap<String, Count> = Default::default();
    for member in &bundle.members {
        let Some(task) = member
            .strip_prefix("runs/")
            .and_then(|m| m.split_once('/'))
            .and_then(|(_, f)| f.strip_suffix(".journal.jsonl"))
        else {
            continue;
        };
        let episodes = results::run::record::read_journal_only(&bundle.root.join(member))?;
        let c = out.entry(task.to_string()).or_insert(Count {
            successes: 0,
            episodes: 0,
        });
        c.episodes += episodes.len() as u64;
        c.successes += episodes.iter().filter(|e| e.success).count() as u64;
    }
    Ok(out)
}

/// ln(k!) for every k up to `n`.
fn ln_factorials(n: u64) -> Vec<f64> {
    let mut t = vec![0.0; n as usize + 1];
    for k in 1..=n as usize {
        t[k] = t[k - 1] + (k as f64).ln();
    }
    t
}

/// One-sided Fisher exact test: the probability, with the margins fixed, that the audited
/// sample has at most as many successes as it had (small when the audited rate is well below
/// the claimed one).
pub fn fisher_lower(claimed: Count, audited: Count) -> f64 {
    let total = claimed.episodes + audited.episodes;
    let successes = claimed.successes + audited.successes;
    let draws = audited.episodes;
    let lf = ln_factorials(total);
    let ln_choose = |n: u64, k: u64| lf[n as usize] - lf[k as usize] - lf[(n - k) as usize];
    let lo = draws.saturating_sub(total - successes);
    let hi = audited.successes.min(successes);
    let denominator = ln_choose(total, draws);
    let p: f64 = (lo..=hi)
        .map(|x| {
            (ln_choose(successes, x) + ln_choose(total - successes, draws - x) - denominator).exp()
        })
        .sum();
    p.min(1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn c(successes: u64, episodes: u64) -> Count {
        Count {
            successes,
            episodes,
        }
    }

    #[test]
    fn fisher_matches_hand_computed_tables() {
        // 2/2 claimed, 0/4 audited: 1 of C(6,2) = 15 tables is as extreme.
        assert!((fisher_lower(c(2, 2), c(0, 4)) - 1.0 / 15.0).abs() < 1e-12);
        // 8/8 against 0/8: 1 / C(16, 8) = 1/12870.
        assert!((fisher_lower(c(8, 8), c(0, 8)) - 1.0 / 12870.0).abs() < 1e-15);
        // The same rate is no evidence at all; a higher audited rate even less.
        assert_eq!(fisher_lower(c(8, 8), c(8, 8)), 1.0);
        assert_eq!(fisher_lower(c(0, 8), c(8, 8)), 1.0);
        // 3/10 claimed, 1/10 audited: P(X <= 1), X ~ Hypergeometric(20, 4, 10) = (C(4,0)C(16,10)
        // + C(4,1)C(16,9)) / C(20,10) = (8008 + 45760) / 184756.
        let want = (8008.0 + 45760.0) / 184756.0;
        assert!((fisher_lower(c(3, 10), c(1, 10)) - want).abs() < 1e-12);
    }

    #[test]
    fn the_rule_flags_a_rate_far_below_the_claim() {
        let a = audit(vec![("t".into(), c(8, 8), c(0, 8))]);
        assert!(!a.consistent);
        let a = audit(vec![("t".into(), c(8, 8), c(7, 8))]);
        assert!(a.consistent, "{a:?}");
    }
}
