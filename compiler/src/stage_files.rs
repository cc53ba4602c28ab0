//! How a chain reads its stage files, and the rules that keep a chain from reading anything
//! else. Protocols arrive from strangers (shared on the web, inside leaderboard submissions), so a
//! stage path is confined to a protocol root (the chain's folder unless widened), must name a
//! regular file of at most [`MAX_STAGE_BYTES`], and must be UTF-8 text. A path that breaks a rule
//! is refused before the file is opened, and the refusal names the rule, never the file's text.
//!
//! [`StageFiles`] is the file-system loader; tests and the fuzzer pass in-memory loaders through
//! the same [`StageLoader`] trait. This module resolves and reads; it does not parse.

use std::cell::RefCell;
use std::collections::BTreeMap;
use std::io::Read;
use std::path::{Component, Path, PathBuf};

/// Largest stage file a chain reads: protocols are a few kilobytes.
pub const MAX_STAGE_BYTES: u64 = 1 << 20;

/// A stage file's text and the name diagnostics use for it.
#[derive(Clone, Debug, PartialEq)]
pub struct StageSource {
    /// The stage path joined to the chain's folder, as a user would type it.
    pub path: String,
    pub text: String,
}

/// Why a stage file was not read.
#[derive(Debug, thiserror::Error)]
pub enum StageError {
    #[error("stage `{path}` is outside the protocol root `{root}`")]
    OutsideRoot { path: String, root: String },
    #[error("stage `{path}` is not a regular file (it is a folder, device, pipe or socket)")]
    NotAFile { path: String },
    #[error("stage `{path}` is {bytes} bytes, more than the {limit} a stage file may have")]
    TooLarge {
        path: String,
        bytes: u64,
        limit: u64,
    },
    /// Where the first byte that is not UTF-8 is.
    #[error("stage `{path}` is not UTF-8 text (first bad byte at line {line}, column {column})")]
    NotUtf8 {
        path: String,
        line: usize,
        column: usize,
    },
    #[error("cannot read stage `{path}`: {error}")]
    Unreadable { path: String, error: std::io::Error },
}

impl StageError {
    /// The diagnostic code a refusal is reported under, for a chain stage or a scene file alike:
    /// E0009 for a path or file the rules refuse, E0008 for text that is not UTF-8, E0006 for a
    /// file that cannot be read.
    pub fn code(&self) -> dsl::Code {
        match self {
            StageError::OutsideRoot { .. }
            | StageError::NotAFile { .. }
            | StageError::TooLarge { .. } => dsl::Code::E0009,
            StageError::NotUtf8 { .. } => dsl::Code::E0008,
            StageError::Unreadable { .. } => dsl::Code::E0006,
        }
    }
}

/// Reads the stage files a chain names.
pub trait StageLoader {
    /// The stage `stage` (a path as the chain writes it) of the chain file `chain_file`.
    fn load(&self, chain_file: &str, stage: &str) -> Result<StageSource, StageError>;
}

/// An in-memory loader: a function from the joined path (`<chain's folder>/<stage>`) to text.
impl<F> StageLoader for F
where
    F: Fn(&str) -> Result<String, StageError>,
{
    fn load(&self, chain_file: &str, stage: &str) -> Result<StageSource, StageError> {
        let path = joined(chain_file, stage);
        self(&path).map(|text| StageSource { path, text })
    }
}

/// The stage path joined to the chain file's folder (as text, unresolved).
pub fn joined(chain_file: &str, stage: &str) -> String {
    let dir = Path::new(chain_file).parent().unwrap_or(Path::new(""));
    dir.join(stage).to_string_lossy().into_owned()
}

/// Stage files from the file system under the access rules; keeps what it read, so that a
/// diagnostic's snippet is shown from the same text that was checked, without reading again.
#[derive(Debug, Default)]
pub struct StageFiles {
    root: Option<PathBuf>,
    read: RefCell<BTreeMap<String, String>>,
}

impl StageFiles {
    /// Stage files confined to each chain's own folder.
    pub fn new() -> Self {
        StageFiles::default()
    }

    /// Stage files confined to `root` (and below) instead of the chain's folder.
    pub fn with_root(root: impl Into<PathBuf>) -> Self {
        StageFiles {
            root: Some(root.into()),
            read: RefCell::default(),
        }
    }

