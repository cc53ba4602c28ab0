//! Submission bundles: finished suite runs (`autobio eval --suite ... --out RUN`) packed into one
//! tar archive (zstd-compressed when its name ends in `.zst`) with a top-level `index.json`:
//! schema version, the autobio version and commit that ran the runs (one for all), the model (name, training note, metadata and
//! profile from the runs' manifests), the suite, and the SHA-256 of every other member.
//!
//! A bundle is a stranger's file. [`unpack`] extracts it into a work folder of its own and
//! refuses, with a message, anything but plain files and folders under plain relative names:
//! absolute paths, `..`, links, devices, duplicate names, members or totals over a limit, and
//! decompression bombs (more than [`Limits::max_ratio`] times the compressed bytes once past
//! [`Limits::ratio_after`]); a truncated or corrupt archive is an error, never a crash, and
//! nothing is written outside the work folder.
//!
//! It packs and unpacks files; checking what they claim is [`crate::verify`].

use results::run::record::{Manifest, sha256_hex};
use results::suite::{SUITE_FILE, Suite};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::io::{Read, Write};
use std::path::{Component, Path, PathBuf};

/// The bundle format this autobio writes and reads.
pub const BUNDLE_SCHEMA_VERSION: u32 = 1;
/// The index member's name.
pub const INDEX: &str = "index.json";

/// A bundle's `index.json`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Index {
    pub schema_version: u32,
    pub autobio_version: String,
    pub git_commit: String,
    pub model: ModelEntry,
    pub suite: Suite,
    /// SHA-256 of the suite file the runs ran (their `suite.toml`).
    pub suite_sha256: String,
    /// Every other member by its path in the archive, with its SHA-256.
    pub files: BTreeMap<String, String>,
}

/// Who the submission is for.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ModelEntry {
    pub name: String,
    /// Free text on how the model was trained ("100 demos").
    pub training: Option<String>,
    /// The wire, profile (name and SHA-256) and metadata the runs' manifests recorded; absent
    /// for a run of a built-in policy.
    pub wire: Option<String>,
    pub profile: Option<String>,
    pub profile_sha256: Option<String>,
    pub metadata: Option<serde_json::Value>,
}

/// Why a bundle could not be written or read.
#[derive(Debug, thiserror::Error)]
pub enum BundleError {
    // The OS error is part of the message and not a `source`: a chain of causes prints it once.
    #[error("cannot {doing} {path}: {why}")]
    Io {
        doing: &'static str,
        path: PathBuf,
        why: std::io::Error,
    },
    #[error("{0}")]
    Runs(String),
    #[error("the archive is truncated or corrupt: {0}")]
    Archive(String),
    #[error("the archive is refused: {0}")]
    Limit(String),
    #[error("the archive member `{member}` is refused: {why}")]
    Member { member: String, why: String },
    /// A member whose name is not a plain relative path ([`UnsafeName`]).
    #[error("the archive member `{member}` is refused: {why}")]
    Name { member: String, why: UnsafeName },
    #[error("the archive has no {INDEX}")]
    NoIndex,
    #[error("{INDEX} does not read: {0}")]
    BadIndex(String),
    #[error("{INDEX} is schema version {0}; this autobio reads version {BUNDLE_SCHEMA_VERSION}")]
    Schema(u32),
}

fn io(doing: &'static str, path: &Path) -> impl FnOnce(std::io::Error) -> BundleError {
    let path = path.to_path_buf();
    move |why| BundleError::Io { doing, path, why }
}

/// What [`submit`] packs besides the runs.
#[derive(Clone, Debug)]
pub struct SubmitOptions {
    pub model_name: String,
    pub training: Option<String>,
    pub out: PathBuf,
}

/// Files of a run folder that go into a bundle (run records, results and recordings).
fn run_files(dir: &Path) -> Result<Vec<PathBuf>, BundleError> {
    let mut files = Vec::new();
    for entry in std::fs::read_dir(dir).map_err(io("read", dir))? {
        let path = entry.map_err(io("read", dir))?.path();
        let name = path
            .file_name()
            .and_then(|n| n.to_str())
            .unwrap_or_default();
        let wanted = name == SUITE_FILE
            || [".manifest.json", ".journal.jsonl", ".results.json", ".mcap"]
                .iter()
                .any(|ext| name.ends_with(ext));
        if wanted && path.is_file() {
            files.push(path);
        }
    }
    files.sort();
    Ok(files)
}

