//! Named numerical tolerances of this crate, each with its unit and reason. Length
//! tolerances that depend on the scan (noise, density) are parameters in
//! [`ExtractParams`](crate::ExtractParams), not constants.

use bt_geom::Real;
/// Smallest eigenvalue gap (relative to the trace, dimensionless) below which a covariance is
/// treated as isotropic. Jacobi sweeps stop when off-diagonal mass falls below this times
/// the trace.
pub const EIGEN_REL: Real = 1e-15;

/// Sine of the smallest angle between two 2-D lines for their intersection to be used as a
/// polygon corner (dimensionless). Below it the lines are treated as parallel (≈ 3°).
pub const PARALLEL_SIN: Real = 0.05;

/// Relative area (dimensionless, fraction of the polygon area) below which a polygon counts
/// as degenerate.
pub const AREA_REL: Real = 1e-9;

/// Cosine of the largest angle between two plane normals for their intersection line to be
/// used as a shared edge (planes closer to parallel than ≈ 30° are not snapped together).
pub const SNAP_MAX_COS: Real = 0.866;

/// Sine of the largest angle (≈ 10°) between a polygon edge and a neighbouring plane's
/// intersection line for the edge to be snapped onto that line.
pub const SNAP_EDGE_SIN: Real = 0.174;

/// Sine of the largest turn (≈ 8°) at a boundary vertex that is merged away as collinear
/// after edge refinement.
pub const MERGE_TURN_SIN: Real = 0.14;

/// Cosine of the largest angle (≈ 30°) between a point's estimated normal and its patch
/// normal for the point to enter the final least-squares refit. Points near a crease have
/// blended normals; leaving them out keeps a patch's plane from tilting towards its
/// neighbour, while they still count for the boundary.
pub const REFIT_GATE_COS: Real = 0.866;

/// Ratio of the middle to the largest covariance eigenvalue (dimensionless) below which a
/// neighbourhood is treated as a line, with no normal.
pub const LINEAR_NEIGHBOURHOOD: Real = 1e-3;

/// Cosine of the largest angle (≈ 5°) between a connected component's own least-squares
/// normal and its RANSAC plane for the component to belong to that plane.
pub const COMPONENT_COS: Real = 0.9962;

/// Sine of the largest turn (≈ 27°) merged away on the raw simplified raster boundary,
/// where a one-cell step over two cells is sampling noise, not shape.
pub const RASTER_MERGE_TURN_SIN: Real = 0.45;

/// Sine of the largest angle (≈ 15°) between a simplified boundary edge and an axis of its
/// patch's minimum-area rectangle for the axis to be the edge's prior direction.
pub const AXIS_PRIOR_SIN: Real = 0.26;

/// Cosine of the largest angle (≈ 3°) between two patches' planes for them to be treated as
/// parallel layers competing for the same points (a pane in front of a wall).
pub const LAYER_PARALLEL_COS: Real = 0.9986;

/// Smallest share (dimensionless) of a point's neighbours that must be nearer a plane for the
/// point to join that plane when re-assigning points between parallel layers. A layer that
/// is really there holds about half (overlapping layers) or all (an occluded wall) of the
/// neighbourhood, even at its edge a quarter; the noise tail of another layer ≈ 2 % at 4 σ.
pub const LAYER_MIN_SHARE: Real = 0.1;

/// Smallest share (dimensionless) of a point's neighbours in the other layer for the point
/// to move there from the patch RANSAC gave it. Inside an overlap a layer holds about half
/// the neighbourhood (all of it where it occludes the other); just outside its edge a
/// quarter or less, and noise-tail points there must not join it (they make corner spikes).
pub const LAYER_JOIN_SHARE: Real = 0.35;

/// Smallest separation of two parallel layers, in units of their noise σ (dimensionless),
/// for them to be kept as distinct surfaces after re-assignment. One Gaussian layer cut at
/// its middle gives two halves ≈ 2.7 σ_half apart; the test room's pane is 4 σ off the wall.
pub const LAYER_SEPARATION_SIGMAS: Real = 3.0;

/// Fewest points (dimensionless count) a gap strip between a patch edge and a crease line
/// must be able to hold, at the patch's density, for its emptiness to be evidence of a real
/// gap; narrower strips are below the data's resolution and may be snapped shut.
pub const SNAP_MIN_EXPECTED: Real = 8.0;

/// Smallest filled fraction (dimensionless) of such a strip, counted against the patch's
/// density, for the strip to be lost surface (snap) rather than a real gap (keep the edge).
/// A lost strip is full (≈ 1), a real gap empty (≈ 0).
pub const SNAP_MIN_FILL: Real = 0.5;

/// Smallest depth (m) of the point band behind a boundary edge used to estimate the points'
/// density across it; guards the division for a band of identical offsets (1 pm: far below
/// any scan noise).
pub const MIN_BAND_DEPTH: Real = 1e-12;