    /// The text of a stage file this loader read, by the path its diagnostics name.
    pub fn text(&self, path: &str) -> Option<String> {
        self.read.borrow().get(path).cloned()
    }
}

impl StageLoader for StageFiles {
    fn load(&self, chain_file: &str, stage: &str) -> Result<StageSource, StageError> {
        let path = joined(chain_file, stage);
        let chain_dir = Path::new(chain_file).parent().unwrap_or(Path::new(""));
        let root = self.root.as_deref().unwrap_or(chain_dir);
        let root_shown = if root.as_os_str().is_empty() {
            ".".to_string()
        } else {
            root.display().to_string()
        };
        let outside = || StageError::OutsideRoot {
            path: stage.to_string(),
            root: root_shown.clone(),
        };
        let cwd = std::env::current_dir().unwrap_or_default();
        // Lexically first, so that nothing outside the root is even looked up...
        let lexical_root = normalise(&cwd.join(root));
        if !normalise(&cwd.join(&path)).starts_with(&lexical_root) {
            return Err(outside());
        }
        // ...then with links resolved, so that a symbolic link cannot point out.
        let unreadable = |error| StageError::Unreadable {
            path: stage.to_string(),
            error,
        };
        let real_root = std::fs::canonicalize(cwd.join(root)).map_err(unreadable)?;
        let real = std::fs::canonicalize(cwd.join(&path)).map_err(unreadable)?;
        if !real.starts_with(&real_root) {
            return Err(outside());
        }
        let regular = |meta: &std::fs::Metadata| {
            if !meta.is_file() {
                return Err(StageError::NotAFile {
                    path: stage.to_string(),
                });
            }
            if meta.len() > MAX_STAGE_BYTES {
                return Err(StageError::TooLarge {
                    path: stage.to_string(),
                    bytes: meta.len(),
                    limit: MAX_STAGE_BYTES,
                });
            }
            Ok(())
        };
        // Decided from the path before opening (a device or a pipe is never opened)...
        regular(&std::fs::metadata(&real).map_err(unreadable)?)?;
        // ...and again on the open handle, in case the file was swapped in between: opened
        // without following a link and without blocking on a pipe.
        let file = {
            use std::os::unix::fs::OpenOptionsExt;
            std::fs::OpenOptions::new()
                .read(true)
                .custom_flags(libc::O_NOFOLLOW | libc::O_NONBLOCK)
                .open(&real)
                .map_err(unreadable)?
        };
        regular(&file.metadata().map_err(unreadable)?)?;
        // Bounded even if the file grows after the check.
        let mut bytes = Vec::new();
        file.take(MAX_STAGE_BYTES + 1)
            .read_to_end(&mut bytes)
            .map_err(unreadable)?;
        if bytes.len() as u64 > MAX_STAGE_BYTES {
            return Err(StageError::TooLarge {
                path: stage.to_string(),
                bytes: bytes.len() as u64,
                limit: MAX_STAGE_BYTES,
            });
        }
        let text = match dsl::source::decode(&bytes) {
            Ok(t) => t.to_string(),
            Err(at) => {
                let (line, column) =
                    dsl::render::line_col(&dsl::source::lossy(&bytes), at.span.start);
                return Err(StageError::NotUtf8 {
                    path: stage.to_string(),
                    line,
                    column,
                });
            }
        };
        self.read.borrow_mut().insert(path.clone(), text.clone());
        Ok(StageSource { path, text })
    }
}

/// `.` and `..` folded away without touching the file system.
fn normalise(p: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for c in p.components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir => {
                out.pop();
            }
            other => out.push(other),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lexical_normalisation_folds_parent_steps() {
        assert_eq!(
            normalise(Path::new("/a/b/../c/./d")),
            PathBuf::from("/a/c/d")
        );
        assert_eq!(normalise(Path::new("/a/../../etc")), PathBuf::from("/etc"));
    }

    #[test]
    fn joins_relative_to_the_chain() {
        assert_eq!(joined("dir/chain.toml", "a.toml"), "dir/a.toml");
        assert_eq!(joined("chain.toml", "a.toml"), "a.toml");
    }
}
