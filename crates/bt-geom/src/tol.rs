//! Named tolerances. Every length tolerance is in metres and is meant for scenes of room to
//! building size (extent 0.1 m .. 1 km); `scaled` adapts a relative tolerance to a scene.

use crate::Real;

/// Relative tolerance of geometric decisions (inside/outside, side of plane) with respect to
/// the scene extent. 1e-9 of a 10 m room is 10 nm: far below any physical meaning, far above
/// f64 round-off (~1e-15 relative) accumulated over a few operations.
pub const REL_GEOMETRY: Real = 1e-9;

/// Maximum distance of a polygon vertex from the best-fit plane, relative to the polygon's
/// extent, before the polygon counts as non-planar (1e-6: 10 µm on a 10 m wall; meshes exported
/// in single precision are planar to ~1e-7).
pub const REL_PLANARITY: Real = 1e-6;

/// Minimum polygon area relative to the square of its extent (1e-12); below it the polygon is
/// degenerate (zero area).
pub const REL_AREA: Real = 1e-12;

/// Vertices closer than this relative distance (to the polygon extent) are repeated vertices.
pub const REL_VERTEX_MERGE: Real = 1e-9;

/// Largest |sine| of the turn at a polygon corner that still counts as straight (1e-12,
/// dimensionless): [`crate::convex::is_convex`] skips such corners.
pub const SIN_STRAIGHT_CORNER: Real = 1e-12;

/// Angle tolerance in radians for the reflection law check of found paths (1e-9 rad).
pub const ANGLE_REFLECTION_LAW: Real = 1e-9;

/// Magnitude below which the denominator of a reflection coefficient counts as zero (1e-12;
/// dimensionless). It vanishes only where the limit is known: the same medium on both sides
/// at grazing incidence (no interface: no reflection), or a lossless slab with |r| = 1 (the
/// slab reflects as its half-space).
pub const COEFFICIENT_DENOMINATOR: Real = 1e-12;

/// A length tolerance in metres for a scene whose bounding box diagonal is `extent` metres.
#[inline]
pub fn scaled(relative: Real, extent: Real) -> Real {
    relative * extent.max(1.0)
}
