//! Shared edges between adjoining planes.
//!
//! Where two non-parallel patches meet (wall and floor, box side and box top), the plane
//! extracted first claims the points within the distance threshold of itself, so the other
//! patch's boundary stops a centimetre or two short of the crease. An edge of patch P that
//! runs along the intersection line of P's plane with patch Q's plane (within the snap
//! distance and ≈ 10°), and whose span lies on or next to Q's polygon, is moved onto that
//! line. Both patches then share the crease exactly. All snaps are computed from the
//! pre-snap polygons, so the result does not depend on patch order.

use bt_geom::{Real, Vec2, Vec3};
use rayon::prelude::*;

use super::boundary::{Line2, intersect, is_simple, lines_of, polygon_from_lines, signed_area};
use crate::spatial::VoxelIndex;
use crate::tol;

/// Points sampled along an edge for the adjacency test (plus one).
const ADJ_SAMPLES: usize = 8;

/// A patch's plane, frame and polygon, as needed for snapping.
pub(crate) struct PatchGeom {
    pub normal: Vec3,
    pub offset: Real,
    pub origin: Vec3,
    pub u: Vec3,
    pub v: Vec3,
    pub poly: Vec<Vec2>,
    pub lo: Vec3,
    pub hi: Vec3,
    /// Points of the patch per m² of its polygon.
    pub density: Real,
}

/// The cloud, for checking that a gap between an edge and a crease line is data, not air.
pub(crate) struct Cloud<'a> {
    pub pts: &'a [Vec3],
    pub index: &'a VoxelIndex,
    /// RANSAC distance threshold, metres: the width of the band a neighbour steals.
    pub band: Real,
}

impl PatchGeom {
    pub(crate) fn lift(&self, p: Vec2) -> Vec3 {
        self.origin + self.u * p.x + self.v * p.y
    }

    pub(crate) fn local(&self, p: Vec3) -> Vec2 {
        let r = p - self.origin;
        Vec2::new(r.dot(self.u), r.dot(self.v))
    }

    pub(crate) fn update_bounds(&mut self) {
        let pts: Vec<Vec3> = self.poly.iter().map(|p| self.lift(*p)).collect();
        self.lo = pts.iter().fold(Vec3::INFINITY, |a, p| a.min(*p));
        self.hi = pts.iter().fold(Vec3::NEG_INFINITY, |a, p| a.max(*p));
    }
}

/// Distance from `p` to the boundary of a polygon, metres.
fn distance_to_boundary(poly: &[Vec2], p: Vec2) -> Real {
    let n = poly.len();
    (0..n)
        .map(|i| {
            let (a, b) = (poly[i], poly[(i + 1) % n]);
            let ab = b - a;
            let t = ((p - a).dot(ab) / ab.length_squared().max(Real::MIN_POSITIVE)).clamp(0.0, 1.0);
            p.distance(a + ab * t)
        })
        .fold(Real::INFINITY, Real::min)
}

/// Distance from `p` to a polygon (0 inside), metres.
fn distance_to_polygon(poly: &[Vec2], p: Vec2) -> Real {
    let n = poly.len();
    let mut inside = false;
    let mut best = Real::INFINITY;
    for i in 0..n {
        let (a, b) = (poly[i], poly[(i + 1) % n]);
        if (a.y > p.y) != (b.y > p.y) && p.x < a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x) {
            inside = !inside;
        }
        let ab = b - a;
        let t = ((p - a).dot(ab) / ab.length_squared().max(Real::MIN_POSITIVE)).clamp(0.0, 1.0);
        best = best.min(p.distance(a + ab * t));
    }
    if inside { 0.0 } else { best }
}

