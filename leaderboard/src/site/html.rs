//! The site's HTML renderer: the front page (rankings, tasks, the paper's reference, refused
//! submissions), a page per task and a page per submission, each a self-contained page (inline
//! style and SVG charts, nothing requested from the network), all text escaped.
//!
//! It turns the view model ([`super::model`]) into text; it computes no figure and writes no
//! file (frames are drawn and written by [`super::build`] before a submission's page is
//! rendered).

use super::chart::chart;
use super::model::{EpisodeTable, Frames, Group, Site, SubmissionPage, TaskPage, TaskRow};
use super::paper::Reference;
use super::stats::Paired;
use super::{across_cell, level_cell, rank_sem_cells, spread_cells};
use std::fmt::Write as _;

/// `index.html`.
pub(super) fn index(site: &Site) -> String {
    let mut body = String::new();
    for g in &site.groups {
        ranking(&mut body, g);
    }
    body.push_str("<h2>Tasks</h2><ul>");
    for t in &site.tasks {
        let _ = write!(
            body,
            "<li><a href=\"tasks/{}.html\">{}</a></li>",
            t.slug,
            esc(&t.id)
        );
    }
    body.push_str("</ul>");
    reference(&mut body, &site.reference);
    if !site.refused.is_empty() {
        body.push_str("<h2>Refused</h2><ul>");
        for r in &site.refused {
            let _ = write!(
                body,
                "<li class=refused>{} ({}): {}</li>",
                esc(&r.model),
                esc(&r.file),
                esc(&r.reasons.join("; "))
            );
        }
        body.push_str("</ul>");
    }
    page("autobio leaderboard", 0, &body)
}

