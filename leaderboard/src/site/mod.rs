//! The leaderboard site: every bundle in a folder turned into static pages (`autobio leaderboard
//! build DIR --out SITE`). A bundle's standing comes from the operator's records beside it
//! (`<bundle>.verification.json`, `<bundle>.audit.json`, written by `verify` and `audit` for
//! that bundle's exact bytes): **audited** (verified, and its live model consistent with it),
//! **verified**, or **reported** (not verified here); a refused bundle is listed with its
//! reasons, never ranked. The paper's own results ship as a reference entry, "reported by the
//! paper, not re-run".
//!
//! Pages: an overall ranking per suite and conditions (results under another suite, autobio
//! version or model profile are never averaged together; a robustness suite's group also shows
//! success per perturbation preset and the drop from clean, `robustness.rs`, `robustness.json`), a page per task (success with its
//! Wilson 95% interval, mean score, mean ± SEM across runs, a chart with error bars, and paired
//! McNemar tests between submissions on the same seeds), a page per submission (conditions,
//! standing, every episode's outcome), and JSON and Markdown exports of each table. Same inputs,
//! same bytes; no page requests anything from the network.
//!
//! How it is built: [`load()`] reads the bundles into [`Submission`]s; [`model::Site::of`]
//! computes once everything the site shows (rankings, task tables, charts, paired comparisons,
//! the paper's reference, submission pages) as plain data; two renderers, `html` and
//! `markdown`, turn that one model into pages and table exports; and [`build`] writes them, the
//! JSON exports and the drawn frames.
//!
//! It reads bundles and records; it runs and verifies nothing.

mod chart;
mod html;
mod load;
mod markdown;
pub mod model;
mod paper;
pub mod robustness;
mod stats;

pub use load::{Record, Standing, Submission, TaskResult, load, record_path, write_record};
pub use paper::{Reference, ReferenceChain, ReferenceEntry, ReferenceScore, paper};
pub use stats::{Paired, RankRow, mcnemar, paired_over_suite, rankings};

use model::{Frames, Site, SubmissionPage, TaskPage};
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Draws a few frames (PNG) of a recording, for a submission's page; the caller's, as this
/// crate links no renderer.
pub type DrawFrames<'a> = dyn Fn(&Path) -> Result<Vec<Vec<u8>>, String> + 'a;

/// Why the site could not be built.
#[derive(Debug, thiserror::Error)]
pub enum SiteError {
    // The OS error is part of the message and not a `source`: a chain of causes prints it once.
    #[error("cannot {doing} {path}: {why}")]
    Io {
        doing: &'static str,
        path: PathBuf,
        why: std::io::Error,
    },
}

fn io(doing: &'static str, path: &Path) -> impl FnOnce(std::io::Error) -> SiteError {
    let path = path.to_path_buf();
    move |why| SiteError::Io { doing, path, why }
}

/// A name for a file: lowercase ASCII letters and digits, other runs of characters one `-`.
fn slug(text: &str) -> String {
    let s: String = text
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() {
                c.to_ascii_lowercase()
            } else {
                '-'
            }
        })
        .collect();
    s.split('-')
        .filter(|p| !p.is_empty())
        .collect::<Vec<_>>()
        .join("-")
}

/// A ranking row's success on one level (percent), `–` where it ran no task of that level:
/// the same cell in HTML and in Markdown.
fn level_cell(r: &RankRow, level: &str) -> String {
    r.by_level
        .get(level)
        .map_or("–".to_string(), |v| format!("{v:.1}"))
}

/// Mean ± SEM across runs (percent), `–` for a single run: the same cell in HTML and Markdown.
fn across_cell(across: Option<(f64, f64)>) -> String {
    across.map_or("–".to_string(), |(mean, sem)| {
        format!("{mean:.1} ± {sem:.1}")
    })
}

/// A percentage with its interval, `62.0 [55.1, 68.4]`: the same cell in HTML and Markdown.
fn interval_cell(value: f64, [lo, hi]: [f64; 2]) -> String {
    format!("{value:.1} [{lo:.1}, {hi:.1}]")
}

/// A robustness cell's change from clean with its interval, negative for a drop
/// (`-5.0 [-12.1, +2.0]`; never a negative zero).
fn change_cell(c: &robustness::RobustCell) -> String {
    let [lo, hi] = c.drop_interval;
    format!("{:+.1} [{:+.1}, {:+.1}]", 0.0 - c.drop, 0.0 - hi, 0.0 - lo)
}

