//! Polygon primitives on plain vertex lists: signed area, even-odd point-in-polygon, segment
//! contact, simplicity, convexity, and the Newell area vector of a 3-D polygon.
//!
//! The one home of these predicates for every crate (the validated [`Polygon`](crate::Polygon),
//! mesh merging, point-cloud boundaries, the study's room generator). Polygons are closed
//! implicitly (the last vertex joins the first); 2-D coordinates are metres in whatever in-plane
//! frame the caller uses. All tests are exact on the given floats: no tolerance is applied here,
//! callers that want one apply it around these calls (or pass it, as [`is_convex`] takes it).

use crate::{Real, Vec2, Vec3};

/// Signed area (m², positive for counter-clockwise vertices) by the shoelace formula, summed as
/// a fan from the first vertex to avoid cancellation far from the origin. Zero below three
/// vertices.
pub fn signed_area(pts: &[Vec2]) -> Real {
    let n = pts.len();
    if n < 3 {
        return 0.0;
    }
    let p0 = pts[0];
    let mut sum = 0.0;
    for i in 1..n - 1 {
        sum += (pts[i] - p0).perp_dot(pts[i + 1] - p0);
    }
    0.5 * sum
}

/// Whether `p` lies inside the polygon by the even-odd (crossing number) rule. Points exactly on
/// the boundary may fall either way; callers needing an inclusive test add a distance check
/// (see [`segment_distance_sq`]).
#[inline]
pub fn contains(pts: &[Vec2], p: Vec2) -> bool {
    let n = pts.len();
    if n == 0 {
        return false;
    }
    let mut inside = false;
    let mut j = n - 1;
    for i in 0..n {
        let (a, b) = (pts[j], pts[i]);
        if (b.y > p.y) != (a.y > p.y) && p.x < b.x + (p.y - b.y) * (a.x - b.x) / (a.y - b.y) {
            inside = !inside;
        }
        j = i;
    }
    inside
}

/// Squared distance (m²) from `q` to the closed segment `a-b` (`a != b`).
#[inline]
pub fn segment_distance_sq(q: Vec2, a: Vec2, b: Vec2) -> Real {
    let ab = b - a;
    let t = ((q - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0);
    (a + t * ab - q).length_squared()
}

/// Whether the closed segments `a-b` and `c-d` share a point (proper crossing, or an endpoint
/// exactly on the other segment).
pub fn segments_touch(a: Vec2, b: Vec2, c: Vec2, d: Vec2) -> bool {
    let o1 = (b - a).perp_dot(c - a);
    let o2 = (b - a).perp_dot(d - a);
    let o3 = (d - c).perp_dot(a - c);
    let o4 = (d - c).perp_dot(b - c);
    // Sign comparisons rather than products: a product of two tiny orientations can underflow.
    let opposite = |x: Real, y: Real| (x > 0.0 && y < 0.0) || (x < 0.0 && y > 0.0);
    if opposite(o1, o2) && opposite(o3, o4) {
        return true;
    }
    let on = |p: Vec2, q: Vec2, r: Vec2| {
        r.x >= p.x.min(q.x) && r.x <= p.x.max(q.x) && r.y >= p.y.min(q.y) && r.y <= p.y.max(q.y)
    };
    (o1 == 0.0 && on(a, b, c))
        || (o2 == 0.0 && on(a, b, d))
        || (o3 == 0.0 && on(c, d, a))
        || (o4 == 0.0 && on(c, d, b))
}

/// First pair `(i, j)`, `i < j`, of non-adjacent edges that touch, where edge `i` runs from
/// vertex `i` to vertex `i + 1` (O(n²): polygons here are small).
pub fn first_crossing(pts: &[Vec2]) -> Option<(usize, usize)> {
    let n = pts.len();
    for i in 0..n {
        let (a, b) = (pts[i], pts[(i + 1) % n]);
        for j in i + 1..n {
            if j == i + 1 || (i == 0 && j == n - 1) {
                continue;
            }
            let (c, d) = (pts[j], pts[(j + 1) % n]);
            if segments_touch(a, b, c, d) {
                return Some((i, j));
            }
        }
    }
    None
}

/// Whether the closed polygon is simple: at least three finite vertices, no zero-length edge, no
/// two non-adjacent edges touching, and no two consecutive edges folding back onto each other.
pub fn is_simple(pts: &[Vec2]) -> bool {
    let n = pts.len();
    if n < 3 || pts.iter().any(|p| !p.is_finite()) {
        return false;
    }
    if (0..n).any(|i| pts[i] == pts[(i + 1) % n]) {
        return false;
    }
    let folds = (0..n).any(|i| {
        let (a, b, c) = (pts[(i + n - 1) % n], pts[i], pts[(i + 1) % n]);
        (b - a).perp_dot(c - b) == 0.0 && (b - a).dot(c - b) < 0.0
    });
    !folds && first_crossing(pts).is_none()
}

/// What [`is_convex`] makes of a straight corner: a vertex where the boundary goes on without
/// turning (its two edges collinear).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum StraightCorners {
    /// Skipped: a corner counts as straight when the |sine| of its turn is at most `sin_tol`,
    /// so a vertex in the middle of an edge keeps a polygon convex.
    Allowed {
        /// Largest |sine| of the turn angle of a straight corner (dimensionless).
        sin_tol: Real,
    },
    /// Refused, with no tolerance: an exactly straight corner makes the polygon non-convex, and
    /// so does a nearly straight one whose turn rounds the wrong way. The safe side for a caller
    /// whose proof needs every corner to turn the same way.
    Refused,
}

