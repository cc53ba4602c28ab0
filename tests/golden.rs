//! Golden tests for every shipped protocol and chain: the parsed AST, the check result, the
//! compiled task, its task sheet and the scene instances seeds 0-4 draw must match the files under tests/golden byte for byte, and
//! compiling twice gives byte-identical tasks. After an intended change, regenerate with
//! `UPDATE_GOLDEN=1 cargo test --release --test golden` and review the diff.

use crate::common;

use std::path::{Path, PathBuf};

fn outputs(path: &Path) -> Vec<(&'static str, String)> {
    let name = path.display().to_string();
    let source = std::fs::read_to_string(path).unwrap();
    let (doc, parse_diags) = dsl::parse(&source);
    let (task, diags) = compiler::compile_source(&source, &name);
    let task = task.unwrap_or_else(|| panic!("{name} must compile: {diags:#?}"));
    let check: String = parse_diags
        .iter()
        .chain(&diags)
        .map(|d| format!("{} {} {:?}\n", d.code, d.message, d.span))
        .collect();
    vec![
        (
            "ast.json",
            serde_json::to_string_pretty(&doc).unwrap() + "\n",
        ),
        (
            "check.txt",
            if check.is_empty() {
                "ok\n".into()
            } else {
                check
            },
        ),
        (
            "task.json",
            serde_json::to_string_pretty(&task).unwrap() + "\n",
        ),
        ("sheet.txt", compiler::describe::describe(&task)),
        // What the first seeds draw: changing the draw order or the generator fails here.
        (
            "draws.jsonl",
            (0..5)
                .map(|seed| serde_json::to_string(&task.sample(seed)).unwrap() + "\n")
                .collect(),
        ),
    ]
}

#[test]
fn shipped_protocols_match_their_golden_outputs() {
    let update = std::env::var_os("UPDATE_GOLDEN").is_some();
    let protocols = common::shipped_protocols();
    assert!(protocols.len() >= 9, "{protocols:?}");
    let mut stale = Vec::new();
    let mut produced = std::collections::BTreeSet::new();
    for path in protocols {
        let stem = path.with_extension("");
        let golden_base = Path::new("tests/golden").join(stem.strip_prefix("protocols").unwrap());
        for (ext, text) in outputs(&path) {
            let golden = PathBuf::from(format!("{}.{ext}", golden_base.display()));
            produced.insert(golden.clone());
            if update {
                std::fs::create_dir_all(golden.parent().unwrap()).unwrap();
                std::fs::write(&golden, &text).unwrap();
                continue;
            }
            let want = std::fs::read_to_string(&golden).unwrap_or_else(|_| {
                panic!("{} is missing: run with UPDATE_GOLDEN=1", golden.display())
            });
            if want != text {
                stale.push(golden.display().to_string());
            }
        }
    }
    // A run that rewrote the goldens compared nothing: it never passes.
    assert!(
        !update,
        "UPDATE_GOLDEN: {} goldens written; review `git diff tests/golden`, then run again without it",
        produced.len()
    );
    assert!(stale.is_empty(), "outputs differ from: {stale:#?}");
    // Every golden is some shipped protocol's (the diagnostics' are tests/cli.rs's): a golden
    // left behind by a removed or renamed protocol is an error, not dead weight.
    let mut orphans = Vec::new();
    let mut walk = vec![PathBuf::from("tests/golden")];
    while let Some(dir) = walk.pop() {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                if path != Path::new("tests/golden/diagnostics") {
                    walk.push(path);
                }
            } else if !produced.contains(&path) {
                orphans.push(path.display().to_string());
            }
        }
    }
    assert!(
        orphans.is_empty(),
        "goldens no shipped protocol produces: {orphans:#?}"
    );
}

/// Within one process: a hash map's iteration order differs between two maps, so output that
/// depended on one would differ here (the goldens pin the bytes across processes).
#[test]
fn compiling_twice_gives_identical_bytes() {
    for path in common::shipped_protocols() {
        let a = outputs(&path);
        let b = outputs(&path);
        assert_eq!(a, b, "{}", path.display());
    }
}

#[test]
fn the_same_seed_draws_the_same_parameters() {
    let source = std::fs::read_to_string("protocols/thermal_mixer/set_parameters.toml").unwrap();
    let (task, _) = compiler::compile_source(&source, "set_parameters.toml");
    let task = task.unwrap();
    let a = task.sample(42);
    assert_eq!(a, task.sample(42));
    assert_ne!(a.params, task.sample(43).params);
    // Exclusions hold on every draw, and the instruction carries the drawn values.
    for seed in 0..200 {
        let s = task.sample(seed);
        assert_ne!(s.params["rpm"], "900");
        assert_ne!(s.params["temp"], "25");
        assert_ne!(s.params["time"], "60");
        assert!(
            s.instruction
                .contains(&format!("speed set to {} RPM", s.params["rpm"]))
        );
    }
    // The rotor's second slot is always across from the first.
    let source = std::fs::read_to_string("protocols/centrifuge/insert_symmetric.toml").unwrap();
    let (task, _) = compiler::compile_source(&source, "insert_symmetric.toml");
    let task = task.unwrap();
    for seed in 0..50 {
        let p = task.sample(seed).params;
        let first: u32 = p["first"].parse().unwrap();
        let balance: u32 = p["balance"].parse().unwrap();
        assert_eq!((first + 14) % 30 + 1, balance, "{p:?}");
    }
}

#[test]
fn the_language_reference_covers_every_code_primitive_and_kind() {
    let doc = std::fs::read_to_string("docs/protocol-language.md").unwrap();
    for c in dsl::Code::ALL {
        assert!(doc.contains(&format!("| {c} | {} |", c.summary())), "{c}");
    }
    for p in compiler::primitives::CATALOGUE {
        assert!(doc.contains(&format!("| `{}` |", p.name)), "{}", p.name);
    }
    for k in labware::KINDS {
        assert!(doc.contains(&format!("`{}`", k.name)), "{}", k.name);
    }
}
