//! Output directories: locked, built in a staging directory inside them, moved in on commit,
//! with a manifest of what was written (`crate::manifest`).

use crate::lock::DirLock;
use crate::manifest::{self, STAGING, Walk, check_relative};
use crate::{MANIFEST, OutputError, check_target, io, parent_of, refuse_input, write_atomic};
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// A file the previous run's manifest listed that the commit did not remove, and why: it is
/// not (or no longer) certainly a file beamtrace wrote. For the user as a warning.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LeftAlone {
    /// The path as listed, joined to the directory.
    pub path: PathBuf,
    /// Why it was not removed.
    pub reason: String,
}

impl std::fmt::Display for LeftAlone {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{}: listed in {MANIFEST} but left alone: {}",
            self.path.display(),
            self.reason
        )
    }
}

/// What a commit did.
#[derive(Debug, Clone, Default)]
pub struct Committed {
    /// The final paths written, sorted.
    pub files: Vec<PathBuf>,
    /// Files of the previous manifest left in place (print them as warnings).
    pub left_alone: Vec<LeftAlone>,
}

/// An output directory under construction: `dir` is locked against other runs, files are
/// written into a staging directory inside it and moved into place by [`OutputDir::commit`].
/// Dropped without a commit, it removes its staging directory (and `dir`, when this run
/// created it) and leaves `dir` as it was.
#[derive(Debug)]
pub struct OutputDir {
    dir: PathBuf,
    staging: PathBuf,
    written: BTreeSet<String>,
    protected: Vec<PathBuf>,
    prefix: String,
    created: bool,
    committed: bool,
    lock: Option<DirLock>,
}

/// Create `dir` (and its parent) unless it exists; whether this call created it.
fn create(dir: &Path) -> Result<bool, OutputError> {
    if let Ok(m) = std::fs::metadata(dir) {
        if m.is_dir() {
            return Ok(false);
        }
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
    match std::fs::create_dir(dir) {
        Ok(()) => Ok(true),
        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => Ok(false),
        Err(e) => Err(io(dir)(e)),
    }
}

impl OutputDir {
    /// Start building `dir` (created, with its parent, if missing): lock it (a second run into
    /// it fails with [`OutputError::Busy`]), remove what a killed run left there, and open a
    /// staging directory. `protected` are the inputs of the run: a commit that would replace
    /// one of them fails before moving anything.
    pub fn begin(dir: &Path, protected: &[PathBuf]) -> Result<OutputDir, OutputError> {
        let created = create(dir)?;
        let locked = DirLock::acquire(dir).and_then(|lock| {
            check_target(&dir.join(MANIFEST))?;
            crate::stale::remove_stale_staging(dir);
            let staging = crate::sibling(&dir.join(STAGING), "");
            std::fs::create_dir(&staging).map_err(io(&staging))?;
            Ok((lock, staging))
        });
        let (lock, staging) = match locked {
            Ok(v) => v,
            Err(e) => {
                if created {
                    let _ = std::fs::remove_dir(dir);
                }
                return Err(e);
            }
        };
        Ok(OutputDir {
            dir: dir.to_path_buf(),
            staging,
            written: BTreeSet::new(),
            protected: protected.to_vec(),
            prefix: String::new(),
            created,
            committed: false,
            lock: Some(lock),
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

    /// Refuse, before anything moves, a file of this run whose place in `dir` is reached
    /// through a symbolic link, holds a directory or special file, or is an input.
    fn check_places(&self) -> Result<(), OutputError> {
        for rel in &self.written {
            let to = self.dir.join(rel);
            if let Walk::Symlink(link) = manifest::walk(&self.dir, rel) {
                return Err(OutputError::ThroughSymlink {
                    path: to.display().to_string(),
                    link: link.display().to_string(),
                });
            }
            check_target(&to)?;
            refuse_input(&to, &self.protected)?;
        }
        Ok(())
    }

    /// Move the files into place; remove the files the previous run listed in the manifest
    /// and this run did not write, when they are still what it wrote (the others are returned
    /// as [`Committed::left_alone`]); write the new manifest.
    pub fn commit(mut self) -> Result<Committed, OutputError> {
        self.check_places()?;
        let mut hashes = BTreeMap::new();
        for rel in &self.written {
            let from = self.staging.join(rel);
            hashes.insert(
                rel.clone(),
                manifest::sha256_file(&from).map_err(io(&from))?,
            );
        }
        let previous = manifest::read(&self.dir).unwrap_or_default();
        for rel in &self.written {
            let (from, to) = (self.staging.join(rel), self.dir.join(rel));
            let parent = parent_of(&to);
            std::fs::create_dir_all(parent).map_err(io(parent))?;
            std::fs::rename(&from, &to).map_err(io(&to))?;
        }
        let mut left_alone = Vec::new();
        for entry in previous.iter().filter(|e| !self.written.contains(&e.rel)) {
            match manifest::removable(&self.dir, entry) {
                Ok(Some(stale)) => std::fs::remove_file(&stale).map_err(io(&stale))?,
                Ok(None) => {}
                Err(reason) => left_alone.push(LeftAlone {
                    path: self.dir.join(&entry.rel),
                    reason,
                }),
            }
        }
        write_atomic(&self.dir.join(MANIFEST), manifest::text(&hashes).as_bytes())?;
        self.committed = true;
        // Only the emptied staging tree this value created.
        let _ = std::fs::remove_dir_all(&self.staging);
        Ok(Committed {
            files: self.written.iter().map(|r| self.dir.join(r)).collect(),
            left_alone,
        })
    }
}

impl Drop for OutputDir {
    fn drop(&mut self) {
        if !self.committed {
            // Only the staging directory, which this value created and filled.
            let _ = std::fs::remove_dir_all(&self.staging);
        }
        // Unlock (removing the lock file) before removing a directory this run created, which
        // is then empty unless someone else put a file there.
        self.lock = None;
        if self.created && !self.committed {
            let _ = std::fs::remove_dir(&self.dir);
        }
    }
}
