//! Diffracting edges, derived once per set of surfaces ([`crate::Scene::edges`]).
//!
//! An edge is a straight piece of a reflector's boundary around which the surfaces that touch
//! it leave a free sector wider than a half-turn: a *wedge* (two faces meeting at an angle,
//! the free space on the reflex side) or a *free edge* (one face alone: a screen, a half-turn
//! on either side). Faces are matched geometrically, whatever shape or material they come
//! from: collinear overlapping pieces of boundary and T-junctions (a boundary lying on another
//! face's interior) split the boundary into intervals, and each interval gets the half-planes
//! of every face around it. Where the widest free sector is a half-turn or less (a concave
//! junction, a seam between coplanar faces, a wall standing on a floor), nothing diffracts.
//! Blockers only occlude: they neither diffract nor count as faces around an edge.
//!
//! **Frame of an edge.** `e` = [`Edge::direction`] (start → end), `t0` = [`Edge::face0`] (unit,
//! ⊥ `e`, in face 0, pointing from the edge into the face), `y0 = e × t0`. The angle φ of a
//! point about the edge is measured from `t0` towards `y0`; the free space (the *exterior*) is
//! φ ∈ (0, nπ), face 0 lies at φ = 0 and face n at φ = nπ, n ∈ (1, 2] ([`Edge::n`]).

mod keller;

pub use keller::{
    EdgeLine, KELLER_PAIR_TOL, KELLER_RESIDUAL, KellerPair, KellerReach, LinePair, NoKellerPair,
    keller_pair, keller_pair_checked, keller_pair_settled,
};

use crate::surface::{Surface, SurfaceId, SurfaceKind};
use bt_geom::{Bvh, Plane, Real, Vec3, bvh::Occluder};
use rayon::prelude::*;
use std::f64::consts::PI;

/// Index of an edge in [`Edges`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize)]
pub struct EdgeId(pub u32);

impl EdgeId {
    /// The index as `usize`.
    #[inline]
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

/// Relative tolerance (to the surfaces' extent) for matching pieces of boundary of different
/// faces: collinear within it, overlapping by more than it (1e-6: 1 mm in a 1 km city, above
/// the 30 µm resolution of single-precision meshes 500 m from their origin).
pub const REL_EDGE_MATCH: Real = 1e-6;

/// A free sector must exceed a half-turn by this much (rad) to diffract: flatter junctions are
/// seams between (nearly) coplanar faces (1e-3 rad ≈ 0.06°).
pub const FLAT_WEDGE_RAD: Real = 1e-3;

/// One diffracting edge: a wedge or a free edge (module docs give its frame).
#[derive(Debug, Clone, PartialEq)]
pub struct Edge {
    /// Start point, metres, scene-local frame.
    pub start: Vec3,
    /// End point, metres, scene-local frame.
    pub end: Vec3,
    /// Unit direction `e`, start → end.
    pub direction: Vec3,
    /// Length, metres.
    pub length: Real,
    /// The face at φ = 0.
    pub face0: SurfaceId,
    /// The face at φ = nπ (the same as `face0` for a free edge).
    pub face_n: SurfaceId,
    /// Unit vector `t0`: ⊥ `e`, in face 0, from the edge into face 0.
    pub t0: Vec3,
    /// Exterior angle over π, in (1, 2]: 2 for a free edge (a half-plane screen), 1.5 for a
    /// right-angled corner of a solid.
    pub n: Real,
    /// Unit vector `tn = cos(nπ)·t0 + sin(nπ)·y0`: ⊥ `e`, in face n, from the edge into face n
    /// (kept so that the exterior tests need no trigonometry).
    pub tn: Vec3,
    /// `y0 = e × t0` (unit): face 0's normal on the exterior's side, kept for
    /// [`Edge::about`] (made once: the same bits as made there at each call before).
    pub y0: Vec3,
    /// `tn × e` (unit): face n's normal on the exterior's side, kept as `y0` is.
    pub yn: Vec3,
    /// Every reflector touching the edge (face 0 and face n among them), ascending: a path
    /// leaving the edge starts on all of them.
    pub touching: Vec<SurfaceId>,
}

impl Edge {
    /// Whether the edge is a free edge (a screen's boundary, one face).
    pub fn is_free(&self) -> bool {
        self.face0 == self.face_n
    }

    /// The point at `t` metres from the start along the edge line.
    #[inline]
    pub fn point(&self, t: Real) -> Vec3 {
        self.start + t * self.direction
    }

