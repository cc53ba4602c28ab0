//! What ARCHITECTURE.md promises that a machine can check: every crate and module starts with a
//! `//!` doc saying what it does; the robots and labware models the docs list are the registries'
//! (`robots::MODELS`, `labware::MODELLED`), not hand-kept copies that drift; and no
//! module reaches itself through its `crate::`/`super::` imports (an import cycle).

use std::path::{Path, PathBuf};

/// Every crate's sources: the CLI's and each workspace member's.
const CRATES: [&str; 19] = [
    "src",
    "dsl/src",
    "interchange/src",
    "compiler/src",
    "primitives/src",
    "planner/src",
    "labware/src",
    "robots/src",
    "physics/src",
    "runtime/src",
    "results/src",
    "policy/src",
    "expert/src",
    "scoring/src",
    "synth/src",
    "dataset/src",
    "demos/src",
    "leaderboard/src",
    "python/src",
];

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
    let crates = CRATES;
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
        let modelled = labware::MODELLED.contains(&kind.name);
        assert_eq!(
            !line.contains("[no simulation model yet]"),
            modelled,
            "{line}"
        );
    }
    // And the architecture's model files are the registry's: one file per registry line.
    let modules = labware::MODEL_MODULES;
    let src = root.join("labware/src");
    assert!(modules.len() >= 7, "{modules:?}");
    for module in modules {
        assert!(src.join(format!("{module}.rs")).is_file(), "{module}");
        assert!(
            arch.contains(&format!("`{module}.rs`")),
            "ARCHITECTURE.md does not map `{module}.rs`"
        );
    }
}

/// A crate's modules (file path -> `a::b` module path), the crate root left out (it only
/// declares and re-exports).
fn modules(src: &Path) -> Vec<(String, PathBuf)> {
    let mut files = Vec::new();
    rust_files(src, &mut files);
    files
        .into_iter()
        .filter_map(|f| {
            let rel = f.strip_prefix(src).unwrap().with_extension("");
            let mut parts: Vec<String> = rel
                .components()
                .map(|c| c.as_os_str().to_string_lossy().into_owned())
                .collect();
            if parts.last().is_some_and(|p| p == "mod") {
                parts.pop();
            }
            (parts != ["lib"] && parts != ["main"]).then(|| (parts.join("::"), f))
        })
        .collect()
}

/// The paths an import names after its `crate::` or `super::` prefix (`rest` starts just after
/// it): one path, or each of a `{...}` group's (nested groups read by their first segment).
fn import_paths(rest: &str) -> Vec<String> {
    let path_char = |c: char| c.is_ascii_alphanumeric() || c == '_' || c == ':';
    let Some(group) = rest.strip_prefix('{') else {
        return vec![rest.chars().take_while(|c| path_char(*c)).collect()];
    };
    let mut depth = 0;
    let mut items = vec![String::new()];
    for c in group.chars() {
        match c {
            '{' => depth += 1,
            '}' if depth == 0 => break,
            '}' => depth -= 1,
            ',' if depth == 0 => items.push(String::new()),
            c if depth == 0 && !c.is_whitespace() => items.last_mut().unwrap().push(c),
            _ => {}
        }
    }
    items
        .into_iter()
        .map(|i| i.chars().take_while(|c| path_char(*c)).collect())
        .collect()
}

