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

/// The modules each module of `src` uses through `crate::` paths and `super::` (code only, not
/// comments), its own ancestors and descendants aside.
fn module_graph(src: &Path) -> std::collections::BTreeMap<String, Vec<String>> {
    let mods = modules(src);
    let names: Vec<&str> = mods.iter().map(|(m, _)| m.as_str()).collect();
    let related = |a: &str, b: &str| {
        a == b || a.starts_with(&format!("{b}::")) || b.starts_with(&format!("{a}::"))
    };
    let mut graph = std::collections::BTreeMap::new();
    for (m, file) in &mods {
        let code: String = std::fs::read_to_string(file)
            .unwrap()
            .lines()
            .map(|l| l.split("//").next().unwrap_or(""))
            .collect::<Vec<_>>()
            .join("\n");
        let mut uses = std::collections::BTreeSet::new();
        for (i, _) in code.match_indices("crate::") {
            if i > 0 && code[..i].ends_with(|c: char| c.is_alphanumeric() || c == '_') {
                continue;
            }
            let path: String = code[i + 7..]
                .chars()
                .take_while(|c| {
                    c.is_ascii_lowercase() || c.is_ascii_digit() || *c == '_' || *c == ':'
                })
                .collect();
            let parts: Vec<&str> = path.split("::").filter(|p| !p.is_empty()).collect();
            let target = (1..=parts.len())
                .rev()
                .map(|k| parts[..k].join("::"))
                .find(|t| names.contains(&t.as_str()));
            if let Some(t) = target.filter(|t| !related(m, t)) {
                uses.insert(t);
            }
        }
        if code.contains("super::")
            && let Some((parent, _)) = m.rsplit_once("::")
            && names.contains(&parent)
        {
            uses.insert(parent.to_string());
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
