//! Convex polygons in 3-D as plain vertex lists: clipping by half-spaces, the outward-grown
//! convex hull of a [`Polygon`], and the two convexity rules of a [`Polygon`] (straight
//! corners allowed or not; both [`poly2::is_convex`]). These are the windows of the beam tree
//! (`bt_paths::beamtree`); every operation errs on the side of keeping more (conservative).

use crate::poly2::{self, StraightCorners};
use crate::{Plane, Polygon, Real, Vec2, Vec3, tol};

/// Clip the convex polygon `poly` to the half-space `{x : plane.signed_distance(x) >= -eps}`
/// (Sutherland-Hodgman), writing the result to `out` (cleared first). `eps` (m) grows the kept
/// side so that round-off never removes a point that lies on the plane; it must be far above
/// the round-off of the unfused distances used here
/// ([`Plane::signed_distance_unfused`]).
pub fn clip(poly: &[Vec3], plane: &Plane, eps: Real, out: &mut Vec<Vec3>) {
    out.clear();
    let n = poly.len();
    if n == 0 {
        return;
    }
    let mut prev = poly[n - 1];
    let mut d_prev = plane.signed_distance_unfused(prev) + eps;
    for &cur in poly {
        let d_cur = plane.signed_distance_unfused(cur) + eps;
        if d_cur >= 0.0 {
            if d_prev < 0.0 {
                out.push(crossing(prev, cur, d_prev, d_cur));
            }
            out.push(cur);
        } else if d_prev >= 0.0 {
            out.push(crossing(prev, cur, d_prev, d_cur));
        }
        prev = cur;
        d_prev = d_cur;
    }
}

/// [`clip`] in place: `poly` becomes its part in `{x : plane.signed_distance(x) >= -eps}`,
/// with `tmp` as scratch. A plane that cuts nothing (the common case for a beam's planes)
/// costs one distance per vertex and no copy; the result is the same as [`clip`]'s.
pub fn clip_in_place(poly: &mut Vec<Vec3>, plane: &Plane, eps: Real, tmp: &mut Vec<Vec3>) {
    if poly
        .iter()
        .all(|&p| plane.signed_distance_unfused(p) + eps >= 0.0)
    {
        return;
    }
    clip(poly, plane, eps, tmp);
    std::mem::swap(poly, tmp);
}

#[inline]
fn crossing(a: Vec3, b: Vec3, da: Real, db: Real) -> Vec3 {
    let t = da / (da - db);
    a + t * (b - a)
}

/// Whether every vertex of `poly` lies strictly inside `{plane.signed_distance >= margin}`.
#[inline]
pub fn all_inside(poly: &[Vec3], plane: &Plane, margin: Real) -> bool {
    poly.iter().all(|p| plane.signed_distance(*p) >= margin)
}

/// Mean of the vertices: a point inside a convex polygon, metres.
pub fn vertex_mean(poly: &[Vec3]) -> Vec3 {
    poly.iter().copied().sum::<Vec3>() / poly.len().max(1) as Real
}

/// The convex hull of `polygon` grown outward in its plane by `margin` metres (each hull edge
/// moved out by `margin`, corners mitred): a superset of every point within `margin` of the
/// polygon. Vertices counter-clockwise in the polygon's 2-D frame.
pub fn grown_hull(polygon: &Polygon, margin: Real) -> Vec<Vec3> {
    let hull = hull_2d(polygon.local_vertices());
    let n = hull.len();
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        // Neighbours without `%` (an integer division per vertex on a hot path).
        let prev = if i == 0 { n - 1 } else { i - 1 };
        let next = if i + 1 == n { 0 } else { i + 1 };
        let (a, b, c) = (hull[prev], hull[i], hull[next]);
        let n1 = outward_normal(a, b);
        let n2 = outward_normal(b, c);
        // Mitre: the point whose distance to both moved edges' lines is `margin`.
        let bisector = n1 + n2;
        let cos_half = bisector.length() * 0.5;
        let corner = if cos_half > 1e-6 {
            b + bisector.normalize() * (margin / cos_half)
        } else {
            b + n1 * margin
        };
        out.push(polygon.from_local(corner));
    }
    out
}

/// Unit normal of the directed edge `a -> b` pointing right (outward for a CCW polygon).
fn outward_normal(a: Vec2, b: Vec2) -> Vec2 {
    let d = (b - a).normalize_or_zero();
    Vec2::new(d.y, -d.x)
}