/// Packs the finished suite runs in `runs` (each an `eval --suite` folder, or shards of one)
/// into a bundle at `opts.out`; returns its index.
pub fn submit(runs: &[PathBuf], opts: &SubmitOptions) -> Result<Index, BundleError> {
    let mut members: Vec<(String, PathBuf)> = Vec::new();
    let mut suite: Option<(Vec<u8>, PathBuf)> = None;
    let mut model: Option<results::run::record::ModelRecord> = None;
    // The autobio that ran the runs (version and commit), one for all.
    let mut build: Option<(String, String, PathBuf)> = None;
    for (k, dir) in runs.iter().enumerate() {
        let suite_file = dir.join(SUITE_FILE);
        let bytes = std::fs::read(&suite_file).map_err(|_| {
            BundleError::Runs(format!(
                "{} is not a suite run (no {SUITE_FILE}): a submission runs a whole suite, \
                 `autobio eval --suite FILE --out DIR`",
                dir.display()
            ))
        })?;
        match &suite {
            Some((first, from)) if *first != bytes => {
                return Err(BundleError::Runs(format!(
                    "{} and {} ran different suites",
                    from.display(),
                    dir.display()
                )));
            }
            Some(_) => {}
            None => suite = Some((bytes, dir.clone())),
        }
        for file in run_files(dir)? {
            let name = file
                .file_name()
                .and_then(|n| n.to_str())
                .unwrap_or_default();
            if name.ends_with(".manifest.json") {
                let m = Manifest::read(&file)
                    .map_err(|e| BundleError::Runs(format!("{}: {e}", file.display())))?;
                refuse_trivial(&m)?;
                let here = (m.autobio_version.clone(), m.git_commit.clone());
                match &build {
                    Some((v, c, first)) if (v, c) != (&here.0, &here.1) => {
                        return Err(BundleError::Runs(format!(
                            "{} was run by autobio {} at {}, {} by {v} at {c}: a submission's \
                             runs are one build's",
                            file.display(),
                            here.0,
                            here.1,
                            first.display()
                        )));
                    }
                    Some(_) => {}
                    None => build = Some((here.0, here.1, file.clone())),
                }
                if let Some(here) = m.model {
                    match &model {
                        Some(first) if first.profile_sha256 != here.profile_sha256 => {
                            return Err(BundleError::Runs(format!(
                                "{} ran the model with another profile than the other runs",
                                file.display()
                            )));
                        }
                        Some(_) => {}
                        None => model = Some(here),
                    }
                }
            }
            members.push((format!("runs/{k}/{name}"), file));
        }
    }
    let Some((suite_bytes, suite_dir)) = suite else {
        return Err(BundleError::Runs("no runs to submit".into()));
    };
    let suite_path = suite_dir.join(SUITE_FILE);
    let parsed = results::suite::parse(&suite_bytes, &suite_path)
        .map_err(|e| BundleError::Runs(e.to_string()))?;
    let mut files = BTreeMap::new();
    for (name, path) in &members {
        let bytes = std::fs::read(path).map_err(io("read", path))?;
        files.insert(name.clone(), sha256_hex(&bytes));
    }
    let (autobio_version, git_commit) = match build {
        Some((v, c, _)) => (v, c),
        None => (
            env!("CARGO_PKG_VERSION").to_string(),
            results::run::record::GIT_COMMIT.to_string(),
        ),
    };
    let index = Index {
        schema_version: BUNDLE_SCHEMA_VERSION,
        autobio_version,
        git_commit,
        model: ModelEntry {
            name: opts.model_name.clone(),
            training: opts.training.clone(),
            wire: model.as_ref().map(|m| m.wire.to_string()),
            profile: model.as_ref().map(|m| m.profile.name.clone()),
            profile_sha256: model.as_ref().map(|m| m.profile_sha256.clone()),
            metadata: model.as_ref().and_then(|m| m.metadata.clone()),
        },
        suite: parsed,
        suite_sha256: sha256_hex(&suite_bytes),
        files,
    };
    write_archive(&opts.out, &index, &members)?;
    Ok(index)
}