/// Whether the closed polygon is convex: at least three vertices and no two corners turning
/// opposite ways (counter-clockwise or clockwise alike); straight corners as `straight` says.
pub fn is_convex(pts: &[Vec2], straight: StraightCorners) -> bool {
    let n = pts.len();
    if n < 3 {
        return false;
    }
    let (mut left, mut right) = (false, false);
    for i in 0..n {
        let (a, b, c) = (pts[i], pts[(i + 1) % n], pts[(i + 2) % n]);
        let turn = (b - a).perp_dot(c - b);
        match straight {
            StraightCorners::Allowed { sin_tol } => {
                if turn.abs() <= sin_tol * (b - a).length() * (c - b).length() {
                    continue;
                }
            }
            StraightCorners::Refused => {
                if turn == 0.0 {
                    return false;
                }
            }
        }
        left |= turn > 0.0;
        right |= turn < 0.0;
    }
    !(left && right)
}

/// Newell's area vector of a closed 3-D polygon: its direction is the normal (right-hand rule on
/// the vertex order), its length twice the area (m²). Summed about the vertex mean, so it is
/// robust for any simple polygon, planar or nearly so, far from the origin. Zero below three
/// vertices.
pub fn newell(points: &[Vec3]) -> Vec3 {
    let n = points.len();
    if n < 3 {
        return Vec3::ZERO;
    }
    let c0 = points.iter().copied().sum::<Vec3>() / n as Real;
    let mut sum = Vec3::ZERO;
    for i in 0..n {
        sum += (points[i] - c0).cross(points[(i + 1) % n] - c0);
    }
    sum
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(x: Real, y: Real) -> Vec2 {
        Vec2::new(x, y)
    }

    #[test]
    fn convexity_and_straight_corners() {
        let square = [v(0., 0.), v(1., 0.), v(1., 1.), v(0., 1.)];
        let with_midpoint = [v(0., 0.), v(0.5, 0.), v(1., 0.), v(1., 1.), v(0., 1.)];
        let l = [
            v(0., 0.),
            v(2., 0.),
            v(2., 1.),
            v(1., 1.),
            v(1., 2.),
            v(0., 2.),
        ];
        let allowed = StraightCorners::Allowed { sin_tol: 1e-12 };
        for straight in [allowed, StraightCorners::Refused] {
            assert!(is_convex(&square, straight));
            let clockwise: Vec<Vec2> = square.iter().rev().copied().collect();
            assert!(is_convex(&clockwise, straight));
            assert!(!is_convex(&l, straight));
            assert!(!is_convex(&square[..2], straight));
        }
        assert!(is_convex(&with_midpoint, allowed));
        assert!(!is_convex(&with_midpoint, StraightCorners::Refused));
    }

    #[test]
    fn area_orientation_and_containment() {
        let sq = [v(0.0, 0.0), v(2.0, 0.0), v(2.0, 2.0), v(0.0, 2.0)];
        assert_eq!(signed_area(&sq), 4.0);
        let mut cw = sq;
        cw.reverse();
        assert_eq!(signed_area(&cw), -4.0);
        assert!(contains(&sq, v(1.0, 1.0)));
        assert!(!contains(&sq, v(3.0, 1.0)));
        assert!(!contains(&[], v(0.0, 0.0)));
        assert_eq!(
            segment_distance_sq(v(1.0, 3.0), v(0.0, 2.0), v(2.0, 2.0)),
            1.0
        );
    }

    #[test]
    fn simplicity() {
        let sq = [v(0.0, 0.0), v(1.0, 0.0), v(1.0, 1.0), v(0.0, 1.0)];
        assert!(is_simple(&sq));
        let bow = [v(0.0, 0.0), v(1.0, 1.0), v(1.0, 0.0), v(0.0, 1.0)];
        assert!(!is_simple(&bow));
        assert_eq!(first_crossing(&bow), Some((0, 2)));
        let fold = [v(0.0, 0.0), v(2.0, 0.0), v(1.0, 0.0), v(1.0, 1.0)];
        assert!(!is_simple(&fold));
        let repeated = [v(0.0, 0.0), v(1.0, 0.0), v(1.0, 0.0), v(0.0, 1.0)];
        assert!(!is_simple(&repeated));
        let nan = [v(0.0, 0.0), v(Real::NAN, 0.0), v(0.0, 1.0)];
        assert!(!is_simple(&nan));
    }

    #[test]
    fn newell_is_twice_the_area_vector() {
        let sq = [
            [5.0, 5.0, 7.0],
            [6.0, 5.0, 7.0],
            [6.0, 6.0, 7.0],
            [5.0, 6.0, 7.0],
        ]
        .map(Vec3::from);
        assert_eq!(newell(&sq), Vec3::new(0.0, 0.0, 2.0));
        assert_eq!(newell(&sq[..2]), Vec3::ZERO);
    }
}