    /// Parameter (m from the start along `e`) of the projection of `p` on the edge line.
    #[inline]
    pub fn parameter(&self, p: Vec3) -> Real {
        (p - self.start).dot(self.direction)
    }

    /// The component of `p − start` perpendicular to the edge (m).
    #[inline]
    pub fn perpendicular(&self, p: Vec3) -> Vec3 {
        let v = p - self.start;
        v - v.dot(self.direction) * self.direction
    }

    /// The angle φ (rad, in [0, 2π)) of `p` about the edge, from face 0 (module docs).
    #[inline]
    pub fn angle(&self, p: Vec3) -> Real {
        let v = self.perpendicular(p);
        let phi = v.dot(self.y0).atan2(v.dot(self.t0));
        if phi < 0.0 { phi + 2.0 * PI } else { phi }
    }

    /// Whether `p` lies in the exterior (the free sector), more than `tol` metres from the edge
    /// line and from both faces' half-planes.
    #[inline]
    pub fn in_exterior(&self, p: Vec3, tol: Real) -> bool {
        let a = self.about(p);
        // Distance from the face at angle 0 (resp. nπ) is r·sin of the angle to it while that
        // angle is below a quarter turn (sine and cosine positive), r beyond.
        let clear = |sin: Real, cos: Real| cos <= 0.0 || sin < 0.0 || sin > tol;
        a.r > tol && a.in_sector(0.0) && clear(a.sin0, a.cos0) && clear(a.sin_n, a.cos_n)
    }

    /// Where `p` lies about the edge ([`About`]). Only `p`'s offset ⊥ the edge matters, and
    /// the frame vectors are ⊥ the edge, so they are dotted with `p − start` directly.
    #[inline]
    pub fn about(&self, p: Vec3) -> About {
        let v = p - self.start;
        let (sin0, cos0) = (v.dot(self.y0), v.dot(self.t0));
        About {
            sin0,
            cos0,
            sin_n: v.dot(self.yn),
            cos_n: v.dot(self.tn),
            r: (sin0 * sin0 + cos0 * cos0).sqrt(),
        }
    }

    /// The Keller point of the straight (unfolded) path `a → edge → b`: the parameter `t` (m
    /// from the start) where the path makes equal angles with the edge,
    /// `t* = (d_b·t_a + d_a·t_b) / (d_a + d_b)` with `d` the distances to the edge line and `t`
    /// the projections on it; `None` when both lie on the line.
    #[inline]
    pub fn keller(&self, a: Vec3, b: Vec3) -> Option<Real> {
        EdgeLine::of(self).keller(a, b)
    }
}

/// The edges of a set of surfaces, with a BVH over their boxes (item `i` = edge `i`).
#[derive(Debug, Clone, Default)]
pub struct Edges {
    edges: Vec<Edge>,
    bvh: Bvh,
}

impl Edges {
    /// All edges, indexed by [`EdgeId`].
    pub fn all(&self) -> &[Edge] {
        &self.edges
    }
    /// The edge with id `id`.
    #[inline]
    pub fn get(&self, id: EdgeId) -> &Edge {
        &self.edges[id.index()]
    }
    /// Number of edges.
    pub fn len(&self) -> usize {
        self.edges.len()
    }
    /// Whether there is none.
    pub fn is_empty(&self) -> bool {
        self.edges.is_empty()
    }
    /// BVH over the edges' boxes.
    pub fn bvh(&self) -> &Bvh {
        &self.bvh
    }

