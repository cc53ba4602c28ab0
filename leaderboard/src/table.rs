//! The results tables as text: one row per task (success rate ± SEM, its Wilson 95% interval,
//! mean score, episodes, wall time), then, over several tasks, the mean per level and overall,
//! and over several runs, each task's per-run rates with their mean ± SEM.

use results::run::EvalReport;
use results::run::stats::aggregate;
use std::fmt::Write;

/// One row per task.
pub fn results_table(rows: &[EvalReport]) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "{:<32} {:>7} {:>16} {:>14} {:>6} {:>9} {:>10}",
        "task", "policy", "success (±SEM)", "Wilson 95%", "score", "episodes", "wall time"
    );
    for r in rows {
        let s = &r.summary;
        let _ = writeln!(
            out,
            "{:<32} {:>7} {:>8.1}% ± {:>4.1} [{:>5.1}, {:>5.1}] {:>6.3} {:>9} {:>9.1}s",
            r.task_id,
            r.policy.split(' ').next().unwrap_or_default(),
            100.0 * s.success_rate,
            100.0 * s.sem,
            100.0 * s.wilson_95[0],
            100.0 * s.wilson_95[1],
            s.mean_score,
            s.episodes,
            s.wall_time_s
        );
    }
    out
}

/// Over several tasks, the mean per level and overall; over several runs, each task's per-run
/// success rates and their mean ± SEM. Empty for one task of one run.
pub fn runs_table(rows: &[EvalReport]) -> String {
    let mut out = String::new();
    if rows.len() > 1 {
        for g in aggregate(rows.iter().map(|r| (r.level.as_str(), &r.summary))) {
            let _ = writeln!(
                out,
                "{:<32} {:>7} {:>8.1}% (mean over {} tasks, {} episodes), score {:.3}",
                g.group,
                "",
                100.0 * g.success_rate,
                g.tasks,
                g.episodes,
                g.mean_score
            );
        }
    }
    for r in rows {
        if let Some(a) = &r.summary.across_runs {
            let each: Vec<String> = r
                .summary
                .runs
                .iter()
                .map(|x| format!("{:.1}%", 100.0 * x.success_rate))
                .collect();
            let _ = writeln!(
                out,
                "{}: {} runs ({}): success {:.1}% ± {:.1} (mean ± SEM over runs), score {:.3} ± {:.3}",
                r.task_id,
                a.runs,
                each.join(", "),
                100.0 * a.success_rate_mean,
                100.0 * a.success_rate_sem,
                a.mean_score_mean,
                a.mean_score_sem
            );
        }
    }
    out
}
