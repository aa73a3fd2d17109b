//! The manifest of an output directory: which files the last run wrote, each with the SHA-256
//! of what it wrote, and the checks that decide whether a listed file may be removed.
//!
//! Text format, one entry a line after `#` comments: `<64 hex digits>  <relative path>` (as
//! `sha256sum` prints). A line without a hash is an entry of an older beamtrace, which recorded
//! none: it is read, never trusted.

use crate::{LOCK, MANIFEST, OutputError};
use sha2::{Digest, Sha256};
use std::collections::{BTreeMap, BTreeSet};
use std::io::Read;
use std::path::{Component, Path, PathBuf};

/// Prefix of the staging directories inside an output directory (`.beamtrace-staging-<pid>-<n>`).
pub(crate) const STAGING: &str = ".beamtrace-staging";

/// One line of a manifest: a relative path and the hash recorded for it, if any.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Entry {
    pub rel: String,
    pub sha256: Option<String>,
}

/// A relative path of plain components, none of them a name the directory reserves for itself
/// (the manifest, the lock, staging directories).
pub(crate) fn check_relative(rel: &str) -> Result<(), OutputError> {
    let p = Path::new(rel);
    let reserved = |first: &str| first == MANIFEST || first == LOCK || first.starts_with(STAGING);
    let first = rel.split('/').next().unwrap_or("");
    let ok = !rel.is_empty()
        && !reserved(first)
        && p.components().all(|c| matches!(c, Component::Normal(_)));
    if ok {
        Ok(())
    } else {
        Err(OutputError::BadRelative(rel.to_string()))
    }
}

/// The SHA-256 of the file at `path`, as 64 lowercase hex digits.
pub(crate) fn sha256_file(path: &Path) -> std::io::Result<String> {
    let mut file = std::fs::File::open(path)?;
    let mut hasher = Sha256::new();
    let mut buf = vec![0u8; 1 << 16];
    loop {
        let n = file.read(&mut buf)?;
        if n == 0 {
            break;
        }
        hasher.update(&buf[..n]);
    }
    Ok(hasher
        .finalize()
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect())
}

/// The manifest of the files `hashes` (relative path → SHA-256).
pub(crate) fn text(hashes: &BTreeMap<String, String>) -> String {
    let mut s = String::from(
        "# files written by beamtrace into this directory, with the SHA-256 of what it wrote\n\
         # (replaced or removed by the next run only while unchanged; others are left alone)\n",
    );
    for (rel, hash) in hashes {
        s.push_str(&format!("{hash}  {rel}\n"));
    }
    s
}

fn parse_line(line: &str) -> Entry {
    match line.split_once("  ") {
        Some((hash, rel))
            if hash.len() == 64
                && hash.bytes().all(|b| b.is_ascii_hexdigit())
                && !rel.is_empty() =>
        {
            Entry {
                rel: rel.to_string(),
                sha256: Some(hash.to_ascii_lowercase()),
            }
        }
        _ => Entry {
            rel: line.to_string(),
            sha256: None,
        },
    }
}

/// The entries of `dir`'s manifest; `None` when it has none that is a regular file (a link or
/// a FIFO in its place is not read).
pub(crate) fn read(dir: &Path) -> Option<Vec<Entry>> {
    let path = dir.join(MANIFEST);
    if !std::fs::symlink_metadata(&path).ok()?.is_file() {
        return None;
    }
    let text = std::fs::read_to_string(path).ok()?;
    Some(
        text.lines()
            .filter(|l| !l.is_empty() && !l.starts_with('#'))
            .map(parse_line)
            .collect(),
    )
}

/// The files (relative, sorted) the last committed run listed in `dir`'s manifest, or `None`
/// when `dir` has no manifest. Only relative paths of plain components inside `dir` are
/// returned (for readers such as `hls sim`; whether a file may be removed is decided by the
/// next commit, which also checks its content).
pub fn manifest_files(dir: &Path) -> Option<BTreeSet<String>> {
    Some(
        read(dir)?
            .into_iter()
            .filter(|e| check_relative(&e.rel).is_ok())
            .map(|e| e.rel)
            .collect(),
    )
}

/// Where the components of `rel` under `dir` lead, checked one by one without following links.
#[derive(Debug)]
pub(crate) enum Walk {
    /// Every directory on the way exists as a real directory; the last component has this
    /// metadata (`None`: it does not exist).
    Reached(Option<std::fs::Metadata>),
    /// A directory on the way does not exist (nothing further exists either).
    Missing,
    /// A component on the way (not the last) is a symbolic link: this prefix.
    Symlink(PathBuf),
    /// A component on the way (not the last) is not a directory: this prefix.
    NotDirectory(PathBuf),
}

/// Walk `rel` (already [`check_relative`]) under `dir` with `symlink_metadata` on each prefix.
pub(crate) fn walk(dir: &Path, rel: &str) -> Walk {
    let parts: Vec<&str> = rel.split('/').collect();
    let mut at = dir.to_path_buf();
    for (k, part) in parts.iter().enumerate() {
        at.push(part);
        let meta = std::fs::symlink_metadata(&at).ok();
        if k + 1 == parts.len() {
            return Walk::Reached(meta);
        }
        match meta {
            None => return Walk::Missing,
            Some(m) if m.file_type().is_symlink() => return Walk::Symlink(at),
            Some(m) if !m.is_dir() => return Walk::NotDirectory(at),
            Some(_) => {}
        }
    }
    Walk::Missing
}

/// Whether the listed `entry` may be removed from `dir`: `Ok(Some(path))` when it is a plain
/// file inside `dir`, reached through no link, whose content has the recorded hash;
/// `Ok(None)` when it is already gone; otherwise why it is left alone.
pub(crate) fn removable(dir: &Path, entry: &Entry) -> Result<Option<PathBuf>, String> {
    check_relative(&entry.rel)
        .map_err(|_| "not a relative path of plain names inside the directory".to_string())?;
    let meta = match walk(dir, &entry.rel) {
        Walk::Reached(Some(m)) => m,
        Walk::Reached(None) | Walk::Missing => return Ok(None),
        Walk::Symlink(link) => {
            return Err(format!(
                "reached through the symbolic link {}",
                link.display()
            ));
        }
        Walk::NotDirectory(at) => return Err(format!("{} is not a directory", at.display())),
    };
    if meta.file_type().is_symlink() {
        return Err("a symbolic link, not a file beamtrace wrote".into());
    }
    if !meta.is_file() {
        return Err("not a regular file".into());
    }
    let Some(recorded) = &entry.sha256 else {
        return Err(
            "listed without a content hash (a manifest of an older beamtrace), so not trusted"
                .into(),
        );
    };
    let path = dir.join(&entry.rel);
    match sha256_file(&path) {
        Ok(hash) if &hash == recorded => Ok(Some(path)),
        Ok(_) => Err("its content is not what beamtrace wrote".into()),
        Err(e) => Err(format!("cannot be read to check its content: {e}")),
    }
}
