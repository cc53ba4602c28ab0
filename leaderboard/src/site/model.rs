//! The site's view model: every table, row, chart and note the site shows, as plain data,
//! computed once from the loaded submissions by [`Site::of`]. The renderers (`site::html`,
//! `site::markdown`) and the JSON exports read it and compute nothing of their own; numbers
//! are kept as numbers (percent where the site shows percent) and text as it came, unescaped.
//!
//! It neither formats, escapes nor writes anything, and draws no frame: [`Shot::frames`] is
//! filled in by [`super::build`] when it is handed a renderer.

use super::load::Spread;
use super::load::{Submission, TaskResult};
use super::paper::{Reference, paper};
use super::slug;
use super::stats::{Paired, RankRow, paired, paired_over_suite, rankings};
use results::run::stats::EvalSummary;
use std::collections::BTreeMap;
use std::path::PathBuf;

/// The whole site.
#[derive(Clone, Debug)]
pub struct Site {
    /// The ranking, one table per group of comparable conditions, in the groups' order.
    pub groups: Vec<Group>,
    /// A page per task any submission ran (refused ones too), in the tasks' order.
    pub tasks: Vec<TaskPage>,
    /// The paper's results, shown as shipped.
    pub reference: Reference,
    /// Refused submissions, listed with their reasons and never ranked.
    pub refused: Vec<Refused>,
    /// A page per submission, in the submissions' order.
    pub submissions: Vec<SubmissionPage>,
}

/// One group's ranking.
#[derive(Clone, Debug)]
pub struct Group {
    /// The conditions (suite, autobio version, model profile).
    pub name: String,
    pub rows: Vec<RankRow>,
    /// Success with the 95% interval of each row (mean ± 1.96 SEM, within 0..100).
    pub chart: Vec<Bar>,
    /// Every two of the group's submissions paired over the suite's episodes.
    pub paired: Vec<Paired>,
    /// When the group's suite names perturbation presets: success under each, and the drop.
    pub robustness: Option<super::robustness::Robustness>,
}

/// One bar of a chart with its error bar (percent).
#[derive(Clone, Debug, PartialEq)]
pub struct Bar {
    pub label: String,
    pub value: f64,
    pub low: f64,
    pub high: f64,
}

/// A refused submission on the front page.
#[derive(Clone, Debug)]
pub struct Refused {
    pub model: String,
    pub file: String,
    pub reasons: Vec<String>,
}

/// One task's page.
#[derive(Clone, Debug)]
pub struct TaskPage {
    pub id: String,
    /// The page's file name, without extension.
    pub slug: String,
    pub level: String,
    /// Every submission not refused that ran the task, in the submissions' order.
    pub rows: Vec<TaskRow>,
    /// Success with its Wilson 95% interval, a bar per row.
    pub chart: Vec<Bar>,
    /// A chain's stages, when the task has more than one.
    pub stages: Option<StageTable>,
    /// Every two submissions of one group paired on the task's seeds.
    pub paired: Vec<Paired>,
    /// The paper's figure for the task, per model of the paper that reports one.
    pub reference: Vec<ReferenceRow>,
}

/// One submission's figures on a task.
#[derive(Clone, Debug)]
pub struct TaskRow {
    pub model: String,
    /// The submission's page, without extension.
    pub submission: String,
    pub group: String,
    pub standing: &'static str,
    /// Success and its Wilson 95% interval (percent), and the mean score.
    pub success: f64,
    pub wilson: [f64; 2],
    pub mean_score: f64,
    /// Over two or more runs: the runs' mean success ± its SEM (percent), and what the runs
    /// are (training seeds, or evaluation runs of one model).
    pub across_runs: Option<(f64, f64)>,
    pub spread: Spread,
    /// The summary as computed, for the JSON export.
    pub summary: EvalSummary,
}

/// The share of episodes that got through each stage (percent), as the paper's concatenation
/// table.
#[derive(Clone, Debug)]
pub struct StageTable {
    pub stages: Vec<String>,
    /// Per submission: the model and a share per stage.
    pub rows: Vec<(String, Vec<f64>)>,
}

/// The paper's figure for one task and one of its models.
#[derive(Clone, Debug)]
pub struct ReferenceRow {
    pub model: String,
    pub training: String,
    pub mean: f64,
    pub sem: f64,
}

