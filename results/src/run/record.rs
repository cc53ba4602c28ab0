//! The run record in an `--out` folder, per task: `<task>.manifest.json` (what the run was
//! measured under, written before its first episode), `<task>.journal.jsonl` (one line per
//! finished episode, fsynced as soon as it finishes) and `<task>.results.json` (at the end).
//! Opening a record decides whether a run may start or resume there.
//!
//! It does not run episodes or compute statistics.

use super::{RunError, Shard};
use crate::episode::EpisodeResult;
use compiler::Task;
use serde::{Deserialize, Serialize};
use std::io::Write;
use std::path::{Path, PathBuf};

/// The git commit autobio was built from (`-dirty` with uncommitted changes).
pub const GIT_COMMIT: &str = env!("AUTOBIO_GIT_COMMIT");

/// SHA-256 of every protocol file a task was compiled from: its own and each stage's.
pub fn protocol_files(task: &Task) -> std::collections::BTreeMap<String, Option<String>> {
    std::iter::once(&task.source)
        .chain(task.stages.iter().map(|s| &s.source))
        .map(|p| (p.clone(), std::fs::read(p).ok().map(|b| sha256_hex(&b))))
        .collect()
}

/// SHA-256 of the compiled task as JSON with the files it was read from left out (`source`):
/// the same task compiled from another path, or on another machine, has the same hash. A
/// verifier compares a submission's with the shipped protocol's.
pub fn task_content_sha256(task: &compiler::Task) -> String {
    let mut task = task.clone();
    task.source.clear();
    for s in &mut task.stages {
        s.source.clear();
    }
    sha256_hex(&serde_json::to_vec(&task).unwrap_or_default())
}

