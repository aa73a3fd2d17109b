//! Scene-local coordinates: the one place where the world frame of the input and the local
//! frame the solvers work in meet.
//!
//! Scenes given in real-world (UTM-like) coordinates lie 10^5-10^7 m from the origin, where
//! doubles are a few nanometres apart, as coarse as the scene's tolerance (`1e-9 × extent`).
//! Validation therefore moves every scene into a local frame near the origin before any polygon
//! is built: `local = world − origin`, and every position that leaves the library goes back
//! through [`crate::Scene::to_world`] (path points in `bt-beams`, terminals and surfaces in the
//! printers). Directions, lengths, angles and gains do not depend on the frame.
//!
//! The origin is chosen so that:
//! - a scene whose bounding-box centre lies within [`RECENTRE_RATIO`] extents of the world
//!   origin keeps origin 0 (every built-in scene: outputs byte-identical to solving in world
//!   coordinates, `to_world` is the identity);
//! - otherwise the centre is rounded to a multiple of a power of two `g ≥ extent`, so that
//!   `world − origin` is exact for every resolvable coordinate (both are multiples of the
//!   coordinate's ulp and the difference is smaller than the coordinate): the local geometry is
//!   the world geometry to the bit, and `to_world(to_local(p)) == p`.

use crate::problem::ProblemSink;
use crate::surface::Pending;
use bt_geom::{Real, Vec3, tol};

/// A scene is recentred when its bounding-box centre is more than this many extents (of at
/// least 1 m) from the world origin. At 64 extents a coordinate's ulp is below 1.5e-5 of the
/// scene's tolerance: nothing to gain below, and common scenes stay exactly as given.
pub const RECENTRE_RATIO: Real = 64.0;

/// Axis-aligned bounds of world points, metres.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Bounds {
    pub lo: Vec3,
    pub hi: Vec3,
}

impl Bounds {
    /// The bounds of the finite points among `points` (empty: lo = +inf, hi = −inf).
    pub fn of(points: impl IntoIterator<Item = Vec3>) -> Bounds {
        points.into_iter().filter(|p| p.is_finite()).fold(
            Bounds {
                lo: Vec3::INFINITY,
                hi: Vec3::NEG_INFINITY,
            },
            |b, p| Bounds {
                lo: b.lo.min(p),
                hi: b.hi.max(p),
            },
        )
    }

    /// Bounding-box diagonal, metres (0 when empty).
    pub fn extent(&self) -> Real {
        if self.lo.cmpgt(self.hi).any() {
            0.0
        } else {
            (self.hi - self.lo).length()
        }
    }

    /// The world position of the local frame's origin for a scene with these bounds (see the
    /// module documentation); zero for an empty or non-finite box.
    pub fn local_origin(&self) -> Vec3 {
        let centre = 0.5 * self.lo + 0.5 * self.hi;
        let extent = self.extent().max(1.0);
        if !(centre.is_finite() && extent.is_finite())
            || centre.abs().max_element() <= RECENTRE_RATIO * extent
        {
            return Vec3::ZERO;
        }
        let grid = extent.log2().ceil().exp2();
        (centre / grid).round() * grid
    }
}

/// Why coordinates of largest magnitude `magnitude` (m, world frame) cannot be resolved to a
/// scene tolerance of `tolerance` metres, or `None` when one ulp there is below it.
pub(crate) fn unresolvable(magnitude: Real, tolerance: Real) -> Option<String> {
    (magnitude * Real::EPSILON >= tolerance).then(|| {
        format!(
            "coordinates of magnitude {magnitude:.3e} m cannot resolve the scene's tolerance \
             {tolerance:.1e} m in double precision; move the scene nearer the origin"
        )
    })
}

/// A world point in the local frame whose origin is `origin` (world, metres).
pub(crate) fn to_local(world: Vec3, origin: Vec3) -> Vec3 {
    if origin == Vec3::ZERO {
        world
    } else {
        world - origin
    }
}

