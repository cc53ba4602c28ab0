//! Suites: what a leaderboard compares models on, named in a file (`suites/*.toml`): the tasks
//! (protocol files, relative to the suite file), episodes per task, the first seed and the runs.
//! `autobio eval --suite FILE` runs one whole, so a submitter cannot pick tasks or seeds, and
//! copies the file into its `--out` ([`SUITE_FILE`]) for the submission to carry.
//!
//! A suite may also name perturbation presets (`perturb = ["light:1", "camera:2"]`,
//! docs/robustness.md): each task is then run clean and under each preset, as a task of its
//! own whose id names the preset (`tube.pick_up@camera-2`) and whose content (so its hash)
//! carries the perturbation ([`Entry::task`]).
//!
//! It reads suite files; it does not compile or run their tasks.

use compiler::perturb::Preset;
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
    /// Perturbation presets (`<dimension>:<strength>`): every task is run clean and under each.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub perturb: Vec<String>,
}

/// One task of a suite run: a listed protocol, clean or under one of the suite's presets.
#[derive(Clone, Debug, PartialEq)]
pub struct Entry {
    /// The protocol file, as a path from here.
    pub protocol: PathBuf,
    /// How the suite lists it (relative to the suite file).
    pub listed: String,
    pub variant: Option<Preset>,
}

impl Entry {
    /// The compiled protocol as this entry runs it: under its preset (over the protocol's own
    /// perturbations), with the preset in its id.
    pub fn task(&self, task: compiler::Task) -> compiler::Task {
        match self.variant {
            None => task,
            Some(p) => {
                let mut t = task.with_perturb(&p.perturb());
                t.id = variant_id(&t.id, p);
                t
            }
        }
    }
}

/// The id of a task run under a preset: `<id>@<dimension>-<strength>`.
pub fn variant_id(id: &str, p: Preset) -> String {
    format!("{id}@{}-{}", p.dimension, p.strength)
}

/// A task id split into the suite task's id and its preset, when it names one.
pub fn split_variant(id: &str) -> (&str, Option<Preset>) {
    match id.split_once('@') {
        Some((base, v)) => {
            let preset = v
                .rsplit_once('-')
                .and_then(|(d, s)| format!("{d}:{s}").parse::<Preset>().ok());
            match preset {
                Some(p) => (base, Some(p)),
                None => (id, None),
            }
        }
        None => (id, None),
    }
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

    /// Every task the suite runs, task by task: each protocol clean, then under each preset in
    /// the suite's order.
    pub fn entries(&self) -> Vec<Entry> {
        let variants: Vec<Option<Preset>> = std::iter::once(None)
            .chain(self.suite.presets().into_iter().map(Some))
            .collect();
        self.suite
            .tasks
            .iter()
            .flat_map(|t| {
                variants.iter().map(move |v| Entry {
                    protocol: self.dir.join(t),
                    listed: t.clone(),
                    variant: *v,
                })
            })
            .collect()
    }
}

impl Suite {
    /// The suite's presets, read (a suite that parsed has only readable ones).
    pub fn presets(&self) -> Vec<Preset> {
        self.perturb.iter().filter_map(|p| p.parse().ok()).collect()
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
    let mut presets = std::collections::BTreeSet::new();
    for p in &s.perturb {
        let preset: Preset = p
            .parse()
            .map_err(|e| invalid(format!("perturb `{p}`: {e}")))?;
        if !presets.insert(preset) {
            return Err(invalid(format!("perturb `{p}` is listed twice")));
        }
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
        let with = |p: &str| good.replace("runs = 1", &format!("runs = 1\nperturb = {p}"));
        assert!(bad(&with("[\"lite:1\"]")).contains("no perturbation dimension `lite`"));
        assert!(bad(&with("[\"light:3\"]")).contains("strength"));
        assert!(bad(&with("[\"light\", \"light:1\"]")).contains("listed twice"));
        let s = parse(
            with("[\"light:2\", \"camera\"]").as_bytes(),
            Path::new("m.toml"),
        )
        .unwrap();
        let loaded = LoadedSuite {
            suite: s,
            sha256: String::new(),
            dir: PathBuf::from("suites"),
        };
        let ids: Vec<String> = loaded
            .entries()
            .iter()
            .map(|e| match e.variant {
                Some(p) => variant_id("t", p),
                None => "t".into(),
            })
            .collect();
        assert_eq!(ids, ["t", "t@light-2", "t@camera-1"]);
        assert_eq!(
            split_variant("t@light-2").1.map(|p| p.to_string()),
            Some("light:2".into())
        );
        assert_eq!(split_variant("t.x").0, "t.x");
    }
}
