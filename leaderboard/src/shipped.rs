//! The suites and protocols this autobio shipped, compiled into it by the build script: what
//! `leaderboard verify` and `audit` check a bundle against when no `--suites` folder is given,
//! from any folder, with no checkout beside the binary.
//!
//! It writes the shipped files out; it compiles and checks nothing.

use std::path::{Path, PathBuf};

include!(concat!(env!("OUT_DIR"), "/shipped.rs"));

/// Writes every shipped suite and protocol under `dir` (`suites/`, `protocols/`, as in the
/// checkout) and returns the suites folder.
pub fn write_out(dir: &Path) -> std::io::Result<PathBuf> {
    for (rel, bytes) in SHIPPED {
        let path = dir.join(rel);
        if let Some(parent) = path.parent() {
            std::fs::create_dir_all(parent)?;
        }
        std::fs::write(&path, bytes)?;
    }
    Ok(dir.join("suites"))
}

/// The shipped files' paths relative to the checkout, in order.
pub fn files() -> impl Iterator<Item = &'static str> {
    SHIPPED.iter().map(|(rel, _)| *rel)
}
