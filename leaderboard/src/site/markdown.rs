//! The site's Markdown renderer: the exports of its tables, `ranking.md` (a table per group of
//! comparable conditions) and `tasks/<slug>.md` (a task's rows), cells made safe for a table.
//!
//! It turns the view model ([`super::model`]) into text; it computes no figure, writes no file,
//! and renders only the ranking and task tables (charts, paired comparisons, the paper's
//! reference and submission pages are the HTML's and the JSON exports').

use super::model::{Site, TaskPage};
use super::{across_cell, change_cell, interval_cell, level_cell, rank_sem_cells, spread_cells};
use std::fmt::Write as _;

/// `ranking.md`.
pub(super) fn ranking(site: &Site) -> String {
    let mut md = String::from("# autobio leaderboard\n");
    for g in &site.groups {
        let _ = write!(
            md,
            "\n## {}\n\n| # | model | training | observation | standing | success % | ± SEM over training seeds | ± SEM over evaluation runs | easy | medium | hard | mean score |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n",
            md_cell(&g.name)
        );
        for r in &g.rows {
            let sem = rank_sem_cells(r);
            let _ = writeln!(
                md,
                "| {} | {} | {} | {} | {} | {:.1} | {} | {} | {} | {} | {} | {:.3} |",
                r.rank,
                md_cell(&r.model),
                md_cell(&r.training),
                md_cell(&r.observation),
                r.standing,
                r.success,
                sem[0],
                sem[1],
                level_cell(r, "easy"),
                level_cell(r, "medium"),
                level_cell(r, "hard"),
                r.mean_score
            );
        }
        if let Some(r) = &g.robustness {
            let _ = write!(
                md,
                "\nRobustness: success under each perturbation [Wilson 95%], and the change from clean over the same tasks [Newcombe 95%].\n\n| model | clean % |{}\n|---|---|{}\n",
                r.presets
                    .iter()
                    .map(|p| format!(" {} |", md_cell(p)))
                    .collect::<String>(),
                "---|".repeat(r.presets.len())
            );
            for row in &r.rows {
                let cells: String = row
                    .cells
                    .iter()
                    .map(|c| match c {
                        Some(c) => format!(
                            " {}, {} |",
                            interval_cell(c.success, c.wilson),
                            change_cell(c)
                        ),
                        None => " – |".into(),
                    })
                    .collect();
                let _ = writeln!(
                    md,
                    "| {} | {} |{cells}",
                    md_cell(&row.model),
                    interval_cell(row.clean.0, row.clean.1)
                );
            }
        }
    }
    md
}

/// `tasks/<slug>.md`.
pub(super) fn task(p: &TaskPage) -> String {
    let mut md = format!(
        "# {}\n\n| model | group | standing | success % | Wilson 95% | mean score | training seeds: mean ± SEM | evaluation runs: mean ± SEM |\n|---|---|---|---|---|---|---|---|\n",
        p.id
    );
    for r in &p.rows {
        let across = spread_cells(r.spread, across_cell(r.across_runs));
        let _ = writeln!(
            md,
            "| {} | {} | {} | {:.1} | [{:.1}, {:.1}] | {:.3} | {} | {} |",
            md_cell(&r.model),
            md_cell(&r.group),
            r.standing,
            r.success,
            r.wilson[0],
            r.wilson[1],
            r.mean_score,
            across[0],
            across[1]
        );
    }
    md
}

/// Text for a Markdown table cell: no cell breaks, no line breaks, no raw HTML.
fn md_cell(s: &str) -> String {
    s.replace('|', "\\|")
        .replace(['\n', '\r'], " ")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}