    /// Derive the edges of `surfaces` (module docs). Deterministic: edges come in the order of
    /// their lowest-numbered face's boundary, then along it.
    pub fn build(surfaces: &[Surface]) -> Edges {
        let tol = match_tolerance(surfaces);
        let segments = boundary_segments(surfaces, tol);
        let segment_bvh = Bvh::build(&segments);
        let polygon_bvh = Bvh::build(
            &surfaces
                .iter()
                .map(|s| Grown(s.polygon.bounds(), tol))
                .collect::<Vec<_>>(),
        );
        // Each segment's edges depend on the segments and surfaces alone: chunks of them on
        // all cores, appended in segment order (the same edges on any number of threads).
        let starts: Vec<usize> = (0..segments.len()).step_by(SEGMENTS_PER_TASK).collect();
        let parts: Vec<Vec<Edge>> = starts
            .par_iter()
            .map(|&start| {
                let mut part = Vec::new();
                let end = (start + SEGMENTS_PER_TASK).min(segments.len());
                for (i, segment) in segments.iter().enumerate().take(end).skip(start) {
                    let around =
                        Around::gather(i, &segments, &segment_bvh, surfaces, &polygon_bvh, tol);
                    around.edges(segment, tol, &mut part);
                }
                part
            })
            .collect();
        let edges: Vec<Edge> = parts.concat();
        let boxes: Vec<Grown> = edges
            .iter()
            .map(|e| Grown((e.start.min(e.end), e.start.max(e.end)), 0.0))
            .collect();
        Edges {
            bvh: Bvh::build(&boxes),
            edges,
        }
    }
}

/// Boundary segments per task of [`Edges::build`] (a few milliseconds of a city's).
const SEGMENTS_PER_TASK: usize = 4096;

/// A box grown by a margin (m) on every side.
struct Grown((Vec3, Vec3), Real);

impl Occluder for Grown {
    fn bounds(&self) -> (Vec3, Vec3) {
        let (lo, hi) = self.0;
        (lo - Vec3::splat(self.1), hi + Vec3::splat(self.1))
    }
}

/// The matching tolerance of `surfaces` (m): [`REL_EDGE_MATCH`] of their extent.
fn match_tolerance(surfaces: &[Surface]) -> Real {
    let extent = crate::model::scene_extent(surfaces, None, None);
    bt_geom::tol::scaled(REL_EDGE_MATCH, extent)
}

/// One side of a reflector's boundary.
struct Segment {
    surface: SurfaceId,
    a: Vec3,
    b: Vec3,
    /// Unit in-plane normal of the side, pointing into the polygon.
    inward: Vec3,
    /// The box, grown by the matching tolerance.
    bounds: (Vec3, Vec3),
}

impl Occluder for Segment {
    fn bounds(&self) -> (Vec3, Vec3) {
        self.bounds
    }
}

fn boundary_segments(surfaces: &[Surface], tol: Real) -> Vec<Segment> {
    let mut out = Vec::new();
    for (i, s) in surfaces.iter().enumerate() {
        if s.kind != SurfaceKind::Reflector {
            continue;
        }
        let v = s.polygon.vertices();
        let normal = s.polygon.plane().normal;
        for k in 0..v.len() {
            let (a, b) = (v[k], v[(k + 1) % v.len()]);
            // Vertices run counter-clockwise about the normal: the inside is on the left.
            let inward = normal.cross(b - a).normalize();
            let grow = Vec3::splat(tol);
            out.push(Segment {
                surface: SurfaceId(i as u32),
                a,
                b,
                inward,
                bounds: (a.min(b) - grow, a.max(b) + grow),
            });
        }
    }
    out
}

/// A half-plane bounded by the edge line: a face's direction away from the line.
#[derive(Debug, Clone, Copy)]
struct HalfPlane {
    surface: SurfaceId,
    direction: Vec3,
    /// The parameter interval (m along the segment) where it holds.
    from: Real,
    to: Real,
}

/// The half-planes around one boundary segment and the breakpoints that split it.
struct Around {
    length: Real,
    direction: Vec3,
    half_planes: Vec<HalfPlane>,
    breaks: Vec<Real>,
}

impl Around {
    /// Collect, for segment `i`, the collinear overlapping sides of other reflectors and the
    /// coplanar reflectors whose interior the segment crosses.
    fn gather(
        i: usize,
        segments: &[Segment],
        segment_bvh: &Bvh,
        surfaces: &[Surface],
        polygon_bvh: &Bvh,
        tol: Real,
    ) -> Around {
        let s = &segments[i];
        let length = s.a.distance(s.b);
        let direction = (s.b - s.a) / length;
        let mut around = Around {
            length,
            direction,
            half_planes: vec![HalfPlane {
                surface: s.surface,
                direction: s.inward,
                from: 0.0,
                to: length,
            }],
            breaks: vec![0.0, length],
        };
        let (lo, hi) = s.bounds;
        let overlaps = |min: Vec3, max: Vec3| min.cmple(hi).all() && max.cmpge(lo).all();
        segment_bvh.visit(overlaps, |j| {
            let other = &segments[j as usize];
            if j as usize != i && other.surface != s.surface {
                around.collinear(s, other, tol);
            }
        });
        polygon_bvh.visit(overlaps, |j| {
            let id = SurfaceId(j);
            let surface = &surfaces[j as usize];
            if id != s.surface && surface.kind == SurfaceKind::Reflector {
                around.crossing(s, id, surface, tol);
            }
        });
        around.breaks.sort_by(Real::total_cmp);
        around
    }

