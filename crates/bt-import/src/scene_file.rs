//! The project's scene file, JSON or TOML (`docs/scene-format.md`): text to
//! [`SceneDescription`] and back. The types are `bt-scene`'s plain serde data.

use crate::ImportError;
use bt_scene::SceneDescription;

/// Parse a JSON scene description; errors carry line and column.
pub fn parse_json(text: &str, path: &str) -> Result<SceneDescription, ImportError> {
    serde_json::from_str(text).map_err(|e| ImportError::Parse {
        path: path.to_string(),
        message: e.to_string(),
    })
}

/// Parse a TOML scene description; errors carry line and column.
pub fn parse_toml(text: &str, path: &str) -> Result<SceneDescription, ImportError> {
    toml::from_str(text).map_err(|e| ImportError::Parse {
        path: path.to_string(),
        message: e.to_string().trim_end().to_string(),
    })
}

/// The description as a scene file in `format` (`json` or `toml`, as [`crate::load`] reads
/// them); absent optional fields are left out, never written as `null`.
pub fn write_description(desc: &SceneDescription, format: &str) -> Result<String, String> {
    match format {
        "json" => serde_json::to_string_pretty(desc)
            .map(|s| s + "\n")
            .map_err(|e| e.to_string()),
        "toml" => toml::to_string_pretty(desc).map_err(|e| e.to_string()),
        other => Err(format!("no scene writer for .{other} (use .json or .toml)")),
    }
}