/// The modules each module of `src` uses through `crate::` and `super::` paths (code only, not
/// comments or a file's trailing `#[cfg(test)]` module): a `super::x` path is `x` beside the
/// module (in its parent), a plain `super::` use the parent itself; `crate::` paths to its own
/// ancestors and descendants aside.
fn module_graph(src: &Path) -> std::collections::BTreeMap<String, Vec<String>> {
    let mods = modules(src);
    let names: Vec<&str> = mods.iter().map(|(m, _)| m.as_str()).collect();
    let related = |a: &str, b: &str| {
        a == b || a.starts_with(&format!("{b}::")) || b.starts_with(&format!("{a}::"))
    };
    // The longest module path that `parts` starts with.
    let module_of = |parts: &[&str]| {
        (1..=parts.len())
            .rev()
            .map(|k| parts[..k].join("::"))
            .find(|t| names.contains(&t.as_str()))
    };
    let mut graph = std::collections::BTreeMap::new();
    for (m, file) in &mods {
        let text = std::fs::read_to_string(file).unwrap();
        // A unit-test module at the end of a file imports `super::` as its own file.
        let text = text.split("#[cfg(test)]").next().unwrap_or("");
        let code: String = text
            .lines()
            .map(|l| l.split("//").next().unwrap_or(""))
            .collect::<Vec<_>>()
            .join("\n");
        let word_before = |i: usize| {
            i > 0 && code[..i].ends_with(|c: char| c.is_alphanumeric() || c == '_' || c == ':')
        };
        let mut uses = std::collections::BTreeSet::new();
        for (i, _) in code.match_indices("crate::") {
            if word_before(i) {
                continue;
            }
            for path in import_paths(&code[i + 7..]) {
                let parts: Vec<&str> = path.split("::").filter(|p| !p.is_empty()).collect();
                if let Some(t) = module_of(&parts).filter(|t| !related(m, t)) {
                    uses.insert(t);
                }
            }
        }
        // `super` of a file module `a::b` is `a` (of a top-level module, the crate root).
        let parent: Vec<&str> = match m.rsplit_once("::") {
            Some((parent, _)) => parent.split("::").collect(),
            None => Vec::new(),
        };
        for (i, _) in code.match_indices("super::") {
            if word_before(i) {
                continue;
            }
            let mut base = parent.clone();
            let mut rest = &code[i + 7..];
            while let Some(r) = rest.strip_prefix("super::") {
                base.pop();
                rest = r;
            }
            for path in import_paths(rest) {
                let mut parts = base.clone();
                parts.extend(path.split("::").filter(|p| !p.is_empty()));
                match module_of(&parts) {
                    Some(t) if &t != m => {
                        uses.insert(t);
                    }
                    _ => {}
                }
            }
        }
        graph.insert(m.clone(), uses.into_iter().collect());
    }
    graph
}

/// A cycle in the graph, if there is one (depth-first search).
fn find_cycle(graph: &std::collections::BTreeMap<String, Vec<String>>) -> Option<Vec<String>> {
    fn visit(
        v: &str,
        graph: &std::collections::BTreeMap<String, Vec<String>>,
        state: &mut std::collections::BTreeMap<String, u8>,
        path: &mut Vec<String>,
    ) -> Option<Vec<String>> {
        state.insert(v.to_string(), 1);
        path.push(v.to_string());
        for w in graph.get(v).into_iter().flatten() {
            match state.get(w.as_str()).copied().unwrap_or(0) {
                1 => {
                    let start = path.iter().position(|p| p == w).unwrap();
                    let mut cycle = path[start..].to_vec();
                    cycle.push(w.clone());
                    return Some(cycle);
                }
                0 => {
                    if let Some(c) = visit(w, graph, state, path) {
                        return Some(c);
                    }
                }
                _ => {}
            }
        }
        path.pop();
        state.insert(v.to_string(), 2);
        None
    }
    let mut state = std::collections::BTreeMap::new();
    for v in graph.keys() {
        if state.get(v.as_str()).copied().unwrap_or(0) == 0
            && let Some(c) = visit(v, graph, &mut state, &mut Vec::new())
        {
            return Some(c);
        }
    }
    None
}

