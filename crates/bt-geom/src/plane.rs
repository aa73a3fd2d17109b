//! Infinite planes `normal · x = offset` (unit normal, offset in metres).

use crate::{Real, Vec3};
use serde::{Deserialize, Serialize};

/// An oriented infinite plane: the points `x` with `normal · x = offset`.
/// `normal` is a unit vector; `offset` is the signed distance of the plane from the origin (m).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Plane {
    /// Unit normal (world frame).
    pub normal: Vec3,
    /// Signed distance from the origin along `normal`, metres.
    pub offset: Real,
}

/// Which side of a plane a point lies on, decided with a tolerance band.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Side {
    /// `normal · x - offset > tol`.
    Front,
    /// `normal · x - offset < -tol`.
    Back,
    /// Within the tolerance band: on the plane.
    On,
}

impl Plane {
    /// Plane through `point` with unit normal `normal` (normalised here; must be non-zero).
    pub fn from_point_normal(point: Vec3, normal: Vec3) -> Self {
        Self::from_point_normal_of_length(point, normal, normal.length())
    }

    /// [`Plane::from_point_normal`] for a `normal` whose length `length` (its `length()`) the
    /// caller already has: the same normalisation (`normalize`: times the length's
    /// reciprocal), so the same bits, without a second square root.
    #[inline]
    pub fn from_point_normal_of_length(point: Vec3, normal: Vec3, length: Real) -> Self {
        let normal = normal * length.recip();
        Self {
            normal,
            offset: normal.dot(point),
        }
    }

    /// Signed distance of `p` from the plane (m), positive on the normal's side.
    /// Uses a fused multiply-add chain so the sign is as exact as f64 allows.
    #[inline]
    pub fn signed_distance(&self, p: Vec3) -> Real {
        self.normal.x.mul_add(
            p.x,
            self.normal
                .y
                .mul_add(p.y, self.normal.z.mul_add(p.z, -self.offset)),
        )
    }

    /// Signed distance of `p` (m) as a plain dot product minus the offset, not fused. It can
    /// differ from [`Plane::signed_distance`] by a few ulps of `|p| + |offset|`, and it avoids
    /// the software `fma` call of builds without the FMA target feature (several times
    /// faster there). Only for tests that keep a margin far above that round-off: the beam
    /// tree's, several length tolerances (`bt_paths::beamtree`).
    #[inline]
    pub fn signed_distance_unfused(&self, p: Vec3) -> Real {
        self.normal.dot(p) - self.offset
    }

    /// Side of `p` with a tolerance band of `tol` metres.
    #[inline]
    pub fn side(&self, p: Vec3, tol: Real) -> Side {
        let d = self.signed_distance(p);
        if d > tol {
            Side::Front
        } else if d < -tol {
            Side::Back
        } else {
            Side::On
        }
    }

    /// Orthogonal projection of `p` onto the plane.
    #[inline]
    pub fn project(&self, p: Vec3) -> Vec3 {
        p - self.signed_distance(p) * self.normal
    }

    /// Mirror image of `p` through the plane (the image source of the image method).
    #[inline]
    pub fn mirror(&self, p: Vec3) -> Vec3 {
        p - 2.0 * self.signed_distance(p) * self.normal
    }

    /// The direction (or any free vector) `v` mirrored through the plane: its component along
    /// the normal reversed.
    #[inline]
    pub fn mirror_direction(&self, v: Vec3) -> Vec3 {
        v - 2.0 * v.dot(self.normal) * self.normal
    }

    /// Parameter `t` where the line `a + t (b - a)` crosses the plane, or `None` when the line
    /// is parallel to it (|n · (b - a)| below `f64::EPSILON` times the segment length).
    #[inline]
    pub fn line_parameter(&self, a: Vec3, b: Vec3) -> Option<Real> {
        Self::crossing_parameter(self.signed_distance(a), self.signed_distance(b), a, b)
    }

    /// Where the segment `a → b` crosses the plane when `a` and `b` lie on opposite sides,
    /// each more than `margin` metres off it, with the sum of their distances from it (m);
    /// `None` otherwise. The crossing is then strictly inside the segment, more than `margin`
    /// from the plane at either end. Unfused distances
    /// ([`Plane::signed_distance_unfused`]): only for margins far above their round-off.
    #[inline]
    pub fn crossing_beyond(&self, a: Vec3, b: Vec3, margin: Real) -> Option<(Vec3, Real)> {
        let (da, db) = (
            self.signed_distance_unfused(a),
            self.signed_distance_unfused(b),
        );
        if (da > 0.0) == (db > 0.0) || da.abs() <= margin || db.abs() <= margin {
            return None;
        }
        Some((a + (da / (da - db)) * (b - a), da.abs() + db.abs()))
    }

    /// [`Plane::line_parameter`] from the signed distances `da`, `db` of `a` and `b` already
    /// computed: `None` when the line is parallel to the plane.
    #[inline]
    pub fn crossing_parameter(da: Real, db: Real, a: Vec3, b: Vec3) -> Option<Real> {
        let denom = da - db;
        if denom.abs() <= Real::EPSILON * (b - a).length() {
            None
        } else {
            Some(da / denom)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mirror_and_projection_of_a_tilted_plane() {
        let plane = Plane::from_point_normal(Vec3::new(0.0, 0.0, 1.0), Vec3::new(0.0, 1.0, 1.0));
        let p = Vec3::new(3.0, -2.0, -1.0);
        let image = plane.mirror(p);
        assert!((plane.signed_distance(image) + plane.signed_distance(p)).abs() < 1e-12);
        let mid = 0.5 * (p + image);
        assert!(plane.signed_distance(mid).abs() < 1e-12);
        assert!(plane.signed_distance(plane.project(p)).abs() < 1e-12);
        assert_eq!(plane.side(p, 1e-9), Side::Back);
    }

    #[test]
    fn line_parameter_is_none_for_parallel_lines() {
        let plane = Plane::from_point_normal(Vec3::ZERO, Vec3::Z);
        assert_eq!(
            plane.line_parameter(Vec3::new(0., 0., 1.), Vec3::new(5., 0., 1.)),
            None
        );
        let t = plane
            .line_parameter(Vec3::new(0., 0., 1.), Vec3::new(0., 0., -3.))
            .unwrap();
        assert!((t - 0.25).abs() < 1e-15);
    }
}
