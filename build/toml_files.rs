//! For build scripts that compile shipped TOML files in (the Python extension's protocols, the
//! leaderboard's suites and protocols): every `.toml` file under a folder, each folder watched
//! for changes. It writes nothing.
use std::path::{Path, PathBuf};

/// Every `.toml` file under `dir` and its subfolders, appended to `files`; cargo reruns the
/// build script when any of those folders changes.
pub(crate) fn walk(dir: &Path, files: &mut Vec<PathBuf>) {
    println!("cargo:rerun-if-changed={}", dir.display());
    for entry in std::fs::read_dir(dir).expect("a readable shipped folder") {
        let path = entry.expect("a readable entry").path();
        if path.is_dir() {
            walk(&path, files);
        } else if path.extension().is_some_and(|e| e == "toml") {
            files.push(path);
        }
    }
}
