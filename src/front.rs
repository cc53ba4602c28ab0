//! What every subcommand that reads protocols shares: the chain root and colour choice, and
//! loading a protocol or chain into a task (its diagnostics shown when it has errors).

use crate::diagnostics;
use anyhow::{Result, bail};
use std::path::{Path, PathBuf};

pub struct Front {
    pub root: Option<PathBuf>,
    pub color: bool,
}

impl Front {
    /// Checks a protocol or chain file and returns its task, or shows its diagnostics and fails.
    pub fn load(&self, path: &Path) -> Result<compiler::Task> {
        let checked = compiler::check_file(path, self.root.as_deref())?;
        match checked.task {
            Some(ref t) if !checked.diagnostics.iter().any(|d| d.is_error()) => Ok(t.clone()),
            _ => {
                err!("{}", diagnostics::render_all(&checked, self.color));
                let name = &checked.file;
                bail!("{name} has errors; run `autobio check {name}`")
            }
        }
    }

    /// Loads every file, stopping at the first with errors.
    pub fn load_all(&self, paths: &[PathBuf]) -> Result<Vec<compiler::Task>> {
        paths.iter().map(|p| self.load(p)).collect()
    }
}