/// Lower-case hex SHA-256.
pub fn sha256_hex(bytes: &[u8]) -> String {
    use sha2::{Digest, Sha256};
    Sha256::digest(bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

pub fn journal_path(dir: &Path, task_id: &str) -> PathBuf {
    dir.join(format!("{task_id}.journal.jsonl"))
}

pub fn manifest_path(dir: &Path, task_id: &str) -> PathBuf {
    dir.join(format!("{task_id}.manifest.json"))
}

pub fn results_path(dir: &Path, task_id: &str) -> PathBuf {
    dir.join(format!("{task_id}.results.json"))
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
                let names = m.state_names();
                let (arm, grip) = names.split_at(m.dof());
                state.extend(arm.iter().map(|n| format!("{}/{n} (rad)", r.name)));
                state.extend(
                    grip.iter()
                        .map(|n| format!("{}/{n} ({})", r.name, m.gripper.state_unit)),
                );
                let names = m.action_names();
                let (arm, grip) = names.split_at(m.dof());
                action.extend(
                    arm.iter()
                        .map(|n| format!("{}/{n} (absolute joint target, rad)", r.name)),
                );
                // A command in actuator units is just a command; another unit is named.
                let unit = match m.gripper.action_unit {
                    "actuator" => String::new(),
                    u => format!(" in {u}"),
                };
                action.extend(grip.iter().map(|n| {
                    format!(
                        "{}/{n} (absolute command{unit}, open {} to closed {})",
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

/// The protocol a model server speaks.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Wire {
    Openpi,
    VlaEval,
}

/// A wire name that is none of [`Wire`]'s.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("unknown wire `{0}`; known: openpi, vla-eval")]
pub struct UnknownWire(pub String);

impl std::str::FromStr for Wire {
    type Err = UnknownWire;
    fn from_str(s: &str) -> Result<Wire, UnknownWire> {
        match s {
            "openpi" => Ok(Wire::Openpi),
            "vla-eval" => Ok(Wire::VlaEval),
            other => Err(UnknownWire(other.to_string())),
        }
    }
}

impl std::fmt::Display for Wire {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Wire::Openpi => "openpi",
            Wire::VlaEval => "vla-eval",
        })
    }
}

/// The model part of a manifest and of results.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ModelRecord {
    pub url: String,
    pub wire: Wire,
    /// `built-in pi0` or the profile file's path.
    pub profile_origin: String,
    pub profile_sha256: String,
    pub profile: crate::profile::Profile,
    /// What the server said about itself on connecting (openpi metadata, vla-eval `hello`);
    /// null when it said nothing or could not be reached.
    pub metadata: Option<serde_json::Value>,
}

/// What a run was measured under, written before its first episode; `--resume` continues a run
/// only when these match, and `results merge` joins only shards whose manifests match.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Manifest {
    pub results_schema_version: u32,
    pub autobio_version: String,
    pub git_commit: String,
    pub task_id: String,
    pub level: String,
    /// The protocol file as given.
    pub protocol: String,
    /// SHA-256 of the compiled task (every stage, parameter and tolerance) as JSON.
    pub task_sha256: String,
    /// SHA-256 of the protocol file as read, when it could be read.
    pub protocol_sha256: Option<String>,
    /// [`task_content_sha256`]: the compiled task whatever path it was read from (absent in
    /// records made before submissions were verified).
    #[serde(default)]
    pub task_content_sha256: Option<String>,
    /// SHA-256 of every protocol file the task was compiled from (a chain's stages too), by
    /// path; null for one that could not be read.
    #[serde(default)]
    pub protocol_files: std::collections::BTreeMap<String, Option<String>>,
    /// The file the protocol was imported from (`autobio import`): its name, format and SHA-256.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub imported_from: Option<compiler::ImportedFrom>,
    pub policy: String,
    /// Run r's episode i uses seed `seed + r * 2^20 + i`.
    pub seed: u64,
    /// Episodes per run and runs (a resumed run may ask for more episodes).
    pub episodes: usize,
    pub runs: u32,
    /// This folder's share of the episodes (`--shard I/N`), if it is a shard.
    pub shard: Option<Shard>,
    /// The checkpoint the model server served, for a run of one training seed's model
    /// (`--checkpoint`): only its run's episodes are in this folder.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub checkpoint: Option<super::Checkpoint>,
    pub conditions: Conditions,
    /// The model server, when the policy is one: its wire and profile are fingerprints (its
    /// address is not: a resumed run may find it elsewhere; its metadata only when both runs
    /// heard it).
    pub model: Option<ModelRecord>,
}

impl Manifest {
    /// The fields in which `other` differs from this manifest, by name (episodes aside: a run
    /// may be extended).
    pub fn differences(&self, other: &Manifest) -> Vec<&'static str> {
        let model =
            |m: &Option<ModelRecord>| m.as_ref().map(|m| (m.wire, m.profile_sha256.clone()));
        let metadata_same = match (&self.model, &other.model) {
            (Some(a), Some(b)) => match (&a.metadata, &b.metadata) {
                (Some(x), Some(y)) => x == y,
                _ => true,
            },
            _ => true,
        };
        let fields: [(&str, bool); 15] = [
            (
                "results schema version",
                self.results_schema_version == other.results_schema_version,
            ),
            (
                "autobio version",
                self.autobio_version == other.autobio_version,
            ),
            ("git commit", self.git_commit == other.git_commit),
            ("task id", self.task_id == other.task_id),
            ("compiled task", self.task_sha256 == other.task_sha256),
            (
                "protocol file",
                self.protocol_sha256 == other.protocol_sha256,
            ),
            ("policy", self.policy == other.policy),
            ("seed", self.seed == other.seed),
            ("runs", self.runs == other.runs),
            ("shard", self.shard == other.shard),
            ("checkpoint", self.checkpoint == other.checkpoint),
            // A shard's share depends on the episodes per run: it cannot change under a shard.
            (
                "episodes per run of a shard",
                self.shard.is_none() || self.episodes == other.episodes,
            ),
            ("conditions", self.conditions == other.conditions),
            (
                "model wire or profile",
                model(&self.model) == model(&other.model),
            ),
            ("model metadata", metadata_same),
        ];
        fields
            .into_iter()
            .filter(|(_, same)| !same)
            .map(|(name, _)| name)
            .collect()
    }

    pub fn read(path: &Path) -> Result<Manifest, RunError> {
        let text = std::fs::read_to_string(path).map_err(|e| RunError::io("read", path, e))?;
        serde_json::from_str(&text).map_err(|e| RunError::Format {
            path: path.to_path_buf(),
            why: e.to_string(),
        })
    }

    pub fn write(&self, path: &Path) -> Result<(), RunError> {
        write_json(path, self)
    }
}

/// Writes JSON to `path` through [`write_atomic`].
pub fn write_json(path: &Path, value: &impl Serialize) -> Result<(), RunError> {
    let text = serde_json::to_string_pretty(value).expect("results serialise") + "\n";
    write_atomic(path, text.as_bytes()).map_err(|e| RunError::io("write", path, e))
}

/// Writes `bytes` to `path` through a synced temporary file and a rename, so that a crash
/// leaves the old file or the new one, never half of one.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let mut tmp = path.as_os_str().to_owned();
    tmp.push(".tmp");
    let tmp = PathBuf::from(tmp);
    std::fs::File::create(&tmp)
        .and_then(|mut f| {
            f.write_all(bytes)?;
            f.sync_all()
        })
        .and_then(|_| std::fs::rename(&tmp, path))
}

