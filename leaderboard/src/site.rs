//! The leaderboard site: every bundle in a folder turned into static pages (`autobio leaderboard
//! build DIR --out SITE`). A bundle's standing comes from the operator's records beside it
//! (`<bundle>.verification.json`, `<bundle>.audit.json`, written by `verify` and `audit` for
//! that bundle's exact bytes): **audited** (verified, and its live model consistent with it),
//! **verified**, or **reported** (not verified here); a refused bundle is listed with its
//! reasons, never ranked. The paper's own results ship as a reference entry, "reported by the
//! paper, not re-run".
//!
//! Pages: an overall ranking per suite and conditions (results under another suite, autobio
//! version or model profile are never averaged together), a page per task (success with its
//! Wilson 95% interval, mean score, mean ± SEM across runs, a chart with error bars, and paired
//! McNemar tests between submissions on the same seeds), a page per submission (conditions,
//! standing, every episode's outcome), and JSON and Markdown exports of each table. Same inputs,
//! same bytes; no page requests anything from the network.
//!
//! It reads bundles and records; it runs and verifies nothing.

use crate::bundle::{Index, Limits, unpack};
use results::EpisodeResult;
use results::run::record::{Manifest, sha256_hex};
use results::run::stats::{EvalSummary, mean_sem, summarise};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// How a bundle stands.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Standing {
    Audited,
    Verified,
    Reported,
    Refused(Vec<String>),
}

impl Standing {
    fn label(&self) -> &'static str {
        match self {
            Standing::Audited => "audited",
            Standing::Verified => "verified",
            Standing::Reported => "reported",
            Standing::Refused(_) => "refused",
        }
    }
}

/// The operator's record of a verification or an audit of one bundle's exact bytes.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Record {
    pub bundle_sha256: String,
    /// Accepted (verification) or consistent (audit).
    pub passed: bool,
    pub reasons: Vec<String>,
}

/// Where the record of `kind` (`verification` or `audit`) of `bundle` is kept.
pub fn record_path(bundle: &Path, kind: &str) -> PathBuf {
    let mut name = bundle.as_os_str().to_owned();
    name.push(format!(".{kind}.json"));
    PathBuf::from(name)
}

/// Writes the record of `kind` for `bundle` beside it.
pub fn write_record(
    bundle: &Path,
    kind: &str,
    passed: bool,
    reasons: &[String],
) -> std::io::Result<()> {
    let record = Record {
        bundle_sha256: sha256_hex(&std::fs::read(bundle)?),
        passed,
        reasons: reasons.to_vec(),
    };
    std::fs::write(
        record_path(bundle, kind),
        serde_json::to_vec_pretty(&record).expect("a record serialises"),
    )
}

/// One task of one submission.
#[derive(Clone, Debug, Serialize)]
pub struct TaskResult {
    pub task: String,
    pub level: String,
    pub summary: EvalSummary,
    #[serde(skip)]
    pub episodes: Vec<EpisodeResult>,
    /// Each episode's recording in the unpacked bundle, by (run, seed), where there is one.
    #[serde(skip)]
    pub recordings: BTreeMap<(u32, u64), PathBuf>,
}

/// Draws a few frames (PNG) of a recording, for a submission's page; the caller's, as this
/// crate links no renderer.
pub type DrawFrames<'a> = dyn Fn(&Path) -> Result<Vec<Vec<u8>>, String> + 'a;

/// One bundle as the site shows it.
#[derive(Clone, Debug, Serialize)]
pub struct Submission {
    pub file: String,
    pub slug: String,
    pub bundle_sha256: String,
    pub standing: Standing,
    pub index: Index,
    /// The conditions results are grouped by (suite, autobio version, model profile).
    pub group: String,
    pub tasks: Vec<TaskResult>,
    /// Manifest facts shown on its page (per task: conditions as JSON).
    pub conditions: BTreeMap<String, serde_json::Value>,
}

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

