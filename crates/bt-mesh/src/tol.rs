//! Named tolerances of the mesh import, each with its unit and reason. The defaults of
//! [`MergeOptions`](crate::MergeOptions) are user-adjustable; [`REL_ZERO_LENGTH`] is the floor
//! under them. Tolerances of the validated scene geometry live in `bt_geom::tol`.

use bt_geom::Real;

/// Default maximum angle between the normals of faces merged into one surface, in degrees.
pub const DEFAULT_ANGLE_TOL_DEG: Real = 1.0;
/// Default maximum distance of a merged face's vertices from the surface plane, in metres
/// (1 mm: well below a wavelength at 60 GHz, 5 mm, and above export rounding).
pub const DEFAULT_DIST_TOL_M: Real = 1e-3;
/// Default distance under which vertices are welded into one, in metres (0.1 mm: OBJ exporters
/// write 6 decimals, single-precision PLY keeps ~0.06 mm at 1 km).
pub const DEFAULT_WELD_TOL_M: Real = 1e-4;

/// Relative length tolerance (dimensionless, to the mesh's bounding-box diagonal, at least
/// 1 m) below which lengths count as zero even when `weld_tol_m` is 0: a few hundred ulps of
/// f64 coordinates.
pub const REL_ZERO_LENGTH: Real = 1e-12;

/// Relative difference (dimensionless, to the area) allowed between an outline's area and the
/// area of the faces it stands for, beyond what removing collinear vertices explains: rounding
/// of sums over thousands of faces (1e-9, far below any lost face).
pub const REL_AREA_MATCH: Real = 1e-9;
