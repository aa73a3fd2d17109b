//! Candidates with two diffractions from the two trees' reaches (issue 28).
//!
//! A path `s1..sp → D1 on E1 → m1..mq → D2 on E2 → s(p+q+1)..sk → RX` unfolds, through its
//! reflections, into a broken line `I → D1 → D2' → J'`: `I` the TX image of the TX tree's node
//! `s1..sp`, `J` the RX image of the RX tree's node, and `E2'`, `D2'`, `J'` the second edge,
//! its point and `J` mirrored through the middle reflections `mq..m1`. So
//! - `D1` lies in the TX node's reach on `E1`, `D2` in the RX node's reach on `E2` (the
//!   parameter along `E2'` is the one along `E2`);
//! - `(D1, D2')` is the two-point Keller solution of `I`, `E1`, `E2'`, `J'`
//!   ([`bt_scene::edges::keller_pair`]): the one stationary point of a convex length.
//!
//! The join keeps `(TX node, middle, RX node)` when that solution lies in both reaches, within
//! the tree's margin, or when it cannot be computed (validation decides): a superset of the
//! valid paths, which property tests check against blind enumeration.

use super::{Pairing, Reach};
use crate::beamtree::{PAIR_TESTS_PER_CANDIDATE, TreeError};
use crate::diffraction::DiffractedSet;
use bt_geom::{Polygon, Real, Vec3};
use bt_scene::edges::{EdgeLine, keller_pair};
use bt_scene::{Edge, EdgeId, Scene, SurfaceId};

/// Angular slack (rad) of the prefilters: far above round-off, far below any angle a valid
/// path could need.
const SLACK: Real = 1e-6;

/// A TX reach on the first edge, as the prefilters read it: its line, its interval (grown by
/// the margin) and the range of cos β0 of rays from its image over the interval.
struct Near {
    edge: usize,
    reach: Reach,
    line: EdgeLine,
    ends: [Vec3; 2],
    /// cos β0 at the interval's ends (increasing along the edge).
    incidence: (Real, Real),
}

/// An RX reach on the second edge and the middle reflections: the edge's line, interval ends
/// and the RX image, unfolded through the middle into the first edge's frame, and the range
/// of cos β0 of rays leaving towards the image.
struct Far<'m> {
    edge: usize,
    reach: Reach,
    middle: &'m [SurfaceId],
    line: EdgeLine,
    image: Vec3,
    ends: [Vec3; 2],
    /// cos β0 of the ray from the interval's ends towards the image.
    leaving: (Real, Real),
}

/// cos of the angle between unit `direction` and the ray from the point at parameter `t` of
/// `line` to `p`: (t_p − t)/√((t_p − t)² + r²), monotone in t.
fn cos_towards(line: &EdgeLine, t: Real, p: Vec3) -> Real {
    let v = p - line.point(t);
    v.dot(line.direction) / v.length()
}

/// Whether `p` lies strictly inside `edge`'s interior wedge (not in its exterior, by more
/// than [`SLACK`]): a convex region, so a segment with both ends there lies in it.
fn deep_inside(edge: &Edge, p: Vec3) -> bool {
    let a = edge.about(p);
    a.r > 0.0 && a.sin0 < -SLACK * a.r && a.sin_n < -SLACK * a.r
}

/// The ranges of cos β between `q − p` and each of the unit `directions`, for `p` on segment
/// `ps` and `q` on segment `qs` (conservative: each numerator's and the length's ranges taken
/// apart; the corners and the length bounds shared).
fn cos_ranges(ps: [Vec3; 2], qs: [Vec3; 2], directions: [Vec3; 2]) -> [(Real, Real); 2] {
    let corners = [qs[0] - ps[0], qs[0] - ps[1], qs[1] - ps[0], qs[1] - ps[1]];
    let d_hi = corners.iter().map(|v| v.length()).fold(0.0, Real::max);
    if d_hi.is_nan() || d_hi <= 0.0 {
        return [(-1.0, 1.0); 2];
    }
    let d_lo = segment_distance_bound(ps, qs);
    let ratio = |n: Real, d: Real| {
        if d > 0.0 {
            (n / d).clamp(-1.0, 1.0)
        } else {
            n.signum()
        }
    };
    directions.map(|direction| {
        let along = corners.map(|v| v.dot(direction));
        let n_lo = along.iter().copied().fold(Real::INFINITY, Real::min);
        let n_hi = along.iter().copied().fold(Real::NEG_INFINITY, Real::max);
        let lo = if n_lo >= 0.0 {
            n_lo / d_hi
        } else {
            ratio(n_lo, d_lo)
        };
        let hi = if n_hi >= 0.0 {
            ratio(n_hi, d_lo)
        } else {
            n_hi / d_hi
        };
        (lo, hi)
    })
}

