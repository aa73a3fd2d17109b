//! Point clouds for beamtrace: extracting the planar surfaces of a scanned scene, and
//! generating synthetic scans. An algorithm crate: reading and writing PLY / PCD files is
//! `bt-import`'s (`bt_import::cloud`).
//!
//! The paper's geometric preprocessing extracts planes from a 3-D point cloud (with Open3D);
//! planes of at least 0.25 m² take part in reflection, smaller ones only block rays. This
//! crate is that step: [`extract_planes`] returns bounded planes
//! ([`ExtractedPlane`]: unit normal, offset, boundary polygon, area, reflector flag) and an
//! [`ExtractionReport`], and [`sample_polygons`] makes synthetic scans for tests and
//! benchmarks.
//!
//! Frames and units: right-handed world frame, z up, metres; areas in m², angles in
//! degrees where a name says `_deg`.

#![warn(missing_docs)]

pub mod cloud;
pub mod error;
pub mod extract;
mod linalg;
mod spatial;
pub mod synth;
pub mod tol;

pub use cloud::PointCloud;
pub use error::PointCloudError;
pub use extract::{
    ExtractParams, ExtractedPlane, Extraction, ExtractionReport, PlaneSummary, Progress, Stage,
    extract_planes, extract_planes_with_progress,
};
pub use synth::sample_polygons;
