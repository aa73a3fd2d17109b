//! Bounded planar polygons: the shape of every reflecting surface and blocker.
//!
//! A [`Polygon`] is validated at construction (finite, at least three distinct vertices,
//! planar, non-zero area, simple) and carries a precomputed in-plane 2-D frame so that the
//! hot inside test is a handful of multiply-adds.

use crate::plane::Plane;
use crate::poly2::{self, segment_distance_sq};
use crate::{Real, Vec2, Vec3, tol};
use serde::Serialize;
use thiserror::Error;

/// Why a vertex list is not a valid bounded planar polygon.
#[derive(Debug, Clone, PartialEq, Error, Serialize)]
pub enum PolygonError {
    /// More vertices than [`MAX_VERTICES`] (the simplicity test is quadratic).
    #[error("polygon has {0} vertices, more than the {MAX_VERTICES} a surface may have; split it")]
    TooManyVertices(usize),
    /// Doubles at the polygon's coordinates are too coarse for its size: one unit in the last
    /// place exceeds the vertex tolerance, so repeated, collinear and inside would be guesses.
    #[error(
        "coordinates of magnitude {magnitude_m:.3e} m cannot resolve a polygon of extent {extent_m:.3e} m \
         in double precision; move the scene nearer the origin"
    )]
    Unresolvable {
        /// Largest absolute coordinate, metres.
        magnitude_m: Real,
        /// The polygon's extent, metres.
        extent_m: Real,
    },
    /// Fewer than three vertices.
    #[error("polygon has {0} vertices, at least 3 are needed")]
    TooFewVertices(usize),
    /// A coordinate is NaN or infinite.
    #[error("vertex {index} has a non-finite coordinate")]
    NonFinite {
        /// Vertex index (0-based).
        index: usize,
    },
    /// Two consecutive vertices coincide (the closing vertex must not repeat the first).
    #[error("vertices {first} and {second} are repeated (same position)")]
    RepeatedVertex {
        /// Index of the first of the pair.
        first: usize,
        /// Index of the second of the pair.
        second: usize,
    },
    /// The polygon encloses (numerically) no area.
    #[error("polygon has zero area (collinear or coincident vertices)")]
    ZeroArea,
    /// A vertex lies too far from the polygon's plane.
    #[error(
        "polygon is not planar: vertex {index} is {distance_m:.3e} m off its plane (tolerance {tolerance_m:.1e} m)"
    )]
    NonPlanar {
        /// Index of the worst vertex.
        index: usize,
        /// Its distance from the best-fit plane, metres.
        distance_m: Real,
        /// The tolerance it exceeded, metres.
        tolerance_m: Real,
    },
    /// Two non-adjacent edges cross.
    #[error("polygon is self-intersecting: edges {0} and {1} cross")]
    SelfIntersecting(usize, usize),
}

/// Most vertices a polygon may have: the simplicity test compares every pair of edges, so a
/// million-vertex polygon would take minutes (a budget, `docs/reliability.md`).
pub const MAX_VERTICES: usize = 10_000;

/// Most vertex pairs the simplicity tests of one scene may compare, Σ n² over its polygons
/// (about 2 s at the 0.68 s measured for one 10,000-vertex polygon, release build): many
/// polygons just under [`MAX_VERTICES`] stop before the work instead of running for minutes
/// (a budget, `docs/reliability.md`).
pub const MAX_VERTEX_PAIRS: u64 = 300_000_000;

/// The vertex pairs the simplicity tests of polygons with `counts` vertices compare, Σ n²
/// (saturating), to hold against [`MAX_VERTEX_PAIRS`] before building them.
pub fn vertex_pairs(counts: impl IntoIterator<Item = usize>) -> u64 {
    counts.into_iter().fold(0u64, |sum, n| {
        sum.saturating_add((n as u64).saturating_mul(n as u64))
    })
}