/// A lower bound on the distance between two segments: the larger of their lines' distance
/// and their midpoints' distance less both half-lengths (0 at worst).
fn segment_distance_bound(ps: [Vec3; 2], qs: [Vec3; 2]) -> Real {
    let (u, v) = (ps[1] - ps[0], qs[1] - qs[0]);
    let spheres =
        (0.5 * (ps[0] + ps[1])).distance(0.5 * (qs[0] + qs[1])) - 0.5 * (u.length() + v.length());
    let normal = u.cross(v);
    let lines = if normal.length_squared() > 1e-24 * u.length_squared() * v.length_squared() {
        (qs[0] - ps[0]).dot(normal).abs() / normal.length()
    } else {
        0.0
    };
    spheres.max(lines).max(0.0)
}

/// Whether no stretch from a point of segment `near` to one of segment `far` (the second
/// edge's interval unfolded through a middle reflection) crosses the reflection's plane within
/// `margin` of its polygon's box, when the segments lie strictly on either side of the plane
/// (`dn`, `df`: the ends' signed distances from it): the crossings lie in the convex hull of the four corner-to-corner crossings
/// (the tetrahedron of the four ends meets the plane there), so when those four are beyond one
/// face of the grown box, every crossing is. Straddling segments are never rejected.
fn misses_window(
    polygon: &Polygon,
    (near, far): ([Vec3; 2], [Vec3; 2]),
    (dn, df): ([Real; 2], [Real; 2]),
    margin: Real,
) -> bool {
    let split =
        |x: [Real; 2], y: [Real; 2]| x.iter().all(|d| *d > 0.0) && y.iter().all(|d| *d < 0.0);
    if !(split(dn, df) || split(df, dn)) {
        return false;
    }
    let crossing = |i: usize, j: usize| near[i] + (far[j] - near[i]) * (dn[i] / (dn[i] - df[j]));
    let crossings = [
        crossing(0, 0),
        crossing(0, 1),
        crossing(1, 0),
        crossing(1, 1),
    ];
    let (lo, hi) = polygon.bounds();
    (0..3).any(|axis| {
        crossings.iter().all(|c| c[axis] > hi[axis] + margin)
            || crossings.iter().all(|c| c[axis] < lo[axis] - margin)
    })
}

/// Whether the ranges overlap, up to [`SLACK`].
fn overlap(a: (Real, Real), b: (Real, Real)) -> bool {
    a.0 <= b.1 + SLACK && b.0 <= a.1 + SLACK
}