    /// Add `other` when it lies on the segment's line and overlaps it.
    fn collinear(&mut self, s: &Segment, other: &Segment, tol: Real) {
        let off = |p: Vec3| {
            let v = p - s.a;
            (v - v.dot(self.direction) * self.direction).length()
        };
        if off(other.a) > tol || off(other.b) > tol {
            return;
        }
        let (ta, tb) = (
            (other.a - s.a).dot(self.direction),
            (other.b - s.a).dot(self.direction),
        );
        let (from, to) = (ta.min(tb).max(0.0), ta.max(tb).min(self.length));
        if to - from <= tol {
            return;
        }
        self.breaks.extend([from, to]);
        self.half_planes.push(HalfPlane {
            surface: other.surface,
            direction: other.inward,
            from,
            to,
        });
    }

    /// Add both half-planes of a reflector whose plane holds the segment, where the segment
    /// runs through its interior (a T-junction: the segment's face stands on it).
    fn crossing(&mut self, s: &Segment, id: SurfaceId, surface: &Surface, tol: Real) {
        let polygon = &surface.polygon;
        let plane: &Plane = polygon.plane();
        if plane.signed_distance(s.a).abs() > tol || plane.signed_distance(s.b).abs() > tol {
            return;
        }
        // Where the segment's line crosses the polygon's sides: candidate ends of the interior
        // part (the inside test at each interval's midpoint decides).
        let mut cuts = vec![0.0, self.length];
        let v = polygon.vertices();
        for k in 0..v.len() {
            if let Some(t) = line_side_crossing(s.a, self.direction, v[k], v[(k + 1) % v.len()])
                && t > 0.0
                && t < self.length
            {
                cuts.push(t);
            }
        }
        cuts.sort_by(Real::total_cmp);
        let side = plane.normal.cross(self.direction).normalize();
        for w in cuts.windows(2) {
            let mid = s.a + 0.5 * (w[0] + w[1]) * self.direction;
            if w[1] - w[0] > tol && polygon.inside_by(mid, tol) {
                self.breaks.extend([w[0], w[1]]);
                for direction in [side, -side] {
                    self.half_planes.push(HalfPlane {
                        surface: id,
                        direction,
                        from: w[0],
                        to: w[1],
                    });
                }
            }
        }
    }

    /// Emit the edges of the segment (those whose lowest boundary face is the segment's own),
    /// merging consecutive intervals with the same wedge.
    fn edges(&self, s: &Segment, tol: Real, out: &mut Vec<Edge>) {
        let mut open: Option<Edge> = None;
        for w in self.breaks.windows(2) {
            if w[1] - w[0] <= tol {
                continue;
            }
            let mid = 0.5 * (w[0] + w[1]);
            let here: Vec<HalfPlane> = self
                .half_planes
                .iter()
                .filter(|h| h.from < mid && mid < h.to)
                .copied()
                .collect();
            let wedge = self.wedge(s, &here, (w[0], w[1]));
            open = match (open.take(), wedge) {
                (Some(mut e), Some(next)) if same_wedge(&e, &next) => {
                    e.end = next.end;
                    e.length = e.start.distance(e.end);
                    e.touching.extend(next.touching);
                    e.touching.sort();
                    e.touching.dedup();
                    Some(e)
                }
                (prev, next) => {
                    out.extend(prev);
                    next
                }
            };
        }
        out.extend(open);
    }