/// Every bundle (`*.tar`, `*.tar.zst`) in `dir`, read with its standing; a bundle that does not
/// unpack is a refused submission with the reason.
pub fn load(dir: &Path, work: &Path) -> Result<Vec<Submission>, SiteError> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(io("read", dir))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            let n = p.to_string_lossy();
            n.ends_with(".tar") || n.ends_with(".tar.zst")
        })
        .collect();
    files.sort();
    let mut out = Vec::new();
    let mut slugs = std::collections::BTreeSet::new();
    for (k, file) in files.iter().enumerate() {
        let bytes = std::fs::read(file).map_err(io("read", file))?;
        let sha = sha256_hex(&bytes);
        let name = file
            .file_name()
            .unwrap_or_default()
            .to_string_lossy()
            .into_owned();
        let here = work.join(k.to_string());
        let unpacked = match unpack(file, &here, &Limits::default()) {
            Ok(u) => u,
            Err(e) => {
                out.push(refused_unreadable(&name, &sha, e.to_string()));
                continue;
            }
        };
        let read = |kind: &str| -> Option<Record> {
            let text = std::fs::read(record_path(file, kind)).ok()?;
            serde_json::from_slice::<Record>(&text)
                .ok()
                .filter(|r| r.bundle_sha256 == sha)
        };
        let standing = match (read("verification"), read("audit")) {
            (Some(v), _) if !v.passed => Standing::Refused(v.reasons),
            (Some(_), Some(a)) if a.passed => Standing::Audited,
            (Some(_), Some(a)) => Standing::Refused(a.reasons),
            (Some(_), None) => Standing::Verified,
            (None, _) => Standing::Reported,
        };
        let mut by_task: BTreeMap<String, (String, Vec<EpisodeResult>)> = BTreeMap::new();
        let mut recordings: BTreeMap<String, BTreeMap<(u32, u64), PathBuf>> = BTreeMap::new();
        let mut conditions = BTreeMap::new();
        let mut profile = String::from("no model profile");
        // Only run folders' files: what verification checks (a verified bundle has no others).
        for member in unpacked.members.iter().filter(|m| m.starts_with("runs/")) {
            let path = here.join(member);
            if let Some(task) = member.strip_suffix(".manifest.json") {
                let task = task.rsplit('/').next().unwrap_or(task).to_string();
                if let Ok(m) = Manifest::read(&path) {
                    by_task.entry(task.clone()).or_default().0 = m.level.clone();
                    conditions.insert(
                        task,
                        serde_json::to_value(&m.conditions).unwrap_or_default(),
                    );
                    if let Some(model) = &m.model {
                        let sha = &model.profile_sha256;
                        profile = format!(
                            "profile {} ({})",
                            model.profile.name,
                            sha.get(..12).unwrap_or(sha)
                        );
                    }
                }
            } else if let Some(task) = member.strip_suffix(".journal.jsonl") {
                let task = task.rsplit('/').next().unwrap_or(task).to_string();
                if let Ok(eps) = results::run::record::read_journal_only(&path) {
                    let run_dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
                    for e in &eps {
                        let rec = run_dir.join(format!("{task}_seed{}.mcap", e.seed));
                        if rec.is_file() {
                            recordings
                                .entry(task.clone())
                                .or_default()
                                .insert((e.run, e.seed), rec);
                        }
                    }
                    by_task.entry(task).or_default().1.extend(eps);
                }
            }
        }
        // The unpacked files stay until the caller drops `work`: pages draw from recordings.
        let tasks = by_task
            .into_iter()
            .map(|(task, (level, mut episodes))| {
                episodes.sort_by_key(|e| (e.run, e.seed));
                TaskResult {
                    summary: summarise(&episodes, 0.0),
                    recordings: recordings.remove(&task).unwrap_or_default(),
                    task,
                    level,
                    episodes,
                }
            })
            .collect();
        let index = unpacked.index;
        let mut s = slug(&format!(
            "{} {}",
            index.model.name,
            index.model.training.clone().unwrap_or_default()
        ));
        if !slugs.insert(s.clone()) {
            s = format!("{s}-{}", &sha[..8]);
            slugs.insert(s.clone());
        }
        out.push(Submission {
            file: name,
            slug: s,
            bundle_sha256: sha,
            standing,
            group: format!(
                "suite {} · autobio {} · {profile}",
                index.suite.name, index.autobio_version
            ),
            index,
            tasks,
            conditions,
        });
    }
    Ok(out)
}

fn refused_unreadable(name: &str, sha: &str, why: String) -> Submission {
    Submission {
        file: name.to_string(),
        slug: slug(name),
        bundle_sha256: sha.to_string(),
        standing: Standing::Refused(vec![why]),
        index: Index {
            schema_version: 0,
            autobio_version: String::new(),
            git_commit: String::new(),
            model: crate::bundle::ModelEntry {
                name: name.to_string(),
                training: None,
                wire: None,
                profile: None,
                profile_sha256: None,
                metadata: None,
            },
            suite: results::suite::Suite {
                name: String::new(),
                description: String::new(),
                episodes: 0,
                seed: 0,
                runs: 0,
                tasks: Vec::new(),
            },
            suite_sha256: String::new(),
            files: BTreeMap::new(),
        },
        group: String::new(),
        tasks: Vec::new(),
        conditions: BTreeMap::new(),
    }
}