impl Pairing<'_> {
    /// The candidates with two diffractions: every TX reach, RX reach and middle sequence
    /// whose depths fit the order (two edges in a row differ) and whose Keller pair lies in
    /// both reaches. Cheap necessary tests come first ([`Pairing::may_pair`]).
    pub(super) fn twice(&self, scene: &Scene, set: &mut DiffractedSet) -> Result<(), TreeError> {
        let deepest = self.side.max_order - 2;
        let reflectors: Vec<SurfaceId> = scene.reflectors().collect();
        let middles: Vec<Vec<Vec<SurfaceId>>> = (0..=deepest)
            .map(|q| crate::diffraction::sequences(&reflectors, q))
            .collect();
        let near = self.near(scene, deepest);
        self.check_pairs(&near, middles.iter().map(Vec::len).collect(), deepest)?;
        let (mut before, mut after) = (Vec::new(), Vec::new());
        // Per far interval, per first edge: whether the interval leaves that edge's interior.
        let mut seen: Vec<Option<bool>> = Vec::new();
        for (e2, on_edge) in self.from_rx.iter().enumerate() {
            for b in on_edge.iter().filter(|b| b.depth <= deepest) {
                for middle in middles[..=deepest - b.depth].iter().flatten() {
                    let far = self.far(scene, (e2, *b), middle);
                    seen.clear();
                    seen.resize(scene.edges().len(), None);
                    let fits = |a: &&Near| a.reach.depth + b.depth + middle.len() <= deepest;
                    for a in near.iter().filter(fits) {
                        if !self.may_pair(scene, (a, &far), &mut seen) || !self.may_join(a, &far) {
                            continue;
                        }
                        self.surfaces((a.reach.node, b.node), (&mut before, &mut after));
                        let pair = (EdgeId(a.edge as u32), EdgeId(e2 as u32));
                        set.push_twice(&before, pair, middle, &after);
                        self.check_budget(set)?;
                    }
                }
            }
        }
        Ok(())
    }

    /// Stop before the pairs' tests when there are more than the budget allows: the TX
    /// reaches of each depth times the RX reaches and middles that fit with them
    /// (`middles[q]`: the number of middle sequences of `q` reflections).
    fn check_pairs(
        &self,
        near: &[Near],
        middles: Vec<usize>,
        deepest: usize,
    ) -> Result<(), TreeError> {
        let count = |depths: &mut dyn Iterator<Item = usize>| {
            let mut by = vec![0u64; deepest + 1];
            depths.for_each(|d| by[d] += 1);
            by
        };
        let tx = count(&mut near.iter().map(|a| a.reach.depth));
        let rx = count(
            &mut self
                .from_rx
                .iter()
                .flatten()
                .map(|b| b.depth)
                .filter(|&d| d <= deepest),
        );
        let mut pairs = 0u64;
        for (p, &a) in tx.iter().enumerate() {
            for (r, &b) in rx.iter().enumerate().take(deepest + 1 - p) {
                let fitting: u64 = middles[..=deepest - p - r].iter().map(|&m| m as u64).sum();
                pairs = pairs.saturating_add(a.saturating_mul(b).saturating_mul(fitting));
            }
        }
        let allowed = self.budget.saturating_mul(PAIR_TESTS_PER_CANDIDATE);
        if pairs > allowed {
            return Err(TreeError::PairBudget {
                pairs,
                allowed,
                budget: self.budget,
                max_order: self.side.max_order,
            });
        }
        Ok(())
    }

    /// The TX reaches that may start a twice-diffracted path (depth at most `deepest`).
    fn near(&self, scene: &Scene, deepest: usize) -> Vec<Near> {
        let m = self.margin;
        let mut out = Vec::new();
        for (e, on_edge) in self.side.reaches.iter().enumerate() {
            let line = EdgeLine::of(&scene.edges().all()[e]);
            for r in on_edge.iter().filter(|r| r.depth <= deepest) {
                let (lo, hi) = (r.lo - m, r.hi + m);
                out.push(Near {
                    edge: e,
                    reach: *r,
                    line,
                    ends: [line.point(lo), line.point(hi)],
                    incidence: (
                        -cos_towards(&line, lo, r.image),
                        -cos_towards(&line, hi, r.image),
                    ),
                });
            }
        }
        out
    }

    /// RX reach `b` on edge `e2` with the `middle` reflections, unfolded ([`Far`]).
    fn far<'m>(&self, scene: &Scene, (e2, b): (usize, Reach), middle: &'m [SurfaceId]) -> Far<'m> {
        let mut line = EdgeLine::of(&scene.edges().all()[e2]);
        let mut image = b.image;
        for id in middle.iter().rev() {
            let plane = scene.surface(*id).polygon.plane();
            line = line.mirrored(plane);
            image = plane.mirror(image);
        }
        let (lo, hi) = (b.lo - self.margin, b.hi + self.margin);
        Far {
            edge: e2,
            reach: b,
            middle,
            line,
            image,
            ends: [line.point(lo), line.point(hi)],
            leaving: (cos_towards(&line, hi, image), cos_towards(&line, lo, image)),
        }
    }

    /// Necessary conditions of a valid path through `a`'s and `far`'s intervals (`seen`
    /// caches, per first edge, the test of `far`'s interval against it), each conservative: two edges in a row differ; the stretch between the edges leaves each
    /// into its exterior (the other interval is not wholly inside its interior wedge);
    /// across one middle reflection both points may lie on one side of its plane; Keller's
    /// law may hold at both points (the cos β0 ranges of the incident and diffracted rays
    /// over the intervals overlap).
    fn may_pair(
        &self,
        scene: &Scene,
        (a, far): (&Near, &Far<'_>),
        seen: &mut [Option<bool>],
    ) -> bool {
        let edges = scene.edges().all();
        if far.middle.is_empty() && a.edge == far.edge {
            return false;
        }
        if let [m] = far.middle {
            // Both points on one side of the middle reflection's plane: the second's real
            // place is its unfolded one mirrored back, on the other side of the plane.
            let plane = scene.surface(*m).polygon.plane();
            let first = a.ends.map(|p| plane.signed_distance(p));
            let second = far.ends.map(|p| -plane.signed_distance(p));
            let opposite = |x: [Real; 2], y: [Real; 2]| {
                x.iter().all(|d| *d > 0.0) && y.iter().all(|d| *d < 0.0)
            };
            if opposite(first, second) || opposite(second, first) {
                return false;
            }
            let unfolded = second.map(|d| -d);
            let polygon = &scene.surface(*m).polygon;
            if misses_window(polygon, (a.ends, far.ends), (first, unfolded), self.margin) {
                return false;
            }
        }
        let inside = |edge: &Edge, ends: [Vec3; 2]| ends.iter().all(|p| deep_inside(edge, *p));
        // The far interval against the first edge: one answer per edge for all its reaches.
        if !*seen[a.edge].get_or_insert_with(|| !inside(&edges[a.edge], far.ends)) {
            return false;
        }
        // The first edge's interval seen from the second edge's own frame: folded back
        // through the middle reflections.
        let folded = a.ends.map(|p| {
            far.middle
                .iter()
                .fold(p, |p, id| scene.surface(*id).polygon.plane().mirror(p))
        });
        if inside(&edges[far.edge], folded) {
            return false;
        }
        let [first, second] = cos_ranges(a.ends, far.ends, [a.line.direction, far.line.direction]);
        overlap(first, a.incidence) && overlap(second, far.leaving)
    }

    /// Whether the Keller pair of `a` and `far` lies in both reaches (within the margin), or
    /// cannot be computed.
    fn may_join(&self, a: &Near, far: &Far<'_>) -> bool {
        let Some((t1, t2)) = keller_pair(a.reach.image, a.line, far.line, far.image) else {
            return true;
        };
        let m = self.margin;
        let (a, b) = (&a.reach, &far.reach);
        t1 >= a.lo - m && t1 <= a.hi + m && t2 >= b.lo - m && t2 <= b.hi + m
    }
}
