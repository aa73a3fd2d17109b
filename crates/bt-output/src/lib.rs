//! Safe outputs: the one home of every write beamtrace makes.
//!
//! Rules (`docs/reliability.md`, "Outputs never destroy data"):
//! - a file is written to a temporary file in its target directory and renamed over the
//!   target ([`write_atomic`], [`write_atomic_with`], [`write_atomic_via`]): a killed run
//!   leaves the old file or the new one, never half of one;
//! - an output directory ([`OutputDir`]) is locked for the run (`DIR/.beamtrace-lock`, an
//!   advisory lock the OS drops when the process dies): a second run into it is refused;
//! - its files are built in `DIR/.beamtrace-staging-<pid>-<n>` and moved into `DIR` only when
//!   complete; a failed run leaves `DIR` as it was and removes its staging directory;
//! - nothing is deleted unless the program wrote it: `DIR/.beamtrace-manifest` lists the files
//!   of the last run with the SHA-256 of what it wrote, and a listed file is removed only when
//!   it is a plain file inside `DIR`, reached through no symbolic link, with that content;
//!   anything else listed is left alone with a warning ([`LeftAlone`]);
//! - an output that is one of the inputs is refused ([`refuse_input`]), and so is an output
//!   path that holds a directory, FIFO, socket or device ([`OutputError::NotRegular`]);
//! - temporary files and staging directories a killed run left are removed by the next run
//!   that writes the same output (`stale`): only names of our exact pattern, only regular
//!   files and real directories, only when their process is gone;
//! - the format follows the extension or the output is refused ([`extension_in`]).

#![warn(missing_docs)]

pub mod csv;
mod dir;
mod lock;
mod manifest;
mod stale;

pub use dir::{Committed, LeftAlone, OutputDir};
pub use manifest::manifest_files;

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// Name of the manifest an [`OutputDir`] keeps in its directory.
pub const MANIFEST: &str = ".beamtrace-manifest";
/// Name of the lock file an [`OutputDir`] holds in its directory while a run writes into it.
pub const LOCK: &str = ".beamtrace-lock";

/// Why an output could not be written.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// The operating system refused an operation on `path`.
    #[error("{path}: {source}")]
    Io {
        /// The file or directory.
        path: String,
        /// The OS error.
        source: std::io::Error,
    },
    /// The output would overwrite an input.
    #[error("refusing to write {output}: it is the input {input}; choose another output path")]
    SameAsInput {
        /// The output path.
        output: String,
        /// The input it names.
        input: String,
    },
    /// The output's extension names no format this writer has.
    #[error("{path}: cannot write this format (extension {found}); use {expected}")]
    Extension {
        /// The output path.
        path: String,
        /// The extension found (or "none").
        found: String,
        /// The extensions this writer supports.
        expected: String,
    },
    /// A path inside an output directory that is absolute or climbs out of it.
    #[error("{0}: not a relative path inside the output directory")]
    BadRelative(String),
    /// A directory stands where a file of the output goes (or the reverse).
    #[error("{0}: exists and is a directory; it is not replaced")]
    IsDirectory(String),
    /// A FIFO, socket or device stands where a file of the output goes.
    #[error("{0}: exists and is not a regular file (a FIFO, socket or device); it is not replaced")]
    NotRegular(String),
    /// A file of an output directory would be reached through a symbolic link inside it.
    #[error(
        "{path}: reached through the symbolic link {link}; outputs go only into real directories"
    )]
    ThroughSymlink {
        /// The output file.
        path: String,
        /// The link on its way.
        link: String,
    },
    /// Another run holds the lock of the output directory.
    #[error(
        "{dir}: another beamtrace run is writing into this directory (it holds {dir}/{LOCK}); wait for it to end or choose another output directory"
    )]
    Busy {
        /// The output directory.
        dir: String,
    },
}

pub(crate) fn io(path: &Path) -> impl FnOnce(std::io::Error) -> OutputError + '_ {
    move |source| OutputError::Io {
        path: path.display().to_string(),
        source,
    }
}

static COUNTER: AtomicU64 = AtomicU64::new(0);

/// A name for a sibling of `path` that no other process or call uses: `<stem><tag>-<pid>-<n>`.
pub(crate) fn sibling(path: &Path, tag: &str) -> PathBuf {
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".into());
    path.with_file_name(format!("{name}{tag}-{}-{n}", std::process::id()))
}

