//! What ARCHITECTURE.md promises that a machine can check: every crate and module starts with a
//! `//!` doc saying what it does; the robots and labware models the docs list are the registries'
//! (`robots::MODELS`, `labware::registry::MODELLED`), not hand-kept copies that drift.

use std::path::{Path, PathBuf};

/// Every `.rs` file under `dir`, recursively.
fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

#[test]
fn every_crate_and_module_says_what_it_does() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let crates = [
        "src",
        "dsl/src",
        "compiler/src",
        "primitives/src",
        "planner/src",
        "labware/src",
        "robots/src",
        "physics/src",
        "runtime/src",
        "results/src",
        "scoring/src",
        "dataset/src",
        "leaderboard/src",
    ];
    let mut files = Vec::new();
    for c in crates {
        rust_files(&root.join(c), &mut files);
    }
    assert!(
        files.len() > 80,
        "{} files: the walk found the sources",
        files.len()
    );
    let undocumented: Vec<String> = files
        .iter()
        .filter(|f| {
            let text = std::fs::read_to_string(f).unwrap();
            !text.trim_start().starts_with("//!")
        })
        .map(|f| f.strip_prefix(root).unwrap().display().to_string())
        .collect();
    assert!(
        undocumented.is_empty(),
        "start these with a `//!` doc: {undocumented:?}"
    );
    // Every workspace member is a crate the walk above covers.
    let manifest = std::fs::read_to_string(root.join("Cargo.toml")).unwrap();
    let members = manifest.split("members = [").nth(1).unwrap();
    let members = &members[..members.find(']').unwrap()];
    for m in members.split(',').map(|m| m.trim().trim_matches('"')) {
        assert!(
            crates.contains(&format!("{m}/src").as_str()),
            "{m} is not walked"
        );
    }
}

#[test]
fn the_docs_name_every_registered_robot_and_labware_model() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let arch = std::fs::read_to_string(root.join("ARCHITECTURE.md")).unwrap();
    for robot in robots::MODELS {
        assert!(
            arch.contains(&format!("`{}`", robot.name)),
            "ARCHITECTURE.md does not name robot `{}`",
            robot.name
        );
    }
    // The catalogue the CLI prints is generated from the registries: every modelled kind is
    // listed as simulated, every other one as not yet.
    let catalogue = compiler::describe::catalogue();
    for kind in labware::KINDS {
        let line = catalogue
            .lines()
            .find(|l| l.trim_start().starts_with(kind.name))
            .unwrap_or_else(|| panic!("the catalogue lists no `{}`", kind.name));
        let modelled = labware::registry::MODELLED.contains(&kind.name);
        assert_eq!(
            !line.contains("[no simulation model yet]"),
            modelled,
            "{line}"
        );
    }
    // And the architecture's model files are the registry's: one file per registry line.
    let registry = std::fs::read_to_string(root.join("labware/src/registry.rs")).unwrap();
    let used = registry
        .lines()
        .find(|l| l.starts_with("use crate::{"))
        .expect("the registry's model modules");
    let used = &used["use crate::{".len()..used.find('}').unwrap()];
    let modules: Vec<&str> = used.split(',').map(str::trim).collect();
    assert!(modules.len() >= 7, "{modules:?}");
    for module in modules {
        assert!(registry.contains(&format!("{module}::Params")), "{module}");
        assert!(
            arch.contains(&format!("`{module}.rs`")),
            "ARCHITECTURE.md does not map `{module}.rs`"
        );
    }
}
