//! The lock of an output directory: an advisory lock (`flock`) on `DIR/.beamtrace-lock`, held
//! from [`crate::OutputDir::begin`] to its commit or drop. The OS drops it when the process
//! dies, so a killed run never blocks the next one; the file itself is removed when the run
//! ends (while still locked), so a finished run leaves nothing behind.

use crate::{LOCK, OutputError, io};
use std::fs::{File, OpenOptions};
use std::io::Write;
use std::path::{Path, PathBuf};

/// A held lock; dropping it removes the file and releases the lock.
#[derive(Debug)]
pub(crate) struct DirLock {
    path: PathBuf,
    // Closed (unlocked) after `drop` has removed the path.
    _file: File,
}

fn open_no_follow(path: &Path) -> std::io::Result<File> {
    let mut options = OpenOptions::new();
    options.read(true).write(true).create(true).truncate(false);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        // A link planted at the lock's name is refused, never followed (nor created through).
        options.custom_flags(libc::O_NOFOLLOW | libc::O_NONBLOCK);
    }
    options.open(path)
}

/// Take an exclusive advisory lock on `file` without waiting: `Ok(false)` when another open
/// file holds one. (`File::try_lock` needs Rust 1.89; the workspace still builds with 1.85.)
#[cfg(unix)]
fn try_lock(file: &File) -> std::io::Result<bool> {
    use std::os::fd::AsRawFd;
    // SAFETY: flock only reads the descriptor, which `file` keeps open for the call.
    let r = unsafe { libc::flock(file.as_raw_fd(), libc::LOCK_EX | libc::LOCK_NB) };
    if r == 0 {
        return Ok(true);
    }
    let e = std::io::Error::last_os_error();
    match e.raw_os_error() {
        Some(libc::EWOULDBLOCK) => Ok(false),
        // A file system without advisory locks: go on unlocked rather than never write.
        Some(libc::ENOLCK | libc::EOPNOTSUPP) => Ok(true),
        _ => Err(e),
    }
}

/// Without `flock` the directory is not locked (beamtrace's platforms are Unix).
#[cfg(not(unix))]
fn try_lock(_: &File) -> std::io::Result<bool> {
    Ok(true)
}

#[cfg(unix)]
fn same_file(a: &std::fs::Metadata, b: &std::fs::Metadata) -> bool {
    use std::os::unix::fs::MetadataExt;
    (a.dev(), a.ino()) == (b.dev(), b.ino())
}

#[cfg(not(unix))]
fn same_file(_: &std::fs::Metadata, _: &std::fs::Metadata) -> bool {
    true
}

impl DirLock {
    /// Lock `dir` (an existing directory) or refuse with [`OutputError::Busy`] naming it.
    pub(crate) fn acquire(dir: &Path) -> Result<DirLock, OutputError> {
        let path = dir.join(LOCK);
        let busy = || OutputError::Busy {
            dir: dir.display().to_string(),
        };
        // A run that ends removes the file while it still holds the lock: one that opened the
        // old file meanwhile locks a file no longer at the path, and tries again.
        for _ in 0..8 {
            if let Ok(m) = std::fs::symlink_metadata(&path)
                && !m.is_file()
            {
                return Err(OutputError::NotRegular(path.display().to_string()));
            }
            let mut file = open_no_follow(&path).map_err(io(&path))?;
            match try_lock(&file) {
                Ok(true) => {}
                Ok(false) => return Err(busy()),
                Err(e) => return Err(io(&path)(e)),
            }
            let held = file.metadata().map_err(io(&path))?;
            if !held.is_file() {
                return Err(OutputError::NotRegular(path.display().to_string()));
            }
            match std::fs::symlink_metadata(&path) {
                Ok(now) if same_file(&held, &now) => {
                    // Who holds it, for a person looking at the directory.
                    let _ = file.set_len(0);
                    let _ = writeln!(file, "{}", std::process::id());
                    return Ok(DirLock { path, _file: file });
                }
                _ => continue,
            }
        }
        Err(busy())
    }
}

impl Drop for DirLock {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.path);
    }
}
