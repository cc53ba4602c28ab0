//! Evaluation runs: N seeded episodes of one task with one policy, made per episode by name through
//! [`crate::policy::make`]. Each finished episode is
//! appended to a JSONL journal immediately (so nothing finished is lost if the run dies), and the
//! run ends with a versioned results JSON.

use crate::episode::{EpisodeOptions, EpisodeResult, run_episode};
use crate::policy;
use compiler::Task;
use serde::{Deserialize, Serialize};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

/// 2: verdicts per stage with scores; `mean_score` in the summary. 3: each episode's `outcome`;
/// the summary's Wilson 95% interval and counts per outcome. 4: the `server_fault` outcome,
/// each episode's `policy_time_s`, the run's `conditions` and (for models) `model`.
pub const RESULTS_SCHEMA_VERSION: u32 = 4;

/// The git commit autobio was built from (`-dirty` with uncommitted changes).
pub const GIT_COMMIT: &str = env!("AUTOBIO_GIT_COMMIT");

/// Lower-case hex SHA-256.
pub fn sha256_hex(bytes: &[u8]) -> String {
    use sha2::{Digest, Sha256};
    Sha256::digest(bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

/// Every condition that changes a score, written into results and manifests.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Conditions {
    pub control_hz: f64,
    /// Physics steps each action is held for.
    pub physics_steps_per_action: u32,
    pub physics_timestep_s: f64,
    pub time_limit_s: f64,
    pub termination: String,
    /// The state's components (robots in task order), with units.
    pub state: Vec<String>,
    /// The action's components: absolute targets, with units.
    pub action: Vec<String>,
    /// Gripper polarity: the command for open and for closed, per robot.
    pub gripper: Vec<String>,
}

impl Conditions {
    pub fn of(task: &Task) -> Conditions {
        let mut state = Vec::new();
        let mut action = Vec::new();
        let mut gripper = Vec::new();
        for r in &task.robots {
            if let Some(m) = robots::model(&r.model) {
                state.extend(
                    m.state_names()
                        .iter()
                        .map(|n| format!("{}/{n} (rad)", r.name)),
                );
                let names = m.action_names();
                let (arm, grip) = names.split_at(m.dof());
                action.extend(
                    arm.iter()
                        .map(|n| format!("{}/{n} (absolute joint target, rad)", r.name)),
                );
                action.extend(grip.iter().map(|n| {
                    format!(
                        "{}/{n} (absolute command, open {} to closed {})",
                        r.name, m.gripper.open, m.gripper.closed
                    )
                }));
                gripper.push(format!(
                    "{}: open {}, closed {}",
                    r.name, m.gripper.open, m.gripper.closed
                ));
            }
        }
        Conditions {
            control_hz: task.physics.control_hz(),
            physics_steps_per_action: task.physics.substeps,
            physics_timestep_s: task.physics.timestep_s,
            time_limit_s: task.time_limit_s,
            termination: "success ends the episode at the first control step where every stage's \
                          checks hold; otherwise it ends at the time limit"
                .into(),
            state,
            action,
            gripper,
        }
    }
}

/// A model server to evaluate: where, what it speaks, and its profile.
#[derive(Clone, Debug)]
pub struct ModelSpec {
    pub url: String,
    pub wire: crate::remote::Wire,
    pub profile: crate::profile::LoadedProfile,
    /// Connection attempts per episode and the first retry's wait (doubled per retry).
    pub attempts: u32,
    pub backoff_s: f64,
}

/// The model part of a manifest and of results.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ModelRecord {
    pub url: String,
    pub wire: crate::remote::Wire,
    /// `built-in pi0` or the profile file's path.
    pub profile_origin: String,
    pub profile_sha256: String,
    pub profile: crate::profile::Profile,
    /// What the server said about itself on connecting (openpi metadata, vla-eval `hello`);
    /// null when it said nothing or could not be reached.
    pub metadata: Option<serde_json::Value>,
}

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
    pub outcomes: std::collections::BTreeMap<crate::episode::Outcome, usize>,
    pub wall_time_s: f64,
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

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EvalReport {
    pub schema_version: u32,
    pub task_id: String,
    pub protocol: String,
    pub policy: String,
    /// Episode i uses seed `seed + i`.
    pub seed: u64,
    pub summary: EvalSummary,
    pub conditions: Conditions,
    pub model: Option<ModelRecord>,
    pub autobio_version: String,
    pub git_commit: String,
    pub episodes: Vec<EpisodeResult>,
}

