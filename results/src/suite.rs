//! Suites: what a leaderboard compares models on, named in a file (`suites/*.toml`): the tasks
//! (protocol files, relative to the suite file), episodes per task, the first seed and the runs.
//! `autobio eval --suite FILE` runs one whole, so a submitter cannot pick tasks or seeds, and
//! copies the file into its `--out` ([`SUITE_FILE`]) for the submission to carry.
//!
//! It reads suite files; it does not compile or run their tasks.

use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The copy of the suite file a suite run leaves in its folder.
pub const SUITE_FILE: &str = "suite.toml";

/// A suite as its file states it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Suite {
    pub name: String,
    #[serde(default)]
    pub description: String,
    pub episodes: usize,
    pub seed: u64,
    pub runs: u32,
    /// Protocol files, relative to the suite file.
    pub tasks: Vec<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SuiteFile {
    format: u32,
    suite: Suite,
}

/// Why a suite file cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum SuiteError {
    // The OS error is part of the message and not a `source`: a chain of causes prints it once.
    #[error("cannot read suite {path}: {why}")]
    Read { path: PathBuf, why: std::io::Error },
    #[error("suite {path} is not a suite file: {why}")]
    Parse { path: PathBuf, why: String },
    #[error("suite {path}: {why}")]
    Invalid { path: PathBuf, why: String },
}

/// A suite read from its file, with the file's SHA-256 and the folder its task paths start from.
#[derive(Clone, Debug)]
pub struct LoadedSuite {
    pub suite: Suite,
    pub sha256: String,
    pub dir: PathBuf,
}

impl LoadedSuite {
    pub fn read(path: &Path) -> Result<LoadedSuite, SuiteError> {
        let bytes = std::fs::read(path).map_err(|why| SuiteError::Read {
            path: path.to_path_buf(),
            why,
        })?;
        let suite = parse(&bytes, path)?;
        Ok(LoadedSuite {
            suite,
            sha256: crate::run::record::sha256_hex(&bytes),
            dir: path.parent().map(Path::to_path_buf).unwrap_or_default(),
        })
    }

    /// The suite's protocol files as paths from here.
    pub fn protocols(&self) -> Vec<PathBuf> {
        self.suite.tasks.iter().map(|t| self.dir.join(t)).collect()
    }
}

/// Parses a suite file's bytes (`path` names it in errors).
pub fn parse(bytes: &[u8], path: &Path) -> Result<Suite, SuiteError> {
    let invalid = |why: String| SuiteError::Invalid {
        path: path.to_path_buf(),
        why,
    };
    let text = std::str::from_utf8(bytes).map_err(|e| SuiteError::Parse {
        path: path.to_path_buf(),
        why: e.to_string(),
    })?;
    let file: SuiteFile = toml::from_str(text).map_err(|e| SuiteError::Parse {
        path: path.to_path_buf(),
        why: e.to_string(),
    })?;
    if file.format != 1 {
        return Err(invalid(format!(
            "format {} (this autobio reads format 1)",
            file.format
        )));
    }
    let s = file.suite;
    if s.name.is_empty()
        || !s
            .name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "_-.".contains(c))
    {
        return Err(invalid(format!(
            "the name `{}` must be letters, digits, `_`, `-` or `.`",
            s.name
        )));
    }
    if s.episodes == 0 || s.runs == 0 || s.tasks.is_empty() {
        return Err(invalid(
            "a suite needs at least one task, one episode and one run".into(),
        ));
    }
    let mut seen = std::collections::BTreeSet::new();
    if let Some(dup) = s.tasks.iter().find(|t| !seen.insert(t.as_str())) {
        return Err(invalid(format!("{dup} is listed twice")));
    }
    Ok(s)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_suite_file_reads_and_bad_ones_say_why() {
        let good = "format = 1\n[suite]\nname = \"mini\"\nepisodes = 2\nseed = 5\nruns = 1\ntasks = [\"a.toml\"]\n";
        let s = parse(good.as_bytes(), Path::new("mini.toml")).unwrap();
        assert_eq!(
            (s.name.as_str(), s.episodes, s.seed, s.runs),
            ("mini", 2, 5, 1)
        );
        let bad = |text: &str| {
            parse(text.as_bytes(), Path::new("x.toml"))
                .unwrap_err()
                .to_string()
        };
        assert!(bad(&good.replace("format = 1", "format = 2")).contains("format 2"));
        assert!(bad(&good.replace("episodes = 2", "episodes = 0")).contains("at least one"));
        assert!(
            bad(&good.replace("[\"a.toml\"]", "[\"a.toml\", \"a.toml\"]")).contains("listed twice")
        );
        assert!(bad(&good.replace("mini", "../x")).contains("must be letters"));
        assert!(bad(&good.replace("runs = 1", "runs = 1\nseeds = 3")).contains("unknown field"));
    }
}