/// A run of a task whose success holds before the first step (W0001) is not submitted: a
/// motionless robot passes it, and `eval` ran it only under `--allow-trivial`. A leaderboard has
/// no such override. The protocol is checked again where the run read it; one that has moved since
/// is left to `leaderboard verify`, which checks the shipped protocols.
fn refuse_trivial(m: &Manifest) -> Result<(), BundleError> {
    let Ok(checked) = compiler::check_file(Path::new(&m.protocol), None) else {
        return Ok(());
    };
    match checked.trivial_at() {
        Some(at) => Err(BundleError::Runs(format!(
            "task `{}` is trivial: its success already holds before the first step \
             (warning[W0001] at {at}), so a robot that does nothing passes it; a leaderboard \
             ranks no such task",
            m.task_id
        ))),
        None => Ok(()),
    }
}

/// Writes the index and the members (in the index's order, with fixed metadata: the same runs
/// give the same bytes).
fn write_archive(
    out: &Path,
    index: &Index,
    members: &[(String, PathBuf)],
) -> Result<(), BundleError> {
    let file = std::fs::File::create(out).map_err(io("create", out))?;
    let sink: Box<dyn Write> = if out.extension().is_some_and(|e| e == "zst") {
        Box::new(
            zstd::Encoder::new(file, 3)
                .map_err(io("compress", out))?
                .auto_finish(),
        )
    } else {
        Box::new(file)
    };
    let mut tar = tar::Builder::new(sink);
    let append = |tar: &mut tar::Builder<Box<dyn Write>>, name: &str, bytes: &[u8]| {
        let mut header = tar::Header::new_gnu();
        header.set_size(bytes.len() as u64);
        header.set_mode(0o644);
        header.set_mtime(0);
        header.set_entry_type(tar::EntryType::Regular);
        tar.append_data(&mut header, name, bytes)
    };
    let index_bytes = serde_json::to_vec_pretty(index).expect("an index serialises");
    append(&mut tar, INDEX, &index_bytes).map_err(io("write", out))?;
    let mut sorted: Vec<&(String, PathBuf)> = members.iter().collect();
    sorted.sort_by(|a, b| a.0.cmp(&b.0));
    for (name, path) in sorted {
        let bytes = std::fs::read(path).map_err(io("read", path))?;
        append(&mut tar, name, &bytes).map_err(io("write", out))?;
    }
    tar.into_inner()
        .and_then(|mut w| w.flush())
        .map_err(io("write", out))
}

/// How much a bundle may unpack to.
#[derive(Clone, Copy, Debug)]
pub struct Limits {
    /// Largest member and largest total, in bytes.
    pub max_member: u64,
    pub max_total: u64,
    /// Past `ratio_after` unpacked bytes, at most `max_ratio` times the bytes read from the
    /// file (MCAP is compressed already: a real bundle unpacks to about its own size).
    pub max_ratio: u64,
    pub ratio_after: u64,
    /// Most members.
    pub max_members: usize,
}

impl Default for Limits {
    fn default() -> Self {
        Limits {
            max_member: 4 << 30,
            max_total: 64 << 30,
            max_ratio: 100,
            ratio_after: 64 << 20,
            max_members: 200_000,
        }
    }
}

/// Counts the bytes read from the file.
struct Counted<R> {
    inner: R,
    read: std::rc::Rc<std::cell::Cell<u64>>,
}

impl<R: Read> Read for Counted<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        self.read.set(self.read.get() + n as u64);
        Ok(n)
    }
}

/// The unpacked stream under the total and ratio limits: every byte the archive reader gets
/// (headers, long names, padding, members) counts, and the first byte past a limit is an
/// error whose reason is kept in `tripped`.
struct Limited<R> {
    inner: R,
    unpacked: u64,
    read: std::rc::Rc<std::cell::Cell<u64>>,
    limits: Limits,
    tripped: std::rc::Rc<std::cell::RefCell<Option<String>>>,
}