/// The paper's reported results (`reference/paper.toml`).
#[derive(Clone, Debug, Deserialize, Serialize)]
pub struct Reference {
    pub source: String,
    pub entry: Vec<ReferenceEntry>,
    pub chain: Vec<ReferenceChain>,
}

#[derive(Clone, Debug, Deserialize, Serialize)]
pub struct ReferenceEntry {
    pub model: String,
    pub training: String,
    pub scores: Vec<ReferenceScore>,
}

#[derive(Clone, Debug, Deserialize, Serialize)]
pub struct ReferenceScore {
    pub task: String,
    #[serde(default)]
    pub level: String,
    pub mean: f64,
    pub sem: f64,
}

#[derive(Clone, Debug, Deserialize, Serialize)]
pub struct ReferenceChain {
    pub model: String,
    pub stages: Vec<ReferenceScore>,
}

/// The paper's results as shipped.
pub fn paper() -> Reference {
    toml::from_str(include_str!("../reference/paper.toml")).expect("the shipped reference reads")
}

/// One ranked row.
#[derive(Clone, Debug, Serialize)]
pub struct RankRow {
    pub rank: usize,
    pub model: String,
    pub training: String,
    pub standing: String,
    pub page: String,
    /// Mean over the suite's tasks of the success rate, and its SEM across runs (percent).
    pub success: f64,
    pub sem: f64,
    pub by_level: BTreeMap<String, f64>,
    pub mean_score: f64,
}

