//! `autobio results merge`: joins the run records of a run's shards (`--shard I/N`, each in its
//! own folder) into one record with the summary one unsharded run would have had. Shards join
//! only when their manifests agree on everything but the shard, every planned episode is there
//! exactly once, and no shard is missing.
//!
//! It reads the shards' records and never writes them (the merged record goes to another
//! folder); it runs nothing.

use super::record::{Manifest, RunRecord, read_journal_only, results_path, write_json};
use super::stats::summarise;
use super::{EvalReport, RESULTS_SCHEMA_VERSION, RunError, plan};
use crate::episode::EpisodeResult;
use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};

/// Merges every task found in the shard folders `dirs` into `out`; one report per task.
pub fn merge(dirs: &[PathBuf], out: &Path) -> Result<Vec<EvalReport>, RunError> {
    // The shards are inputs, read and never written: the merged record goes to a folder of
    // its own (into a shard's folder it would rewrite that shard's manifest and journal).
    if let Ok(target) = out.canonicalize()
        && let Some(shard) = dirs
            .iter()
            .find(|d| d.canonicalize().is_ok_and(|d| d == target))
    {
        return Err(RunError::Merge(format!(
            "{} is one of the shards being merged; write the merged record to a new folder",
            shard.display()
        )));
    }
    let mut by_task: BTreeMap<String, Vec<(PathBuf, Manifest)>> = BTreeMap::new();
    for dir in dirs {
        let entries = std::fs::read_dir(dir).map_err(|e| RunError::io("read", dir, e))?;
        for entry in entries {
            let path = entry.map_err(|e| RunError::io("read", dir, e))?.path();
            let name = path
                .file_name()
                .and_then(|n| n.to_str())
                .unwrap_or_default();
            if name.ends_with(".manifest.json") {
                let m = Manifest::read(&path)?;
                by_task
                    .entry(m.task_id.clone())
                    .or_default()
                    .push((dir.clone(), m));
            }
        }
    }
    if by_task.is_empty() {
        return Err(RunError::Merge(format!(
            "no run records (`<task>.manifest.json`) in {}",
            dirs.iter()
                .map(|d| d.display().to_string())
                .collect::<Vec<_>>()
                .join(", ")
        )));
    }
    // Every task is checked before anything is written: a refused merge leaves `out` as it was,
    // so it can be run again once the shards are finished.
    let merged: Vec<(Manifest, EvalReport)> = by_task
        .iter()
        .map(|(task, shards)| merge_task(task, shards))
        .collect::<Result<_, _>>()?;
    for (manifest, _) in &merged {
        let journal = super::record::journal_path(out, &manifest.task_id);
        if std::fs::metadata(&journal).is_ok_and(|m| m.len() > 0) {
            return Err(RunError::Exists {
                dir: out.to_path_buf(),
                task: manifest.task_id.clone(),
                journal,
            });
        }
    }
    merged
        .into_iter()
        .map(|(manifest, report)| {
            let (mut record, _) = RunRecord::open(out, &manifest, false)?;
            for e in &report.episodes {
                record.append(e)?;
            }
            write_json(&results_path(out, &report.task_id), &report)?;
            Ok(report)
        })
        .collect()
}

/// One task's merged manifest and report, checked, not yet written.
fn merge_task(
    task: &str,
    shards: &[(PathBuf, Manifest)],
) -> Result<(Manifest, EvalReport), RunError> {
    let fail = |why: String| Err(RunError::Merge(format!("{task}: {why}")));
    let (first_dir, first) = &shards[0];
    let Some(count) = first.shard.map(|s| s.count) else {
        return fail(format!("{} holds an unsharded run", first_dir.display()));
    };
    let mut seen = vec![None; count as usize];
    for (dir, m) in shards {
        let mut unsharded = m.clone();
        unsharded.shard = first.shard;
        let differs = first.differences(&unsharded);
        if !differs.is_empty() {
            return fail(format!(
                "{} and {} were measured under another {}",
                first_dir.display(),
                dir.display(),
                differs.join(", ")
            ));
        }
        let Some(s) = m.shard.filter(|s| s.count == count && s.index < count) else {
            return fail(format!("{} is not a shard of {count}", dir.display()));
        };
        if let Some(other) = seen[s.index as usize].replace(dir.clone()) {
            return fail(format!(
                "shard {s} is in both {} and {}",
                other.display(),
                dir.display()
            ));
        }
    }
    let missing: Vec<String> = seen
        .iter()
        .enumerate()
        .filter(|(_, d)| d.is_none())
        .map(|(i, _)| format!("{i}/{count}"))
        .collect();
    if !missing.is_empty() {
        return fail(format!("shards {} are missing", missing.join(", ")));
    }
    let planned = plan(first.seed, first.episodes, first.runs, None);
    let position: HashMap<u64, usize> = planned
        .iter()
        .enumerate()
        .map(|(k, (_, s))| (*s, k))
        .collect();
    let mut episodes: Vec<Option<EpisodeResult>> = vec![None; planned.len()];
    for (dir, _) in shards {
        for e in read_journal_only(&super::record::journal_path(dir, task))? {
            let Some(&k) = position.get(&e.seed) else {
                return fail(format!(
                    "{} has seed {}, which no shard plans",
                    dir.display(),
                    e.seed
                ));
            };
            if episodes[k].replace(e).is_some() {
                return fail(format!("seed {} is in two shards' journals", planned[k].1));
            }
        }
    }
    let absent: Vec<u64> = planned
        .iter()
        .zip(&episodes)
        .filter(|(_, e)| e.is_none())
        .map(|((_, s), _)| *s)
        .collect();
    if !absent.is_empty() {
        let shown: Vec<String> = absent.iter().take(5).map(u64::to_string).collect();
        return fail(format!(
            "{} planned episodes are not finished (seeds {}{}); resume those shards first",
            absent.len(),
            shown.join(", "),
            if absent.len() > 5 { ", ..." } else { "" }
        ));
    }
    let episodes: Vec<EpisodeResult> = episodes.into_iter().flatten().collect();
    let mut merged = first.clone();
    merged.shard = None;
    let wall = episodes.iter().map(|e| e.wall_time_s).sum();
    let report = EvalReport {
        schema_version: RESULTS_SCHEMA_VERSION,
        task_id: task.to_string(),
        level: first.level.clone(),
        protocol: first.protocol.clone(),
        policy: match &first.model {
            Some(m) => format!("model {} ({}, {})", m.url, m.wire, m.profile.name),
            None => first.policy.clone(),
        },
        seed: first.seed,
        summary: summarise(&episodes, wall),
        conditions: first.conditions.clone(),
        model: first.model.clone(),
        autobio_version: first.autobio_version.clone(),
        git_commit: first.git_commit.clone(),
        shard: None,
        episodes,
    };
    Ok((merged, report))
}
