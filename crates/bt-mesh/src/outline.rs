//! A group's plane and the outlines drawn in it: the 2-D polygons that become surfaces.
//!
//! Both ways of outlining a group (tracing its whole boundary, [`crate::trace`], or splitting it
//! into pieces, [`crate::split`]) end here: [`outline`] cleans a loop of projected points and
//! accepts it only as a polygon the scene will take, simple by a margin; [`area_matches`]
//! checks that outlines hold exactly the area of the faces they stand for.

use bt_geom::poly2::{first_contact, signed_area};
use bt_geom::polygon::MAX_VERTICES;
use bt_geom::{Real, Vec2, Vec3};

use crate::merge::Faces;
use crate::tol;

/// A group's plane: the area-weighted normal and centroid of its faces, and an in-plane frame.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Frame {
    /// Unit normal.
    pub normal: Vec3,
    /// A point on the plane, metres.
    pub origin: Vec3,
    /// In-plane unit axes, `u × v = normal`.
    pub u: Vec3,
    pub v: Vec3,
}

impl Frame {
    /// The plane of the faces `members` (indices into `faces`, at least one).
    pub fn of_faces(faces: &Faces, members: &[usize]) -> Frame {
        let mut normal_sum = Vec3::ZERO;
        let mut centroid_sum = Vec3::ZERO;
        let mut area_sum = 0.0;
        for &f in members {
            normal_sum += faces[f].normal * faces[f].area;
            centroid_sum += faces[f].centroid * faces[f].area;
            area_sum += faces[f].area;
        }
        let normal = normal_sum.normalize();
        let u = normal.any_orthonormal_vector();
        Frame {
            normal,
            origin: centroid_sum / area_sum,
            u,
            v: normal.cross(u),
        }
    }

    /// In-plane coordinates (metres) of `p`'s projection onto the plane.
    pub fn project(&self, p: Vec3) -> Vec2 {
        let d = p - self.origin;
        Vec2::new(d.dot(self.u), d.dot(self.v))
    }

    /// The point of the plane at in-plane coordinates `q`.
    pub fn lift(&self, q: Vec2) -> Vec3 {
        self.origin + self.u * q.x + self.v * q.y
    }

    /// Area (m²) of the faces `members` projected onto the plane: what their outlines must hold.
    pub fn projected_area(&self, faces: &Faces, members: &[usize]) -> Real {
        members
            .iter()
            .map(|&f| faces[f].area * faces[f].normal.dot(self.normal))
            .sum()
    }
}

/// A simple counter-clockwise polygon in a group's [`Frame`], ready to become a surface.
#[derive(Debug, Clone)]
pub(crate) struct Outline {
    /// Vertices in frame coordinates, metres, counter-clockwise seen from the normal.
    pub points: Vec<Vec2>,
    /// Area, m² (positive).
    pub area: Real,
    /// Number of distinct file faces it stands for.
    pub source_faces: usize,
}

/// The closed loop `points` (frame coordinates) cleaned of repeated, collinear and spike
/// vertices, when the result is a polygon the scene accepts: at most [`MAX_VERTICES`]
/// vertices, counter-clockwise with an area above the cleaning's reach, and no two edges
/// within `eps` of each other where they should not be (so that rounding cannot make it touch
/// itself in the scene's exact test). `source_faces` is carried into the result.
pub(crate) fn outline(points: Vec<Vec2>, source_faces: usize, eps: Real) -> Option<Outline> {
    let points = simplify(points, eps);
    if points.len() < 3 || points.len() > MAX_VERTICES {
        return None;
    }
    let area = signed_area(&points);
    if area <= 0.5 * eps * perimeter(&points) || first_contact(&points, eps).is_some() {
        return None;
    }
    Some(Outline {
        points,
        area,
        source_faces,
    })
}

/// Whether `outlines` hold the area `expected` (m², the faces' projected area) up to what
/// cleaning their loops may change: each vertex it removed lay within `eps` of its neighbours'
/// chord, so the area moves by at most `eps` times the perimeter, plus rounding.
pub(crate) fn area_matches(outlines: &[Outline], expected: Real, eps: Real) -> bool {
    let area: Real = outlines.iter().map(|o| o.area).sum();
    let perimeter: Real = outlines.iter().map(|o| perimeter(&o.points)).sum();
    (area - expected).abs() <= eps * perimeter + tol::REL_AREA_MATCH * expected.abs()
}

/// Length of the closed loop, metres.
pub(crate) fn perimeter(pts: &[Vec2]) -> Real {
    (0..pts.len())
        .map(|i| pts[i].distance(pts[(i + 1) % pts.len()]))
        .sum()
}

/// Whether `p` is redundant between `a` and `b`: within `eps` of the line through them, or `a`
/// and `b` coincide (a spike).
fn redundant(a: Vec2, p: Vec2, b: Vec2, eps: Real) -> bool {
    let ab = b - a;
    let len = ab.length();
    len <= eps || ab.perp_dot(p - a).abs() <= eps * len
}