/// The two ± columns, over training seeds and over evaluation runs of one model: `cell` in the
/// one its runs are, `–` in the other (the two are never one column).
fn spread_cells(over: load::Spread, cell: String) -> [String; 2] {
    match over {
        load::Spread::TrainingSeeds => [cell, "–".into()],
        load::Spread::EvaluationRuns => ["–".into(), cell],
    }
}

/// A ranking row's ± cells (see [`spread_cells`]): its SEM over two or more runs, else `–`.
fn rank_sem_cells(r: &stats::RankRow) -> [String; 2] {
    let cell = if r.runs > 1 {
        format!("{:.1}", r.sem)
    } else {
        "–".into()
    };
    spread_cells(r.spread, cell)
}

/// Writes the site for `subs` into `out` (made if missing); with `frames`, each submission's
/// page shows frames of its best and worst episode of every task. Returns the files written.
pub fn build(
    subs: &[Submission],
    out: &Path,
    frames: Option<&DrawFrames>,
) -> Result<Vec<PathBuf>, SiteError> {
    let mut site = Site::of(subs);
    let mut files = Files {
        out,
        written: Vec::new(),
    };
    files.write("index.html", html::index(&site).as_bytes())?;
    files.write("ranking.md", markdown::ranking(&site).as_bytes())?;
    let ranks: BTreeMap<&str, &Vec<RankRow>> = site
        .groups
        .iter()
        .map(|g| (g.name.as_str(), &g.rows))
        .collect();
    files.write("ranking.json", &json(&ranks))?;
    // A robustness suite's tables, by group (only where a group's suite names presets).
    let robust: BTreeMap<&str, &robustness::Robustness> = site
        .groups
        .iter()
        .filter_map(|g| Some((g.name.as_str(), g.robustness.as_ref()?)))
        .collect();
    if !robust.is_empty() {
        files.write("robustness.json", &json(&robust))?;
    }
    files.write("reference.json", &json(&site.reference))?;
    for page in &site.tasks {
        let file = &page.slug;
        files.write(&format!("tasks/{file}.html"), html::task(page).as_bytes())?;
        files.write(&format!("tasks/{file}.md"), markdown::task(page).as_bytes())?;
        files.write(&format!("tasks/{file}.json"), &task_json(page))?;
    }
    for page in &mut site.submissions {
        if let Some(draw) = frames {
            draw_shots(page, draw, &mut files)?;
        }
        files.write(
            &format!("submissions/{}.html", page.slug),
            html::submission(page).as_bytes(),
        )?;
    }
    Ok(files.written)
}

/// The site's folder, and the files written into it so far.
struct Files<'a> {
    out: &'a Path,
    written: Vec<PathBuf>,
}

impl Files<'_> {
    /// Writes one file of the site (its path relative to the site's folder).
    fn write(&mut self, rel: &str, bytes: &[u8]) -> Result<(), SiteError> {
        let path = self.out.join(rel);
        if let Some(p) = path.parent() {
            std::fs::create_dir_all(p).map_err(io("create", p))?;
        }
        std::fs::write(&path, bytes).map_err(io("write", &path))?;
        self.written.push(path);
        Ok(())
    }
}

/// Draws each shot of a submission's page from its recording and writes the frames beside the
/// page (`submissions/<slug>/<task>-<label>-<k>.png`); a recording that does not draw is noted
/// on the page.
fn draw_shots(
    page: &mut SubmissionPage,
    draw: &DrawFrames,
    files: &mut Files,
) -> Result<(), SiteError> {
    for t in &mut page.tasks {
        for shot in &mut t.shots {
            shot.frames = Some(match draw(&shot.recording) {
                Ok(pngs) => {
                    let mut names = Vec::new();
                    for (k, png) in pngs.iter().enumerate() {
                        let name = format!("{}/{}-{}-{k}.png", page.slug, t.slug, shot.label);
                        files.write(&format!("submissions/{name}"), png)?;
                        names.push(name);
                    }
                    Frames::Drawn(names)
                }
                Err(why) => Frames::Failed(why),
            });
        }
    }
    Ok(())
}

/// Pretty JSON with a final newline.
fn json(value: &impl Serialize) -> Vec<u8> {
    (serde_json::to_string_pretty(value).unwrap_or_default() + "\n").into_bytes()
}

/// `tasks/<slug>.json`: the task's rows with their summaries, and its paired comparisons.
fn task_json(page: &TaskPage) -> Vec<u8> {
    let rows: Vec<serde_json::Value> = page
        .rows
        .iter()
        .map(|r| {
            serde_json::json!({
                "model": r.model, "group": r.group, "standing": r.standing,
                "summary": r.summary,
            })
        })
        .collect();
    json(&serde_json::json!({"task": page.id, "rows": rows, "paired": page.paired}))
}
