//! Points stored as three coordinate arrays (structure of arrays), for tests of many points
//! against the same planes: one plane's distances to every point run in vector lanes, with
//! no branch per point.

use crate::{Plane, Real, Vec3};

/// Points (world frame, m) as three coordinate arrays, each with a tag (the caller's index),
/// in the order they were pushed.
#[derive(Debug, Clone, Default)]
pub struct Points {
    x: Vec<Real>,
    y: Vec<Real>,
    z: Vec<Real>,
    tags: Vec<u32>,
}

impl Points {
    /// Empty the batch, keeping its memory.
    pub fn clear(&mut self) {
        self.x.clear();
        self.y.clear();
        self.z.clear();
        self.tags.clear();
    }

    /// Append point `p` with tag `tag`.
    pub fn push(&mut self, p: Vec3, tag: u32) {
        self.x.push(p.x);
        self.y.push(p.y);
        self.z.push(p.z);
        self.tags.push(tag);
    }

    /// The number of points.
    pub fn len(&self) -> usize {
        self.tags.len()
    }

    /// Whether there are no points.
    pub fn is_empty(&self) -> bool {
        self.tags.is_empty()
    }

    /// The tags, in the order of the points.
    pub fn tags(&self) -> &[u32] {
        &self.tags
    }

    /// Into `inside` (resized to [`Points::len`]): per point, whether it lies on the positive
    /// side of every plane of `planes` within `margin` (m), that is whether
    /// `plane.signed_distance_unfused(p) >= -margin` for each plane, bit for bit the scalar
    /// test (a NaN distance is outside). Returns whether any point is inside. Planes are
    /// taken in order and the test stops when no point is left inside.
    pub fn inside_all(&self, planes: &[Plane], margin: Real, inside: &mut Vec<bool>) -> bool {
        inside.clear();
        inside.resize(self.len(), true);
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU supports AVX2 (checked just above).
            return unsafe { self.inside_all_avx2(planes, margin, inside) };
        }
        self.inside_all_impl(planes, margin, inside)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn inside_all_avx2(&self, planes: &[Plane], margin: Real, inside: &mut [bool]) -> bool {
        self.inside_all_impl(planes, margin, inside)
    }

    /// [`Points::inside_all`]'s body, inlined into both of its builds. The distance is
    /// `((nx·x + ny·y) + nz·z) − offset`, the operations of `Vec3::dot` and
    /// [`Plane::signed_distance_unfused`] in their order, never fused (the compiler does not
    /// contract a multiply and an add), so each lane gives the scalar test's bits.
    #[inline(always)]
    fn inside_all_impl(&self, planes: &[Plane], margin: Real, inside: &mut [bool]) -> bool {
        let n = self.len();
        let (x, y, z) = (&self.x[..n], &self.y[..n], &self.z[..n]);
        let inside = &mut inside[..n];
        let mut any = n > 0;
        for pl in planes {
            if !any {
                break;
            }
            let (nx, ny, nz, off) = (pl.normal.x, pl.normal.y, pl.normal.z, pl.offset);
            let mut left = false;
            for j in 0..n {
                let d = nx * x[j] + ny * y[j] + nz * z[j] - off;
                inside[j] &= d >= -margin;
                left |= inside[j];
            }
            any = left;
        }
        any
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn coordinate() -> impl Strategy<Value = Real> {
        prop_oneof![
            8 => -50.0..50.0f64,
            1 => Just(0.0),
            1 => Just(Real::NAN),
        ]
    }

    fn point() -> impl Strategy<Value = Vec3> {
        (coordinate(), coordinate(), coordinate()).prop_map(|(x, y, z)| Vec3::new(x, y, z))
    }

    fn plane() -> impl Strategy<Value = Plane> {
        (point(), -1.0..1.0f64, -1.0..1.0f64, 0.1..1.0f64).prop_map(|(p, a, b, c)| {
            let p = if p.is_finite() { p } else { Vec3::ZERO };
            Plane::from_point_normal(p, Vec3::new(a, b, c))
        })
    }

    proptest! {
        /// Each point's answer is the scalar test's, for any number of points (lanes and
        /// the tail), planes and margins, NaN coordinates included.
        #[test]
        fn inside_all_is_the_scalar_test(
            points in prop::collection::vec(point(), 0..40),
            planes in prop::collection::vec(plane(), 0..6),
            margin in prop_oneof![Just(0.0), 1e-9..1.0f64],
        ) {
            let mut batch = Points::default();
            for (k, &p) in points.iter().enumerate() {
                batch.push(p, k as u32 * 3);
            }
            let mut inside = Vec::new();
            let any = batch.inside_all(&planes, margin, &mut inside);
            let expected: Vec<bool> = points
                .iter()
                .map(|&p| planes.iter().all(|pl| pl.signed_distance_unfused(p) >= -margin))
                .collect();
            prop_assert_eq!(&inside, &expected);
            prop_assert_eq!(any, expected.contains(&true));
            prop_assert_eq!(batch.tags(), &(0..points.len() as u32).map(|k| k * 3).collect::<Vec<_>>()[..]);
        }
    }

    #[test]
    fn a_point_just_outside_the_margin_is_out_and_one_on_it_is_in() {
        let plane = Plane::from_point_normal(Vec3::ZERO, Vec3::Z);
        let mut batch = Points::default();
        batch.push(Vec3::new(0.0, 0.0, -0.5), 0);
        batch.push(Vec3::new(0.0, 0.0, -0.5 - 1e-12), 1);
        batch.push(Vec3::new(3.0, 4.0, 7.0), 2);
        let mut inside = Vec::new();
        assert!(batch.inside_all(&[plane], 0.5, &mut inside));
        assert_eq!(inside, [true, false, true]);
        assert!(!batch.inside_all(
            &[
                plane,
                Plane {
                    normal: -plane.normal,
                    offset: -plane.offset
                }
            ],
            0.0,
            &mut inside
        ));
    }
}
