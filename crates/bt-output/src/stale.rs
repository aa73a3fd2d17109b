//! What a killed run leaves behind, removed by the next run that writes the same output.
//!
//! The rule (`docs/reliability.md`): only entries whose name has our exact pattern for this
//! output, only in the output's own directory, only a regular file (temporary files) or a real
//! directory (staging) as `symlink_metadata` sees it (a link of that name is never followed nor
//! removed), and only when the process named in it is gone (`/proc/<pid>` absent; on systems
//! without `/proc` nothing is removed). Inside a locked output directory every staging
//! directory is stale: the lock shows no other run writes there.

use crate::manifest::STAGING;
use std::ffi::OsStr;
use std::path::Path;

/// `<pid>-<n>` with both parts decimal: the pid.
fn pid_and_counter(rest: &str) -> Option<u32> {
    let (pid, n) = rest.split_once('-')?;
    let digits = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
    if digits(pid) && digits(n) {
        pid.parse().ok()
    } else {
        None
    }
}

/// The pid of `name` when it is `<prefix><pid>-<n><suffix>`.
pub(crate) fn tagged_pid(name: &str, prefix: &str, suffix: &str) -> Option<u32> {
    pid_and_counter(name.strip_prefix(prefix)?.strip_suffix(suffix)?)
}

/// Whether process `pid` may still be running (always true where this cannot be known).
fn alive(pid: u32) -> bool {
    if pid == std::process::id() {
        return true;
    }
    if cfg!(target_os = "linux") {
        Path::new("/proc").join(pid.to_string()).exists()
    } else {
        true
    }
}

/// Remove the entries of `dir` that `stale` picks (given the name), each only when
/// `symlink_metadata` shows the wanted kind (`want_dir`: a real directory, else a regular file).
fn remove_matching(dir: &Path, want_dir: bool, stale: impl Fn(&str) -> bool) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let name = entry.file_name();
        let Some(name) = name.to_str() else { continue };
        if !stale(name) {
            continue;
        }
        let path = entry.path();
        let Ok(meta) = std::fs::symlink_metadata(&path) else {
            continue;
        };
        // `remove_dir_all` does not follow links inside the directory either.
        let _ = if want_dir && meta.is_dir() {
            std::fs::remove_dir_all(&path)
        } else if !want_dir && meta.is_file() {
            std::fs::remove_file(&path)
        } else {
            Ok(())
        };
    }
}

/// Temporary files of earlier atomic writes of `name` in `dir` (`.<name>.tmp-<pid>-<n>` and,
/// when the output has an extension, `.<ext>` after it) whose process is gone.
pub(crate) fn remove_stale_temporaries(dir: &Path, name: &str, ext: Option<&OsStr>) {
    let prefix = format!(".{name}.tmp-");
    let suffix = match ext.and_then(OsStr::to_str) {
        Some(e) => format!(".{e}"),
        None => String::new(),
    };
    remove_matching(dir, false, |n| {
        tagged_pid(n, &prefix, &suffix).is_some_and(|pid| !alive(pid))
    });
}

/// Staging directories inside the locked output directory `dir` (`.beamtrace-staging-<pid>-<n>`,
/// any pid but ours), and those an older beamtrace built beside it (`<DIR>.tmp-<pid>-<n>`)
/// whose process is gone.
pub(crate) fn remove_stale_staging(dir: &Path) {
    let inside = format!("{STAGING}-");
    let ours = std::process::id();
    remove_matching(dir, true, |n| {
        tagged_pid(n, &inside, "").is_some_and(|pid| pid != ours)
    });
    let Some(name) = dir.file_name().and_then(OsStr::to_str) else {
        return;
    };
    let beside = format!("{name}.tmp-");
    remove_matching(crate::parent_of(dir), true, |n| {
        tagged_pid(n, &beside, "").is_some_and(|pid| !alive(pid))
    });
}