pub struct EvalOptions {
    /// The policy's name (see [`crate::policy::POLICIES`]).
    pub policy: String,
    pub episodes: usize,
    pub seed: u64,
    /// Where to write recordings (`<task>_seed<seed>.mcap`), the journal and results.json.
    pub out: Option<PathBuf>,
    pub record: bool,
    pub image_every: u32,
    /// Continue the run whose journal is in `out`: only when its manifest's fingerprints match,
    /// and never rerunning a finished episode.
    pub resume: bool,
    /// A model server; `policy` is ignored when given.
    pub model: Option<ModelSpec>,
}

/// What a run was measured under, written before its first episode (`<task>.manifest.json`);
/// `--resume` continues a run only when these match.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Manifest {
    pub results_schema_version: u32,
    pub autobio_version: String,
    pub git_commit: String,
    pub task_id: String,
    /// SHA-256 of the compiled task (every stage, parameter and tolerance) as JSON.
    pub task_sha256: String,
    /// SHA-256 of the protocol file as read, when it could be read.
    pub protocol_sha256: Option<String>,
    pub policy: String,
    /// Episode i uses seed `seed + i`.
    pub seed: u64,
    pub conditions: Conditions,
    /// The model server, when the policy is one: its wire and profile are fingerprints (its
    /// address and metadata are not: a resumed run may find it elsewhere).
    pub model: Option<ModelRecord>,
}

impl Manifest {
    pub fn of(task: &Task, policy: &str, seed: u64, model: Option<ModelRecord>) -> Manifest {
        Manifest {
            results_schema_version: RESULTS_SCHEMA_VERSION,
            autobio_version: env!("CARGO_PKG_VERSION").to_string(),
            git_commit: GIT_COMMIT.to_string(),
            task_id: task.id.clone(),
            task_sha256: sha256_hex(&serde_json::to_vec(task).unwrap_or_default()),
            protocol_sha256: std::fs::read(&task.source).ok().map(|b| sha256_hex(&b)),
            policy: policy.to_string(),
            seed,
            conditions: Conditions::of(task),
            model,
        }
    }

    /// The fields in which `other` differs from this manifest.
    fn differences(&self, other: &Manifest) -> Vec<&'static str> {
        let model =
            |m: &Option<ModelRecord>| m.as_ref().map(|m| (m.wire, m.profile_sha256.clone()));
        // Metadata counts only when both runs heard it (a server may be down at either time).
        let metadata_same = match (&self.model, &other.model) {
            (Some(a), Some(b)) => match (&a.metadata, &b.metadata) {
                (Some(x), Some(y)) => x == y,
                _ => true,
            },
            _ => true,
        };
        let fields: [(&str, bool); 11] = [
            (
                "results schema version",
                self.results_schema_version == other.results_schema_version,
            ),
            (
                "autobio version",
                self.autobio_version == other.autobio_version,
            ),
            ("task id", self.task_id == other.task_id),
            ("compiled task", self.task_sha256 == other.task_sha256),
            (
                "protocol file",
                self.protocol_sha256 == other.protocol_sha256,
            ),
            ("policy", self.policy == other.policy),
            ("seed", self.seed == other.seed),
            ("conditions", self.conditions == other.conditions),
            (
                "model wire or profile",
                model(&self.model) == model(&other.model),
            ),
            ("model metadata", metadata_same),
            ("git commit", self.git_commit == other.git_commit),
        ];
        fields
            .into_iter()
            .filter(|(_, same)| !same)
            .map(|(name, _)| name)
            .collect()
    }
}