impl<R: Read> Read for Limited<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        self.unpacked += n as u64;
        let why = if self.unpacked > self.limits.max_total {
            Some(format!(
                "it unpacks to more than {} bytes",
                self.limits.max_total
            ))
        } else if self.unpacked > self.limits.ratio_after
            && self.unpacked > self.limits.max_ratio * self.read.get().max(1)
        {
            Some(format!(
                "a decompression bomb: {} bytes unpacked from {} read",
                self.unpacked,
                self.read.get()
            ))
        } else {
            None
        };
        if let Some(why) = why {
            *self.tripped.borrow_mut() = Some(why.clone());
            return Err(std::io::Error::other(why));
        }
        Ok(n)
    }
}

/// A bundle unpacked into its work folder.
#[derive(Debug)]
pub struct Unpacked {
    pub index: Index,
    pub root: PathBuf,
    /// Every member's path (the index too), as unpacked.
    pub members: Vec<String>,
}

/// Why an archive member's name is not a plain relative path (the member it names is the
/// context [`BundleError::Name`] gives).
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum UnsafeName {
    #[error("its name is not UTF-8")]
    NotUtf8,
    /// `..`, at the component it was found.
    #[error("its path climbs out with `..`")]
    ClimbsOut { at: usize },
    #[error("its path is absolute")]
    Absolute,
    #[error("its name is empty")]
    Empty,
}

/// A member's name as a safe relative path, or why it is not one.
fn safe_name(raw: &[u8]) -> Result<PathBuf, UnsafeName> {
    let name = std::str::from_utf8(raw).map_err(|_| UnsafeName::NotUtf8)?;
    let path = Path::new(name);
    let mut clean = PathBuf::new();
    for (at, c) in path.components().enumerate() {
        match c {
            Component::Normal(part) => clean.push(part),
            Component::CurDir => {}
            Component::ParentDir => return Err(UnsafeName::ClimbsOut { at }),
            Component::RootDir | Component::Prefix(_) => return Err(UnsafeName::Absolute),
        }
    }
    if clean.as_os_str().is_empty() {
        return Err(UnsafeName::Empty);
    }
    Ok(clean)
}

