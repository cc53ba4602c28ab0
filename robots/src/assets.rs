//! Shared asset preparation: editing an installed MJCF file as text and writing the result into a
//! content-addressed folder under the temp dir (so concurrent runs and tests share it safely).

use sha2::{Digest, Sha256};
use std::path::{Path, PathBuf};

#[derive(Debug, thiserror::Error)]
pub enum AssetError {
    #[error("robot model files not found under {0} (run `make setup`)")]
    Missing(PathBuf),
    #[error("cannot prepare the robot model at {path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
}

pub(crate) fn read(path: &Path) -> Result<String, AssetError> {
    std::fs::read_to_string(path).map_err(|source| AssetError::Io {
        path: path.to_path_buf(),
        source,
    })
}

pub(crate) fn absolute(path: &Path) -> Result<String, AssetError> {
    std::fs::canonicalize(path)
        .map(|p| p.display().to_string())
        .map_err(|source| AssetError::Io {
            path: path.to_path_buf(),
            source,
        })
}

/// Removes the first element that starts with `open` up to and including `close`.
pub(crate) fn strip_element(s: &str, open: &str, close: &str) -> String {
    match s.find(open) {
        Some(a) => match s[a..].find(close) {
            Some(b) => format!("{}{}", &s[..a], &s[a + b + close.len()..]),
            None => s.to_string(),
        },
        None => s.to_string(),
    }
}

/// A folder under the temp dir named by the hash of `content`.
pub(crate) fn content_dir(stem: &str, content: &str) -> Result<PathBuf, AssetError> {
    let d = Sha256::digest(content.as_bytes());
    let hash: String = d.iter().take(8).map(|b| format!("{b:02x}")).collect();
    let dir = std::env::temp_dir().join(format!("{stem}-{hash}"));
    std::fs::create_dir_all(&dir).map_err(|source| AssetError::Io {
        path: dir.clone(),
        source,
    })?;
    Ok(dir)
}

pub(crate) fn write_if_changed(path: &Path, text: &str) -> Result<(), AssetError> {
    if std::fs::read_to_string(path).ok().as_deref() == Some(text) {
        return Ok(());
    }
    // Unique per process and per call: tests build scenes from several threads at once, and a shared
    // temporary name lets one thread rename the other's file away.
    static WRITES: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    let n = WRITES.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let tmp = path.with_extension(format!("tmp{}-{n}", std::process::id()));
    let io = |source| AssetError::Io {
        path: path.to_path_buf(),
        source,
    };
    std::fs::write(&tmp, text).map_err(io)?;
    std::fs::rename(tmp, path).map_err(io)
}

/// The text between the first `open` and the first `close` after it.
pub(crate) fn between<'a>(s: &'a str, open: &str, close: &str) -> Option<&'a str> {
    let a = s.find(open)? + open.len();
    let b = s[a..].find(close)?;
    Some(&s[a..a + b])
}

/// Removes every ` name="..."` attribute called `name`.
pub(crate) fn strip_attribute(s: &str, name: &str) -> String {
    let key = format!(" {name}=\"");
    let mut out = String::with_capacity(s.len());
    let mut rest = s;
    while let Some(a) = rest.find(&key) {
        out.push_str(&rest[..a]);
        let value = &rest[a + key.len()..];
        rest = match value.find('"') {
            Some(b) => &value[b + 1..],
            None => "",
        };
    }
    out.push_str(rest);
    out
}

/// A package file that does not have the shape preparation expects.
pub(crate) fn malformed(path: &Path, what: &str) -> AssetError {
    AssetError::Io {
        path: path.to_path_buf(),
        source: std::io::Error::new(std::io::ErrorKind::InvalidData, what.to_string()),
    }
}