/// One group's ranking table, its chart and its paired comparisons.
fn ranking(body: &mut String, g: &Group) {
    let _ = write!(
        body,
        "<h2>{}</h2><table><tr><th>#</th><th>model</th><th>training</th><th>observation</th><th>standing</th>\
         <th>success %</th><th>± SEM over training seeds</th><th>± SEM over evaluation runs</th>\
         <th>easy</th><th>medium</th><th>hard</th><th>mean score</th></tr>",
        esc(&g.name)
    );
    for r in &g.rows {
        let sem = rank_sem_cells(r);
        let _ = write!(
            body,
            "<tr><td>{}</td><td class=l><a href=\"{}\">{}</a></td><td class=l>{}</td><td class=l>{}</td><td class=\"l {}\">{}</td>\
             <td>{:.1}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{:.3}</td></tr>",
            r.rank,
            r.page,
            esc(&r.model),
            esc(&r.training),
            esc(&r.observation),
            r.standing,
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
    body.push_str("</table>");
    body.push_str(&chart(&g.chart));
    if !g.paired.is_empty() {
        body.push_str("<h3>Paired over the suite (same tasks and seeds, exact McNemar)</h3>");
        body.push_str(&paired_table(&g.paired));
    }
    if let Some(r) = &g.robustness {
        robustness(body, r);
    }
}

/// A robustness suite's table: clean success, then per preset its success and the drop from
/// clean over the same tasks, each with its 95% interval.
fn robustness(body: &mut String, r: &super::robustness::Robustness) {
    body.push_str(
        "<h3>Robustness: success under each perturbation (Wilson 95%) and its change from clean \
         over the same tasks, negative for a drop (Newcombe 95%)</h3><table class=robustness><tr><th>model</th><th>clean %</th>",
    );
    for p in &r.presets {
        let _ = write!(body, "<th>{}</th>", esc(p));
    }
    body.push_str("</tr>");
    for row in &r.rows {
        let _ = write!(
            body,
            "<tr><td class=l><a href=\"submissions/{}.html\">{}</a></td><td>{}</td>",
            row.submission,
            esc(&row.model),
            super::interval_cell(row.clean.0, row.clean.1)
        );
        for c in &row.cells {
            match c {
                Some(c) => {
                    let _ = write!(
                        body,
                        "<td>{}<br>change {}</td>",
                        super::interval_cell(c.success, c.wilson),
                        super::change_cell(c)
                    );
                }
                None => body.push_str("<td>–</td>"),
            }
        }
        body.push_str("</tr>");
    }
    body.push_str("</table>");
}

/// The paper's tables: its per-task scores and its long-horizon (concatenation) table.
fn reference(body: &mut String, reference: &Reference) {
    let _ = write!(
        body,
        "<h2>Reference: reported by the paper, not re-run</h2><p><small>{}. Score in percent; \
         tasks without an autobio id do not ship yet.</small></p><table><tr><th>model</th><th>training</th>",
        esc(&reference.source)
    );
    for t in reference.entry.first().map_or(&[][..], |e| &e.scores) {
        let _ = write!(body, "<th>{}</th>", esc(&t.task));
    }
    body.push_str("</tr>");
    for e in &reference.entry {
        let _ = write!(
            body,
            "<tr><td class=l>{}</td><td class=l>{}</td>",
            esc(&e.model),
            esc(&e.training)
        );
        for s in &e.scores {
            let _ = write!(body, "<td>{:.1} ± {:.1}</td>", s.mean, s.sem);
        }
        body.push_str("</tr>");
    }
    body.push_str("</table>");
    if !reference.notes.is_empty() {
        body.push_str("<ul>");
        for n in &reference.notes {
            let _ = write!(body, "<li><small>{}</small></li>", esc(n));
        }
        body.push_str("</ul>");
    }
    body.push_str(
        "<h3>Long horizon (the paper's concatenation table)</h3><table><tr><th>model</th>",
    );
    for s in reference.chain.first().map_or(&[][..], |c| &c.stages) {
        let _ = write!(body, "<th>{}</th>", esc(&s.task));
    }
    body.push_str("</tr>");
    for c in &reference.chain {
        let _ = write!(body, "<tr><td class=l>{}</td>", esc(&c.model));
        for s in &c.stages {
            let _ = write!(body, "<td>{:.1} ± {:.1}</td>", s.mean, s.sem);
        }
        body.push_str("</tr>");
    }
    body.push_str("</table>");
}

/// `tasks/<slug>.html`.
pub(super) fn task(p: &TaskPage) -> String {
    let mut body = format!("<p>level: {}</p>", esc(&p.level));
    body.push_str("<table><tr><th>model</th><th>conditions</th><th>standing</th><th>success %</th><th>Wilson 95%</th><th>mean score</th><th>training seeds: mean ± SEM</th><th>evaluation runs: mean ± SEM</th></tr>");
    for r in &p.rows {
        task_row(&mut body, r);
    }
    body.push_str("</table>");
    body.push_str(&chart(&p.chart));
    if let Some(t) = &p.stages {
        body.push_str("<h2>Stage by stage</h2><table><tr><th>model</th>");
        for id in &t.stages {
            let _ = write!(body, "<th>{}</th>", esc(id));
        }
        body.push_str("</tr>");
        for (model, done) in &t.rows {
            let _ = write!(body, "<tr><td class=l>{}</td>", esc(model));
            for d in done {
                let _ = write!(body, "<td>{d:.1}</td>");
            }
            body.push_str("</tr>");
        }
        body.push_str("</table>");
    }
    if !p.paired.is_empty() {
        body.push_str("<h2>Paired comparisons (same seeds, exact McNemar)</h2>");
        body.push_str(&paired_table(&p.paired));
    }
    if !p.reference.is_empty() {
        body.push_str("<h2>Reported by the paper, not re-run</h2><table><tr><th>model</th><th>training</th><th>score %</th></tr>");
        for r in &p.reference {
            let _ = write!(
                body,
                "<tr><td class=l>{}</td><td class=l>{}</td><td>{:.1} ± {:.1}</td></tr>",
                esc(&r.model),
                esc(&r.training),
                r.mean,
                r.sem
            );
        }
        body.push_str("</table>");
    }
    page(&p.id, 1, &body)
}

fn task_row(body: &mut String, r: &TaskRow) {
    let across = spread_cells(r.spread, across_cell(r.across_runs));
    let _ = write!(
        body,
        "<tr><td class=l><a href=\"../submissions/{}.html\">{}</a></td><td class=l><small>{}</small></td><td class=\"l {}\">{}</td>\
         <td>{:.1}</td><td>[{:.1}, {:.1}]</td><td>{:.3}</td><td>{}</td><td>{}</td></tr>",
        r.submission,
        esc(&r.model),
        esc(&r.group),
        r.standing,
        r.standing,
        r.success,
        r.wilson[0],
        r.wilson[1],
        r.mean_score,
        across[0],
        across[1]
    );
}

/// `submissions/<slug>.html`.
pub(super) fn submission(p: &SubmissionPage) -> String {
    let mut body = format!(
        "<p class=\"{}\">standing: <b>{}</b></p><table>",
        p.standing, p.standing
    );
    for (k, v) in &p.facts {
        let _ = write!(
            body,
            "<tr><td class=l>{k}</td><td class=l>{}</td></tr>",
            esc(v)
        );
    }
    body.push_str("</table>");
    if let Some(why) = &p.refused {
        body.push_str("<h2>Why it is refused</h2><ul>");
        for w in why {
            let _ = write!(body, "<li>{}</li>", esc(w));
        }
        body.push_str("</ul>");
    }
    for t in &p.tasks {
        episodes(&mut body, t);
    }
    page(&p.model, 1, &body)
}

/// A task of a submission: the frames drawn of its best and worst episode, and every episode.
fn episodes(body: &mut String, t: &EpisodeTable) {
    for s in &t.shots {
        let Some(frames) = &s.frames else { continue };
        let label = s.label;
        let _ = write!(
            body,
            "<p>{label} episode: run {}, seed {}, score {:.3}</p><p>",
            s.run, s.seed, s.score
        );
        match frames {
            Frames::Drawn(names) => {
                for (k, name) in names.iter().enumerate() {
                    let _ = write!(
                        body,
                        "<img src=\"{name}\" alt=\"{label} episode, frame {k}\" width=224 height=224> "
                    );
                }
            }
            Frames::Failed(why) => {
                let _ = write!(
                    body,
                    "<small>(frames could not be drawn: {})</small>",
                    esc(why)
                );
            }
        }
        body.push_str("</p>");
    }
    let _ = write!(
        body,
        "<h2>{}</h2><p><small>conditions: {}</small></p><table><tr><th>run</th><th>seed</th><th>outcome</th><th>score</th><th>steps</th></tr>",
        esc(&t.task),
        esc(&t.conditions)
    );
    for e in &t.episodes {
        let _ = write!(
            body,
            "<tr><td>{}</td><td>{}</td><td class=l>{}</td><td>{:.3}</td><td>{}</td></tr>",
            e.run, e.seed, e.outcome, e.score, e.steps
        );
    }
    body.push_str("</table>");
}

/// The paired comparisons of a table.
fn paired_table(pairs: &[Paired]) -> String {
    let mut html = String::from(
        "<table><tr><th>first</th><th>second</th><th>pairs</th><th>only first won</th>\
         <th>only second won</th><th>p</th><th>at 5%</th></tr>",
    );
    for p in pairs {
        let _ = write!(
            html,
            "<tr><td class=l>{}</td><td class=l>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{:.3e}</td><td>{}</td></tr>",
            esc(&p.first),
            esc(&p.second),
            p.pairs,
            p.only_first,
            p.only_second,
            p.p_value,
            if p.significant {
                "significant"
            } else {
                "not significant"
            }
        );
    }
    html.push_str("</table>");
    html
}

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

const STYLE: &str = "body{font-family:system-ui,sans-serif;margin:2rem auto;max-width:72rem;\
padding:0 1rem;color:#222}table{border-collapse:collapse;margin:1rem 0;display:block;overflow-x:auto}th,td{border-bottom:1px \
solid #ddd;padding:.3rem .6rem;text-align:right}th:first-child,td:first-child,td.l{text-align:left}\
.audited{color:#075}.verified{color:#047}.reported{color:#777}.refused{color:#a00}small{color:#666}";

/// A whole page: `body` under the title, with the style and a link home (`depth` folders up).
fn page(title: &str, depth: usize, body: &str) -> String {
    let up = "../".repeat(depth);
    format!(
        "<!doctype html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{t}</title>\
         <style>{STYLE}</style></head><body><p><a href=\"{up}index.html\">autobio leaderboard</a></p>\
         <h1>{t}</h1>\n{body}</body></html>\n",
        t = esc(title)
    )
}