/// A local point back in the world frame (the identity, signed zeros kept, for origin 0).
pub(crate) fn to_world(local: Vec3, origin: Vec3) -> Vec3 {
    if origin == Vec3::ZERO {
        local
    } else {
        local + origin
    }
}

/// Move the raw surfaces of a scene file or mesh into the local frame before their polygons are
/// built, and return the frame's origin (world, metres). The origin is chosen from the bounds of
/// every vertex and of the terminals given (world); a surface whose coordinates are too large
/// to resolve the scene's tolerance is reported and dropped (its polygon would be a guess).
pub(crate) fn recentre(
    raw: &mut Vec<Pending>,
    terminals: [Option<Vec3>; 2],
    problems: &mut impl ProblemSink,
) -> Vec3 {
    let bounds = Bounds::of(
        raw.iter()
            .flat_map(|r| r.vertices.iter().copied())
            .chain(terminals.into_iter().flatten()),
    );
    let tolerance = scene_tolerance(bounds.extent());
    raw.retain(|r| {
        let magnitude = r
            .vertices
            .iter()
            .filter(|p| p.is_finite())
            .fold(0.0, |m: Real, p| m.max(p.abs().max_element()));
        match unresolvable(magnitude, tolerance) {
            Some(why) => {
                problems.report(&format!("{}.vertices", r.location()), why);
                false
            }
            None => true,
        }
    });
    let origin = bounds.local_origin();
    for r in raw.iter_mut() {
        for v in &mut r.vertices {
            *v = to_local(*v, origin);
        }
    }
    origin
}

/// The scene's geometric tolerance for a world bounding-box diagonal `extent`, metres.
pub(crate) fn scene_tolerance(extent: Real) -> Real {
    tol::scaled(tol::REL_GEOMETRY, extent)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn origin(lo: [Real; 3], hi: [Real; 3]) -> Vec3 {
        Bounds {
            lo: Vec3::from_array(lo),
            hi: Vec3::from_array(hi),
        }
        .local_origin()
    }

    #[test]
    fn scenes_near_the_origin_keep_their_coordinates() {
        assert_eq!(origin([0.0; 3], [6.0, 5.0, 3.0]), Vec3::ZERO);
        assert_eq!(origin([100.0, 0.0, 0.0], [110.0, 5.0, 3.0]), Vec3::ZERO);
        assert_eq!(Bounds::of([]).local_origin(), Vec3::ZERO);
    }

    #[test]
    fn far_scenes_get_a_power_of_two_grid_origin_and_exact_round_trips() {
        let o = origin([1e7, 1e7, 100.0], [1e7 + 60.0, 1e7 + 40.0, 112.0]);
        // extent 73.1 m -> grid 128 m; z centre 106 rounds to 128
        assert_eq!(o, Vec3::new(10_000_000.0, 10_000_000.0, 128.0));
        let mut seed = 0x9e37_79b9_7f4a_7c15_u64;
        for _ in 0..1000 {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let f = (seed >> 11) as Real / (1u64 << 53) as Real;
            let p = Vec3::new(1e7 + 60.0 * f, 1e7 + 40.0 * (1.0 - f), 100.0 + 12.0 * f);
            let local = p - o;
            assert_eq!(local + o, p, "round trip of {p:?}");
            assert!(local.abs().max_element() < 128.0);
        }
        let n = origin([-3e5, 2e6, -50.0], [-3e5 + 8.0, 2e6 + 6.0, -47.0]);
        assert!(
            (n - Vec3::new(-3e5 + 4.0, 2e6 + 3.0, -48.5))
                .abs()
                .max_element()
                <= 8.0
        );
    }

    #[test]
    fn one_ulp_above_the_tolerance_is_unresolvable() {
        assert!(unresolvable(1e7, 8e-9).is_none());
        assert!(
            unresolvable(1e300, 4e-9)
                .unwrap()
                .contains("nearer the origin")
        );
    }
}