/// The finished episodes of a journal; a last line cut short by a crash is dropped from the file.
fn read_journal(path: &Path) -> Result<Vec<EpisodeResult>, String> {
    let text = match std::fs::read_to_string(path) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Vec::new()),
        Err(e) => return Err(format!("{}: {e}", path.display())),
    };
    let mut done = Vec::new();
    let mut kept = 0;
    for line in text.split_inclusive('\n') {
        match serde_json::from_str::<EpisodeResult>(line.trim_end()) {
            Ok(r) if line.ends_with('\n') => {
                done.push(r);
                kept += line.len();
            }
            _ => break,
        }
    }
    if kept < text.len() {
        std::fs::OpenOptions::new()
            .write(true)
            .open(path)
            .and_then(|f| f.set_len(kept as u64))
            .map_err(|e| format!("{}: {e}", path.display()))?;
    }
    Ok(done)
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
    EvalSummary {
        episodes: n,
        successes: k,
        success_rate: p,
        sem,
        wilson_95: wilson(k, n, 1.96),
        mean_score: if n > 0 {
            episodes.iter().map(|e| e.verdict.score).sum::<f64>() / n as f64
        } else {
            0.0
        },
        outcomes: episodes.iter().fold(Default::default(), |mut m, e| {
            *m.entry(e.outcome).or_insert(0) += 1;
            m
        }),
        wall_time_s: wall,
    }
}

/// Opens the run record in `dir`: checks or writes the manifest, reads what a resumed run has
/// finished, and opens the journal for appending.
fn open_run(
    task: &Task,
    opts: &EvalOptions,
    here: &Manifest,
    dir: &Path,
) -> Result<(Vec<EpisodeResult>, std::fs::File), String> {
    let jp = dir.join(format!("{}.journal.jsonl", task.id));
    let manifest_path = dir.join(format!("{}.manifest.json", task.id));
    let started = std::fs::metadata(&jp).is_ok_and(|m| m.len() > 0);
    let mut finished = Vec::new();
    if opts.resume {
        let text = std::fs::read_to_string(&manifest_path).map_err(|e| {
            format!(
                "cannot resume: no manifest {}: {e}",
                manifest_path.display()
            )
        })?;
        let there: Manifest = serde_json::from_str(&text)
            .map_err(|e| format!("cannot resume: {}: {e}", manifest_path.display()))?;
        let differs = here.differences(&there);
        if !differs.is_empty() {
            return Err(format!(
                "cannot resume the run in {}: it was measured under another {}; start a new run in another --out",
                dir.display(),
                differs.join(", ")
            ));
        }
        finished = read_journal(&jp)?;
    } else if started {
        return Err(format!(
            "{} already has a run of {} (its journal {}); continue it with --resume, or use another --out",
            dir.display(),
            task.id,
            jp.display()
        ));
    } else {
        let text = serde_json::to_string_pretty(here).map_err(|e| e.to_string())?;
        std::fs::write(&manifest_path, text)
            .map_err(|e| format!("{}: {e}", manifest_path.display()))?;
    }
    let journal = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(&jp)
        .map_err(|e| format!("{}: {e}", jp.display()))?;
    // The folder's entry for a new journal is on disk too, not only its lines.
    std::fs::File::open(dir)
        .and_then(|d| d.sync_all())
        .map_err(|e| format!("{}: {e}", dir.display()))?;
    Ok((finished, journal))
}