#[test]
fn no_module_reaches_itself_through_its_imports() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut checked = 0;
    for c in CRATES {
        let graph = module_graph(&root.join(c));
        checked += graph.len();
        if let Some(cycle) = find_cycle(&graph) {
            panic!("{c}: an import cycle: {}", cycle.join(" -> "));
        }
    }
    assert!(checked > 80, "{checked} modules: the walk found them");
    // The check can fail: a crate of two modules that import each other, read by the same walk
    // from files on disk, is a cycle; with one of the imports gone it is not.
    let dir = crate::common::scratch("import-cycle");
    std::fs::create_dir_all(dir.join("src")).unwrap();
    std::fs::write(
        dir.join("src/lib.rs"),
        "//! x\nmod check;\nmod primitives;\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("src/check.rs"),
        "//! x\nuse crate::primitives::Step;\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("src/primitives.rs"),
        "//! x\npub struct Step;\nfn f() { crate::check::run(); }\n",
    )
    .unwrap();
    let cycle = find_cycle(&module_graph(&dir.join("src"))).expect("the two modules are a cycle");
    assert_eq!(cycle, ["check", "primitives", "check"]);
    std::fs::write(
        dir.join("src/primitives.rs"),
        "//! x\npub struct Step;\n// crate::check::run() in a comment is no import\n",
    )
    .unwrap();
    assert_eq!(find_cycle(&module_graph(&dir.join("src"))), None);
    // Two siblings that import each other through `super::` are a cycle too (a `super::`
    // path names a module beside the importer, not only its parent); a unit-test module's
    // `use super::*` is no import of the file's.
    std::fs::create_dir_all(dir.join("src/site")).unwrap();
    std::fs::write(dir.join("src/lib.rs"), "//! x\nmod site;\n").unwrap();
    std::fs::write(
        dir.join("src/site/mod.rs"),
        "//! x\nmod load;\nmod stats;\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("src/site/load.rs"),
        "//! x\nuse super::{io, stats::Spread};\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("src/site/stats.rs"),
        "//! x\nuse super::load::Submission;\n#[cfg(test)]\nmod tests {\n    use super::*;\n}\n",
    )
    .unwrap();
    let _ = std::fs::remove_file(dir.join("src/check.rs"));
    let _ = std::fs::remove_file(dir.join("src/primitives.rs"));
    let cycle = find_cycle(&module_graph(&dir.join("src"))).expect("the siblings are a cycle");
    assert_eq!(cycle, ["site::load", "site::stats", "site::load"]);
    std::fs::write(dir.join("src/site/load.rs"), "//! x\nuse super::io;\n").unwrap();
    assert_eq!(find_cycle(&module_graph(&dir.join("src"))), None);
}

/// The Python package's modules say what they do too: each starts with a docstring, which
/// `help()` shows.
#[test]
fn every_python_module_starts_with_a_docstring() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("python/autobio");
    let modules: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "py"))
        .collect();
    assert!(
        modules.len() >= 6,
        "{modules:?}: the walk found the package"
    );
    let bare: Vec<String> = modules
        .iter()
        .filter(|p| {
            !std::fs::read_to_string(p)
                .unwrap()
                .trim_start()
                .starts_with("\"\"\"")
        })
        .map(|p| p.display().to_string())
        .collect();
    assert!(bare.is_empty(), "start these with a docstring: {bare:?}");
}

/// The `mod` lines of a test binary's root (`tests/suite.rs`), and the test files beside it that
/// no line names: such a file is never compiled, its tests never run.
fn files_outside_the_suite(tests: &Path) -> Vec<String> {
    let suite = std::fs::read_to_string(tests.join("suite.rs")).unwrap();
    let declared: Vec<&str> = suite
        .lines()
        .filter_map(|l| l.trim().strip_prefix("mod ")?.strip_suffix(';'))
        .collect();
    let mut missing = Vec::new();
    for entry in std::fs::read_dir(tests).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_stem().unwrap().to_string_lossy().into_owned();
        let is_module = if path.is_dir() {
            path.join("mod.rs").is_file()
        } else {
            path.extension().is_some_and(|e| e == "rs") && name != "suite"
        };
        if is_module && !declared.contains(&name.as_str()) {
            missing.push(name);
        }
    }
    missing.sort();
    missing
}

#[test]
fn every_test_file_is_a_module_of_the_suite() {
    let tests = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests");
    assert_eq!(
        files_outside_the_suite(&tests),
        Vec::<String>::new(),
        "test files tests/suite.rs does not name (`mod <file>;`), so their tests never run"
    );
    // The check can fail: a file beside a suite that names only the other one.
    let dir = crate::common::scratch("suite-modules");
    std::fs::create_dir_all(dir.join("helpers")).unwrap();
    std::fs::write(dir.join("suite.rs"), "mod named;\n// mod forgotten;\n").unwrap();
    std::fs::write(dir.join("named.rs"), "").unwrap();
    std::fs::write(dir.join("forgotten.rs"), "").unwrap();
    std::fs::write(dir.join("helpers/mod.rs"), "").unwrap();
    assert_eq!(files_outside_the_suite(&dir), ["forgotten", "helpers"]);
}
