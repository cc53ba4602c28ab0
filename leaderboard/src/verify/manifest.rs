//! A run's records against what verification derives: each manifest against the shipped task,
//! its suite and the index; the index against the manifests; each results file against the
//! report of its verified journal.
//!
//! A run compiled the shipped protocol from its own path (`<prefix><suite entry>`): the task
//! "as run" is the shipped task with that prefix in place of the verifier's in every source
//! path. Its SHA-256, and every protocol file's, must then be the manifest's. This module reads
//! records and compares; it re-enacts nothing.

use super::differ;
use crate::bundle::Index;
use compiler::Task;
use results::episode::EpisodeResult;
use results::run::record::{Conditions, Manifest, protocol_files, sha256_hex};
use results::run::{EvalReport, RESULTS_SCHEMA_VERSION};
use std::path::{Path, PathBuf};

/// A shipped task as a run's manifest must match it.
pub(super) struct Shipped<'a> {
    pub task: &'a Task,
    /// [`results::run::record::task_content_sha256`] of the task.
    pub content: &'a str,
    /// The shipped protocol file, and the suite's entry for it (relative to the suite).
    pub protocol: &'a Path,
    pub entry: &'a str,
    pub suite: &'a results::suite::Suite,
}

/// The task as the run compiled it (the shipped task under the run's paths; `None` where its
/// path does not name the shipped protocol or it ran another task, so that its episodes cannot
/// be re-derived), and each
/// way the manifest (shown as `shown`) differs from what verification derives.
pub(super) fn check(
    m: &Manifest,
    shown: &str,
    want: &Shipped,
    index: &Index,
) -> (Option<Task>, Vec<String>) {
    let (task, suite) = (want.task, want.suite);
    let mut failures = Vec::new();
    if m.results_schema_version != RESULTS_SCHEMA_VERSION {
        failures.push(format!(
            "{shown}: results schema version {}; this autobio writes and reads version \
             {RESULTS_SCHEMA_VERSION}",
            m.results_schema_version
        ));
    }
    if m.task_id != task.id || m.level != task.level {
        failures.push(format!(
            "{shown}: task `{}` at level {}; the shipped task is `{}` at level {}",
            m.task_id, m.level, task.id, task.level
        ));
    }
    if m.autobio_version != index.autobio_version || m.git_commit != index.git_commit {
        failures.push(format!(
            "{shown}: autobio {} at commit {}; the index says {} at {}",
            m.autobio_version, m.git_commit, index.autobio_version, index.git_commit
        ));
    }
    if !is_commit(&m.git_commit) {
        failures.push(format!(
            "{shown}: `{}` is not a commit (40 hexadecimal digits, `-dirty` where the work tree \
             had changes, or `unknown`)",
            m.git_commit
        ));
    }
    if m.task_content_sha256.as_deref() != Some(want.content) {
        // Everything else derived from the task (its hashes, files, conditions, episodes)
        // differs for this one reason.
        let under = results::suite::split_variant(&task.id)
            .1
            .map(|p| format!(" under the suite's `{p}`"))
            .unwrap_or_default();
        failures.push(format!(
            "{shown}: the results are for a modified task (its compiled content \
             differs from the shipped {}{under})",
            want.protocol.display()
        ));
        return (None, failures);
    }
    // The run's path to the shipped protocol: its own prefix, then the suite's entry.
    let ours = want.protocol.display().to_string();
    let our_prefix = ours.strip_suffix(want.entry).unwrap_or_default();
    let run_prefix = match m.protocol.strip_suffix(want.entry) {
        Some(p) if p.is_empty() || p.ends_with('/') || p.ends_with('\\') => Some(p),
        _ => {
            failures.push(format!(
                "{shown}: protocol `{}` is not the suite's `{}`",
                m.protocol, want.entry
            ));
            None
        }
    };
    let ran = as_run(task, our_prefix, run_prefix.unwrap_or(our_prefix));
    let shipped_sha = std::fs::read(want.protocol).ok().map(|b| sha256_hex(&b));
    if m.protocol_sha256 != shipped_sha {
        failures.push(format!(
            "{shown}: protocol SHA-256 {}; the shipped file's is {}",
            m.protocol_sha256.as_deref().unwrap_or("null"),
            shipped_sha.as_deref().unwrap_or("null")
        ));
    }
    let task_sha = serde_json::to_vec(&ran)
        .map(|b| sha256_hex(&b))
        .unwrap_or_default();
    if run_prefix.is_some() && m.task_sha256 != task_sha {
        failures.push(format!(
            "{shown}: compiled task SHA-256 {}; the shipped task compiled from its paths is {}",
            m.task_sha256, task_sha
        ));
    }
    // Every file read where the verifier has it, named as the run named it.
    let files: std::collections::BTreeMap<String, Option<String>> = protocol_files(task)
        .into_iter()
        .map(|(k, sha)| {
            (
                swap_prefix(&k, our_prefix, run_prefix.unwrap_or(our_prefix)),
                sha,
            )
        })
        .collect();
    if run_prefix.is_some() && m.protocol_files != files {
        failures.push(format!(
            "{shown}: protocol files: {}",
            differ::first_difference(
                &differ::as_json(&m.protocol_files),
                &differ::as_json(&files)
            )
            .unwrap_or_default()
        ));
    }
    if (m.seed, m.episodes, m.runs) != (suite.seed, suite.episodes, suite.runs) {
        failures.push(format!(
            "{shown}: seed {}, {} episodes x {} runs; the suite says seed {}, {} x {}",
            m.seed, m.episodes, m.runs, suite.seed, suite.episodes, suite.runs
        ));
    }
    let conditions = Conditions::of(task);
    if m.conditions != conditions {
        failures.push(format!(
            "{shown}: conditions: {}",
            differ::first_difference(
                &differ::as_json(&m.conditions),
                &differ::as_json(&conditions)
            )
            .unwrap_or_default()
        ));
    }
    let model_policy = m.model.is_some() == (m.policy == "model");
    if !model_policy {
        failures.push(format!(
            "{shown}: policy `{}` with {} model server",
            m.policy,
            if m.model.is_some() { "a" } else { "no" }
        ));
    }
    match (&m.model, &index.model.wire) {
        (Some(model), _) => {
            let same = index.model.wire.as_deref() == Some(&model.wire.to_string())
                && index.model.profile.as_deref() == Some(&model.profile.name)
                && index.model.profile_sha256.as_deref() == Some(&model.profile_sha256)
                // A resumed run may not have heard the server describe itself (its manifest
                // keeps none): where it did, it is the index's.
                && (model.metadata.is_none() || index.model.metadata == model.metadata);
            if !same {
                failures.push(format!(
                    "{shown}: its model server's wire, profile or metadata is not the index's"
                ));
            }
        }
        (None, None) if index.model.profile.is_none() && index.model.metadata.is_none() => {}
        (None, _) => failures.push(format!("{shown}: no model server, but the index names one")),
    }
    (run_prefix.is_some().then_some(ran), failures)
}

