//! Special files for the tests of outputs that must never replace one (`docs/reliability.md`).

use std::path::Path;

/// Create a FIFO at `path` with the system's `mkfifo` (no FFI in the tests).
pub fn mkfifo(path: &Path) {
    let ok = std::process::Command::new("mkfifo")
        .arg(path)
        .status()
        .expect("mkfifo runs")
        .success();
    assert!(ok, "mkfifo {}", path.display());
}

/// Whether `path` itself (not what a link points to) is a FIFO.
pub fn is_fifo(path: &Path) -> bool {
    use std::os::unix::fs::FileTypeExt;
    std::fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_fifo())
}
