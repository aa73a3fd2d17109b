//! Shared edges between adjoining planes.
//!
//! Where two non-parallel patches meet (wall and floor, box side and box top), the plane
//! extracted first claims the points within the distance threshold of itself, so the other
//! patch's boundary stops a centimetre or two short of the crease. An edge of patch P that
//! runs along the intersection line of P's plane with patch Q's plane (within the snap
//! distance and ≈ 10°), and whose span lies on or next to Q's polygon, is moved onto that
//! line. Both patches then share the crease exactly. All snaps are computed from the
//! pre-snap polygons, so the result does not depend on patch order.

use glam::{DVec2, DVec3};
use rayon::prelude::*;

use super::boundary::{Line2, intersect, is_simple, lines_of, polygon_from_lines, signed_area};
use crate::tol;

/// Points sampled along an edge for the adjacency test (plus one).
const ADJ_SAMPLES: usize = 8;

/// A patch's plane, frame and polygon, as needed for snapping.
pub(crate) struct PatchGeom {
    pub normal: DVec3,
    pub offset: f64,
    pub origin: DVec3,
    pub u: DVec3,
    pub v: DVec3,
    pub poly: Vec<DVec2>,
    pub lo: DVec3,
    pub hi: DVec3,
}

impl PatchGeom {
    pub(crate) fn lift(&self, p: DVec2) -> DVec3 {
        self.origin + self.u * p.x + self.v * p.y
    }

    pub(crate) fn local(&self, p: DVec3) -> DVec2 {
        let r = p - self.origin;
        DVec2::new(r.dot(self.u), r.dot(self.v))
    }

    pub(crate) fn update_bounds(&mut self) {
        let pts: Vec<DVec3> = self.poly.iter().map(|p| self.lift(*p)).collect();
        self.lo = pts.iter().fold(DVec3::INFINITY, |a, p| a.min(*p));
        self.hi = pts.iter().fold(DVec3::NEG_INFINITY, |a, p| a.max(*p));
    }
}

/// Distance from `p` to the boundary of a polygon, metres.
fn distance_to_boundary(poly: &[DVec2], p: DVec2) -> f64 {
    let n = poly.len();
    (0..n)
        .map(|i| {
            let (a, b) = (poly[i], poly[(i + 1) % n]);
            let ab = b - a;
            let t = ((p - a).dot(ab) / ab.length_squared().max(f64::MIN_POSITIVE)).clamp(0.0, 1.0);
            p.distance(a + ab * t)
        })
        .fold(f64::INFINITY, f64::min)
}

/// Distance from `p` to a polygon (0 inside), metres.
fn distance_to_polygon(poly: &[DVec2], p: DVec2) -> f64 {
    let n = poly.len();
    let mut inside = false;
    let mut best = f64::INFINITY;
    for i in 0..n {
        let (a, b) = (poly[i], poly[(i + 1) % n]);
        if (a.y > p.y) != (b.y > p.y) && p.x < a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x) {
            inside = !inside;
        }
        let ab = b - a;
        let t = ((p - a).dot(ab) / ab.length_squared().max(f64::MIN_POSITIVE)).clamp(0.0, 1.0);
        best = best.min(p.distance(a + ab * t));
    }
    if inside { 0.0 } else { best }
}

/// Snap edges of every patch onto intersection lines with adjoining patches; returns the
/// new polygons (unchanged where no snap applies or the snapped polygon would be invalid).
pub(crate) fn snap_all(patches: &[PatchGeom], snap: f64, cell: f64) -> Vec<Vec<DVec2>> {
    patches
        .par_iter()
        .enumerate()
        .map(|(pi, p)| {
            let mut lines = lines_of(&p.poly);
            let n = p.poly.len();
            let mut snapped = vec![false; n];
            let mut any = false;
            for i in 0..n {
                let line = &mut lines[i];
                let (a, b) = (p.poly[i], p.poly[(i + 1) % n]);
                let (a3, b3) = (p.lift(a), p.lift(b));
                let (elo, ehi) = (
                    a3.min(b3) - DVec3::splat(snap),
                    a3.max(b3) + DVec3::splat(snap),
                );
                let mut best: Option<(f64, Line2)> = None;
                for (qi, q) in patches.iter().enumerate() {
                    if qi == pi || p.normal.dot(q.normal).abs() > tol::SNAP_MAX_COS {
                        continue;
                    }
                    if (ehi.cmplt(q.lo)).any() || (elo.cmpgt(q.hi)).any() {
                        continue;
                    }
                    let l = p.normal.cross(q.normal);
                    let l2 = l.length_squared();
                    let x0 = (p.offset * q.normal.cross(l) + q.offset * l.cross(p.normal)) / l2;
                    let dir = l / l2.sqrt();
                    let mut d2 = DVec2::new(dir.dot(p.u), dir.dot(p.v)).normalize_or_zero();
                    let e = (b - a).normalize_or_zero();
                    if d2.dot(e) < 0.0 {
                        d2 = -d2;
                    }
                    let o2 = p.local(x0);
                    let cand = Line2 { p: o2, d: d2 };
                    let dist = |x: DVec2| (x - o2).perp_dot(d2).abs();
                    let worst = dist(a).max(dist(b));
                    if worst > snap || e.perp_dot(d2).abs() > tol::SNAP_EDGE_SIN {
                        continue;
                    }
                    // Most of the edge's span, moved onto the line, must lie on or next to Q
                    // (most, not all: a floor edge runs past a doorway in the wall).
                    let on_line = |x: DVec2| o2 + d2 * (x - o2).dot(d2);
                    let near = (0..=ADJ_SAMPLES)
                        .filter(|&k| {
                            let x = a + (b - a) * (k as f64 / ADJ_SAMPLES as f64);
                            distance_to_polygon(&q.poly, q.local(p.lift(on_line(x)))) <= snap
                        })
                        .count();
                    let adj = 2 * near > ADJ_SAMPLES + 1;
                    if adj && best.is_none_or(|(w, _)| worst < w) {
                        best = Some((worst, cand));
                    }
                }
                if let Some((_, l)) = best {
                    *line = l;
                    snapped[i] = true;
                    any = true;
                }
            }
            if !any {
                return p.poly.clone();
            }
            // A short chamfer left between two snapped edges (a corner where both
            // neighbours stole points) is dropped so the corner is the lines' intersection.
            let mut old = p.poly.clone();
            loop {
                let n = lines.len();
                if n <= 3 {
                    break;
                }
                let cur = polygon_from_lines(&lines, &old);
                let chamfer = (0..n).find(|&i| {
                    let (prev, next) = ((i + n - 1) % n, (i + 1) % n);
                    !snapped[i]
                        && snapped[prev]
                        && snapped[next]
                        && cur[i].distance(cur[next]) < 2.0 * snap + cell
                        && intersect(lines[prev], lines[next]).is_some_and(|x| {
                            x.distance(cur[i]).max(x.distance(cur[next])) <= 2.0 * snap + cell
                        })
                });
                let Some(i) = chamfer else { break };
                let next = (i + 1) % n;
                old[next] = (old[i] + old[next]) * 0.5;
                lines.remove(i);
                snapped.remove(i);
                old.remove(i);
            }
            let out = polygon_from_lines(&lines, &old);
            let near_old = out
                .iter()
                .all(|&x| distance_to_boundary(&p.poly, x) <= 2.0 * snap + cell);
            if near_old
                && is_simple(&out)
                && signed_area(&out) > tol::AREA_REL * signed_area(&p.poly)
            {
                out
            } else {
                p.poly.clone()
            }
        })
        .collect()
}