/// Runs the named policy on `task`. `progress` is called after each episode.
pub fn evaluate(
    task: &Task,
    opts: &EvalOptions,
    mut progress: impl FnMut(&EpisodeResult),
) -> Result<EvalReport, String> {
    let start = Instant::now();
    if let Some(dir) = &opts.out {
        std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    }
    // A model: one connection for the run, greeted before the manifest is written so that the
    // manifest holds what the server said about itself.
    let (mut model, layout) = match &opts.model {
        Some(spec) => {
            let layout = spec
                .profile
                .profile
                .resolve(task)
                .map_err(|e| e.to_string())?;
            let mut m = crate::remote::Model::new(&spec.url, spec.wire, spec.profile.clone())
                .map_err(|e| e.to_string())?;
            m.set_retries(
                spec.attempts,
                std::time::Duration::from_secs_f64(spec.backoff_s),
            );
            // An unreachable server is not fatal: each episode then fails as a server fault.
            m.open().ok();
            (Some(m), Some(layout))
        }
        None => (None, None),
    };
    let model_record = model.as_ref().map(|m| ModelRecord {
        url: m.url().to_string(),
        wire: m.wire,
        profile_origin: m.profile.origin.clone(),
        profile_sha256: m.profile.sha256(),
        profile: m.profile.profile.clone(),
        metadata: m.metadata.clone(),
    });
    let policy_label = match &model {
        Some(_) => "model".to_string(),
        None => opts.policy.clone(),
    };
    let here = Manifest::of(task, &policy_label, opts.seed, model_record.clone());
    let (finished, mut journal) = match &opts.out {
        Some(dir) => {
            let (finished, journal) = open_run(task, opts, &here, dir)?;
            (finished, Some(journal))
        }
        None => (Vec::new(), None),
    };
    let mut scene: Option<Arc<runtime::Scene>> = None;
    let mut results = Vec::new();
    let mut policy_name = policy_label.clone();
    for i in 0..opts.episodes {
        let seed = opts.seed.wrapping_add(i as u64);
        // A finished episode is never run again: its journal line stands.
        if let Some(done) = finished.iter().find(|r| r.seed == seed) {
            results.push(done.clone());
            continue;
        }
        let instance = task.sample(seed);
        if scene
            .as_ref()
            .is_none_or(|s| s.placements != instance.labware_placement)
        {
            scene = Some(Arc::new(
                runtime::Scene::build(task, &instance).map_err(|e| e.to_string())?,
            ));
        }
        let sc = scene.as_ref().expect("built above");
        let record = match (&opts.out, opts.record) {
            (Some(d), true) => Some(recording_path(d, task, seed)),
            _ => None,
        };
        let eo = EpisodeOptions {
            record,
            image_every: opts.image_every,
        };
        // A policy that cannot be made for this episode fails this episode, not the run.
        let made = match (model.as_mut(), &layout) {
            (Some(m), Some(layout)) => {
                let info = crate::remote::EpisodeInfo {
                    task_id: &task.id,
                    seed,
                    instruction: &instance.instruction,
                };
                crate::remote::ModelPolicy::start(m, layout.clone(), &info)
                    .map(|p| Box::new(p) as Box<dyn policy::Policy>)
            }
            _ => policy::make(&opts.policy, task, sc, &instance),
        };
        let r = match made {
            Ok(mut policy) => {
                policy_name = policy.name();
                run_episode(task, sc, &instance, policy.as_mut(), &eo)?
            }
            Err(policy::PolicyError::Unknown(name)) => {
                return Err(policy::PolicyError::Unknown(name).to_string());
            }
            Err(e) => crate::episode::policy_failed(task, sc, &instance, &e),
        };
        if let Some(j) = journal.as_mut() {
            let line = serde_json::to_string(&r).map_err(|e| e.to_string())?;
            // On disk before the next episode starts: a crash loses no finished episode.
            writeln!(j, "{line}")
                .and_then(|_| j.flush())
                .and_then(|_| j.sync_data())
                .map_err(|e| format!("journal: {e}"))?;
        }
        progress(&r);
        results.push(r);
    }
    let report = EvalReport {
        schema_version: RESULTS_SCHEMA_VERSION,
        task_id: task.id.clone(),
        protocol: task.source.clone(),
        policy: policy_name,
        seed: opts.seed,
        summary: summarise(&results, start.elapsed().as_secs_f64()),
        conditions: here.conditions.clone(),
        model: model_record,
        autobio_version: here.autobio_version.clone(),
        git_commit: here.git_commit.clone(),
        episodes: results,
    };
    if let Some(dir) = &opts.out {
        let p = dir.join(format!("{}.results.json", task.id));
        let text = serde_json::to_string_pretty(&report).map_err(|e| e.to_string())?;
        std::fs::write(&p, text).map_err(|e| format!("{}: {e}", p.display()))?;
    }
    Ok(report)
}

pub fn recording_path(dir: &Path, task: &Task, seed: u64) -> PathBuf {
    dir.join(format!("{}_seed{seed}.mcap", task.id))
}

#[cfg(test)]
mod tests {
    use super::wilson;

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
}