/// Whether the strip between edge `a`–`b` of patch `p` and the crease line `line` (both in
/// `p`'s frame) is surface the extraction lost rather than a real gap.
///
/// Near a crease, the neighbour `q` takes every point within the band of its plane, i.e.
/// within `band / sin θ` of the line in `p`'s plane, and points whose normals blend the two
/// planes may be left unassigned; those points are still in the cloud, on `p`'s plane. So
/// the strip from the edge to the stolen band is filled with cloud points on `p`'s plane
/// when the edge really ends at the crease, and empty when the surface ends short of it (a
/// cabinet top 5 cm in front of a wall). Only snaps that extend the patch are checked;
/// trimming an edge that overshoots the line is always allowed. Strips too narrow to hold
/// [`tol::SNAP_MIN_EXPECTED`] points at `p`'s density cannot tell, and may be snapped.
fn gap_is_surface(
    p: &PatchGeom,
    q: &PatchGeom,
    a: Vec2,
    b: Vec2,
    line: Line2,
    cell: Real,
    cloud: &Cloud<'_>,
) -> bool {
    let sin = p.normal.cross(q.normal).length();
    let stolen = cloud.band / sin.max(Real::MIN_POSITIVE);
    // Trimming an edge that overshoots the line (the line runs inside the polygon, which
    // lies to the left of a counter-clockwise edge) closes no gap: nothing to check.
    let len = a.distance(b);
    let e = (b - a) / len;
    let outward = Vec2::new(e.y, -e.x);
    let mid = (a + b) * 0.5;
    let foot = line.p + line.d * (mid - line.p).dot(line.d);
    if (foot - mid).dot(outward) <= 0.0 {
        return true;
    }
    let side = |x: Vec2| (x - line.p).perp_dot(line.d);
    let (sa, sb) = (side(a), side(b));
    if sa * sb < 0.0 {
        return true; // the edge crosses the line: nothing to measure
    }
    let sign = if sa + sb >= 0.0 { 1.0 } else { -1.0 };
    let (sa, sb) = (sa.abs(), sb.abs());
    let trim = if len > 4.0 * cell { cell } else { 0.0 };
    let (t0, t1) = (trim / len, 1.0 - trim / len);
    // Expected count: density × area of the strip beyond the stolen band (linear in t).
    let depth = |t: Real| (sa + (sb - sa) * t - stolen).max(0.0);
    let steps = 16;
    let strip_area = (0..steps)
        .map(|k| depth(t0 + (t1 - t0) * (k as Real + 0.5) / steps as Real))
        .sum::<Real>()
        / steps as Real
        * len
        * (t1 - t0);
    let expected = p.density * strip_area;
    if expected < tol::SNAP_MIN_EXPECTED {
        return true;
    }
    let corners = [
        p.lift(a + e * trim),
        p.lift(b - e * trim),
        p.lift(line.p + line.d * (a + e * trim - line.p).dot(line.d)),
        p.lift(line.p + line.d * (b - e * trim - line.p).dot(line.d)),
    ];
    let pad = Vec3::splat(cloud.band);
    let lo = corners.iter().fold(Vec3::INFINITY, |m, c| m.min(*c)) - pad;
    let hi = corners.iter().fold(Vec3::NEG_INFINITY, |m, c| m.max(*c)) + pad;
    let mut found = 0usize;
    cloud.index.for_each_in_box(cloud.pts, lo, hi, |j| {
        let x = cloud.pts[j as usize];
        if (p.normal.dot(x) - p.offset).abs() > cloud.band {
            return;
        }
        let x2 = p.local(x);
        let t = (x2 - a).dot(e) / len;
        if !(t0..=t1).contains(&t) {
            return;
        }
        let s = side(x2) * sign;
        if s >= stolen && s < sa + (sb - sa) * t {
            found += 1;
        }
    });
    found as Real >= tol::SNAP_MIN_FILL * expected
}

/// Snap edges of every patch onto intersection lines with adjoining patches; returns the
/// new polygons (unchanged where no snap applies or the snapped polygon would be invalid).
/// An edge is only snapped across a gap the data cannot show to be real (see
/// [`gap_is_surface`]).
pub(crate) fn snap_all(
    patches: &[PatchGeom],
    snap: Real,
    cell: Real,
    cloud: &Cloud<'_>,
) -> Vec<Vec<Vec2>> {
    patches
        .par_iter()
        .enumerate()
        .map(|(pi, _)| snap_patch(pi, patches, snap, cell, cloud))
        .collect()
}

