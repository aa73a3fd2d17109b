//! The crate's only filesystem access.

use std::path::Path;

use crate::error::MeshError;
use crate::{MergeOptions, MeshImport, read_obj, read_ply};

/// Reads the mesh file at `path` and merges its faces into planar surfaces, choosing the
/// reader by extension (`.obj` or `.ply`, case-insensitive). Coordinates are in metres.
pub fn read_mesh_path(path: &Path, opts: &MergeOptions) -> Result<MeshImport, MeshError> {
    let file = path.display().to_string();
    let extension = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    let reader = match extension.as_str() {
        "obj" => read_obj,
        "ply" => read_ply,
        _ => return Err(MeshError::UnsupportedExtension { file, extension }),
    };
    opts.validate()?;
    let bytes = std::fs::read(path).map_err(|source| MeshError::Io {
        file: file.clone(),
        source,
    })?;
    reader(&bytes, Some(&file), opts)
}