/// Removes repeated, collinear and spike vertices of a closed loop until none is left. In
/// place: each pass writes the loop it keeps over the one it reads (never ahead of it).
pub(crate) fn simplify(mut pts: Vec<Vec2>, eps: Real) -> Vec<Vec2> {
    loop {
        let before = pts.len();
        // The kept loop is `pts[..kept]`.
        let mut kept = 0;
        for read in 0..before {
            let p = pts[read];
            if kept > 0 && pts[kept - 1].distance(p) <= eps {
                continue;
            }
            pts[kept] = p;
            kept += 1;
            // The middle of the last three goes while it is redundant.
            while kept >= 3 && redundant(pts[kept - 3], pts[kept - 2], pts[kept - 1], eps) {
                pts[kept - 2] = pts[kept - 1];
                kept -= 1;
            }
        }
        pts.truncate(kept);
        // Close the loop: the seam between the last and the first vertex.
        while pts.len() >= 2 && pts[0].distance(pts[pts.len() - 1]) <= eps {
            pts.pop();
        }
        while pts.len() >= 3 {
            let n = pts.len();
            if redundant(pts[n - 2], pts[n - 1], pts[0], eps) {
                pts.pop();
            } else if redundant(pts[n - 1], pts[0], pts[1], eps) {
                pts.remove(0);
            } else {
                break;
            }
        }
        if pts.len() == before || pts.len() < 3 {
            return pts;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pts(xy: &[(Real, Real)]) -> Vec<Vec2> {
        xy.iter().map(|&(x, y)| Vec2::new(x, y)).collect()
    }

    /// [`simplify`] as it was written before it worked in place: a new list per pass.
    fn simplify_by_copies(mut pts: Vec<Vec2>, eps: Real) -> Vec<Vec2> {
        loop {
            let before = pts.len();
            let mut out: Vec<Vec2> = Vec::with_capacity(before);
            for &p in &pts {
                if out.last().is_some_and(|q| q.distance(p) <= eps) {
                    continue;
                }
                out.push(p);
                while out.len() >= 3 {
                    let n = out.len();
                    if redundant(out[n - 3], out[n - 2], out[n - 1], eps) {
                        out.remove(n - 2);
                    } else {
                        break;
                    }
                }
            }
            while out.len() >= 2 && out[0].distance(out[out.len() - 1]) <= eps {
                out.pop();
            }
            while out.len() >= 3 {
                let n = out.len();
                if redundant(out[n - 2], out[n - 1], out[0], eps) {
                    out.pop();
                } else if redundant(out[n - 1], out[0], out[1], eps) {
                    out.remove(0);
                } else {
                    break;
                }
            }
            if out.len() == before || out.len() < 3 {
                return out;
            }
            pts = out;
        }
    }

    proptest::proptest! {
        /// In place, the loop comes out as the copying version made it: loops on a coarse
        /// grid, so that repeated, collinear and spike vertices are common.
        #[test]
        fn simplify_in_place_matches_copies(
            xy in proptest::collection::vec((-3i32..3, -3i32..3), 0..24),
            eps in proptest::prop_oneof![proptest::strategy::Just(1e-9), 0.01f64..0.6],
        ) {
            let pts: Vec<Vec2> = xy.iter().map(|&(x, y)| Vec2::new(x as Real, y as Real)).collect();
            proptest::prop_assert_eq!(simplify(pts.clone(), eps), simplify_by_copies(pts, eps));
        }
    }

    #[test]
    fn simplify_removes_collinear_and_spikes() {
        let square = pts(&[
            (0.0, 0.0),
            (0.5, 0.0),
            (1.0, 0.0),
            (1.0, 1.0),
            (1.0, 2.0),
            (1.0, 1.0),
            (0.0, 1.0),
            (0.0, 0.5),
        ]);
        let out = simplify(square, 1e-9);
        assert_eq!(out.len(), 4, "{out:?}");
        assert!((signed_area(&out) - 1.0).abs() < 1e-12);
    }

    #[test]
    fn outline_refuses_clockwise_and_touching_loops() {
        let square = pts(&[(0.0, 0.0), (2.0, 0.0), (2.0, 2.0), (0.0, 2.0)]);
        let ok = outline(square.clone(), 2, 1e-6).expect("a square is an outline");
        assert_eq!((ok.points.len(), ok.area, ok.source_faces), (4, 4.0, 2));
        assert!(area_matches(std::slice::from_ref(&ok), 4.0, 1e-6));
        assert!(!area_matches(&[ok], 3.9, 1e-6));
        let clockwise: Vec<Vec2> = square.iter().rev().copied().collect();
        assert!(outline(clockwise, 1, 1e-6).is_none());
        // Two squares meeting at the vertex (1, 1): simple as a list, but it touches itself.
        let pinched = pts(&[
            (0.0, 0.0),
            (1.0, 0.0),
            (1.0, 1.0),
            (2.0, 1.0),
            (2.0, 2.0),
            (1.0, 2.0),
            (1.0, 1.0),
            (0.0, 1.0),
        ]);
        assert!(outline(pinched, 2, 1e-6).is_none());
    }
}