pub(crate) fn parent_of(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

/// Write `bytes` to `path` atomically (temporary file in the same directory, flushed, synced,
/// renamed over `path`). The parent directory must exist.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    write_atomic_with(path, |w| w.write_all(bytes).map_err(io(path)))
}

/// Write `path` atomically through `fill`, which writes the whole content to the buffered
/// temporary file. On any error the temporary file is removed and `path` is untouched.
pub fn write_atomic_with<E: From<OutputError>>(
    path: &Path,
    fill: impl FnOnce(&mut BufWriter<File>) -> Result<(), E>,
) -> Result<(), E> {
    write_atomic_via(path, |tmp| {
        let file = File::create(tmp).map_err(io(path))?;
        let mut w = BufWriter::new(file);
        fill(&mut w)?;
        let file = w.into_inner().map_err(|e| io(path)(e.into_error()))?;
        file.sync_all().map_err(io(path))?;
        Ok(())
    })
}

/// Write `path` atomically through `produce`, which creates the whole file at the temporary
/// path it is given (for writers that only take a path, such as plotters' backends). The
/// temporary file is a hidden sibling of `path` that keeps its extension, so a writer that
/// picks the format by extension picks the right one. On any error the temporary file is
/// removed and `path` is untouched.
pub fn write_atomic_via<E: From<OutputError>>(
    path: &Path,
    produce: impl FnOnce(&Path) -> Result<(), E>,
) -> Result<(), E> {
    check_target(path)?;
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    stale::remove_stale_temporaries(parent_of(path), &name, path.extension());
    let mut tmp = sibling(&parent_of(path).join(format!(".{name}")), ".tmp");
    if let Some(ext) = path.extension() {
        tmp.as_mut_os_string().push(".");
        tmp.as_mut_os_string().push(ext);
    }
    let result = produce(&tmp).and_then(|()| Ok(std::fs::rename(&tmp, path).map_err(io(path))?));
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// Refuse an output path that holds anything but a regular file (or a symbolic link to one, which
/// the rename replaces, leaving its target alone): a directory, FIFO, socket or device would be
/// replaced by a regular file. A path that does not exist yet is fine.
pub fn check_target(path: &Path) -> Result<(), OutputError> {
    let Ok(own) = std::fs::symlink_metadata(path) else {
        return Ok(());
    };
    // A link is judged by what it points to (a dangling link is replaced like a missing file).
    let kind = match std::fs::metadata(path) {
        Ok(target) => target.file_type(),
        Err(_) => own.file_type(),
    };
    let shown = || path.display().to_string();
    if kind.is_dir() {
        Err(OutputError::IsDirectory(shown()))
    } else if kind.is_file() || kind.is_symlink() {
        Ok(())
    } else {
        Err(OutputError::NotRegular(shown()))
    }
}

/// The identity of an existing file (device and inode on Unix, the canonical path elsewhere).
pub(crate) fn identity(path: &Path) -> Option<(u64, u64, PathBuf)> {
    let canonical = path.canonicalize().ok()?;
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        let m = std::fs::metadata(&canonical).ok()?;
        Some((m.dev(), m.ino(), PathBuf::new()))
    }
    #[cfg(not(unix))]
    {
        Some((0, 0, canonical))
    }
}

/// Refuse `output` when it is (a link to, or another spelling of) one of `inputs`: the same
/// file (device and inode), whatever the path. Inputs that do not exist are no file to
/// protect.
pub fn refuse_input(output: &Path, inputs: &[PathBuf]) -> Result<(), OutputError> {
    let Some(out) = identity(output) else {
        return Ok(()); // the output does not exist yet: it is no input
    };
    for input in inputs {
        if identity(input).as_ref() == Some(&out) {
            return Err(OutputError::SameAsInput {
                output: output.display().to_string(),
                input: input.display().to_string(),
            });
        }
    }
    Ok(())
}

/// The lowercase extension of `path` when it is one of `allowed` (lowercase, without dot);
/// otherwise an error naming the extensions the writer supports.
pub fn extension_in<'a>(path: &Path, allowed: &[&'a str]) -> Result<&'a str, OutputError> {
    let found = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    if let Some(f) = &found
        && let Some(a) = allowed.iter().find(|a| **a == f.as_str())
    {
        return Ok(a);
    }
    Err(OutputError::Extension {
        path: path.display().to_string(),
        found: found.map_or_else(|| "none".into(), |f| format!(".{f}")),
        expected: allowed
            .iter()
            .map(|a| format!(".{a}"))
            .collect::<Vec<_>>()
            .join(" or "),
    })
}

#[cfg(test)]
mod tests;
