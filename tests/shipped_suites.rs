//! The shipped suites against the shipped protocols: `all` is every simulated shipped task (a
//! task added under protocols/ and missing from it fails here), and every suite's every task
//! compiles with no error and is not trivial, so that a submission of any shipped suite can
//! verify. The shipped tree compiled into the binary is the checkout's.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            walk(&p, out);
        } else if p.extension().is_some_and(|x| x == "toml") {
            out.push(p);
        }
    }
}

/// Every shipped protocol file that compiles to a task whose every item the runtime can build
/// (a workflow's stage files aside: the task is the chain), relative to the checkout.
fn simulated_tasks() -> BTreeSet<String> {
    let mut files = Vec::new();
    walk(&root().join("protocols"), &mut files);
    files
        .iter()
        .filter(|f| !f.components().any(|c| c.as_os_str() == "stages"))
        .filter_map(|f| {
            let task = compiler::check_file(f, None).ok()?.task?;
            task.labware
                .iter()
                .all(|l| l.params.instrument().is_some())
                .then(|| f.strip_prefix(root()).unwrap().display().to_string())
        })
        .collect()
}

fn suite_tasks(name: &str) -> BTreeSet<String> {
    let s = results::suite::LoadedSuite::read(&root().join("suites").join(name)).unwrap();
    s.protocols()
        .iter()
        .map(|p| {
            let p = p.strip_prefix(root().join("suites")).unwrap();
            p.strip_prefix("..").unwrap().display().to_string()
        })
        .collect()
}

#[test]
fn the_all_suite_is_every_simulated_shipped_task() {
    let shipped = simulated_tasks();
    // Sanity: the walk found the task families it must (a broken walk finds nothing).
    for t in [
        "protocols/pipette/aspirate.toml",
        "protocols/workflows/centrifuge_run.toml",
        "protocols/tube/screw_cap.toml",
    ] {
        assert!(shipped.contains(t), "{t} not among {shipped:?}");
    }
    let all = suite_tasks("all.toml");
    let missing: Vec<_> = shipped.difference(&all).collect();
    let extra: Vec<_> = all.difference(&shipped).collect();
    assert!(
        missing.is_empty() && extra.is_empty(),
        "suites/all.toml lacks {missing:?} and lists {extra:?}, which is not a simulated shipped task"
    );
}

#[test]
fn every_shipped_suite_compiles_and_none_is_trivial() {
    let mut names: Vec<String> = std::fs::read_dir(root().join("suites"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".toml"))
        .collect();
    names.sort();
    assert_eq!(
        names,
        [
            "all.toml",
            "baseline.toml",
            "demo.toml",
            "lab.toml",
            "learned-smoke.toml",
            "paper.toml",
            "robustness-smoke.toml",
            "robustness.toml",
            "smoke.toml"
        ]
    );
    for name in &names {
        let s = results::suite::LoadedSuite::read(&root().join("suites").join(name)).unwrap();
        assert!(!s.suite.tasks.is_empty(), "{name} has no task");
        for p in s.protocols() {
            let c = compiler::check_file(&p, None).unwrap();
            let errors: Vec<_> = c.diagnostics.iter().filter(|d| d.is_error()).collect();
            assert!(
                errors.is_empty(),
                "{name}: {} has errors: {errors:?}",
                p.display()
            );
            assert!(
                c.task.is_some(),
                "{name}: {} compiles to no task",
                p.display()
            );
            assert_eq!(c.trivial_at(), None, "{name}: {} is trivial", p.display());
        }
        // Each preset the suite names keeps every task's cameras on the work (E0045's check).
        for e in s.entries() {
            let task = e.task(
                compiler::check_file(&e.protocol, None)
                    .unwrap()
                    .task
                    .unwrap(),
            );
            if let Some(shake) = task.perturb.as_ref().and_then(|p| p.camera.as_ref()) {
                let problem = compiler::perturb::camera_problem(&task, shake);
                assert_eq!(problem, None, "{name}: {}", task.id);
            }
        }
    }
}

#[test]
fn the_binary_ships_the_checkouts_suites_and_protocols() {
    // What `leaderboard verify` checks against with no --suites: byte for byte the checkout's.
    let out = tempfile::tempdir().unwrap();
    let suites = leaderboard::shipped::write_out(out.path()).unwrap();
    let mut ours = Vec::new();
    walk(&root().join("suites"), &mut ours);
    walk(&root().join("protocols"), &mut ours);
    let mut theirs = Vec::new();
    walk(&suites, &mut theirs);
    walk(&out.path().join("protocols"), &mut theirs);
    assert_eq!(ours.len(), theirs.len());
    assert!(ours.len() > 40, "{} files", ours.len());
    for f in &ours {
        let rel = f.strip_prefix(root()).unwrap();
        assert_eq!(
            std::fs::read(f).unwrap(),
            std::fs::read(out.path().join(rel)).unwrap(),
            "{}",
            rel.display()
        );
    }
}