/// A validated simple planar polygon in 3-D.
///
/// The normal follows the right-hand rule of the vertex order (counter-clockwise seen from the
/// side the normal points to). Surfaces reflect from both sides, so the orientation only fixes
/// the sign convention of [`Plane::signed_distance`].
#[derive(Debug, Clone, PartialEq)]
pub struct Polygon {
    vertices: Vec<Vec3>,
    plane: Plane,
    origin: Vec3,
    u: Vec3,
    v: Vec3,
    local: Vec<Vec2>,
    /// Bounding box of `local`: the inside test rejects points beyond it (plus the tolerance)
    /// before looking at any edge.
    local_min: Vec2,
    local_max: Vec2,
    /// For a strictly convex polygon, each edge's line in the 2-D frame as (inward unit
    /// normal, offset): `normal · q − offset` is `q`'s distance inside that edge's line, m.
    /// Empty otherwise.
    convex_lines: Vec<(Vec2, Real)>,
    area: Real,
    centroid: Vec3,
    extent: Real,
    min: Vec3,
    max: Vec3,
}

impl Polygon {
    /// Validate `vertices` (metres, world frame) and build the polygon.
    pub fn new(vertices: Vec<Vec3>) -> Result<Self, PolygonError> {
        let n = vertices.len();
        if n < 3 {
            return Err(PolygonError::TooFewVertices(n));
        }
        if n > MAX_VERTICES {
            return Err(PolygonError::TooManyVertices(n));
        }
        if let Some(index) = vertices.iter().position(|p| !p.is_finite()) {
            return Err(PolygonError::NonFinite { index });
        }
        let (min, max) = bounds(&vertices);
        let extent = (max - min).length();
        let merge = tol::scaled(tol::REL_VERTEX_MERGE, extent);
        let magnitude = min.abs().max(max.abs()).max_element();
        if magnitude * Real::EPSILON >= merge {
            return Err(PolygonError::Unresolvable {
                magnitude_m: magnitude,
                extent_m: extent,
            });
        }
        for i in 0..n {
            let j = (i + 1) % n;
            if vertices[i].distance(vertices[j]) <= merge {
                let (first, second) = if j == 0 { (0, i) } else { (i, j) };
                return Err(PolygonError::RepeatedVertex { first, second });
            }
        }
        // Newell's method: robust normal and twice the area vector for any simple polygon.
        let c0 = vertices.iter().copied().sum::<Vec3>() / n as Real;
        let newell = poly2::newell(&vertices);
        let area = 0.5 * newell.length();
        if area <= tol::REL_AREA * extent * extent || !area.is_normal() {
            return Err(PolygonError::ZeroArea);
        }
        let normal = newell / (2.0 * area);
        let plane = Plane {
            normal,
            offset: normal.dot(c0),
        };
        let planarity = tol::REL_PLANARITY * extent;
        let (index, distance_m) = vertices
            .iter()
            .enumerate()
            .map(|(i, p)| (i, plane.signed_distance(*p).abs()))
            .fold(
                (0, 0.0),
                |best, cur| if cur.1 > best.1 { cur } else { best },
            );
        if distance_m > planarity {
            return Err(PolygonError::NonPlanar {
                index,
                distance_m,
                tolerance_m: planarity,
            });
        }
        let (u, v) = normal.any_orthonormal_pair();
        let origin = plane.project(c0);
        let local: Vec<Vec2> = vertices
            .iter()
            .map(|p| {
                let d = *p - origin;
                Vec2::new(d.dot(u), d.dot(v))
            })
            .collect();
        if let Some((i, j)) = poly2::first_crossing(&local) {
            return Err(PolygonError::SelfIntersecting(i, j));
        }
        let centroid = area_centroid(&local, origin, u, v);
        let (local_min, local_max) = local
            .iter()
            .fold((Vec2::INFINITY, Vec2::NEG_INFINITY), |(lo, hi), p| {
                (lo.min(*p), hi.max(*p))
            });
        let convex_lines = inward_lines(&local);
        Ok(Self {
            vertices,
            plane,
            origin,
            u,
            v,
            local,
            local_min,
            local_max,
            convex_lines,
            area,
            centroid,
            extent,
            min,
            max,
        })
    }

    /// Vertices in the order given, metres.
    pub fn vertices(&self) -> &[Vec3] {
        &self.vertices
    }

    /// Supporting plane; its normal follows the vertex order (right-hand rule).
    pub fn plane(&self) -> &Plane {
        &self.plane
    }