/// One submission's page.
#[derive(Clone, Debug)]
pub struct SubmissionPage {
    /// The page's file name, without extension.
    pub slug: String,
    pub model: String,
    pub standing: &'static str,
    /// The bundle's facts, by name, in the order shown.
    pub facts: Vec<(&'static str, String)>,
    /// Why it is refused, when it is.
    pub refused: Option<Vec<String>>,
    pub tasks: Vec<EpisodeTable>,
}

/// One task of a submission: its conditions, its best and worst episode, and every episode.
#[derive(Clone, Debug)]
pub struct EpisodeTable {
    pub task: String,
    /// The task's slug, in its frames' file names.
    pub slug: String,
    /// The task's conditions as recorded (JSON), empty when none were.
    pub conditions: String,
    pub shots: Vec<Shot>,
    pub episodes: Vec<EpisodeRow>,
}

/// One episode in a submission's table.
#[derive(Clone, Debug)]
pub struct EpisodeRow {
    pub run: u32,
    pub seed: u64,
    /// How it ended, as the results name it (`success`, `time_limit`, ...).
    pub outcome: String,
    pub score: f64,
    pub steps: u64,
}

/// The best or the worst episode of a task, to be drawn from its recording.
#[derive(Clone, Debug)]
pub struct Shot {
    /// `best` or `worst`.
    pub label: &'static str,
    pub run: u32,
    pub seed: u64,
    pub score: f64,
    pub recording: PathBuf,
    /// What drawing it gave; none until drawn (and then not shown).
    pub frames: Option<Frames>,
}

/// A shot's frames as drawn.
#[derive(Clone, Debug)]
pub enum Frames {
    /// The frames' file names, relative to the submissions' folder.
    Drawn(Vec<String>),
    /// Why they could not be drawn.
    Failed(String),
}

impl Site {
    /// The site for `subs`.
    pub fn of(subs: &[Submission]) -> Site {
        let reference = paper();
        Site {
            groups: groups(subs),
            tasks: task_pages(subs, &reference),
            refused: subs
                .iter()
                .filter_map(|s| match &s.standing {
                    super::Standing::Refused(why) => Some(Refused {
                        model: s.index.model.name.clone(),
                        file: s.file.clone(),
                        reasons: why.clone(),
                    }),
                    _ => None,
                })
                .collect(),
            submissions: subs.iter().map(submission_page).collect(),
            reference,
        }
    }
}

fn groups(subs: &[Submission]) -> Vec<Group> {
    rankings(subs)
        .into_iter()
        .map(|(name, rows)| {
            let chart = rows
                .iter()
                .map(|r| Bar {
                    label: r.model.clone(),
                    value: r.success,
                    low: (r.success - 1.96 * r.sem).max(0.0),
                    high: (r.success + 1.96 * r.sem).min(100.0),
                })
                .collect();
            let members: Vec<&Submission> = subs
                .iter()
                .filter(|s| s.group == name && !s.standing.is_refused())
                .collect();
            let mut paired = Vec::new();
            for (i, a) in members.iter().enumerate() {
                for b in members.iter().skip(i + 1) {
                    paired.extend(paired_over_suite(a, b));
                }
            }
            let robustness = super::robustness::table(&members);
            Group {
                name,
                rows,
                chart,
                paired,
                robustness,
            }
        })
        .collect()
}

fn task_pages(subs: &[Submission], reference: &Reference) -> Vec<TaskPage> {
    // Every task by its id, with the level the last submission to run it gave.
    let mut levels: BTreeMap<&str, &str> = BTreeMap::new();
    for t in subs.iter().flat_map(|s| &s.tasks) {
        levels.insert(&t.task, &t.level);
    }
    levels
        .into_iter()
        .map(|(id, level)| {
            let entries: Vec<(&Submission, &TaskResult)> = subs
                .iter()
                .filter(|s| !s.standing.is_refused())
                .filter_map(|s| s.tasks.iter().find(|t| t.task == id).map(|t| (s, t)))
                .collect();
            let rows: Vec<TaskRow> = entries.iter().map(|(s, t)| task_row(s, t)).collect();
            let chart = rows
                .iter()
                .map(|r| Bar {
                    label: r.model.clone(),
                    value: r.success,
                    low: r.wilson[0],
                    high: r.wilson[1],
                })
                .collect();
            let mut paired_here = Vec::new();
            for (i, (a, ta)) in entries.iter().enumerate() {
                for (b, tb) in entries.iter().skip(i + 1) {
                    if a.group == b.group
                        && let Some(p) = paired(a, ta, b, tb)
                    {
                        paired_here.push(p);
                    }
                }
            }
            TaskPage {
                id: id.to_string(),
                slug: slug(id),
                level: level.to_string(),
                stages: stage_table(&entries),
                paired: paired_here,
                reference: reference
                    .entry
                    .iter()
                    .filter_map(|e| {
                        let s = e.scores.iter().find(|s| s.task == id)?;
                        Some(ReferenceRow {
                            model: e.model.clone(),
                            training: e.training.clone(),
                            mean: s.mean,
                            sem: s.sem,
                        })
                    })
                    .collect(),
                rows,
                chart,
            }
        })
        .collect()
}

fn task_row(s: &Submission, t: &TaskResult) -> TaskRow {
    let m = &t.summary;
    TaskRow {
        model: s.index.model.name.clone(),
        submission: s.slug.clone(),
        group: s.group.clone(),
        standing: s.standing.label(),
        success: 100.0 * m.success_rate,
        wilson: [100.0 * m.wilson_95[0], 100.0 * m.wilson_95[1]],
        mean_score: m.mean_score,
        across_runs: m
            .across_runs
            .as_ref()
            .map(|a| (100.0 * a.success_rate_mean, 100.0 * a.success_rate_sem)),
        spread: s.spread(),
        summary: m.clone(),
    }
}

/// A chain's stages (their ids from each submission's first episode, in order), when there is
/// more than one.
fn stage_table(entries: &[(&Submission, &TaskResult)]) -> Option<StageTable> {
    let stages: Vec<String> = entries
        .iter()
        .flat_map(|(_, t)| t.episodes.first())
        .flat_map(|e| e.verdict.stages.iter().map(|st| st.id.clone()))
        .fold(Vec::new(), |mut ids, id| {
            if !ids.contains(&id) {
                ids.push(id);
            }
            ids
        });
    if stages.len() <= 1 {
        return None;
    }
    let rows = entries
        .iter()
        .map(|(s, t)| {
            let done = stages
                .iter()
                .map(|id| {
                    let done = t
                        .episodes
                        .iter()
                        .filter(|e| e.verdict.stages.iter().any(|st| &st.id == id && st.success))
                        .count();
                    100.0 * done as f64 / t.episodes.len().max(1) as f64
                })
                .collect();
            (s.index.model.name.clone(), done)
        })
        .collect();
    Some(StageTable { stages, rows })
}

fn submission_page(s: &Submission) -> SubmissionPage {
    let i = &s.index;
    SubmissionPage {
        slug: s.slug.clone(),
        model: i.model.name.clone(),
        standing: s.standing.label(),
        facts: vec![
            ("bundle", s.file.clone()),
            ("bundle SHA-256", s.bundle_sha256.clone()),
            ("training", i.model.training.clone().unwrap_or_default()),
            ("suite", i.suite.name.clone()),
            (
                "autobio",
                format!("{} ({})", i.autobio_version, i.git_commit),
            ),
            ("wire", i.model.wire.clone().unwrap_or_default()),
            ("profile", i.model.profile.clone().unwrap_or_default()),
            ("conditions", s.group.clone()),
            (
                "runs",
                match s.spread() {
                    Spread::EvaluationRuns => "evaluation runs of one model".into(),
                    Spread::TrainingSeeds => s
                        .checkpoints
                        .iter()
                        .map(|(run, name)| format!("training seed {run}: {name}"))
                        .collect::<Vec<_>>()
                        .join("; "),
                },
            ),
        ],
        refused: match &s.standing {
            super::Standing::Refused(why) => Some(why.clone()),
            _ => None,
        },
        tasks: s
            .tasks
            .iter()
            .map(|t| EpisodeTable {
                task: t.task.clone(),
                slug: slug(&t.task),
                conditions: s
                    .conditions
                    .get(&t.task)
                    .map(|c| c.to_string())
                    .unwrap_or_default(),
                shots: shots(t),
                episodes: t
                    .episodes
                    .iter()
                    .map(|e| EpisodeRow {
                        run: e.run,
                        seed: e.seed,
                        outcome: serde_json::to_value(e.outcome)
                            .ok()
                            .and_then(|v| v.as_str().map(str::to_string))
                            .unwrap_or_default(),
                        score: e.verdict.score,
                        steps: e.control_steps,
                    })
                    .collect(),
            })
            .collect(),
    }
}

/// The best and the worst episode of a task that have a recording (highest and lowest score,
/// the first in plan order on a tie); one shot when they are the same episode.
fn shots(t: &TaskResult) -> Vec<Shot> {
    let drawn: Vec<_> = t
        .episodes
        .iter()
        .filter_map(|e| t.recordings.get(&(e.run, e.seed)).map(|r| (e, r)))
        .collect();
    let best = drawn.iter().copied().reduce(|a, b| {
        if b.0.verdict.score > a.0.verdict.score {
            b
        } else {
            a
        }
    });
    let worst = drawn.iter().copied().reduce(|a, b| {
        if b.0.verdict.score < a.0.verdict.score {
            b
        } else {
            a
        }
    });
    let mut shots: Vec<Shot> = Vec::new();
    for (label, found) in [("best", best), ("worst", worst)] {
        let Some((e, recording)) = found else {
            continue;
        };
        if shots.iter().any(|s| (s.run, s.seed) == (e.run, e.seed)) {
            continue;
        }
        shots.push(Shot {
            label,
            run: e.run,
            seed: e.seed,
            score: e.verdict.score,
            recording: recording.clone(),
            frames: None,
        });
    }
    shots
}
