//! Joining datasets recorded in shards (`autobio demo --shard I/N`) into one
//! (`autobio dataset merge`): the shards must be every share of one plan (the same tasks,
//! episodes and seed, each index once) and share version, layout, codec and image size. Episodes
//! are put back in plan order and re-indexed, so the merged frames tables are those one unsharded
//! run would write; statistics are rebuilt from the episodes' (images' are kept, the rest
//! recomputed from the re-indexed rows). The shards are read, never changed.

use crate::writer::{DatasetWriter, Source};
use crate::{Codec, DatasetError};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// What a shard was asked for, kept in `meta/autobio_shard.json` of a shard's dataset.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
/// The share of a generation plan a shard dataset was recorded with (`meta/autobio_shard.json`).
pub struct ShardPlan {
    pub shard: results::run::Shard,
    pub tasks: Vec<String>,
    pub episodes: usize,
    pub seed: u64,
}

/// Where a shard dataset keeps its [`ShardPlan`].
pub const SHARD_FILE: &str = "meta/autobio_shard.json";

impl ShardPlan {
    fn write(&self, root: &Path) -> Result<(), DatasetError> {
        let p = root.join(SHARD_FILE);
        let text = serde_json::to_string_pretty(self).expect("json") + "\n";
        results::run::record::write_atomic(&p, text.as_bytes())
            .map_err(|e| DatasetError::io("write", &p, e))
    }

    /// Records the plan of a new shard, or checks that a resumed one was recorded with it.
    pub fn write_new(&self, root: &Path) -> Result<(), DatasetError> {
        if root.join(SHARD_FILE).exists() {
            let before = ShardPlan::read(root)?;
            if before != *self {
                return Err(DatasetError::Existing {
                    path: root.to_path_buf(),
                    why: format!(
                        "was recorded as shard {} of another plan; resume it with the same protocols, --episodes, --seed and --shard",
                        before.shard
                    ),
                });
            }
            return Ok(());
        }
        self.write(root)
    }

    fn read(root: &Path) -> Result<ShardPlan, DatasetError> {
        let p = root.join(SHARD_FILE);
        let text = std::fs::read_to_string(&p).map_err(|_| DatasetError::Existing {
            path: root.to_path_buf(),
            why: format!(
                "is not a shard (no {SHARD_FILE}; record shards with autobio demo --shard I/N)"
            ),
        })?;
        serde_json::from_str(&text).map_err(|e| DatasetError::Existing {
            path: p,
            why: e.to_string(),
        })
    }
}

/// What a merge wrote.
#[derive(Clone, Debug, PartialEq)]
pub struct Merged {
    pub shards: usize,
    pub episodes: usize,
    pub frames: usize,
}

/// Merges the shard datasets into a new dataset at `out` (see the module doc).
pub fn merge(shards: &[PathBuf], out: &Path) -> Result<Merged, DatasetError> {
    let refuse = |path: &Path, why: String| DatasetError::Existing {
        path: path.to_path_buf(),
        why,
    };
    let first_path = shards
        .first()
        .ok_or_else(|| refuse(out, "no shard to merge".into()))?;
    let mut plans = Vec::new();
    let mut sources = Vec::new();
    for root in shards {
        std::fs::metadata(root).map_err(|e| DatasetError::io("read the shard", root, e))?;
        plans.push(ShardPlan::read(root)?);
        sources.push(Source::open(root)?);
    }
    // Every share of one plan, once.
    let (plan0, src0) = (&plans[0], &sources[0]);
    let count = plan0.shard.count as usize;
    let mut seen: Vec<Option<&PathBuf>> = vec![None; count];
    for ((root, plan), src) in shards.iter().zip(&plans).zip(&sources) {
        let same_plan = (plan.shard.count, &plan.tasks, plan.episodes, plan.seed)
            == (plan0.shard.count, &plan0.tasks, plan0.episodes, plan0.seed);
        if !same_plan {
            return Err(refuse(
                root,
                format!(
                    "is a shard of another plan than {} (tasks, episodes, seed or shard count differ)",
                    first_path.display()
                ),
            ));
        }
        let same_layout = src.version == src0.version
            && src.layout() == src0.layout()
            && (&src.codec, src.size) == (&src0.codec, src0.size);
        if !same_layout {
            return Err(refuse(
                root,
                format!(
                    "differs from {} in version, robots, cameras, codec or image size",
                    first_path.display()
                ),
            ));
        }
        let slot = &mut seen[plan.shard.index as usize];
        if let Some(other) = slot {
            return Err(refuse(
                root,
                format!("is shard {} again (also {})", plan.shard, other.display()),
            ));
        }
        *slot = Some(root);
    }
    if let Some(missing) = seen.iter().position(Option::is_none) {
        return Err(refuse(
            out,
            format!("shard {missing}/{count} is missing; merge needs all {count}"),
        ));
    }
    let mut order: Vec<(usize, usize)> = sources
        .iter()
        .enumerate()
        .flat_map(|(s, src)| (0..src.done.len()).map(move |e| (s, e)))
        .collect();
    let key = |&(s, e): &(usize, usize)| {
        let c = &sources[s].done[e];
        (c.plan.unwrap_or(usize::MAX), c.task_id.clone(), c.seed)
    };
    order.sort_by_key(key);
    if let Some(w) = order.windows(2).find(|w| {
        let (a, b) = (key(&w[0]), key(&w[1]));
        (&a.1, a.2) == (&b.1, b.2)
    }) {
        let (task, seed) = (
            &sources[w[0].0].done[w[0].1].task_id,
            sources[w[0].0].done[w[0].1].seed,
        );
        return Err(refuse(
            &sources[w[1].0].root,
            format!("holds episode {seed} of {task}, which another shard holds too"),
        ));
    }
    let codec = match src0.codec.as_str() {
        "av1" => Codec::Av1,
        "h264" => Codec::H264,
        other => return Err(refuse(first_path, format!("has videos in `{other}`"))),
    };
    let mut writer =
        DatasetWriter::open(out, src0.version, codec, src0.layout(), src0.size, false)?;
    writer.set_file_sizes(src0.file_sizes);
    let mut frames = 0;
    for (s, e) in &order {
        frames += writer.adopt(&sources[*s], *e)?;
    }
    let episodes = writer.finish()?;
    Ok(Merged {
        shards: shards.len(),
        episodes,
        frames,
    })
}
