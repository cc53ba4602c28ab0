//! `autobio results merge` reads shard folders and never writes them: after a merge, a refused
//! merge (an unfinished shard, a missing one, the output pointed at a shard) and a merge whose
//! output already holds the run, every byte under every shard folder is as it was.

use crate::common;

use common::{autobio, scratch, text};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

const TASK: &str = "thermal_cycler.close_lid";

/// Every file under `dirs`, by path, with its bytes.
fn snapshot(dirs: &[&Path]) -> BTreeMap<PathBuf, Vec<u8>> {
    let mut files = BTreeMap::new();
    for dir in dirs {
        for entry in std::fs::read_dir(dir).unwrap() {
            let path = entry.unwrap().path();
            files.insert(path.clone(), std::fs::read(&path).unwrap());
        }
    }
    files
}

fn merge(shards: &[&Path], out: &Path) -> std::process::Output {
    let mut args = vec!["results", "merge"];
    args.extend(shards.iter().map(|d| d.to_str().unwrap()));
    args.extend(["--out", out.to_str().unwrap()]);
    autobio(&args)
}

/// The no-motion control's `episodes` episodes run as shards 0/2 and 1/2 into two folders.
fn hold_shards(first: &Path, second: &Path, episodes: &str) {
    for (dir, shard) in [(first, "0/2"), (second, "1/2")] {
        let out = autobio(&[
            "eval",
            "--protocol",
            "protocols/thermal_cycler/close_lid.toml",
            "--policy",
            "hold",
            "--episodes",
            episodes,
            "--seed",
            "0",
            "--shard",
            shard,
            "--out",
            dir.to_str().unwrap(),
        ]);
        assert!(out.status.success(), "{}", text(&out.stderr));
    }
}

#[test]
fn merging_never_writes_a_shard() {
    let root = scratch("merge");
    let (s0, s1) = (root.join("s0"), root.join("s1"));
    hold_shards(&s0, &s1, "3");
    // One episode over two shards: shard 1 plans none, and its journal is empty.
    let (e0, e1) = (root.join("e0"), root.join("e1"));
    hold_shards(&e0, &e1, "1");
    let empty = [e0.as_path(), e1.as_path()];
    let before_empty = snapshot(&empty);
    assert_eq!(
        before_empty[&e1.join(format!("{TASK}.journal.jsonl"))].len(),
        0
    );
    let out = merge(&empty, &e1);
    let said = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{said}");
    assert!(said.contains("is one of the shards being merged"), "{said}");
    assert!(
        snapshot(&empty) == before_empty,
        "the empty shard was written"
    );

    let shards = [s0.as_path(), s1.as_path()];
    let before = snapshot(&shards);
    assert!(
        before.len() >= 6,
        "two manifests, journals and results: {:?}",
        before.keys()
    );
    let unchanged = |when: &str| {
        assert!(
            snapshot(&shards) == before,
            "{when}: a shard's files changed"
        );
    };

    let merged = root.join("merged");
    let out = merge(&shards, &merged);
    assert!(out.status.success(), "{}", text(&out.stderr));
    unchanged("after the merge");
    let journal = common::journal(&merged, TASK);
    assert_eq!(journal.len(), 3);

    // Merged again into the same output: refused (it holds the run), shards untouched.
    let out = merge(&shards, &merged);
    assert_eq!(out.status.code(), Some(2), "{}", text(&out.stderr));
    unchanged("after a merge into a finished output");

    // The output pointed at a shard's own folder: refused, with why.
    for (i, shard) in shards.iter().enumerate() {
        let out = merge(&shards, shard);
        let said = text(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{said}");
        assert!(said.contains("is one of the shards being merged"), "{said}");
        unchanged(&format!("after a merge into shard {i}"));
    }

    // A shard missing: refused.
    let out = merge(&shards[..1], &root.join("half"));
    let said = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{said}");
    assert!(said.contains("shards 1/2 are missing"), "{said}");
    unchanged("after a merge with a shard missing");

    // A shard whose journal a crash cut short: refused as unfinished, the fragment kept.
    let j1 = s1.join(format!("{TASK}.journal.jsonl"));
    let whole = std::fs::read_to_string(&j1).unwrap();
    let cut = &whole[..whole.len() / 2];
    std::fs::write(&j1, cut).unwrap();
    let before_cut = snapshot(&shards);
    let out = merge(&shards, &root.join("cut"));
    let said = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{said}");
    assert!(snapshot(&shards) == before_cut, "the cut shard was written");
    assert_eq!(std::fs::read_to_string(&j1).unwrap(), cut);
}