    /// The wedge of one interval `(from, to)` with half-planes `here`, when its widest free
    /// sector exceeds a half-turn and the segment's face is the lowest-numbered face bounded
    /// there (each interval is then emitted once).
    fn wedge(&self, s: &Segment, here: &[HalfPlane], (from, to): (Real, Real)) -> Option<Edge> {
        let bounded = here.iter().filter(|h| h.surface != s.surface);
        if bounded
            .clone()
            .any(|h| h.surface < s.surface && is_side(h, here))
        {
            return None;
        }
        let e = self.direction;
        let x0 = e.any_orthonormal_vector();
        let y0 = e.cross(x0);
        let mut angles: Vec<(Real, HalfPlane)> = here
            .iter()
            .map(|h| {
                let d = h.direction - h.direction.dot(e) * e;
                let a = d.dot(y0).atan2(d.dot(x0));
                (if a < 0.0 { a + 2.0 * PI } else { a }, *h)
            })
            .collect();
        angles.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.surface.cmp(&b.1.surface)));
        let (gap, k) = widest_gap(&angles);
        if gap <= PI + FLAT_WEDGE_RAD {
            return None;
        }
        let (h0, hn) = (angles[k].1, angles[(k + 1) % angles.len()].1);
        let t0 = (h0.direction - h0.direction.dot(e) * e).normalize();
        let mut touching: Vec<SurfaceId> = here.iter().map(|h| h.surface).collect();
        touching.sort();
        touching.dedup();
        let tn = face_direction(e, t0, gap);
        Some(Edge {
            start: s.a + from * e,
            end: s.a + to * e,
            direction: e,
            length: to - from,
            face0: h0.surface,
            face_n: if angles.len() == 1 {
                h0.surface
            } else {
                hn.surface
            },
            t0,
            // A free edge's gap is a whole turn; rounding may make it a hair more (two
            // coplanar faces on one side of the edge): n stays in UTD's [1, 2].
            n: (gap / PI).min(2.0),
            tn,
            y0: e.cross(t0),
            yn: tn.cross(e),
            touching,
        })
    }
}

/// The unit vector ⊥ `e` at angle `angle` (rad) from `t0` towards `e × t0`.
fn face_direction(e: Vec3, t0: Vec3, angle: Real) -> Vec3 {
    let (sin, cos) = angle.sin_cos();
    cos * t0 + sin * e.cross(t0)
}

/// Where a point lies about an edge ([`Edge::about`]), without trigonometry: with `r` its
/// distance from the edge line (m) and φ its angle from face 0 (module docs).
#[derive(Debug, Clone, Copy)]
pub struct About {
    /// r·sin φ: the distance from face 0's plane, positive on the exterior side (m).
    pub sin0: Real,
    /// r·cos φ (m).
    pub cos0: Real,
    /// r·sin(nπ − φ): the distance from face n's plane, positive on the exterior side (m).
    pub sin_n: Real,
    /// r·cos(nπ − φ) (m).
    pub cos_n: Real,
    /// r (m).
    pub r: Real,
}

impl About {
    /// Whether the point lies in the closed sector φ ∈ [0, nπ] up to `slack` metres: within a
    /// half-turn after face 0 or within a half-turn before face n (for n ∈ (1, 2] the two cover
    /// the sector).
    #[inline]
    pub fn in_sector(&self, slack: Real) -> bool {
        self.sin0 >= -slack || self.sin_n >= -slack
    }
}

/// Whether half-plane `h` comes from a face's boundary (not a T-junction's interior, which
/// gives two opposite half-planes of one surface).
fn is_side(h: &HalfPlane, here: &[HalfPlane]) -> bool {
    here.iter().filter(|o| o.surface == h.surface).count() == 1
}

/// The widest angular gap between consecutive sorted angles (cyclic) and the index of the
/// angle it starts at: a full turn for a single half-plane.
fn widest_gap(angles: &[(Real, HalfPlane)]) -> (Real, usize) {
    let n = angles.len();
    (0..n)
        .map(|k| {
            let next = if k + 1 == n {
                angles[0].0 + 2.0 * PI
            } else {
                angles[k + 1].0
            };
            (next - angles[k].0, k)
        })
        .fold((Real::NEG_INFINITY, 0), |best, cur| {
            if cur.0 > best.0 { cur } else { best }
        })
}

/// Whether two consecutive pieces of a boundary diffract alike (same faces, same opening).
fn same_wedge(a: &Edge, b: &Edge) -> bool {
    a.face0 == b.face0
        && a.face_n == b.face_n
        && (a.n - b.n).abs() <= FLAT_WEDGE_RAD
        && a.t0.dot(b.t0) >= (FLAT_WEDGE_RAD).cos()
}

/// Parameter along the line `p + t·d` (unit `d`) where it crosses the side `a → b` within the
/// side, in the plane holding both; `None` when parallel.
fn line_side_crossing(p: Vec3, d: Vec3, a: Vec3, b: Vec3) -> Option<Real> {
    let side = b - a;
    let n = d.cross(side);
    let n2 = n.length_squared();
    if n2 <= Real::EPSILON * side.length_squared() {
        return None;
    }
    // Solve p + t d = a + u side (least squares in the common plane).
    let w = a - p;
    let t = w.cross(side).dot(n) / n2;
    let u = w.cross(d).dot(n) / n2;
    (0.0..=1.0).contains(&u).then_some(t)
}

#[cfg(test)]
mod tests;
