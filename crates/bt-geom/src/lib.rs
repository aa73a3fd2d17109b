//! Geometry kernel of beamtrace: the scalar type, named tolerances, planes, bounded planar
//! polygons, segment tests and a bounding-volume hierarchy for occlusion queries.
//!
//! Frames and units: right-handed world frame, z up, metres. See `docs/conventions.md`.
#![warn(missing_docs)]

pub mod bvh;
pub mod convex;
pub mod count;
pub mod hash;
pub mod plane;
pub mod points;
pub mod poly2;
pub mod polygon;
pub mod real;
pub mod tol;

#[cfg(test)]
mod fixtures;

pub use bvh::{Bvh, Occluder};
pub use count::{AtLeast, Budget, Count, OverBudget};
pub use plane::{Plane, Side};
pub use points::Points;
pub use polygon::{Polygon, PolygonError};

/// The one scalar type of the project (metres, seconds, radians unless a name says otherwise).
pub type Real = f64;
/// A point or vector in the world frame (metres, z up).
pub type Vec3 = glam::DVec3;
/// A point or vector in a polygon's 2-D in-plane frame (metres).
pub type Vec2 = glam::DVec2;