    /// Area, square metres.
    pub fn area(&self) -> Real {
        self.area
    }

    /// Area centroid (lies in the plane, not necessarily inside a concave polygon), metres.
    pub fn centroid(&self) -> Vec3 {
        self.centroid
    }

    /// Length of the bounding-box diagonal, metres.
    pub fn extent(&self) -> Real {
        self.extent
    }

    /// Axis-aligned bounding box `(min, max)`, metres.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        (self.min, self.max)
    }

    /// Coordinates of `p` (assumed on or near the plane) in the polygon's 2-D frame.
    #[inline]
    pub fn to_local(&self, p: Vec3) -> Vec2 {
        let d = p - self.origin;
        Vec2::new(d.dot(self.u), d.dot(self.v))
    }

    /// The world point of in-plane coordinates `q` (inverse of [`Polygon::to_local`] on the plane).
    #[inline]
    pub fn from_local(&self, q: Vec2) -> Vec3 {
        self.origin + q.x * self.u + q.y * self.v
    }

    /// Vertices in the in-plane 2-D frame of [`Polygon::to_local`], metres.
    pub fn local_vertices(&self) -> &[Vec2] {
        &self.local
    }

    /// Signed distance (m) of the projection of `p` from the polygon boundary, measured in the
    /// plane: positive inside, negative outside, zero on an edge.
    pub fn signed_boundary_distance(&self, p: Vec3) -> Real {
        let q = self.to_local(p);
        let n = self.local.len();
        let best = (0..n)
            .map(|i| segment_distance_sq(q, self.local[(i + n - 1) % n], self.local[i]))
            .fold(Real::INFINITY, Real::min);
        let inside = poly2::contains(&self.local, q);
        let d = best.sqrt();
        if inside { d } else { -d }
    }

    /// Whether the projection of `p` onto the plane lies inside the polygon or within `tol`
    /// metres of its boundary (inclusive test, used for interaction points).
    /// Same answer as `signed_boundary_distance(p) >= -tol`, without square roots, without any
    /// distance computation for points strictly inside, and without looking at the edges for
    /// points beyond the polygon's 2-D bounding box grown by `tol` (most rejected paths).
    #[inline]
    pub fn contains(&self, p: Vec3, tol: Real) -> bool {
        let q = self.to_local(p);
        if q.x < self.local_min.x - tol
            || q.x > self.local_max.x + tol
            || q.y < self.local_min.y - tol
            || q.y > self.local_max.y + tol
        {
            return false;
        }
        poly2::contains(&self.local, q) || self.near_boundary(q, tol)
    }

    /// Whether the projection of `p` onto the plane lies inside the polygon by more than
    /// `margin` metres (`margin >= 0`): `signed_boundary_distance(p) > margin` up to rounding,
    /// without square roots, and without looking at the edges for points within `margin` of
    /// the polygon's 2-D bounding box (a ray from such a point to the box meets the boundary
    /// within `margin`). A strictly convex polygon asks its edges' lines alone: inside it, the
    /// distance to the boundary is the least distance to an edge's line.
    #[inline]
    pub fn inside_by(&self, p: Vec3, margin: Real) -> bool {
        let q = self.to_local(p);
        if !self.convex_lines.is_empty() {
            return (self.convex_lines.iter())
                .all(|&(normal, offset)| normal.dot(q) - offset > margin);
        }
        self.inside_by_edges(q, margin)
    }

    /// Whether every corner turns the same way, exactly (no straight corner): decided once,
    /// when the polygon is built ([`crate::convex::is_strictly_convex`] asks here).
    pub(crate) fn is_strictly_convex(&self) -> bool {
        !self.convex_lines.is_empty()
    }

    /// [`Polygon::inside_by`] for the in-plane point `q`, by the bounding box, the crossing
    /// number and the edges' segments (any simple polygon).
    #[inline]
    fn inside_by_edges(&self, q: Vec2, margin: Real) -> bool {
        if q.x - self.local_min.x <= margin
            || self.local_max.x - q.x <= margin
            || q.y - self.local_min.y <= margin
            || self.local_max.y - q.y <= margin
            || !poly2::contains(&self.local, q)
        {
            return false;
        }
        !self.near_boundary(q, margin)
    }

    /// Whether the in-plane point `q` lies within `dist` metres of an edge (squared distances,
    /// no square root).
    #[inline]
    fn near_boundary(&self, q: Vec2, dist: Real) -> bool {
        let dist2 = dist * dist;
        let n = self.local.len();
        let mut j = n - 1;
        (0..n).any(|i| {
            let near = segment_distance_sq(q, self.local[j], self.local[i]) <= dist2;
            j = i;
            near
        })
    }

    /// Whether the open segment `a -> b` passes through the polygon: it crosses the plane at a
    /// parameter `t` in `[t_min, 1 - t_min]` at a point inside the polygon or within `tol` of
    /// its boundary (grazing an edge counts as blocked: the conservative choice for occlusion).
    #[inline(always)]
    pub fn blocks_segment(&self, a: Vec3, b: Vec3, t_min: Real, tol: Real) -> bool {
        let da = self.plane.signed_distance(a);
        let db = self.plane.signed_distance(b);
        if (da > tol && db > tol) || (da < -tol && db < -tol) {
            return false;
        }
        match Plane::crossing_parameter(da, db, a, b) {
            Some(t) if t >= t_min && t <= 1.0 - t_min => self.contains(a + t * (b - a), tol),
            _ => false,
        }
    }

    /// Whether `other` lies in this polygon's plane (every vertex within `tol` of it) and the
    /// two interiors share a region of positive area: some point lies inside both by more
    /// than `tol`. Witnesses, each checked in both polygons: a proper crossing of two edges, a
    /// vertex of one strictly inside the other, and each edge's midpoint moved `4·tol` into
    /// its own polygon (identical, nested, shifted and crossing polygons). No false positive:
    /// every witness is a point inside both.
    pub fn overlaps_coplanar(&self, other: &Polygon, tol: Real) -> bool {
        if other
            .vertices
            .iter()
            .any(|p| self.plane.signed_distance(*p).abs() > tol)
        {
            return false;
        }
        let (a, b) = (self, other);
        let crossing = a.edges().any(|(p, q)| {
            b.edges().any(|(r, s)| {
                let (p2, q2, r2, s2) = (a.to_local(p), a.to_local(q), a.to_local(r), a.to_local(s));
                poly2::segments_touch(p2, q2, r2, s2)
                    && [r, s].iter().all(|x| !a.contains(*x, tol))
                    && [p, q].iter().all(|x| !b.contains(*x, tol))
            })
        });
        crossing || a.witness_inside(b, tol) || b.witness_inside(a, tol)
    }

    /// Whether `other` is this polygon again: as many vertices, each within `tol` (metres) of
    /// one of this polygon's and the other way round (any start, either winding), and the
    /// interiors overlapping ([`Polygon::overlaps_coplanar`]).
    pub fn coincides(&self, other: &Polygon, tol: Real) -> bool {
        let near = |p: &Vec3, all: &[Vec3]| all.iter().any(|q| q.distance(*p) <= tol);
        self.vertices.len() == other.vertices.len()
            && self.vertices.iter().all(|p| near(p, &other.vertices))
            && other.vertices.iter().all(|p| near(p, &self.vertices))
            && self.overlaps_coplanar(other, tol)
    }

    /// Whether a vertex of this polygon, or one of its edges' midpoints moved `4·tol` inwards,
    /// lies inside both this polygon and `other` by more than `tol`.
    fn witness_inside(&self, other: &Polygon, tol: Real) -> bool {
        let ccw = poly2::signed_area(&self.local) > 0.0;
        let inward = |p: Vec3, q: Vec3| {
            let d = (self.to_local(q) - self.to_local(p)).normalize_or_zero();
            let left = Vec2::new(-d.y, d.x);
            self.from_local(
                self.to_local(0.5 * (p + q)) + 4.0 * tol * if ccw { left } else { -left },
            )
        };
        self.vertices.iter().any(|p| other.inside_by(*p, tol))
            || self
                .edges()
                .map(|(p, q)| inward(p, q))
                .any(|m| self.inside_by(m, tol) && other.inside_by(m, tol))
    }

    /// The edges `(vertex i, vertex i + 1)`, closing the loop.
    fn edges(&self) -> impl Iterator<Item = (Vec3, Vec3)> + '_ {
        let n = self.vertices.len();
        (0..n).map(move |i| (self.vertices[i], self.vertices[(i + 1) % n]))
    }
}

