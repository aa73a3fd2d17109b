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

/// First pair `(i, j)`, `i < j`, of edges that come within `eps` metres of each other where a
/// polygon simple by a margin of `eps` has none: two non-adjacent edges closer than `eps` (or
/// touching), or two adjacent edges where the far end of one lies within `eps` of the other (a
/// fold back, or a corner sharper than the margin). Edge `i` runs from vertex `i` to vertex
/// `i + 1`. With `eps = 0` the non-adjacent part is [`first_crossing`]'s test. The caller
/// ensures at least three vertices and no zero-length edge (the distances assume it).
///
/// Edges are swept in the order of their smallest x, so polygons whose edges are short compared
/// with their extent (outlines of merged mesh regions, thousands of vertices) cost about
/// n log n instead of n² pairs.
pub fn first_contact(pts: &[Vec2], eps: Real) -> Option<(usize, usize)> {
    let n = pts.len();
    let ends = |i: usize| (pts[i], pts[(i + 1) % n]);
    // Whether the edges' bounding boxes, grown by `eps`, overlap; then the exact rule.
    let near = |i: usize, j: usize| {
        let ((a, b), (c, d)) = (ends(i), ends(j));
        let apart = |lo1: Real, hi1: Real, lo2: Real, hi2: Real| lo2 > hi1 + eps || lo1 > hi2 + eps;
        !apart(a.x.min(b.x), a.x.max(b.x), c.x.min(d.x), c.x.max(d.x))
            && !apart(a.y.min(b.y), a.y.max(b.y), c.y.min(d.y), c.y.max(d.y))
            && edges_in_contact(pts, (i.min(j), i.max(j)), eps)
    };
    // Most outlines are a few vertices: every pair, in order, costs less than sorting.
    if n <= 16 {
        return (0..n)
            .flat_map(|i| (i + 1..n).map(move |j| (i, j)))
            .find(|&(i, j)| near(i, j));
    }
    let low_x = |i: usize| pts[i].x.min(pts[(i + 1) % n].x);
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| low_x(a).total_cmp(&low_x(b)).then(a.cmp(&b)));
    let mut first: Option<(usize, usize)> = None;
    for (k, &i) in order.iter().enumerate() {
        let (a, b) = ends(i);
        let high_x = a.x.max(b.x) + eps;
        for &j in &order[k + 1..] {
            if low_x(j) > high_x {
                break;
            }
            let pair = (i.min(j), i.max(j));
            if first.is_none_or(|f| pair < f) && near(i, j) {
                first = Some(pair);
            }
        }
    }
    first
}

/// Whether edges `i < j` of the closed polygon `pts` are in contact by [`first_contact`]'s rule.
fn edges_in_contact(pts: &[Vec2], (i, j): (usize, usize), eps: Real) -> bool {
    let n = pts.len();
    let eps2 = eps * eps;
    let (a, b) = (pts[i], pts[(i + 1) % n]);
    let (c, d) = (pts[j], pts[(j + 1) % n]);
    if j == i + 1 {
        // b == c: the far ends are a and d.
        return segment_distance_sq(d, a, b) <= eps2 || segment_distance_sq(a, c, d) <= eps2;
    }
    if i == 0 && j == n - 1 {
        // d == a: the far ends are b and c.
        return segment_distance_sq(c, a, b) <= eps2 || segment_distance_sq(b, c, d) <= eps2;
    }
    segments_touch(a, b, c, d)
        || segment_distance_sq(a, c, d) <= eps2
        || segment_distance_sq(b, c, d) <= eps2
        || segment_distance_sq(c, a, b) <= eps2
        || segment_distance_sq(d, a, b) <= eps2
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
    fn contact_within_a_margin() {
        let sq = [v(0.0, 0.0), v(1.0, 0.0), v(1.0, 1.0), v(0.0, 1.0)];
        assert_eq!(first_contact(&sq, 0.0), None);
        assert_eq!(first_contact(&sq, 0.4), None);
        // Adjacent edges' far ends are 1 m from the other edge.
        assert_eq!(first_contact(&sq, 1.0), Some((0, 1)));
        let bow = [v(0.0, 0.0), v(1.0, 1.0), v(1.0, 0.0), v(0.0, 1.0)];
        assert_eq!(first_contact(&bow, 0.0), Some((0, 2)));
        // A notch whose tip comes 1 mm from the opposite edge: simple, but not by 1 cm.
        let notch = [
            v(0.0, 0.0),
            v(2.0, 0.0),
            v(2.0, 1.0),
            v(1.0, 1.0),
            v(1.0, 0.001),
            v(0.9, 1.0),
            v(0.0, 1.0),
        ];
        assert_eq!(first_contact(&notch, 0.0), None);
        assert_eq!(first_contact(&notch, 0.01), Some((0, 3)));
        // A T-junction: vertex 4 lies on edge 0.
        let touching = [
            v(0.0, 0.0),
            v(2.0, 0.0),
            v(2.0, 1.0),
            v(1.5, 1.0),
            v(1.0, 0.0),
            v(0.5, 1.0),
            v(0.0, 1.0),
        ];
        assert_eq!(first_contact(&touching, 0.0), first_crossing(&touching));
        assert!(first_contact(&touching, 0.0).is_some());
        // The sweep for long outlines finds what checking every pair finds: a comb of 20 teeth
        // (82 vertices) whose tips are 1 m above the base edge, then one tip 0.3 m above it,
        // then one on it.
        let brute = |pts: &[Vec2], eps: Real| {
            let n = pts.len();
            (0..n)
                .flat_map(|i| (i + 1..n).map(move |j| (i, j)))
                .find(|&pair| edges_in_contact(pts, pair, eps))
        };
        let mut comb = vec![v(0.0, 0.0), v(80.0, 0.0)];
        for t in (0..20).rev() {
            let x = 4.0 * Real::from(t);
            comb.extend([
                v(x + 4.0, 5.0),
                v(x + 3.0, 5.0),
                v(x + 2.0, 1.0),
                v(x + 1.0, 5.0),
            ]);
        }
        assert_eq!(comb.len(), 82);
        for eps in [0.0, 0.5] {
            assert_eq!(first_contact(&comb, eps), None);
        }
        comb[44].y = 0.3;
        assert_eq!(first_contact(&comb, 0.0), None);
        assert_eq!(first_contact(&comb, 0.5), Some((0, 43)));
        comb[44].y = 0.0;
        assert_eq!(first_contact(&comb, 0.0), first_crossing(&comb));
        for eps in [0.0, 0.5, 0.99, 1.5] {
            assert_eq!(first_contact(&comb, eps), brute(&comb, eps), "eps {eps}");
        }
        // A fold back: vertex 2 returns onto edge 0.
        let fold = [v(0.0, 0.0), v(2.0, 0.0), v(1.0, 0.0), v(1.0, 1.0)];
        assert_eq!(first_contact(&fold, 0.0), Some((0, 1)));
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