/// A commit as `results` records it: 40 hexadecimal digits, `-dirty` where the work tree had
/// changes, or `unknown` outside a checkout.
fn is_commit(c: &str) -> bool {
    let hex = c.strip_suffix("-dirty").unwrap_or(c);
    c == "unknown" || (hex.len() == 40 && hex.bytes().all(|b| b.is_ascii_hexdigit()))
}

/// `path` with `from` in place of `ours` at its start.
fn swap_prefix(path: &str, ours: &str, from: &str) -> String {
    match path.strip_prefix(ours) {
        Some(rest) => format!("{from}{rest}"),
        None => path.to_string(),
    }
}

/// `task` with `from` in place of `ours` at the start of every source path.
fn as_run(task: &Task, ours: &str, from: &str) -> Task {
    let mut t = task.clone();
    t.source = swap_prefix(&t.source, ours, from);
    for s in &mut t.stages {
        s.source = swap_prefix(&s.source, ours, from);
    }
    t
}

/// The index against the manifests it packs: every one was made by the index's autobio and
/// commit (checked per manifest), and a bundle of runs names no model server that no run used.
pub(super) fn check_index(index: &Index, path: &Path, manifests: &[Manifest]) -> Vec<String> {
    let mut failures = Vec::new();
    let text = std::fs::read(path).unwrap_or_default();
    if let Err(e) = differ::strict::<Index>(&text) {
        failures.push(format!("{}: {e}", crate::bundle::INDEX));
    }
    if index.model.name.trim().is_empty() {
        failures.push("the index names no model".to_string());
    }
    if !manifests.is_empty()
        && manifests.iter().all(|m| m.model.is_none())
        && index.model.wire.is_some()
    {
        failures.push("the index names a model server no run used".to_string());
    }
    if index.model.metadata.is_some()
        && !manifests.iter().any(|m| {
            m.model
                .as_ref()
                .is_some_and(|x| x.metadata == index.model.metadata)
        })
    {
        failures.push("the index's model metadata is what no run's manifest recorded".to_string());
    }
    failures
}

/// One task's run in one run folder: its manifest and journal.
pub(super) struct Reported {
    pub dir: PathBuf,
    pub manifest: Manifest,
    pub episodes: Vec<EpisodeResult>,
}

/// The folder's results file for the task, if it has one, against the report of its verified
/// journal (the wall time of the whole run aside, which nothing re-derives).
pub(super) fn check_results(r: &Reported, root: &Path) -> Vec<String> {
    let m = &r.manifest;
    let path = results::run::record::results_path(&r.dir, &m.task_id);
    let shown = super::rel(root, &path);
    let text = match std::fs::read(&path) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Vec::new(),
        Err(e) => return vec![format!("{shown}: {e}")],
    };
    let claimed: EvalReport = match differ::strict(&text) {
        Ok(c) => c,
        Err(e) => return vec![format!("{shown}: not a results file: {e}")],
    };
    let wall = claimed.summary.wall_time_s;
    if !(wall.is_finite() && wall >= 0.0) {
        return vec![format!("{shown}: wall time {wall} s")];
    }
    let position: std::collections::BTreeMap<(u32, u64), usize> =
        results::run::plan(m.seed, m.episodes, m.runs, m.shard)
            .into_iter()
            .enumerate()
            .map(|(k, p)| (p, k))
            .collect();
    let mut episodes = r.episodes.clone();
    episodes.sort_by_key(|e| position.get(&(e.run, e.seed)).copied());
    let policy = match &m.model {
        Some(model) => format!(
            "model {} ({}, {})",
            model.url, model.wire, model.profile.name
        ),
        None => m.policy.clone(),
    };
    let derived = EvalReport {
        schema_version: RESULTS_SCHEMA_VERSION,
        task_id: m.task_id.clone(),
        level: m.level.clone(),
        protocol: m.protocol.clone(),
        policy,
        seed: m.seed,
        summary: results::run::stats::summarise(&episodes, wall),
        conditions: m.conditions.clone(),
        model: m.model.clone(),
        autobio_version: m.autobio_version.clone(),
        git_commit: m.git_commit.clone(),
        shard: m.shard,
        episodes,
    };
    match differ::first_difference(&differ::as_json(&claimed), &differ::as_json(&derived)) {
        None => Vec::new(),
        Some(d) => vec![format!(
            "{shown}: not the report of its verified journal: {d}"
        )],
    }
}