/// The edges' lines of the 2-D polygon `local` as (inward unit normal, offset) when it is
/// strictly convex ([`poly2::is_convex`] without straight corners: the one test of
/// [`crate::convex::is_strictly_convex`]), else none.
fn inward_lines(local: &[Vec2]) -> Vec<(Vec2, Real)> {
    if !poly2::is_convex(local, poly2::StraightCorners::Refused) {
        return Vec::new();
    }
    // Counter-clockwise vertices have the interior on each edge's left.
    let left = if poly2::signed_area(local) > 0.0 {
        1.0
    } else {
        -1.0
    };
    let n = local.len();
    (0..n)
        .map(|i| {
            let (a, b) = (local[i], local[(i + 1) % n]);
            let normal = left * (b - a).perp().normalize();
            (normal, normal.dot(a))
        })
        .collect()
}

/// The axis-aligned box `(min, max)` of `points` (metres), exactly as [`Polygon::bounds`]
/// gives it for a polygon of these vertices (empty: `(+inf, -inf)`): callers may index
/// vertices before their polygon is built, and get the same bits.
pub fn bounds(points: &[Vec3]) -> (Vec3, Vec3) {
    points
        .iter()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(*p), hi.max(*p))
        })
}

fn area_centroid(local: &[Vec2], origin: Vec3, u: Vec3, v: Vec3) -> Vec3 {
    let n = local.len();
    let (mut a2, mut cx, mut cy) = (0.0, 0.0, 0.0);
    for i in 0..n {
        let p = local[i];
        let q = local[(i + 1) % n];
        let cross = p.perp_dot(q);
        a2 += cross;
        cx += (p.x + q.x) * cross;
        cy += (p.y + q.y) * cross;
    }
    let c = Vec2::new(cx, cy) / (3.0 * a2);
    origin + c.x * u + c.y * v
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Axis-aligned rectangle `x0..x1 × y0..y1` at height `z`, turned clockwise when `cw`.
    fn rect(x0: Real, y0: Real, x1: Real, y1: Real, z: Real, cw: bool) -> Polygon {
        let mut v = vec![
            Vec3::new(x0, y0, z),
            Vec3::new(x1, y0, z),
            Vec3::new(x1, y1, z),
            Vec3::new(x0, y1, z),
        ];
        if cw {
            v.reverse();
        }
        Polygon::new(v).unwrap()
    }

    #[test]
    fn coplanar_overlap_is_found_whatever_its_shape() {
        let tol = 1e-9;
        let base = rect(0., 0., 2., 2., 0., false);
        let overlapping = [
            ("identical", rect(0., 0., 2., 2., 0., false)),
            (
                "identical, turned the other way",
                rect(0., 0., 2., 2., 0., true),
            ),
            ("shifted by half", rect(1., 0., 3., 2., 0., false)),
            ("nested", rect(0.5, 0.5, 1.5, 1.5, 0., true)),
            ("nested on a shared edge", rect(0., 0., 1., 2., 0., false)),
            ("crossing like a plus", rect(0.5, -1., 1.5, 3., 0., false)),
        ];
        for (what, other) in &overlapping {
            assert!(base.overlaps_coplanar(other, tol), "{what}");
            assert!(other.overlaps_coplanar(&base, tol), "{what}, swapped");
        }
        let apart = [
            ("sharing an edge", rect(2., 0., 4., 2., 0., false)),
            ("sharing a corner", rect(2., 2., 4., 4., 0., true)),
            ("beside it", rect(3., 0., 4., 2., 0., false)),
            ("parallel, 1 m above", rect(0., 0., 2., 2., 1., false)),
            (
                "within a tolerance of the edge",
                rect(2. - 0.5 * tol, 0., 4., 2., 0., false),
            ),
        ];
        for (what, other) in &apart {
            assert!(!base.overlaps_coplanar(other, tol), "{what}");
            assert!(!other.overlaps_coplanar(&base, tol), "{what}, swapped");
        }
        // A square in the notch of an L touches it along two edges only.
        let l = Polygon::new(
            [[0., 0.], [2., 0.], [2., 1.], [1., 1.], [1., 2.], [0., 2.]]
                .map(|[x, y]| Vec3::new(x, y, 0.))
                .to_vec(),
        )
        .unwrap();
        let notch = rect(1., 1., 2., 2., 0., false);
        assert!(!l.overlaps_coplanar(&notch, tol) && !notch.overlaps_coplanar(&l, tol));
        assert!(l.overlaps_coplanar(&rect(0.5, 0.5, 1.5, 1.5, 0., false), tol));
        // The same polygon again, whatever its winding: only the first two.
        let same: Vec<bool> = overlapping
            .iter()
            .map(|(_, o)| base.coincides(o, tol))
            .collect();
        assert_eq!(same, [true, true, false, false, false, false]);
        assert!(!base.coincides(&rect(0., 0., 2., 2., 1., false), tol));
    }

    fn square(z: Real) -> Vec<Vec3> {
        vec![
            Vec3::new(0., 0., z),
            Vec3::new(2., 0., z),
            Vec3::new(2., 2., z),
            Vec3::new(0., 2., z),
        ]
    }

    #[test]
    fn square_area_normal_centroid() {
        let p = Polygon::new(square(1.0)).unwrap();
        assert!((p.area() - 4.0).abs() < 1e-12);
        assert!((p.plane().normal - Vec3::Z).length() < 1e-12);
        assert!((p.centroid() - Vec3::new(1., 1., 1.)).length() < 1e-12);
        assert!(p.contains(Vec3::new(1.0, 1.0, 5.0), 1e-9));
        assert!(p.contains(Vec3::new(2.0, 1.0, 1.0), 1e-9));
        assert!(!p.contains(Vec3::new(2.1, 1.0, 1.0), 1e-9));
        assert!((p.signed_boundary_distance(Vec3::new(0.5, 1.0, 1.0)) - 0.5).abs() < 1e-12);
    }

    #[test]
    fn concave_polygon_inside_test() {
        // An L: the notch at (1.5, 1.5) is outside.
        let l = crate::fixtures::l_shape();
        assert!((l.area() - 3.0).abs() < 1e-12);
        assert!(l.contains(Vec3::new(0.5, 1.5, 0.), 1e-9));
        assert!(!l.contains(Vec3::new(1.5, 1.5, 0.), 1e-9));
    }

    #[test]
    fn inside_by_agrees_with_the_boundary_distance() {
        // An L (concave) in a tilted plane, points on a grid around it, several margins.
        let l = [(0., 0.), (3., 0.), (3., 1.), (1., 1.), (1., 2.5), (0., 2.5)];
        let tilt = |x: Real, y: Real| Vec3::new(x, y * 0.6, y * 0.8);
        let p = Polygon::new(l.iter().map(|&(x, y)| tilt(x, y)).collect()).unwrap();
        let mut checked = 0;
        for i in -10..=80 {
            for j in -10..=70 {
                let q = tilt(i as Real * 0.05, j as Real * 0.05) + 0.3 * p.plane().normal;
                let d = p.signed_boundary_distance(q);
                for margin in [0.0, 0.01, 0.1, 0.3, 0.55] {
                    if (d - margin).abs() > 1e-9 {
                        assert_eq!(p.inside_by(q, margin), d > margin, "{q} {margin} {d}");
                        checked += 1;
                    }
                }
            }
        }
        assert!(checked > 30_000);
    }

    #[test]
    fn invalid_polygons_are_reported() {
        assert_eq!(
            Polygon::new(square(0.0)[..2].to_vec()),
            Err(PolygonError::TooFewVertices(2))
        );
        let mut nan = square(0.0);
        nan[2].y = Real::NAN;
        assert_eq!(Polygon::new(nan), Err(PolygonError::NonFinite { index: 2 }));
        let mut rep = square(0.0);
        rep.push(rep[0]);
        assert_eq!(
            Polygon::new(rep),
            Err(PolygonError::RepeatedVertex {
                first: 0,
                second: 4
            })
        );
        let line = vec![Vec3::ZERO, Vec3::X, Vec3::new(2., 0., 0.)];
        assert_eq!(Polygon::new(line), Err(PolygonError::ZeroArea));
        let mut bent = square(0.0);
        bent[2].z = 0.1;
        assert!(matches!(
            Polygon::new(bent),
            Err(PolygonError::NonPlanar { .. })
        ));
        let bow = vec![
            Vec3::new(0., 0., 0.),
            Vec3::new(4., 0., 0.),
            Vec3::new(4., 2., 0.),
            Vec3::new(1., -1., 0.),
        ];
        assert!(matches!(
            Polygon::new(bow),
            Err(PolygonError::SelfIntersecting(..))
        ));
    }

    #[test]
    fn segment_blocking() {
        let p = Polygon::new(square(1.0)).unwrap();
        let tol = 1e-9;
        assert!(p.blocks_segment(Vec3::new(1., 1., 0.), Vec3::new(1., 1., 2.), 1e-9, tol));
        assert!(!p.blocks_segment(Vec3::new(3., 1., 0.), Vec3::new(3., 1., 2.), 1e-9, tol));
        assert!(!p.blocks_segment(Vec3::new(1., 1., 0.), Vec3::new(1., 1., 0.5), 1e-9, tol));
        // A segment ending on the polygon does not count as crossing it.
        assert!(!p.blocks_segment(Vec3::new(1., 1., 0.), Vec3::new(1., 1., 1.), 1e-9, tol));
    }
}

