//! The validated point-cloud type.

use crate::error::PointCloudError;
use bt_geom::Vec3;

/// A set of 3-D points in the world frame (metres, right-handed, z up), optionally with one
/// normal per point.
///
/// Invariants (checked by the constructors): every coordinate is finite, and if normals are
/// present there is exactly one per point. Normals need not be unit length or consistently
/// oriented; extraction only uses them to pick the sign of plane normals.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PointCloud {
    points: Vec<Vec3>,
    normals: Option<Vec<Vec3>>,
}

impl PointCloud {
    /// Build a cloud from points (metres). Fails with [`PointCloudError::InvalidCloud`] naming
    /// the first non-finite point.
    pub fn new(points: Vec<Vec3>) -> Result<Self, PointCloudError> {
        check_finite(&points, "point")?;
        Ok(Self {
            points,
            normals: None,
        })
    }

    /// Build a cloud from points (metres) and one normal per point (any length, any sign).
    pub fn with_normals(points: Vec<Vec3>, normals: Vec<Vec3>) -> Result<Self, PointCloudError> {
        if normals.len() != points.len() {
            return Err(PointCloudError::InvalidCloud {
                reason: format!("{} normals for {} points", normals.len(), points.len()),
            });
        }
        check_finite(&points, "point")?;
        check_finite(&normals, "normal")?;
        Ok(Self {
            points,
            normals: Some(normals),
        })
    }

    /// Internal constructor for callers that have already filtered non-finite values.
    pub(crate) fn from_parts_unchecked(points: Vec<Vec3>, normals: Option<Vec<Vec3>>) -> Self {
        debug_assert!(points.iter().all(|p| p.is_finite()));
        debug_assert!(normals.as_ref().is_none_or(|n| n.len() == points.len()));
        Self { points, normals }
    }

    /// The points, metres, world frame.
    pub fn points(&self) -> &[Vec3] {
        &self.points
    }

    /// The per-point normals, if the source provided them.
    pub fn normals(&self) -> Option<&[Vec3]> {
        self.normals.as_deref()
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// True when the cloud has no points.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Axis-aligned bounds `(min, max)` in metres, `None` for an empty cloud.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        let first = *self.points.first()?;
        Some(
            self.points
                .iter()
                .fold((first, first), |(lo, hi), p| (lo.min(*p), hi.max(*p))),
        )
    }
}

fn check_finite(v: &[Vec3], what: &str) -> Result<(), PointCloudError> {
    match v.iter().position(|p| !p.is_finite()) {
        Some(i) => Err(PointCloudError::InvalidCloud {
            reason: format!("{what} {i} is not finite"),
        }),
        None => Ok(()),
    }
}
