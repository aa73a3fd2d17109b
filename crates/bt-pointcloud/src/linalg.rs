//! Small dense linear algebra: symmetric 3×3 eigen-decomposition and least-squares plane fit.

use bt_geom::{Real, Vec3};
use glam::DMat3;

use crate::tol;

/// Eigen-decomposition of a symmetric 3×3 matrix by cyclic Jacobi rotations.
/// Returns eigenvalues in ascending order and the matching unit eigenvectors.
pub(crate) fn sym_eigen(m: DMat3) -> ([Real; 3], [Vec3; 3]) {
    let mut a = [
        [m.x_axis.x, m.y_axis.x, m.z_axis.x],
        [m.x_axis.y, m.y_axis.y, m.z_axis.y],
        [m.x_axis.z, m.y_axis.z, m.z_axis.z],
    ];
    let mut v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let scale = a[0][0].abs() + a[1][1].abs() + a[2][2].abs();
    for _sweep in 0..50 {
        let off = a[0][1].abs() + a[0][2].abs() + a[1][2].abs();
        if off <= tol::EIGEN_REL * scale || off == 0.0 {
            break;
        }
        for (p, q) in [(0, 1), (0, 2), (1, 2)] {
            if a[p][q] == 0.0 {
                continue;
            }
            let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
            let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
            let t = if theta == 0.0 { 1.0 } else { t };
            let c = 1.0 / (t * t + 1.0).sqrt();
            let s = t * c;
            for row in &mut a {
                let (akp, akq) = (row[p], row[q]);
                row[p] = c * akp - s * akq;
                row[q] = s * akp + c * akq;
            }
            let (rp, rq) = (a[p], a[q]);
            for k in 0..3 {
                a[p][k] = c * rp[k] - s * rq[k];
                a[q][k] = s * rp[k] + c * rq[k];
            }
            for row in &mut v {
                let (vp, vq) = (row[p], row[q]);
                row[p] = c * vp - s * vq;
                row[q] = s * vp + c * vq;
            }
        }
    }
    let mut idx = [0usize, 1, 2];
    idx.sort_by(|&i, &j| a[i][i].total_cmp(&a[j][j]));
    let vals = idx.map(|i| a[i][i]);
    let vecs = idx.map(|i| Vec3::new(v[0][i], v[1][i], v[2][i]).normalize_or(Vec3::Z));
    (vals, vecs)
}

/// A least-squares plane: unit `normal`, `offset` with `normal · x = offset` (metres),
/// and the centroid of the fitted points (metres).
#[derive(Debug, Clone, Copy)]
pub(crate) struct PlaneFit {
    pub normal: Vec3,
    pub offset: Real,
    pub centroid: Vec3,
}

/// Fit a plane through `points` by PCA (the normal is the eigenvector of the smallest
/// eigenvalue of the covariance). `None` for fewer than three points.
pub(crate) fn fit_plane<I>(points: I) -> Option<PlaneFit>
where
    I: Iterator<Item = Vec3> + Clone,
{
    let (n, sum) = points
        .clone()
        .fold((0usize, Vec3::ZERO), |(n, s), p| (n + 1, s + p));
    if n < 3 {
        return None;
    }
    let c = sum / n as Real;
    let mut cov = DMat3::ZERO;
    for p in points {
        let d = p - c;
        cov += DMat3::from_cols(d * d.x, d * d.y, d * d.z);
    }
    cov *= 1.0 / n as Real;
    let (_, vecs) = sym_eigen(cov);
    let normal = vecs[0];
    Some(PlaneFit {
        normal,
        offset: normal.dot(c),
        centroid: c,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn eigen_of_diagonal_and_rotated() {
        let (vals, vecs) = sym_eigen(DMat3::from_diagonal(Vec3::new(3.0, 1.0, 2.0)));
        assert_eq!(vals, [1.0, 2.0, 3.0]);
        assert!((vecs[0].dot(Vec3::Y)).abs() > 1.0 - 1e-12);
        let r = DMat3::from_axis_angle(Vec3::new(1.0, 2.0, 3.0).normalize(), 0.7);
        let m = r * DMat3::from_diagonal(Vec3::new(5.0, 0.1, 2.0)) * r.transpose();
        let (vals, vecs) = sym_eigen(m);
        assert!((vals[0] - 0.1).abs() < 1e-12 && (vals[2] - 5.0).abs() < 1e-12);
        assert!((vecs[0].dot(r * Vec3::Y)).abs() > 1.0 - 1e-12);
    }

    #[test]
    fn plane_fit_recovers_plane() {
        let n = Vec3::new(0.2, -0.3, 0.9).normalize();
        let u = n.any_orthonormal_vector();
        let v = n.cross(u);
        let pts: Vec<Vec3> = (0..100)
            .map(|i| n * 1.5 + u * (i % 10) as Real * 0.1 + v * (i / 10) as Real * 0.1)
            .collect();
        let f = fit_plane(pts.iter().copied()).unwrap();
        assert!(f.normal.dot(n).abs() > 1.0 - 1e-12);
        assert!((f.offset * f.normal.dot(n).signum() - 1.5).abs() < 1e-12);
        assert!(
            pts.iter()
                .all(|p| (f.normal.dot(*p) - f.offset).abs() < 1e-9)
        );
    }
}