/// Patch `pi` of [`snap_all`]: each edge onto the best adjoining line, short chamfers between
/// snapped edges dropped, the result kept only if it stays near the old outline, simple and
/// not much smaller.
fn snap_patch(
    pi: usize,
    patches: &[PatchGeom],
    snap: Real,
    cell: Real,
    cloud: &Cloud<'_>,
) -> Vec<Vec2> {
    let p = &patches[pi];
    let mut lines = lines_of(&p.poly);
    let n = p.poly.len();
    let mut snapped = vec![false; n];
    let mut any = false;
    for i in 0..n {
        let edge = (p.poly[i], p.poly[(i + 1) % n]);
        if let Some(l) = best_line(pi, patches, edge, (snap, cell), cloud) {
            lines[i] = l;
            snapped[i] = true;
            any = true;
        }
    }
    if !any {
        return p.poly.clone();
    }
    let old = drop_chamfers(&mut lines, &mut snapped, p.poly.clone(), snap, cell);
    let out = polygon_from_lines(&lines, &old);
    let near_old = out
        .iter()
        .all(|&x| distance_to_boundary(&p.poly, x) <= 2.0 * snap + cell);
    if near_old && is_simple(&out) && signed_area(&out) > tol::AREA_REL * signed_area(&p.poly) {
        out
    } else {
        p.poly.clone()
    }
}

/// The intersection line with another patch that edge `(a, b)` of patch `pi` should snap to:
/// of the non-parallel patches whose line lies within `snap` of both ends and nearly along
/// the edge, next to most of the edge's span, across a gap the data cannot show to be real,
/// the one nearest the edge.
fn best_line(
    pi: usize,
    patches: &[PatchGeom],
    (a, b): (Vec2, Vec2),
    (snap, cell): (Real, Real),
    cloud: &Cloud<'_>,
) -> Option<Line2> {
    let p = &patches[pi];
    let (a3, b3) = (p.lift(a), p.lift(b));
    let (elo, ehi) = (
        a3.min(b3) - Vec3::splat(snap),
        a3.max(b3) + Vec3::splat(snap),
    );
    let mut best: Option<(Real, Line2)> = None;
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
        let mut d2 = Vec2::new(dir.dot(p.u), dir.dot(p.v)).normalize_or_zero();
        let e = (b - a).normalize_or_zero();
        if d2.dot(e) < 0.0 {
            d2 = -d2;
        }
        let o2 = p.local(x0);
        let cand = Line2 { p: o2, d: d2 };
        let dist = |x: Vec2| (x - o2).perp_dot(d2).abs();
        let worst = dist(a).max(dist(b));
        if worst > snap || e.perp_dot(d2).abs() > tol::SNAP_EDGE_SIN {
            continue;
        }
        // Most of the edge's span, moved onto the line, must lie on or next to Q
        // (most, not all: a floor edge runs past a doorway in the wall).
        let on_line = |x: Vec2| o2 + d2 * (x - o2).dot(d2);
        let near = (0..=ADJ_SAMPLES)
            .filter(|&k| {
                let x = a + (b - a) * (k as Real / ADJ_SAMPLES as Real);
                distance_to_polygon(&q.poly, q.local(p.lift(on_line(x)))) <= snap
            })
            .count();
        let adj = 2 * near > ADJ_SAMPLES + 1;
        if adj
            && best.is_none_or(|(w, _)| worst < w)
            && gap_is_surface(p, q, a, b, cand, cell, cloud)
        {
            best = Some((worst, cand));
        }
    }
    best.map(|(_, l)| l)
}

/// Drops each short chamfer left between two snapped edges (a corner where both neighbours
/// stole points) so the corner is the lines' intersection; returns the outline `old` with the
/// same edges removed (the reference points of [`polygon_from_lines`]).
fn drop_chamfers(
    lines: &mut Vec<Line2>,
    snapped: &mut Vec<bool>,
    mut old: Vec<Vec2>,
    snap: Real,
    cell: Real,
) -> Vec<Vec2> {
    loop {
        let n = lines.len();
        if n <= 3 {
            return old;
        }
        let cur = polygon_from_lines(lines, &old);
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
        let Some(i) = chamfer else { return old };
        let next = (i + 1) % n;
        old[next] = (old[i] + old[next]) * 0.5;
        lines.remove(i);
        snapped.remove(i);
        old.remove(i);
    }
}
