//! Bundles read for the site: every bundle in a folder unpacked into a [`Submission`] with its
//! [`Standing`] (from the operator's [`Record`]s beside it), its tasks' episodes, summaries,
//! recordings and conditions; and where those records are kept and how they are written.
//!
//! It reads bundles and records and writes records; it computes no ranking and renders nothing
//! (that is [`super::model`] and the renderers).

use super::{SiteError, io, slug};
use crate::bundle::{Index, Limits, unpack};
use results::episode::EpisodeResult;
use results::run::record::{Manifest, sha256_hex};
use results::run::stats::{EvalSummary, summarise};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
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
    pub(super) fn label(&self) -> &'static str {
        match self {
            Standing::Audited => "audited",
            Standing::Verified => "verified",
            Standing::Reported => "reported",
            Standing::Refused(_) => "refused",
        }
    }

    pub(super) fn is_refused(&self) -> bool {
        matches!(self, Standing::Refused(_))
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

/// One bundle as the site shows it.
#[derive(Clone, Debug, Serialize)]
pub struct Submission {
    pub file: String,
    pub slug: String,
    pub bundle_sha256: String,
    pub standing: Standing,
    pub index: Index,
    /// The conditions results are grouped by (suite, autobio version, model profile, what the
    /// policy observes).
    pub group: String,
    /// What the policy observes: `vision` (cameras and robot state), `state` (the privileged
    /// environment state: its own group, never ranked with vision models) or `scripted` (the
    /// expert and the controls, which read the simulator).
    pub observation: String,
    pub tasks: Vec<TaskResult>,
    /// Manifest facts shown on its page (per task: conditions as JSON).
    pub conditions: BTreeMap<String, serde_json::Value>,
    /// The checkpoint each run evaluated, by run, for a submission of training-seed runs
    /// (`eval --checkpoint`); empty for runs of one model.
    pub checkpoints: BTreeMap<u32, String>,
}

impl Submission {
    /// What its ± is taken over: training seeds when its runs name their checkpoints (verify
    /// refuses a bundle where only some do), else evaluation runs of one model.
    pub fn spread(&self) -> Spread {
        if self.checkpoints.is_empty() {
            Spread::EvaluationRuns
        } else {
            Spread::TrainingSeeds
        }
    }
}

/// What a ± is taken over. The paper's is the SEM over three models trained alike on different
/// training seeds; re-evaluating one model on fresh seeds measures only the evaluation's own
/// spread, a smaller one. The site never puts the two in one column.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Spread {
    TrainingSeeds,
    EvaluationRuns,
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
        let standing = standing(file, &sha);
        // The unpacked files stay until the caller drops `work`: pages draw from recordings.
        let runs = read_runs(&here, &unpacked.members);
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
                "suite {} · autobio {} · {} · {} observation",
                index.suite.name, index.autobio_version, runs.profile, runs.observation
            ),
            observation: runs.observation,
            index,
            tasks: runs.tasks,
            conditions: runs.conditions,
            checkpoints: runs.checkpoints,
        });
    }
    Ok(out)
}

/// A bundle's standing from the operator's records for its exact bytes (`sha`); a record for
/// other bytes, or one that does not read, is no record.
fn standing(file: &Path, sha: &str) -> Standing {
    let read = |kind: &str| -> Option<Record> {
        let text = std::fs::read(record_path(file, kind)).ok()?;
        serde_json::from_slice::<Record>(&text)
            .ok()
            .filter(|r| r.bundle_sha256 == sha)
    };
    match (read("verification"), read("audit")) {
        (Some(v), _) if !v.passed => Standing::Refused(v.reasons),
        (Some(_), Some(a)) if a.passed => Standing::Audited,
        (Some(_), Some(a)) => Standing::Refused(a.reasons),
        (Some(_), None) => Standing::Verified,
        (None, _) => Standing::Reported,
    }
}

/// What an unpacked bundle's run folders hold, per task.
struct Runs {
    tasks: Vec<TaskResult>,
    conditions: BTreeMap<String, serde_json::Value>,
    checkpoints: BTreeMap<u32, String>,
    /// The model profile the runs recorded, as the group names it.
    profile: String,
    /// What the policy observes (`Submission::observation`).
    observation: String,
}

/// Reads the run folders' manifests and journals of a bundle unpacked in `here`; a file that
/// does not read is skipped (verification is where it is refused).
fn read_runs(here: &Path, members: &[String]) -> Runs {
    let mut by_task: BTreeMap<String, (String, Vec<EpisodeResult>)> = BTreeMap::new();
    let mut recordings: BTreeMap<String, BTreeMap<(u32, u64), PathBuf>> = BTreeMap::new();
    let mut conditions = BTreeMap::new();
    let mut checkpoints = BTreeMap::new();
    let mut profile = String::from("no model profile");
    let mut observation = String::from("scripted");
    // Only run folders' files: what verification checks (a verified bundle has no others).
    for member in members.iter().filter(|m| m.starts_with("runs/")) {
        let path = here.join(member);
        if let Some(task) = member.strip_suffix(".manifest.json") {
            let task = task.rsplit('/').next().unwrap_or(task).to_string();
            if let Ok(m) = Manifest::read(&path) {
                by_task.entry(task.clone()).or_default().0 = m.level.clone();
                if let Some(c) = &m.checkpoint {
                    checkpoints.insert(c.run, c.name.clone());
                }
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
                    observation = model.profile.observation_mode().to_string();
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
    Runs {
        tasks,
        conditions,
        checkpoints,
        profile,
        observation,
    }
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
                perturb: Vec::new(),
            },
            suite_sha256: String::new(),
            files: BTreeMap::new(),
        },
        group: String::new(),
        observation: String::new(),
        tasks: Vec::new(),
        conditions: BTreeMap::new(),
        checkpoints: BTreeMap::new(),
    }
}
