//! Safe outputs: the one home of every write beamtrace makes.
//!
//! Rules (`docs/reliability.md`):
//! - a file is written to a temporary file in its target directory and renamed over the
//!   target ([`write_atomic`], [`write_atomic_with`], [`write_atomic_via`]): a killed run
//!   leaves the old file or the new one, never half of one;
//! - an output directory is built aside in `DIR.tmp-<pid>-<n>` ([`OutputDir`]) and its files are
//!   moved into `DIR` only when complete (the whole directory is renamed into place when `DIR`
//!   does not exist yet); a failed run leaves `DIR` as it was and removes its staging directory;
//! - nothing in `DIR` is deleted unless the program wrote it: `DIR/.beamtrace-manifest` lists
//!   the files of the last run, and only those are replaced or removed;
//! - an output that is one of the inputs is refused ([`refuse_input`]);
//! - the format follows the extension or the output is refused ([`extension_in`]).

#![warn(missing_docs)]

pub mod csv;

use std::collections::BTreeSet;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Component, Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// Name of the manifest an [`OutputDir`] keeps in its directory.
pub const MANIFEST: &str = ".beamtrace-manifest";

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
}

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> OutputError + '_ {
    move |source| OutputError::Io {
        path: path.display().to_string(),
        source,
    }
}

static COUNTER: AtomicU64 = AtomicU64::new(0);

/// A name for a sibling of `path` that no other process or call uses: `<stem><tag>-<pid>-<n>`.
fn sibling(path: &Path, tag: &str) -> PathBuf {
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".into());
    path.with_file_name(format!("{name}{tag}-{}-{n}", std::process::id()))
}