/// The finished episodes of a journal; a last line cut short by a crash is dropped from the file.
/// A complete line that does not parse is an error: it is not a crash's trace, and nothing after
/// it may be thrown away.
pub fn read_journal(path: &Path) -> Result<Vec<EpisodeResult>, RunError> {
    let (done, kept, len) = parse_journal(path)?;
    if kept < len {
        std::fs::OpenOptions::new()
            .write(true)
            .open(path)
            .and_then(|f| f.set_len(kept as u64))
            .map_err(|e| RunError::io("truncate", path, e))?;
    }
    Ok(done)
}

/// The finished episodes of a journal, read only (a last line cut short is skipped, the file
/// left as it is): for merging shards that may still be written.
pub fn read_journal_only(path: &Path) -> Result<Vec<EpisodeResult>, RunError> {
    parse_journal(path).map(|(done, _, _)| done)
}

/// The complete lines' episodes, the bytes they take, and the file's length.
fn parse_journal(path: &Path) -> Result<(Vec<EpisodeResult>, usize, usize), RunError> {
    let text = match std::fs::read_to_string(path) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok((Vec::new(), 0, 0)),
        Err(e) => return Err(RunError::io("read", path, e)),
    };
    let mut done = Vec::new();
    let mut kept = 0;
    for (number, line) in text.split_inclusive('\n').enumerate() {
        if !line.ends_with('\n') {
            break; // cut short by a crash
        }
        let r = serde_json::from_str::<EpisodeResult>(line.trim_end()).map_err(|e| {
            RunError::Format {
                path: path.to_path_buf(),
                why: format!("line {} is not an episode result: {e}", number + 1),
            }
        })?;
        done.push(r);
        kept += line.len();
    }
    Ok((done, kept, text.len()))
}

/// An open run record: appends finished episodes to the journal.
pub struct RunRecord {
    journal: std::fs::File,
    path: PathBuf,
}

impl RunRecord {
    /// Opens the record of `here.task_id` in `dir`: checks (`resume`) or writes the manifest,
    /// and returns what a resumed run has finished. Resuming where the task has no record yet
    /// starts a new one.
    pub fn open(
        dir: &Path,
        here: &Manifest,
        resume: bool,
    ) -> Result<(RunRecord, Vec<EpisodeResult>), RunError> {
        std::fs::create_dir_all(dir).map_err(|e| RunError::io("create", dir, e))?;
        let jp = journal_path(dir, &here.task_id);
        let mp = manifest_path(dir, &here.task_id);
        let started = std::fs::metadata(&jp).is_ok_and(|m| m.len() > 0);
        let mut finished = Vec::new();
        // `--resume` where this task has no record yet starts it: a retried job array shard
        // resumes the tasks it finished and starts the ones it never reached.
        let recorded = started || mp.exists();
        if resume && recorded {
            let resume_err = |why: String| RunError::Resume {
                dir: dir.to_path_buf(),
                why,
            };
            let there = match Manifest::read(&mp) {
                Ok(m) => m,
                Err(e) => return Err(resume_err(format!("no readable manifest: {e}"))),
            };
            let differs = here.differences(&there);
            if !differs.is_empty() {
                return Err(resume_err(format!(
                    "it was measured under another {}; start a new run in another --out",
                    differs.join(", ")
                )));
            }
            finished = read_journal(&jp)?;
        } else if started {
            return Err(RunError::Exists {
                dir: dir.to_path_buf(),
                task: here.task_id.clone(),
                journal: jp,
            });
        }
        here.write(&mp)?;
        let journal = std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(&jp)
            .map_err(|e| RunError::io("open", &jp, e))?;
        // The folder's entries for a new journal and manifest are on disk too.
        std::fs::File::open(dir)
            .and_then(|d| d.sync_all())
            .map_err(|e| RunError::io("sync", dir, e))?;
        Ok((RunRecord { journal, path: jp }, finished))
    }

    /// Appends one finished episode, on disk before this returns.
    pub fn append(&mut self, r: &EpisodeResult) -> Result<(), RunError> {
        let line = serde_json::to_string(r).expect("episode results serialise");
        writeln!(self.journal, "{line}")
            .and_then(|_| self.journal.flush())
            .and_then(|_| self.journal.sync_data())
            .map_err(|e| RunError::io("append to", &self.path, e))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wires_parse_by_name() {
        assert_eq!("vla-eval".parse::<Wire>(), Ok(Wire::VlaEval));
        assert_eq!(
            "grpc".parse::<Wire>().unwrap_err().to_string(),
            "unknown wire `grpc`; known: openpi, vla-eval"
        );
    }
}