/// Rankings per group of comparable conditions.
pub fn rankings(subs: &[Submission]) -> BTreeMap<String, Vec<RankRow>> {
    let mut groups: BTreeMap<String, Vec<RankRow>> = BTreeMap::new();
    for s in subs {
        if matches!(s.standing, Standing::Refused(_)) || s.tasks.is_empty() {
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
            standing: s.standing.label().to_string(),
            page: format!("submissions/{}.html", s.slug),
            success: 100.0 * rates.iter().sum::<f64>() / rates.len() as f64,
            sem: 100.0 * if runs > 1 { sem } else { 0.0 },
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

fn paired(a: &Submission, ta: &TaskResult, b: &Submission, tb: &TaskResult) -> Option<Paired> {
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

/// The paired comparisons of a table, as HTML.
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

/// Text for a Markdown table cell: no cell breaks, no line breaks, no raw HTML.
fn md_cell(s: &str) -> String {
    s.replace('|', "\\|")
        .replace(['\n', '\r'], " ")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
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

fn page(title: &str, depth: usize, body: &str) -> String {
    let up = "../".repeat(depth);
    format!(
        "<!doctype html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{t}</title>\
         <style>{STYLE}</style></head><body><p><a href=\"{up}index.html\">autobio leaderboard</a></p>\
         <h1>{t}</h1>\n{body}</body></html>\n",
        t = esc(title)
    )
}

/// Bars with error bars, drawn with plotters (SVG).
fn chart(bars: &[(String, f64, f64, f64)]) -> String {
    use plotters::prelude::*;
    let mut svg = String::new();
    {
        let height = 70 + 36 * bars.len() as u32;
        let root = SVGBackend::with_string(&mut svg, (640, height)).into_drawing_area();
        let _ = root.fill(&WHITE);
        let n = bars.len().max(1) as i32;
        if let Ok(mut c) = ChartBuilder::on(&root)
            .margin(10)
            .x_label_area_size(55)
            .y_label_area_size(200)
            .build_cartesian_2d(0f64..100f64, (0..n).into_segmented())
        {
            let labels: Vec<String> = bars.iter().map(|b| b.0.clone()).collect();
            let _ = c
                .configure_mesh()
                .disable_y_mesh()
                .x_labels(6)
                .x_label_formatter(&|v| format!("{v:.0}"))
                .label_style(("sans-serif", 20))
                .axis_desc_style(("sans-serif", 20))
                .x_desc("success, % (bars: 95% interval)")
                .y_label_formatter(&|v| match v {
                    SegmentValue::CenterOf(i) => {
                        labels.get(*i as usize).cloned().unwrap_or_default()
                    }
                    _ => String::new(),
                })
                .draw();
            let _ = c.draw_series(bars.iter().enumerate().map(|(i, b)| {
                Rectangle::new(
                    [
                        (0.0, SegmentValue::Exact(i as i32)),
                        (b.1, SegmentValue::Exact(i as i32 + 1)),
                    ],
                    RGBColor(70, 130, 180).filled(),
                )
            }));
            let _ = c.draw_series(bars.iter().enumerate().map(|(i, b)| {
                PathElement::new(
                    vec![
                        (b.2, SegmentValue::CenterOf(i as i32)),
                        (b.3, SegmentValue::CenterOf(i as i32)),
                    ],
                    BLACK.stroke_width(2),
                )
            }));
        }
        let _ = root.present();
    }
    svg
}

/// Writes the site for `subs` into `out` (made if missing); with `frames`, each submission's
/// page shows frames of its best and worst episode of every task. Returns the files written.
pub fn build(
    subs: &[Submission],
    out: &Path,
    frames: Option<&DrawFrames>,
) -> Result<Vec<PathBuf>, SiteError> {
    let mut written = Vec::new();
    let mut write = |rel: &str, bytes: &[u8]| -> Result<(), SiteError> {
        let path = out.join(rel);
        if let Some(p) = path.parent() {
            std::fs::create_dir_all(p).map_err(io("create", p))?;
        }
        std::fs::write(&path, bytes).map_err(io("write", &path))?;
        written.push(path);
        Ok(())
    };
    let ranks = rankings(subs);
    let reference = paper();
    // The ranking.
    let mut body = String::new();
    let mut md = String::from("# autobio leaderboard\n");
    for (group, rows) in &ranks {
        let _ = write!(
            body,
            "<h2>{}</h2><table><tr><th>#</th><th>model</th><th>training</th><th>standing</th>\
             <th>success %</th><th>± SEM</th><th>easy</th><th>medium</th><th>hard</th><th>mean score</th></tr>",
            esc(group)
        );
        let _ = write!(
            md,
            "\n## {}\n\n| # | model | training | standing | success % | ± SEM | easy | medium | hard | mean score |\n|---|---|---|---|---|---|---|---|---|---|\n",
            md_cell(group)
        );
        for r in rows {
            let lvl = |l: &str| {
                r.by_level
                    .get(l)
                    .map_or("–".to_string(), |v| format!("{v:.1}"))
            };
            let _ = write!(
                body,
                "<tr><td>{}</td><td class=l><a href=\"{}\">{}</a></td><td class=l>{}</td><td class=\"l {}\">{}</td>\
                 <td>{:.1}</td><td>{:.1}</td><td>{}</td><td>{}</td><td>{}</td><td>{:.3}</td></tr>",
                r.rank,
                r.page,
                esc(&r.model),
                esc(&r.training),
                r.standing,
                r.standing,
                r.success,
                r.sem,
                lvl("easy"),
                lvl("medium"),
                lvl("hard"),
                r.mean_score
            );
            let _ = writeln!(
                md,
                "| {} | {} | {} | {} | {:.1} | {:.1} | {} | {} | {} | {:.3} |",
                r.rank,
                md_cell(&r.model),
                md_cell(&r.training),
                r.standing,
                r.success,
                r.sem,
                lvl("easy"),
                lvl("medium"),
                lvl("hard"),
                r.mean_score
            );
        }
        body.push_str("</table>");
        let bars: Vec<(String, f64, f64, f64)> = rows
            .iter()
            .map(|r| {
                (
                    r.model.clone(),
                    r.success,
                    (r.success - 1.96 * r.sem).max(0.0),
                    (r.success + 1.96 * r.sem).min(100.0),
                )
            })
            .collect();
        body.push_str(&chart(&bars));
        // Every two submissions of the group, paired over the suite's episodes.
        let members: Vec<&Submission> = subs
            .iter()
            .filter(|s| &s.group == group && !matches!(s.standing, Standing::Refused(_)))
            .collect();
        let mut pairs = Vec::new();
        for (i, a) in members.iter().enumerate() {
            for b in members.iter().skip(i + 1) {
                pairs.extend(paired_over_suite(a, b));
            }
        }
        if !pairs.is_empty() {
            body.push_str("<h3>Paired over the suite (same tasks and seeds, exact McNemar)</h3>");
            body.push_str(&paired_table(&pairs));
        }
    }
    // The tasks.
    let mut task_ids: BTreeMap<String, String> = BTreeMap::new();
    for s in subs {
        for t in &s.tasks {
            task_ids.insert(t.task.clone(), t.level.clone());
        }
    }
    let _ = write!(body, "<h2>Tasks</h2><ul>");
    for id in task_ids.keys() {
        let _ = write!(
            body,
            "<li><a href=\"tasks/{}.html\">{}</a></li>",
            slug(id),
            esc(id)
        );
    }
    body.push_str("</ul>");
    // The reference entry.
    let _ = write!(
        body,
        "<h2>Reference: reported by the paper, not re-run</h2><p><small>{}. Score in percent; \
         tasks without an autobio id do not ship yet.</small></p><table><tr><th>model</th><th>training</th>",
        esc(&reference.source)
    );
    let ref_tasks: Vec<&ReferenceScore> = reference
        .entry
        .first()
        .map(|e| e.scores.iter().collect())
        .unwrap_or_default();
    for t in &ref_tasks {
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
    body.push_str(
        "</table><h3>Long horizon (the paper's concatenation table)</h3><table><tr><th>model</th>",
    );
    if let Some(c) = reference.chain.first() {
        for s in &c.stages {
            let _ = write!(body, "<th>{}</th>", esc(&s.task));
        }
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
    let refused: Vec<&Submission> = subs
        .iter()
        .filter(|s| matches!(s.standing, Standing::Refused(_)))
        .collect();
    if !refused.is_empty() {
        body.push_str("<h2>Refused</h2><ul>");
        for s in refused {
            if let Standing::Refused(why) = &s.standing {
                let _ = write!(
                    body,
                    "<li class=refused>{} ({}): {}</li>",
                    esc(&s.index.model.name),
                    esc(&s.file),
                    esc(&why.join("; "))
                );
            }
        }
        body.push_str("</ul>");
    }
    write(
        "index.html",
        page("autobio leaderboard", 0, &body).as_bytes(),
    )?;
    write("ranking.md", md.as_bytes())?;
    write(
        "ranking.json",
        (serde_json::to_string_pretty(&ranks).unwrap_or_default() + "\n").as_bytes(),
    )?;
    write(
        "reference.json",
        (serde_json::to_string_pretty(&reference).unwrap_or_default() + "\n").as_bytes(),
    )?;
    // A page per task.
    for (id, level) in &task_ids {
        let mut body = format!("<p>level: {}</p>", esc(level));
        let mut rows_json = Vec::new();
        let mut md = format!(
            "# {id}\n\n| model | group | standing | success % | Wilson 95% | mean score | runs: mean ± SEM |\n|---|---|---|---|---|---|---|\n"
        );
        body.push_str("<table><tr><th>model</th><th>conditions</th><th>standing</th><th>success %</th><th>Wilson 95%</th><th>mean score</th><th>runs: mean ± SEM</th></tr>");
        let mut bars = Vec::new();
        let entries: Vec<(&Submission, &TaskResult)> = subs
            .iter()
            .filter(|s| !matches!(s.standing, Standing::Refused(_)))
            .filter_map(|s| s.tasks.iter().find(|t| &t.task == id).map(|t| (s, t)))
            .collect();
        for (s, t) in &entries {
            let m = &t.summary;
            let across = m.across_runs.as_ref().map_or("–".to_string(), |a| {
                format!(
                    "{:.1} ± {:.1}",
                    100.0 * a.success_rate_mean,
                    100.0 * a.success_rate_sem
                )
            });
            let _ = write!(
                body,
                "<tr><td class=l><a href=\"../submissions/{}.html\">{}</a></td><td class=l><small>{}</small></td><td class=\"l {}\">{}</td>\
                 <td>{:.1}</td><td>[{:.1}, {:.1}]</td><td>{:.3}</td><td>{}</td></tr>",
                s.slug,
                esc(&s.index.model.name),
                esc(&s.group),
                s.standing.label(),
                s.standing.label(),
                100.0 * m.success_rate,
                100.0 * m.wilson_95[0],
                100.0 * m.wilson_95[1],
                m.mean_score,
                across
            );
            let _ = writeln!(
                md,
                "| {} | {} | {} | {:.1} | [{:.1}, {:.1}] | {:.3} | {} |",
                md_cell(&s.index.model.name),
                md_cell(&s.group),
                s.standing.label(),
                100.0 * m.success_rate,
                100.0 * m.wilson_95[0],
                100.0 * m.wilson_95[1],
                m.mean_score,
                across
            );
            bars.push((
                s.index.model.name.clone(),
                100.0 * m.success_rate,
                100.0 * m.wilson_95[0],
                100.0 * m.wilson_95[1],
            ));
            rows_json.push(serde_json::json!({
                "model": s.index.model.name, "group": s.group, "standing": s.standing.label(),
                "summary": m,
            }));
        }
        body.push_str("</table>");
        body.push_str(&chart(&bars));
        // A chain's stages, as the paper's concatenation table: the share of episodes that got
        // through each stage.
        let stage_ids: Vec<String> = entries
            .iter()
            .flat_map(|(_, t)| t.episodes.first())
            .flat_map(|e| e.verdict.stages.iter().map(|st| st.id.clone()))
            .fold(Vec::new(), |mut ids, id| {
                if !ids.contains(&id) {
                    ids.push(id);
                }
                ids
            });
        if stage_ids.len() > 1 {
            body.push_str("<h2>Stage by stage</h2><table><tr><th>model</th>");
            for id in &stage_ids {
                let _ = write!(body, "<th>{}</th>", esc(id));
            }
            body.push_str("</tr>");
            for (s, t) in &entries {
                let _ = write!(body, "<tr><td class=l>{}</td>", esc(&s.index.model.name));
                for id in &stage_ids {
                    let done = t
                        .episodes
                        .iter()
                        .filter(|e| e.verdict.stages.iter().any(|st| &st.id == id && st.success))
                        .count();
                    let _ = write!(
                        body,
                        "<td>{:.1}</td>",
                        100.0 * done as f64 / t.episodes.len().max(1) as f64
                    );
                }
                body.push_str("</tr>");
            }
            body.push_str("</table>");
        }
        // Paired comparisons between submissions of one group on the same seeds.
        let mut pairs = Vec::new();
        for (i, (a, ta)) in entries.iter().enumerate() {
            for (b, tb) in entries.iter().skip(i + 1) {
                if a.group == b.group
                    && let Some(p) = paired(a, ta, b, tb)
                {
                    pairs.push(p);
                }
            }
        }
        if !pairs.is_empty() {
            body.push_str("<h2>Paired comparisons (same seeds, exact McNemar)</h2>");
            body.push_str(&paired_table(&pairs));
        }
        if let Some(r) = reference
            .entry
            .iter()
            .find(|e| e.scores.iter().any(|s| &s.task == id))
        {
            let _ = r;
            body.push_str("<h2>Reported by the paper, not re-run</h2><table><tr><th>model</th><th>training</th><th>score %</th></tr>");
            for e in &reference.entry {
                if let Some(s) = e.scores.iter().find(|s| &s.task == id) {
                    let _ = write!(
                        body,
                        "<tr><td class=l>{}</td><td class=l>{}</td><td>{:.1} ± {:.1}</td></tr>",
                        esc(&e.model),
                        esc(&e.training),
                        s.mean,
                        s.sem
                    );
                }
            }
            body.push_str("</table>");
        }
        let file = slug(id);
        write(&format!("tasks/{file}.html"), page(id, 1, &body).as_bytes())?;
        write(&format!("tasks/{file}.md"), md.as_bytes())?;
        write(
            &format!("tasks/{file}.json"),
            (serde_json::to_string_pretty(
                &serde_json::json!({"task": id, "rows": rows_json, "paired": pairs}),
            )
            .unwrap_or_default()
                + "\n")
                .as_bytes(),
        )?;
    }
    // A page per submission.
    for s in subs {
        let mut body = format!(
            "<p class=\"{}\">standing: <b>{}</b></p><table>",
            s.standing.label(),
            s.standing.label()
        );
        let facts = [
            ("bundle", s.file.clone()),
            ("bundle SHA-256", s.bundle_sha256.clone()),
            (
                "training",
                s.index.model.training.clone().unwrap_or_default(),
            ),
            ("suite", s.index.suite.name.clone()),
            (
                "autobio",
                format!("{} ({})", s.index.autobio_version, s.index.git_commit),
            ),
            ("wire", s.index.model.wire.clone().unwrap_or_default()),
            ("profile", s.index.model.profile.clone().unwrap_or_default()),
            ("conditions", s.group.clone()),
        ];
        for (k, v) in facts {
            let _ = write!(
                body,
                "<tr><td class=l>{k}</td><td class=l>{}</td></tr>",
                esc(&v)
            );
        }
        body.push_str("</table>");
        if let Standing::Refused(why) = &s.standing {
            body.push_str("<h2>Why it is refused</h2><ul>");
            for w in why {
                let _ = write!(body, "<li>{}</li>", esc(w));
            }
            body.push_str("</ul>");
        }
        for t in &s.tasks {
            if let Some(draw) = frames {
                body.push_str(&episode_frames(s, t, draw, &mut write)?);
            }
            let _ = write!(
                body,
                "<h2>{}</h2><p><small>conditions: {}</small></p><table><tr><th>run</th><th>seed</th><th>outcome</th><th>score</th><th>steps</th></tr>",
                esc(&t.task),
                esc(&s
                    .conditions
                    .get(&t.task)
                    .map(|c| c.to_string())
                    .unwrap_or_default())
            );
            for e in &t.episodes {
                let outcome = serde_json::to_value(e.outcome)
                    .ok()
                    .and_then(|v| v.as_str().map(str::to_string))
                    .unwrap_or_default();
                let _ = write!(
                    body,
                    "<tr><td>{}</td><td>{}</td><td class=l>{}</td><td>{:.3}</td><td>{}</td></tr>",
                    e.run, e.seed, outcome, e.verdict.score, e.control_steps
                );
            }
            body.push_str("</table>");
        }
        write(
            &format!("submissions/{}.html", s.slug),
            page(&s.index.model.name, 1, &body).as_bytes(),
        )?;
    }
    Ok(written)
}

/// Writes one file of the site (its path relative to the site's folder).
type WriteFile<'a> = dyn FnMut(&str, &[u8]) -> Result<(), SiteError> + 'a;

/// The best and the worst episode of a task (highest and lowest score, the first in plan order
/// on a tie), drawn from their recordings: an HTML fragment, the PNGs written beside the page.
fn episode_frames(
    s: &Submission,
    t: &TaskResult,
    draw: &DrawFrames,
    write: &mut WriteFile,
) -> Result<String, SiteError> {
    let drawn: Vec<&EpisodeResult> = t
        .episodes
        .iter()
        .filter(|e| t.recordings.contains_key(&(e.run, e.seed)))
        .collect();
    let best = drawn.iter().copied().reduce(|a, b| {
        if b.verdict.score > a.verdict.score {
            b
        } else {
            a
        }
    });
    let worst = drawn.iter().copied().reduce(|a, b| {
        if b.verdict.score < a.verdict.score {
            b
        } else {
            a
        }
    });
    let mut html = String::new();
    let mut shown = Vec::new();
    for (label, e) in [("best", best), ("worst", worst)] {
        let Some(e) = e else { continue };
        if shown.contains(&(e.run, e.seed)) {
            continue;
        }
        shown.push((e.run, e.seed));
        let _ = write!(
            html,
            "<p>{label} episode: run {}, seed {}, score {:.3}</p><p>",
            e.run, e.seed, e.verdict.score
        );
        match draw(&t.recordings[&(e.run, e.seed)]) {
            Ok(pngs) => {
                for (k, png) in pngs.iter().enumerate() {
                    let name = format!("{}/{}-{label}-{k}.png", s.slug, slug(&t.task));
                    write(&format!("submissions/{name}"), png)?;
                    let _ = write!(
                        html,
                        "<img src=\"{name}\" alt=\"{label} episode, frame {k}\" width=224 height=224> "
                    );
                }
            }
            Err(why) => {
                let _ = write!(
                    html,
                    "<small>(frames could not be drawn: {})</small>",
                    esc(&why)
                );
            }
        }
        html.push_str("</p>");
    }
    Ok(html)
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

    #[test]
    fn the_paper_reference_reads_with_its_nine_tasks() {
        let p = paper();
        assert_eq!(p.entry.len(), 4);
        assert!(p.entry.iter().all(|e| e.scores.len() == 9));
        let pi0_100 = &p.entry[1];
        assert_eq!(
            (pi0_100.model.as_str(), pi0_100.training.as_str()),
            ("pi0", "100 demos")
        );
        assert_eq!(pi0_100.scores[0].mean, 99.7);
        assert_eq!(p.chain[1].stages[3].mean, 8.7);
    }
}
