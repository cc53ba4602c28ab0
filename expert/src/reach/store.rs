//! Reach outcomes kept between runs, so that `autobio check` re-solves only what an edit
//! touched: each layout's outcome (the steps missed in one seed's layout, with or without base
//! hints) is a small JSON file named by a hash of everything it depends on: the compiled task
//! (its scene, robots, labware, plan and parameters), the seed, whether hints were searched,
//! and the build of the program that solved it (its commit and its executable's size and time).
//! A protocol whose task is unchanged is answered from its files; an edited one misses and is
//! solved afresh; a rebuilt program starts over. A file that cannot be read or parsed is a miss,
//! never an error (two checks writing one entry at once can leave it so: it is solved again), and
//! entries are written to a temporary name and renamed (`results::run::record::write_atomic`).
//!
//! Where the files go is the caller's choice ([`Store::from_env`]: `AUTOBIO_CACHE_DIR`, else the
//! user's cache folder; [`Store::none`] keeps nothing). It does not decide what is solved (the
//! pass does) or report anything.

use super::Unreachable;
use compiler::Task;
use std::path::PathBuf;

/// The format of an entry; bumped when [`Unreachable`] or the pass's meaning changes.
const FORMAT: &str = "reach-1";

/// Where reach outcomes are kept, if anywhere.
#[derive(Clone, Debug, Default)]
pub struct Store {
    dir: Option<PathBuf>,
}

impl Store {
    /// Keeps nothing: every layout is solved.
    pub fn none() -> Store {
        Store { dir: None }
    }

    /// Keeps outcomes under `dir` (made when first written).
    pub fn at(dir: impl Into<PathBuf>) -> Store {
        Store {
            dir: Some(dir.into()),
        }
    }

    /// `AUTOBIO_CACHE_DIR/reach` (an empty value keeps nothing), else `reach` in
    /// `$XDG_CACHE_HOME/autobio` or `~/.cache/autobio`; nothing where none of these is set.
    pub fn from_env() -> Store {
        let root = match std::env::var_os("AUTOBIO_CACHE_DIR") {
            Some(v) if v.is_empty() => return Store::none(),
            Some(v) => Some(PathBuf::from(v)),
            None => std::env::var_os("XDG_CACHE_HOME")
                .filter(|v| !v.is_empty())
                .map(|v| PathBuf::from(v).join("autobio"))
                .or_else(|| {
                    std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache/autobio"))
                }),
        };
        Store {
            dir: root.map(|r| r.join("reach")),
        }
    }

    /// The outcome for `task`'s layout `seed` (with base hints where `hint`): kept, or `solve`d
    /// and kept.
    pub(super) fn misses(
        &self,
        task: &Task,
        seed: u64,
        hint: bool,
        solve: impl FnOnce() -> Vec<Unreachable>,
    ) -> Vec<Unreachable> {
        let Some(path) = self.entry(task, seed, hint) else {
            return solve();
        };
        if let Some(kept) = std::fs::read(&path)
            .ok()
            .and_then(|bytes| serde_json::from_slice(&bytes).ok())
        {
            return kept;
        }
        let solved = solve();
        if let Ok(bytes) = serde_json::to_vec(&solved) {
            // A store that cannot be written is a store that keeps nothing.
            let _ = path
                .parent()
                .map_or(Ok(()), std::fs::create_dir_all)
                .and_then(|_| results::run::record::write_atomic(&path, &bytes));
        }
        solved
    }

    /// The file for one layout's outcome, `None` where nothing is kept (or the task cannot be
    /// written out to be named).
    fn entry(&self, task: &Task, seed: u64, hint: bool) -> Option<PathBuf> {
        let dir = self.dir.as_ref()?;
        let mut key = format!(
            "{FORMAT}\n{}\n{}\n{seed}\n{hint}\n",
            results::run::record::GIT_COMMIT,
            build_identity()
        )
        .into_bytes();
        key.extend(serde_json::to_vec(task).ok()?);
        let name = results::run::record::sha256_hex(&key);
        Some(dir.join(format!("{name}.json")))
    }
}

/// The running program's executable, as its size and modification time: a rebuilt program (the
/// same commit, other code) does not read what an earlier build solved.
fn build_identity() -> String {
    std::env::current_exe()
        .and_then(std::fs::metadata)
        .map(|m| {
            let modified = m
                .modified()
                .ok()
                .and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok())
                .map(|d| d.as_nanos())
                .unwrap_or_default();
            format!("{}:{modified}", m.len())
        })
        .unwrap_or_default()
}