#[cfg(test)]
mod contains_props {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig { rng_seed: proptest::test_runner::RngSeed::Fixed(7), ..ProptestConfig::default() })]
        /// The fast inside test agrees with the signed boundary distance everywhere.
        #[test]
        fn contains_matches_signed_distance(x in -0.5f64..2.5, y in -0.5f64..2.5, tol in prop_oneof![Just(0.0), Just(1e-9), Just(0.1)]) {
            let l = Polygon::new(vec![
                Vec3::new(0., 0., 0.), Vec3::new(2., 0., 0.), Vec3::new(2., 1., 0.),
                Vec3::new(1., 1., 0.), Vec3::new(1., 2., 0.), Vec3::new(0., 2., 0.),
            ]).unwrap();
            let p = Vec3::new(x, y, 0.3);
            prop_assert_eq!(l.contains(p, tol), l.signed_boundary_distance(p) >= -tol);
        }

        /// On convex polygons (tilted, either winding) the inside test by the edges' lines
        /// gives the general test's answer, and both the signed boundary distance's, except
        /// within round-off of the margin.
        #[test]
        fn convex_inside_by_matches_the_edges(
            sides in 3usize..9,
            turn in 0.0f64..6.3,
            clockwise: bool,
            tilt in -1.5f64..1.5,
            (x, y) in (-1.5f64..1.5, -1.5f64..1.5),
            margin in prop_oneof![Just(0.0), Just(1e-9), Just(0.05), 0.0f64..0.6],
        ) {
            let mut ring: Vec<Vec3> = (0..sides)
                .map(|k| {
                    let a = turn + k as Real * std::f64::consts::TAU / sides as Real;
                    let (u, v) = (a.cos() * (1.0 + 0.1 * k as Real), a.sin());
                    Vec3::new(u, v * tilt.cos(), v * tilt.sin() + 3.0)
                })
                .collect();
            if clockwise {
                ring.reverse();
            }
            let Ok(polygon) = Polygon::new(ring) else { return Ok(()) };
            prop_assume!(polygon.is_strictly_convex());
            let p = Vec3::new(x, y * tilt.cos(), y * tilt.sin() + 3.0);
            let distance = polygon.signed_boundary_distance(p);
            prop_assume!((distance - margin).abs() > 1e-12);
            let general = polygon.inside_by_edges(polygon.to_local(p), margin);
            prop_assert_eq!(polygon.inside_by(p, margin), general);
            prop_assert_eq!(general, distance > margin);
        }
    }
}
