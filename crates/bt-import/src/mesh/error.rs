//! The error of the mesh readers.

use bt_geom::Real;
use std::fmt;

/// Where in a mesh file a problem is: a text line, an element of a PLY body, or both.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Position {
    /// A 1-based line number of a text file (OBJ, PLY header, ASCII PLY body).
    Line(usize),
    /// The 0-based `index` of an element named `element` (`vertex`, `face`, ...) in a PLY body,
    /// with the 1-based line it starts on when the body is ASCII.
    Element {
        /// The PLY element name, e.g. `vertex` or `face`.
        element: String,
        /// 0-based index of the element within its element block.
        index: u64,
        /// 1-based line number in an ASCII body; `None` in a binary body.
        line: Option<usize>,
    },
}

impl fmt::Display for Position {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Position::Line(line) => write!(f, "line {line}"),
            Position::Element {
                element,
                index,
                line: Some(line),
            } => write!(f, "{element} {index} (line {line})"),
            Position::Element {
                element,
                index,
                line: None,
            } => write!(f, "{element} {index}"),
        }
    }
}

/// Everything that can go wrong while turning a mesh file into surfaces. Every variant names the
/// file (`"<input>"` when parsing bytes without a name) and, where it applies, the position.
#[derive(Debug, thiserror::Error)]
pub enum MeshError {
    /// The file could not be read from disk.
    #[error("{file}: cannot read file: {source}")]
    Io {
        /// File name as given.
        file: String,
        /// The underlying I/O error.
        #[source]
        source: std::io::Error,
    },
    /// The file extension is none of `.obj`, `.ply` and `.stl` (case-insensitive).
    #[error("{file}: unsupported mesh file extension {extension:?}: expected .obj, .ply or .stl")]
    UnsupportedExtension {
        /// File name as given.
        file: String,
        /// The extension found (empty when there is none).
        extension: String,
    },
    /// The merge options are out of range (negative or non-finite tolerance, angle >= 90 deg).
    #[error(transparent)]
    Merge(#[from] bt_mesh::MergeError),
    /// A statement or token that cannot be parsed (OBJ line, PLY header line, ASCII PLY value).
    #[error("{file}: {position}: {detail}")]
    Syntax {
        /// File name as given.
        file: String,
        /// Where the bad text is.
        position: Position,
        /// What is wrong, naming the offending text.
        detail: String,
    },
    /// A face refers to a vertex that does not exist (0, or beyond the vertex count).
    #[error(
        "{file}: {position}: vertex index {index} out of range: the file has {vertex_count} vertices"
    )]
    IndexOutOfRange {
        /// File name as given.
        file: String,
        /// The face statement or element.
        position: Position,
        /// The index as written in the file (1-based or negative in OBJ, 0-based in PLY).
        index: i64,
        /// Number of vertices available to this face.
        vertex_count: usize,
    },
    /// A face with fewer than three vertices.
    #[error("{file}: {position}: face has {count} vertices, at least 3 are needed")]
    FaceTooSmall {
        /// File name as given.
        file: String,
        /// The face statement or element.
        position: Position,
        /// Number of vertices the face lists.
        count: usize,
    },
    /// A vertex coordinate is NaN or infinite.
    #[error("{file}: {position}: vertex coordinate {axis} is not finite ({value})")]
    NonFiniteCoordinate {
        /// File name as given.
        file: String,
        /// The vertex statement or element.
        position: Position,
        /// `x`, `y` or `z`.
        axis: char,
        /// The value read.
        value: Real,
    },
    /// A vertex left the finite numbers when mapped through a caller's transform (a scene
    /// file's `to_world` with a huge scale).
    #[error("{file}: vertex {vertex} is not finite after the shape's transform")]
    NonFiniteTransformed {
        /// File name as given.
        file: String,
        /// Zero-based vertex index in the file.
        vertex: usize,
    },
    /// A PLY header claims more elements than the body can possibly hold. Checked before any
    /// allocation, so a hostile header cannot exhaust memory.
    #[error(
        "{file}: element \"{}\" claims {count} entries, which need {} bytes, but the body has only {body_bytes} bytes",
        bt_scene::name::shown(.element),
        bt_geom::AtLeast(*.min_bytes)
    )]
    CountTooLarge {
        /// File name as given.
        file: String,
        /// The PLY element name.
        element: String,
        /// The claimed count.
        count: u64,
        /// Minimum number of body bytes that many entries need (saturating).
        min_bytes: u64,
        /// Bytes available after the header.
        body_bytes: u64,
    },
    /// The file holds more vertices or faces than [`bt_mesh::MergeOptions::max_elements`].
    #[error(
        "{file}: {count} {element}, more than the budget of {budget} {element}; raise it \
         with --max-mesh-elements (load options: merge.max_elements)"
    )]
    Budget {
        /// File name as given.
        file: String,
        /// `vertices` or `faces`.
        element: &'static str,
        /// How many: the header's count (PLY), or "at least N (line L)" (OBJ, which stops
        /// reading at the first element beyond the budget).
        count: String,
        /// The budget.
        budget: u64,
    },
    /// The PLY body ends before all elements the header declares were read.
    #[error("{file}: {position}: file is truncated: {detail}")]
    Truncated {
        /// File name as given.
        file: String,
        /// The element being read when the data ran out.
        position: Position,
        /// What was expected.
        detail: String,
    },
    /// A valid file that uses a feature this reader does not handle (PLY format version,
    /// missing `x y z` properties, no face list, ...).
    #[error("{file}: unsupported: {detail}")]
    Unsupported {
        /// File name as given.
        file: String,
        /// What is not supported.
        detail: String,
    },
}
