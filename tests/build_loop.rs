//! One build of the workspace's crates serves the tests, the CLI and the wheel. Cargo compiles a
//! crate again whenever its features differ, and it resolves features over the packages a
//! command selects: `cargo test --workspace` (with dev-dependencies), a plain `cargo build` (the
//! workspace's default members) and maturin (the `autobio-python` package alone) must therefore
//! give every crate they share the same features, or each rebuilds what the last one built
//! (7.5 minutes of CI once, for `syn`'s features alone). This reads `cargo tree`'s resolved
//! features for the three selections and compares them.

use std::collections::BTreeMap;
use std::process::Command;

/// Every package `args` selects, with the features Cargo resolved for it.
fn features(args: &[&str]) -> BTreeMap<String, String> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let out = Command::new(cargo)
        .args(["tree", "--offline", "--prefix", "none", "-f", "{p}|{f}"])
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("cargo runs");
    assert!(
        out.status.success(),
        "cargo tree {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .filter_map(|l| {
            let (package, features) = l.split_once('|')?;
            let features = features.trim_end_matches(" (*)").trim_end_matches("(*)");
            Some((package.to_string(), features.trim().to_string()))
        })
        .collect()
}

/// The packages `of` resolves with other features than `all` does: `package: theirs | all's`.
fn differences(of: &BTreeMap<String, String>, all: &BTreeMap<String, String>) -> Vec<String> {
    of.iter()
        .filter_map(|(package, f)| {
            let whole = all.get(package)?;
            (whole != f).then(|| format!("{package}: {f} | {whole}"))
        })
        .collect()
}

#[test]
fn the_tests_the_cli_and_the_wheel_resolve_every_shared_crate_alike() {
    let tests = features(&["--workspace", "-e", "normal,build,dev"]);
    let cli = features(&["-e", "normal,build"]);
    let wheel = features(&["-p", "autobio-python", "-e", "normal,build"]);
    assert!(
        cli.keys().any(|p| p.starts_with("autobio v")) && wheel.len() > 100,
        "the trees were not read: {} and {} packages",
        cli.len(),
        wheel.len()
    );
    // A plain `cargo build` selects every member, the wheel's package among them.
    assert!(
        cli.keys().any(|p| p.starts_with("autobio-python v")),
        "`cargo build` leaves the wheel's crate out (workspace.default-members)"
    );
    assert_eq!(
        differences(&cli, &tests),
        Vec::<String>::new(),
        "cargo build"
    );
    assert_eq!(
        differences(&wheel, &tests),
        Vec::<String>::new(),
        "the wheel's build (pin the feature in python/Cargo.toml)"
    );
}

#[test]
fn a_crate_with_other_features_is_a_difference() {
    let all = BTreeMap::from([
        ("syn v2.0.0".to_string(), "full,visit-mut".to_string()),
        ("serde v1.0.0".to_string(), "std".to_string()),
    ]);
    let wheel = BTreeMap::from([
        ("syn v2.0.0".to_string(), "full".to_string()),
        ("serde v1.0.0".to_string(), "std".to_string()),
        ("pyo3 v0.30.0".to_string(), "abi3".to_string()),
    ]);
    assert_eq!(
        differences(&wheel, &all),
        ["syn v2.0.0: full | full,visit-mut"]
    );
}
