//! The crate's single error type.

/// Every failure of this crate: invalid input clouds and invalid extraction parameters.
/// Messages are lowercase and name what is wrong.
#[derive(Debug, thiserror::Error)]
pub enum PointCloudError {
    /// In-memory input that violates a precondition (e.g. a NaN point handed to
    /// [`PointCloud::new`](crate::PointCloud::new), or normals of the wrong length).
    #[error("invalid point cloud: {reason}")]
    InvalidCloud {
        /// What is wrong.
        reason: String,
    },
    /// Extraction parameters out of range; every problem is listed at once.
    #[error("invalid extraction parameters: {}", problems.join("; "))]
    InvalidParams {
        /// One message per offending parameter.
        problems: Vec<String>,
    },
}