/// Convex hull (Andrew's monotone chain), counter-clockwise, collinear points dropped.
pub fn hull_2d(points: &[Vec2]) -> Vec<Vec2> {
    let mut pts: Vec<Vec2> = points.to_vec();
    pts.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    pts.dedup();
    if pts.len() < 3 {
        return pts;
    }
    let cross = |o: Vec2, a: Vec2, b: Vec2| (a - o).perp_dot(b - o);
    let mut hull: Vec<Vec2> = Vec::with_capacity(2 * pts.len());
    for pass in 0..2 {
        let start = hull.len();
        let iter: Box<dyn Iterator<Item = &Vec2>> = if pass == 0 {
            Box::new(pts.iter())
        } else {
            Box::new(pts.iter().rev())
        };
        for &p in iter {
            while hull.len() >= start + 2
                && cross(hull[hull.len() - 2], hull[hull.len() - 1], p) <= 0.0
            {
                hull.pop();
            }
            hull.push(p);
        }
        hull.pop();
    }
    hull
}

/// Whether the polygon is convex, straight corners allowed (|sine of the turn| at most
/// [`tol::SIN_STRAIGHT_CORNER`]): a polygon whose windows may be clipped as convex (the beam
/// tree). [`is_strictly_convex`] is the rule without straight corners.
pub fn is_convex(polygon: &Polygon) -> bool {
    let straight = StraightCorners::Allowed {
        sin_tol: tol::SIN_STRAIGHT_CORNER,
    };
    poly2::is_convex(polygon.local_vertices(), straight)
}

/// Whether every corner of the polygon turns the same way, exactly (no straight corner, no
/// tolerance): an occluder the weak visibility network may use in its proof
/// (`bt_paths::wvrn::occludes`). A nearly straight corner whose turn rounds the wrong way
/// makes the polygon count as non-convex, which only skips it as an occluder (the safe side).
pub fn is_strictly_convex(polygon: &Polygon) -> bool {
    polygon.is_strictly_convex()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fixtures::l_shape;

    #[test]
    fn grown_hull_contains_the_polygon_band_and_is_convex() {
        let l = l_shape();
        let hull = grown_hull(&l, 0.1);
        let hp = Polygon::new(hull.clone()).unwrap();
        assert!(is_convex(&hp));
        assert!(!is_convex(&l));
        assert!(!is_strictly_convex(&l));
        let square = Polygon::new(vec![
            Vec3::new(0., 0., 0.),
            Vec3::new(1., 0., 0.),
            Vec3::new(1., 1., 0.),
            Vec3::new(0., 1., 0.),
        ])
        .unwrap();
        assert!(is_convex(&square) && is_strictly_convex(&square));
        // every point within 0.1 of the L lies in the grown hull
        for i in 0..=40 {
            for j in 0..=40 {
                let p = Vec3::new(-0.2 + i as Real * 0.06, -0.2 + j as Real * 0.06, 0.0);
                if l.signed_boundary_distance(p) >= -0.1 {
                    assert!(hp.contains(p, 1e-12), "{p}");
                }
            }
        }
        // and nothing beyond the hull's band of 0.1 + mitres
        assert!(!hp.contains(Vec3::new(2.2, 2.2, 0.0), 0.0));
    }

    #[test]
    fn clip_keeps_the_half_and_the_band() {
        let square = vec![
            Vec3::new(0., 0., 0.),
            Vec3::new(1., 0., 0.),
            Vec3::new(1., 1., 0.),
            Vec3::new(0., 1., 0.),
        ];
        let plane = Plane::from_point_normal(Vec3::new(0.5, 0., 0.), Vec3::X);
        let mut out = Vec::new();
        clip(&square, &plane, 0.0, &mut out);
        let area = Polygon::new(out.clone()).unwrap().area();
        assert!((area - 0.5).abs() < 1e-12);
        clip(&square, &plane, 0.1, &mut out);
        assert!((Polygon::new(out.clone()).unwrap().area() - 0.6).abs() < 1e-12);
        let far = Plane::from_point_normal(Vec3::new(2., 0., 0.), Vec3::X);
        clip(&square, &far, 0.0, &mut out);
        assert!(out.is_empty());
        // In place: the same result, and no copy when nothing is cut.
        let flip_x = Plane::from_point_normal(Vec3::new(-1., 0., 0.), Vec3::X);
        for (pl, eps) in [(plane, 0.0), (plane, 0.1), (far, 0.0), (flip_x, 0.0)] {
            clip(&square, &pl, eps, &mut out);
            let mut poly = square.to_vec();
            clip_in_place(&mut poly, &pl, eps, &mut Vec::new());
            assert_eq!(poly, out);
        }
    }
}