fn parent_of(path: &Path) -> &Path {
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
    if path.is_dir() {
        return Err(OutputError::IsDirectory(path.display().to_string()).into());
    }
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
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

/// The identity of an existing file (device and inode on Unix, the canonical path elsewhere).
fn identity(path: &Path) -> Option<(u64, u64, PathBuf)> {
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

/// Refuse `output` when it is (a link to, or another spelling of) one of `inputs`.
pub fn refuse_input(output: &Path, inputs: &[&Path]) -> Result<(), OutputError> {
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

/// An output directory under construction: files are written into a staging directory beside
/// `dir` and moved into `dir` by [`OutputDir::commit`]. Dropped without a commit, it removes
/// its staging directory and leaves `dir` untouched.
#[derive(Debug)]
pub struct OutputDir {
    dir: PathBuf,
    staging: PathBuf,
    written: BTreeSet<String>,
    protected: Vec<PathBuf>,
    prefix: String,
    committed: bool,
}

fn check_relative(rel: &str) -> Result<(), OutputError> {
    let p = Path::new(rel);
    let ok = !rel.is_empty()
        && rel != MANIFEST
        && p.components().all(|c| matches!(c, Component::Normal(_)));
    if ok {
        Ok(())
    } else {
        Err(OutputError::BadRelative(rel.to_string()))
    }
}

impl OutputDir {
    /// Start building `dir` (whose parent is created if missing). `protected` are the inputs of
    /// the run: a commit that would replace one of them fails before moving anything.
    pub fn begin(dir: &Path, protected: &[&Path]) -> Result<OutputDir, OutputError> {
        if dir.exists() && !dir.is_dir() {
            return Err(OutputError::Io {
                path: dir.display().to_string(),
                source: std::io::Error::new(
                    std::io::ErrorKind::AlreadyExists,
                    "exists and is not a directory",
                ),
            });
        }
        let parent = parent_of(dir);
        std::fs::create_dir_all(parent).map_err(io(parent))?;
        let staging = sibling(dir, ".tmp");
        std::fs::create_dir(&staging).map_err(io(&staging))?;
        Ok(OutputDir {
            dir: dir.to_path_buf(),
            staging,
            written: BTreeSet::new(),
            protected: protected.iter().map(|p| p.to_path_buf()).collect(),
            prefix: String::new(),
            committed: false,
        })
    }

    /// The final directory.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Put every following file under `prefix` (`""`, or a relative directory ending in `/`),
    /// so a writer of one directory can fill a subdirectory (`step-3/`) of this one.
    pub fn set_prefix(&mut self, prefix: &str) -> Result<(), OutputError> {
        if !prefix.is_empty() {
            check_relative(prefix.trim_end_matches('/'))?;
        }
        self.prefix = prefix.to_string();
        Ok(())
    }

    /// Reserve `rel` (a relative path with `/` separators, under the current prefix) and
    /// return where to write it now, inside the staging directory (parents created). For
    /// writers that need a path.
    pub fn path(&mut self, rel: &str) -> Result<PathBuf, OutputError> {
        check_relative(rel)?;
        let rel = format!("{}{rel}", self.prefix);
        let rel = rel.as_str();
        let path = self.staging.join(rel);
        let parent = parent_of(&path);
        std::fs::create_dir_all(parent).map_err(io(parent))?;
        self.written.insert(rel.to_string());
        Ok(path)
    }

    /// Write `rel` with `bytes`.
    pub fn write(&mut self, rel: &str, bytes: &[u8]) -> Result<(), OutputError> {
        let path = self.path(rel)?;
        std::fs::write(&path, bytes).map_err(io(&path))
    }

    /// The files written so far, relative to the directory, sorted.
    pub fn files(&self) -> impl Iterator<Item = &str> {
        self.written.iter().map(String::as_str)
    }

    /// Move the files into place; remove files the previous run listed in the manifest and
    /// this run did not write; write the new manifest. Returns the final paths written.
    pub fn commit(mut self) -> Result<Vec<PathBuf>, OutputError> {
        let finals: Vec<PathBuf> = self.written.iter().map(|r| self.dir.join(r)).collect();
        let manifest = manifest_text(&self.written);
        if !self.dir.exists() {
            std::fs::write(self.staging.join(MANIFEST), &manifest).map_err(io(&self.staging))?;
            std::fs::rename(&self.staging, &self.dir).map_err(io(&self.dir))?;
            self.committed = true;
            return Ok(finals);
        }
        for f in &finals {
            if f.is_dir() {
                return Err(OutputError::IsDirectory(f.display().to_string()));
            }
            let inputs: Vec<&Path> = self.protected.iter().map(PathBuf::as_path).collect();
            refuse_input(f, &inputs)?;
        }
        let previous = read_manifest(&self.dir);
        for rel in &self.written {
            let (from, to) = (self.staging.join(rel), self.dir.join(rel));
            let parent = parent_of(&to);
            std::fs::create_dir_all(parent).map_err(io(parent))?;
            std::fs::rename(&from, &to).map_err(io(&to))?;
        }
        for rel in previous.difference(&self.written) {
            if check_relative(rel).is_ok() {
                let stale = self.dir.join(rel);
                if stale.is_file() {
                    std::fs::remove_file(&stale).map_err(io(&stale))?;
                }
            }
        }
        write_atomic(&self.dir.join(MANIFEST), manifest.as_bytes())?;
        Ok(finals)
    }
}

impl Drop for OutputDir {
    fn drop(&mut self) {
        if !self.committed {
            // Only the staging directory, which this value created and filled.
            let _ = std::fs::remove_dir_all(&self.staging);
        }
    }
}

fn manifest_text(files: &BTreeSet<String>) -> String {
    let mut s = String::from(
        "# files written by beamtrace into this directory (replaced on the next run; others are left alone)\n",
    );
    for f in files {
        s.push_str(f);
        s.push('\n');
    }
    s
}

fn read_manifest(dir: &Path) -> BTreeSet<String> {
    manifest_files(dir).unwrap_or_default()
}

/// The files (relative, sorted) the last committed run wrote into `dir`, or `None` when `dir`
/// has no manifest.
pub fn manifest_files(dir: &Path) -> Option<BTreeSet<String>> {
    let text = std::fs::read_to_string(dir.join(MANIFEST)).ok()?;
    Some(
        text.lines()
            .filter(|l| !l.is_empty() && !l.starts_with('#'))
            .map(str::to_string)
            .collect(),
    )
}

#[cfg(test)]
mod tests;