/// Unpacks `bundle` into `work` (created; it must not exist or be empty) under `limits`.
pub fn unpack(bundle: &Path, work: &Path, limits: &Limits) -> Result<Unpacked, BundleError> {
    let mut magic = [0u8; 4];
    let mut file = std::fs::File::open(bundle).map_err(io("open", bundle))?;
    let n = file.read(&mut magic).map_err(io("read", bundle))?;
    let file = std::fs::File::open(bundle).map_err(io("open", bundle))?;
    let read = std::rc::Rc::new(std::cell::Cell::new(0u64));
    let counted = Counted {
        inner: std::io::BufReader::new(file),
        read: read.clone(),
    };
    let decoded: Box<dyn Read> = if n == 4 && magic == [0x28, 0xb5, 0x2f, 0xfd] {
        Box::new(zstd::Decoder::new(counted).map_err(|e| BundleError::Archive(e.to_string()))?)
    } else {
        Box::new(counted)
    };
    let tripped = std::rc::Rc::new(std::cell::RefCell::new(None));
    let source = Limited {
        inner: decoded,
        unpacked: 0,
        read: read.clone(),
        limits: *limits,
        tripped: tripped.clone(),
    };
    // An error after a limit tripped is the limit's, whatever the reader made of it.
    let archive_error = |e: std::io::Error| match tripped.borrow().clone() {
        Some(why) => BundleError::Limit(why),
        None => BundleError::Archive(e.to_string()),
    };
    if work.exists()
        && std::fs::read_dir(work)
            .map_err(io("read", work))?
            .next()
            .is_some()
    {
        return Err(BundleError::Io {
            doing: "unpack into",
            path: work.to_path_buf(),
            why: std::io::Error::other("the work folder is not empty"),
        });
    }
    std::fs::create_dir_all(work).map_err(io("create", work))?;
    let mut archive = tar::Archive::new(source);
    let entries = archive.entries().map_err(archive_error)?;
    let mut members = Vec::new();
    let mut seen = std::collections::BTreeSet::new();
    for entry in entries {
        let mut entry = entry.map_err(archive_error)?;
        let raw = entry.path_bytes().into_owned();
        let shown = String::from_utf8_lossy(&raw).into_owned();
        let refuse = |why: String| BundleError::Member {
            member: shown.clone(),
            why,
        };
        let name = safe_name(&raw).map_err(|why| BundleError::Name {
            member: shown.clone(),
            why,
        })?;
        let kind = entry.header().entry_type();
        if kind.is_dir() {
            continue;
        }
        if !kind.is_file() {
            return Err(refuse(match kind {
                tar::EntryType::Symlink | tar::EntryType::Link => {
                    "it is a link; a bundle holds plain files only".into()
                }
                other => format!("it is a {other:?} entry; a bundle holds plain files only"),
            }));
        }
        let key = name.to_string_lossy().into_owned();
        if !seen.insert(key.clone()) {
            return Err(refuse("the archive has two members of that name".into()));
        }
        if seen.len() > limits.max_members {
            return Err(refuse(format!(
                "the archive has more than {} members",
                limits.max_members
            )));
        }
        // The size the reader will deliver (a PAX record may override the header's).
        let declared = entry.size();
        if declared > limits.max_member {
            return Err(refuse(format!(
                "it is {declared} bytes; a member may be at most {}",
                limits.max_member
            )));
        }
        // Errors name the member, not the work folder (the same bundle, the same message).
        let dest = work.join(&name);
        let write_err = |e: std::io::Error| refuse(format!("it cannot be written: {e}"));
        if let Some(parent) = dest.parent() {
            std::fs::create_dir_all(parent).map_err(write_err)?;
        }
        let mut out = std::fs::File::create(&dest).map_err(write_err)?;
        let mut buf = vec![0u8; 1 << 16];
        let mut this = 0u64;
        loop {
            let n = entry
                .read(&mut buf)
                .map_err(|e| match tripped.borrow().clone() {
                    Some(why) => BundleError::Limit(why),
                    None => BundleError::Archive(format!("reading `{shown}`: {e}")),
                })?;
            if n == 0 {
                break;
            }
            this += n as u64;
            if this > limits.max_member {
                return Err(refuse(format!(
                    "it is over {} bytes, a member's limit",
                    limits.max_member
                )));
            }
            out.write_all(&buf[..n]).map_err(write_err)?;
        }
        members.push(key);
    }
    if !members.iter().any(|m| m == INDEX) {
        return Err(BundleError::NoIndex);
    }
    let text = std::fs::read(work.join(INDEX)).map_err(io("read", work))?;
    let value: serde_json::Value =
        serde_json::from_slice(&text).map_err(|e| BundleError::BadIndex(e.to_string()))?;
    let version = value["schema_version"].as_u64().unwrap_or(0) as u32;
    if version != BUNDLE_SCHEMA_VERSION {
        return Err(BundleError::Schema(version));
    }
    let index: Index =
        serde_json::from_value(value).map_err(|e| BundleError::BadIndex(e.to_string()))?;
    Ok(Unpacked {
        index,
        root: work.to_path_buf(),
        members,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_plain_relative_names_are_safe() {
        assert_eq!(
            safe_name(b"runs/0/a.json"),
            Ok(PathBuf::from("runs/0/a.json"))
        );
        assert_eq!(safe_name(b"./index.json"), Ok(PathBuf::from("index.json")));
        let why = |raw: &[u8]| safe_name(raw).unwrap_err().to_string();
        assert!(why(b"../evil").contains(".."));
        assert!(why(b"runs/../../evil").contains(".."));
        assert_eq!(
            safe_name(b"runs/../../evil"),
            Err(UnsafeName::ClimbsOut { at: 1 })
        );
        assert!(why(b"/etc/passwd").contains("absolute"));
        assert!(why(b"").contains("empty"));
        assert!(why(b"\xff").contains("UTF-8"));
    }
}
