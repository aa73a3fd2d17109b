//! Per-point normal estimation by PCA over a fixed-radius neighbourhood.

use bt_geom::{Real, Vec3};
use glam::DMat3;
use rayon::prelude::*;

use crate::linalg::sym_eigen;
use crate::spatial::VoxelIndex;
use crate::tol;

/// Fewest neighbours (including the point) for a normal estimate; fewer gives `ZERO`.
const MIN_NEIGHBOURS: usize = 5;

/// Unit normal (unoriented) per point from the covariance of the neighbours within `radius`
/// metres; `Vec3::ZERO` where the neighbourhood is too sparse or degenerate (a line).
pub(crate) fn estimate_normals(points: &[Vec3], radius: Real) -> Vec<Vec3> {
    let index = VoxelIndex::build(points, radius);
    points
        .par_iter()
        .map(|&p| {
            // Moments in single sums of scalars: cheaper than accumulating DMat3s.
            let (mut n, mut sx, mut sy, mut sz) = (0usize, 0.0, 0.0, 0.0);
            let (mut xx, mut xy, mut xz, mut yy, mut yz, mut zz) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
            index.for_each_near(points, p, radius, |j| {
                let d = points[j as usize] - p;
                n += 1;
                sx += d.x;
                sy += d.y;
                sz += d.z;
                xx += d.x * d.x;
                xy += d.x * d.y;
                xz += d.x * d.z;
                yy += d.y * d.y;
                yz += d.y * d.z;
                zz += d.z * d.z;
            });
            if n < MIN_NEIGHBOURS {
                return Vec3::ZERO;
            }
            let k = 1.0 / n as Real;
            let m = Vec3::new(sx, sy, sz) * k;
            let cov = DMat3::from_cols(
                Vec3::new(xx * k - m.x * m.x, xy * k - m.x * m.y, xz * k - m.x * m.z),
                Vec3::new(xy * k - m.x * m.y, yy * k - m.y * m.y, yz * k - m.y * m.z),
                Vec3::new(xz * k - m.x * m.z, yz * k - m.y * m.z, zz * k - m.z * m.z),
            );
            let (vals, vecs) = sym_eigen(cov);
            // A neighbourhood that is (nearly) a line has no defined plane normal.
            if vals[1] <= tol::LINEAR_NEIGHBOURHOOD * vals[2] || !vecs[0].is_finite() {
                return Vec3::ZERO;
            }
            vecs[0]
        })
        .collect()
}
