//! Build script of the `results` package: the source's git commit for run manifests
//! (`AUTOBIO_GIT_COMMIT`: the commit, with `-dirty` when the work tree had changes, or `unknown`
//! outside a git checkout). No MuJoCo: `results` links no simulator.
// A build script speaks to Cargo through `cargo:` lines on stdout.
#![allow(clippy::print_stdout)]
use std::process::Command;

fn main() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let git = |args: &[&str]| {
        Command::new("git")
            .arg("-C")
            .arg(&root)
            .args(args)
            .output()
            .ok()
            .filter(|o| o.status.success())
            .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
    };
    let commit = match git(&["rev-parse", "HEAD"]) {
        Some(c) if !c.is_empty() => {
            let dirty = git(&["status", "--porcelain", "--untracked-files=no"])
                .is_some_and(|s| !s.is_empty());
            if dirty { format!("{c}-dirty") } else { c }
        }
        _ => "unknown".to_string(),
    };
    println!("cargo:rustc-env=AUTOBIO_GIT_COMMIT={commit}");
    // Sources edited since the last build make the commit `-dirty`: rerun when they change.
    for dir in [
        "src",
        "dsl",
        "compiler",
        "primitives",
        "labware",
        "robots",
        "physics",
        "runtime",
        "scoring",
        "results",
        "leaderboard",
        "dataset",
        "profiles",
        "build",
        "Cargo.toml",
        "Cargo.lock",
    ] {
        println!("cargo:rerun-if-changed={}", root.join(dir).display());
    }
    if let Some(dir) = git(&["rev-parse", "--absolute-git-dir"]) {
        println!("cargo:rerun-if-changed={dir}/HEAD");
        println!("cargo:rerun-if-changed={dir}/index");
        if let Some(r) = git(&["symbolic-ref", "-q", "HEAD"]) {
            println!("cargo:rerun-if-changed={dir}/{r}");
        }
    }
}
