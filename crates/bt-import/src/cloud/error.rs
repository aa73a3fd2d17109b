//! The error of the point-cloud readers and writers.

use std::fmt;
use std::path::{Path, PathBuf};

/// Where the bytes being parsed came from: a file path when known, otherwise nothing
/// (an in-memory buffer or a stream). Displays as `"path: "` or as the empty string so
/// that messages read `"room.ply: line 4: ..."`.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Origin(pub Option<PathBuf>);

impl fmt::Display for Origin {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.0 {
            Some(p) => write!(f, "{}: ", p.display()),
            None => Ok(()),
        }
    }
}

/// Position of a problem inside the data section: the zero-based element (point) index and,
/// for text formats, the one-based line number in the file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DataPos {
    /// Zero-based index of the element (point record) being read.
    pub element: u64,
    /// One-based line number for ASCII data, `None` for binary data.
    pub line: Option<usize>,
}

impl fmt::Display for DataPos {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.line {
            Some(l) => write!(f, "line {l} (point {})", self.element),
            None => write!(f, "point {}", self.element),
        }
    }
}

/// Every failure of reading and writing point clouds, and of extracting their planes. Messages are lowercase, name the file when known and say
/// where (line / point index) and what is wrong. Parsers never panic on malformed input.
#[derive(Debug, thiserror::Error)]
pub enum CloudError {
    /// An output could not be written safely (atomic write, never over an input).
    #[error(transparent)]
    Output(#[from] bt_output::OutputError),
    /// The operating system reported an error while opening, reading or writing.
    #[error("{origin}i/o error: {source}")]
    Io {
        /// File concerned, if known.
        origin: Origin,
        /// Underlying error.
        #[source]
        source: std::io::Error,
    },
    /// Neither the extension nor the first bytes identify a PLY or PCD file.
    #[error("{origin}unknown point-cloud format (expected a .ply or .pcd file)")]
    UnknownFormat {
        /// File concerned, if known.
        origin: Origin,
    },
    /// The header is malformed (bad keyword, bad number, inconsistent declarations, no end).
    #[error("{origin}line {line}: bad header: {reason}")]
    Header {
        /// File concerned, if known.
        origin: Origin,
        /// One-based header line number.
        line: usize,
        /// What is wrong.
        reason: String,
    },
    /// A valid but unsupported variant of the format (e.g. PCD `binary_compressed`).
    #[error("{origin}line {line}: unsupported: {what}")]
    Unsupported {
        /// File concerned, if known.
        origin: Origin,
        /// One-based header line number that declares the feature.
        line: usize,
        /// The unsupported feature.
        what: String,
    },
    /// A required coordinate field (x, y or z) is not declared in the header.
    #[error("{origin}header declares no '{field}' field for the points")]
    MissingField {
        /// File concerned, if known.
        origin: Origin,
        /// The missing field name.
        field: String,
    },
    /// The header declares more points than the budget [`crate::cloud::ReadOptions::max_points`].
    #[error(
        "{origin}header declares {claimed} points, more than the budget of {budget} points; \
         raise it with --max-cloud-points (read options: max_points)"
    )]
    OverBudget {
        /// File concerned, if known.
        origin: Origin,
        /// Number of points declared by the header.
        claimed: u64,
        /// The budget.
        budget: u64,
    },
    /// The header claims more points than the remaining bytes can possibly hold; detected
    /// before any allocation for the points.
    #[error(
        "{origin}header claims {claimed} points, needing at least {min_bytes} bytes, \
         but only {available} bytes follow the header"
    )]
    CountExceedsData {
        /// File concerned, if known.
        origin: Origin,
        /// Number of points (or elements) claimed by the header.
        claimed: u64,
        /// Minimum number of bytes such a claim needs.
        min_bytes: u128,
        /// Bytes actually available after the header.
        available: usize,
    },
    /// The data section ends before all claimed points were read.
    #[error("{origin}truncated data: ends at {at} of {expected} points")]
    Truncated {
        /// File concerned, if known.
        origin: Origin,
        /// The element that could not be read completely.
        at: DataPos,
        /// Number of points the header claims.
        expected: u64,
    },
    /// A value in the data section cannot be parsed.
    #[error("{origin}{at}: bad value: {reason}")]
    BadValue {
        /// File concerned, if known.
        origin: Origin,
        /// Where.
        at: DataPos,
        /// What is wrong.
        reason: String,
    },
    /// A point has a NaN or infinite coordinate and the policy is
    /// [`NonFinitePolicy::Reject`](crate::cloud::NonFinitePolicy::Reject).
    #[error("{origin}{at}: non-finite coordinate")]
    NonFinite {
        /// File concerned, if known.
        origin: Origin,
        /// Where.
        at: DataPos,
    },
    /// The cloud is invalid for extraction, or the extraction parameters are out of range
    /// (`bt-pointcloud`'s error).
    #[error(transparent)]
    Extract(#[from] bt_pointcloud::PointCloudError),
}

impl CloudError {
    /// Attach a file path to an error produced while parsing an in-memory buffer.
    pub fn with_path(mut self, path: &Path) -> Self {
        let o = Origin(Some(path.to_path_buf()));
        match &mut self {
            Self::Io { origin, .. }
            | Self::UnknownFormat { origin }
            | Self::Header { origin, .. }
            | Self::Unsupported { origin, .. }
            | Self::MissingField { origin, .. }
            | Self::CountExceedsData { origin, .. }
            | Self::OverBudget { origin, .. }
            | Self::Truncated { origin, .. }
            | Self::BadValue { origin, .. }
            | Self::NonFinite { origin, .. } => *origin = o,
            Self::Extract(_) | Self::Output(_) => {}
        }
        self
    }
}
