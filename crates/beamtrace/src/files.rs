//! Every file the CLI writes goes through here (atomic, never over an input, format from the
//! extension); the rules live in `bt_output` (`docs/reliability.md`). The inputs of a run are
//! the files its load read (`bt_import::Loaded::sources`: the scene file and the meshes an XML
//! scene names) and any other file the command reads (`view --paths`).

use anyhow::Context;
use std::path::{Path, PathBuf};

/// Write `bytes` to `path` atomically after checking it is none of `inputs` and its extension
/// is one of `formats` (lowercase, without dot; empty: any).
pub fn write(
    path: &Path,
    bytes: &[u8],
    inputs: &[PathBuf],
    formats: &[&str],
) -> anyhow::Result<()> {
    check(path, inputs, formats)?;
    bt_output::write_atomic(path, bytes).with_context(|| format!("writing {}", path.display()))
}

/// What [`write()`] checks before writing `path`, for commands of several outputs to check them
/// all before writing the first: a refusal then leaves no output behind.
pub fn check(path: &Path, inputs: &[PathBuf], formats: &[&str]) -> anyhow::Result<()> {
    bt_output::refuse_input(path, inputs)?;
    if !formats.is_empty() {
        bt_output::extension_in(path, formats)?;
    }
    bt_output::check_target(path)?;
    Ok(())
}

/// Print a warning for each file of an earlier run's manifest that a commit left in place.
pub fn warn_left_alone(done: &bt_output::Committed) {
    for left in &done.left_alone {
        eprintln!("warning: {left}");
    }
}
