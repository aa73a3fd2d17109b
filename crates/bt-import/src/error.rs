//! The crate's one error type: every way a source can fail to become a scene.

/// Errors of scene loading: reading files, parsing formats, validating the result.
#[derive(Debug, thiserror::Error)]
pub enum ImportError {
    /// The file could not be read.
    #[error("{path}: {source}")]
    Io {
        /// File path.
        path: String,
        /// Underlying error.
        source: std::io::Error,
    },
    /// The file is not valid JSON/TOML of the scene format.
    #[error("{path}: {message}")]
    Parse {
        /// File path.
        path: String,
        /// Parser message with line and column.
        message: String,
    },
    /// A mesh file could not be imported.
    #[error(transparent)]
    Mesh(#[from] crate::mesh::MeshError),
    /// A point cloud could not be read, or its planes not extracted.
    #[error(transparent)]
    PointCloud(#[from] crate::cloud::CloudError),
    /// The extension is not one of the supported formats.
    #[error(
        "{path}: unsupported scene format (expected .json, .toml, .xml, .obj, .ply, .stl, .gltf, .glb, .pcd or builtin:NAME)"
    )]
    UnsupportedFormat {
        /// File path.
        path: String,
    },
    /// A Mitsuba/Sionna XML scene is malformed or uses what beamtrace does not support.
    #[error("{path}: line {line}, column {column}: {message}")]
    Xml {
        /// File path.
        path: String,
        /// 1-based line of the offending element.
        line: u32,
        /// 1-based column.
        column: u32,
        /// What is wrong, naming the element.
        message: String,
    },
    /// A directory was given where a scene file is expected.
    #[error("{path}: is a directory, not a scene file")]
    IsDirectory {
        /// The directory's path.
        path: String,
    },
    /// `builtin:NAME` names no built-in scene.
    #[error("unknown built-in scene \"{name}\" (built-in scenes: {known})")]
    UnknownBuiltin {
        /// The name after `builtin:`.
        name: String,
        /// The known names, comma-separated.
        known: String,
    },
    /// The parsed scene is invalid (every problem listed), see [`bt_scene::SceneError`].
    #[error(transparent)]
    Scene(#[from] bt_scene::SceneError),
    /// The mesh merge options are out of range, whatever the source (a built-in scene merges
    /// nothing, but a NaN given is still a mistake to report).
    #[error(transparent)]
    MergeOptions(#[from] bt_mesh::MergeError),
    /// The load cache was asked for but has no directory (no `BEAMTRACE_CACHE_DIR`,
    /// `XDG_CACHE_HOME` or `HOME`).
    #[error("--cache: no cache directory: set BEAMTRACE_CACHE_DIR, XDG_CACHE_HOME or HOME")]
    NoCacheDir,
    /// A load option is out of its range (NaN, infinite, negative).
    #[error("{option} must be {range}, got {value}")]
    Option {
        /// The option, by its CLI flag.
        option: &'static str,
        /// The range it must lie in.
        range: &'static str,
        /// The value given.
        value: bt_geom::Real,
    },
}
