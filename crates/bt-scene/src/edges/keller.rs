//! The two diffraction points of a path over two edges (issue 28).
//!
//! Unfolded through its reflections, a path `a → D1 → D2 → b` with D1 on one edge line and D2
//! on another has the length f(t1, t2) = |P1(t1) − a| + |P2(t2) − P1(t1)| + |b − P2(t2)|, a
//! convex function of the two parameters (a sum of norms of affine maps), strictly so when
//! neither `a` nor `b` lies on its line. Its minimum is the one point where both diffractions
//! obey Keller's law. [`keller_pair`] finds it by Newton's method from the one-edge closed
//! forms ([`EdgeLine::keller`]), falling back to a coordinate round (each point moved to its
//! neighbours' Keller point, which never lengthens the path) whenever a Newton step would not
//! shorten it.

use super::Edge;
use bt_geom::{Plane, Real, Vec3};

/// A line of an unfolded path: a point on it and its unit direction (metres, scene frame).
/// Parameters are metres from `start` along `direction`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EdgeLine {
    /// A point of the line (an edge's start), metres.
    pub start: Vec3,
    /// Unit direction.
    pub direction: Vec3,
}

/// Stop when a round moves neither point by more than this, metres.
pub const KELLER_PAIR_TOL: Real = 1e-10;

/// The Keller residual (|cos β_in − cos β_out| at either edge) [`keller_pair`] aims for once
/// the points have settled.
pub const KELLER_RESIDUAL: Real = 1e-10;

/// Rounds [`keller_pair`] may add after the points settled, for [`KELLER_RESIDUAL`].
const POLISH_ROUNDS: usize = 3;

/// Most rounds of [`keller_pair`] before it gives up.
const MAX_ROUNDS: usize = 64;

impl EdgeLine {
    /// The line of `edge` (same start and parameters).
    pub fn of(edge: &Edge) -> Self {
        EdgeLine {
            start: edge.start,
            direction: edge.direction,
        }
    }

    /// The point at parameter `t`.
    #[inline]
    pub fn point(&self, t: Real) -> Vec3 {
        self.start + t * self.direction
    }

    /// The line mirrored through `plane` (a parameter names the mirrored point).
    pub fn mirrored(&self, plane: &Plane) -> Self {
        EdgeLine {
            start: plane.mirror(self.start),
            direction: plane.mirror_direction(self.direction),
        }
    }

    /// The distance of `p` from the line (m).
    #[inline]
    pub fn distance(&self, p: Vec3) -> Real {
        self.offset(p).length()
    }

    /// `p`'s offset from the line, perpendicular to it (m).
    #[inline]
    fn offset(&self, p: Vec3) -> Vec3 {
        let v = p - self.start;
        v - v.dot(self.direction) * self.direction
    }

    /// The parameter of `p`'s projection on the line (m).
    #[inline]
    pub fn along(&self, p: Vec3) -> Real {
        (p - self.start).dot(self.direction)
    }

    /// The Keller point of `a → line → b`: the parameter `t* = (d_b·t_a + d_a·t_b)/(d_a + d_b)`,
    /// `d` the distances to the line and `t` the projections on it (the one closed form,
    /// [`Edge::keller`] too); `None` when both lie on the line.
    #[inline]
    pub fn keller(&self, a: Vec3, b: Vec3) -> Option<Real> {
        self.keller_from(self.distance(a), self.along(a), b)
    }

    /// [`Self::keller`] with `a` given by its distance from the line and its parameter (for
    /// one `a` against many `b`; the same value, bit for bit).
    #[inline]
    pub fn keller_from(&self, a_distance: Real, a_along: Real, b: Vec3) -> Option<Real> {
        let (da, db) = (a_distance, self.distance(b));
        let sum = da + db;
        (sum > 0.0 && sum.is_finite()).then(|| (db * a_along + da * self.along(b)) / sum)
    }

    /// An interval of parameters on this line holding the Keller point of `a` and each point
    /// of `other` with its parameter in `range` (m), `a` given by its distance from this line
    /// and its parameter ([`Self::keller_from`]). Conservative: the Keller point is
    /// `t_a + (t_q − t_a)·d_a/(d_a + d_q)` for `q` at distance `d_q` and parameter `t_q`, and
    /// the offset `t_q − t_a` (affine along `other`: extreme at the ends) and the weight (from
    /// the least and greatest `d_q`, the distance being convex along `other`) are bounded
    /// apart. `None` when the Keller point may be undefined (a point of `other` in the range
    /// and `a` both on this line) or a value is not finite.
    #[inline(always)]
    pub fn keller_range(
        &self,
        focus: (Real, Real),
        other: &EdgeLine,
        range: (Real, Real),
    ) -> Option<(Real, Real)> {
        self.keller_reach(other, range).range(focus)
    }

    /// The part of [`Self::keller_range`] that depends on `other` and `range` alone, for one
    /// stretch against several points `a` ([`KellerReach::range`]; the same interval, bit for
    /// bit).
    #[inline(always)]
    pub fn keller_reach(&self, other: &EdgeLine, (lo, hi): (Real, Real)) -> KellerReach {
        let (p, q) = (other.point(lo), other.point(hi));
        // The offset from the line is affine along `other`.
        let u = self.offset(p);
        let w = self.offset(q) - u;
        let ww = w.length_squared();
        let s = if ww > 0.0 {
            (-u.dot(w) / ww).clamp(0.0, 1.0)
        } else {
            0.0
        };
        KellerReach {
            along: (self.along(p), self.along(q)),
            distance: ((u + s * w).length(), u.length().max((u + w).length())),
        }
    }
}

/// A stretch of another line as [`EdgeLine::keller_range`] reads it, seen from this line: its
/// ends' parameters on this line and the least and greatest distances of its points from
/// this line (m).
#[derive(Debug, Clone, Copy)]
pub struct KellerReach {
    along: (Real, Real),
    distance: (Real, Real),
}

impl KellerReach {
    /// [`EdgeLine::keller_range`] of the stretch and `a`, given by its distance from the line
    /// and its parameter (m).
    #[inline(always)]
    pub fn range(&self, (a_distance, a_along): (Real, Real)) -> Option<(Real, Real)> {
        let (m0, m1) = (self.along.0 - a_along, self.along.1 - a_along);
        let (d_lo, d_hi) = self.distance;
        let (w_lo, w_hi) = (
            a_distance / (a_distance + d_hi),
            a_distance / (a_distance + d_lo),
        );
        let bounds = [m0 * w_lo, m0 * w_hi, m1 * w_lo, m1 * w_hi];
        let k_lo = bounds.iter().copied().fold(Real::INFINITY, Real::min);
        let k_hi = bounds.iter().copied().fold(Real::NEG_INFINITY, Real::max);
        (a_distance + d_lo > 0.0 && k_lo.is_finite() && k_hi.is_finite())
            .then_some((a_along + k_lo, a_along + k_hi))
    }
}

/// The parameters (t1 on `first`, t2 on `second`) of the shortest path `a → first → second →
/// b` (module docs), to [`KELLER_PAIR_TOL`] and, a few rounds allowing, [`KELLER_RESIDUAL`].
/// `None` when a point of the path falls on its neighbour (the two points on the lines'
/// crossing included) or the solve does not settle from either end.
///
/// The solve starts from one end (its first guess is that end's Keller point), so it runs
/// from the end that sorts first (`a` or `b`, by coordinates), then from the other if that
/// fails: a path and its reverse get the same parameters, bit for bit, and a start that
/// stalls (a short middle leg near the lines' crossing) gets a second chance.
pub fn keller_pair(a: Vec3, first: EdgeLine, second: EdgeLine, b: Vec3) -> Option<(Real, Real)> {
    keller_pair_settled(a, first, second, b).map(|pair| pair.at)
}

/// The parameters of [`keller_pair`] and the Keller residual where its solve stopped.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KellerPair {
    /// (t1 on the first line, t2 on the second), metres: [`keller_pair`]'s, bit for bit.
    pub at: (Real, Real),
    /// The larger of |cos β_in − cos β_out| at the two points, at `at` (at most
    /// [`KELLER_RESIDUAL`] unless the solve stopped on its round cap; infinite when a leg had
    /// no length there, NaN when the residual could not be made).
    pub residual: Real,
}

/// [`keller_pair`] with the residual where its solve stopped ([`KellerPair`]).
pub fn keller_pair_settled(
    a: Vec3,
    first: EdgeLine,
    second: EdgeLine,
    b: Vec3,
) -> Option<KellerPair> {
    keller_pair_checked(a, first, second, b).ok()
}

/// Why [`keller_pair_checked`] gives no pair.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NoKellerPair {
    /// The lines cross and the shortest path runs through their crossing, both points
    /// there: the length is convex, so it has no other stationary point (another would be
    /// a minimum too, and the strictly convex length has one), and no path over both lines
    /// obeys Keller's law with a middle leg of positive length.
    Crossing,
    /// The solve did not settle from either end, or a point fell on its neighbour.
    Unsettled,
}

/// [`keller_pair_settled`], telling why there is no pair ([`NoKellerPair`]): the same pair,
/// bit for bit, when there is one.
pub fn keller_pair_checked(
    a: Vec3,
    first: EdgeLine,
    second: EdgeLine,
    b: Vec3,
) -> Result<KellerPair, NoKellerPair> {
    let lines = LinePair::new(first, second);
    lines.keller_pair((a, focus(&first, a)), (b, focus(&second, b)))
}

/// Two edge lines of [`keller_pair_checked`] (first, second) and their crossing, when they
/// cross: what its solve makes of the lines alone, made once for one pair of lines against
/// many ends ([`LinePair::keller_pair`]).
#[derive(Debug, Clone, Copy)]
pub struct LinePair {
    lines: (EdgeLine, EdgeLine),
    /// The crossing (the middle of the lines' closest points), `d1·d2` and `1 − (d1·d2)²`,
    /// when the lines are not parallel and pass within a nanometre of each other.
    crossing: Option<(Vec3, Real, Real)>,
}

impl LinePair {
    /// The pair `first`, `second`.
    #[inline(always)]
    pub fn new(first: EdgeLine, second: EdgeLine) -> Self {
        LinePair {
            lines: (first, second),
            crossing: crossing(first, second),
        }
    }

    /// [`keller_pair_checked`] of `a` and `b` on these lines, each end given with its
    /// distance from its line and its parameter on it (`a` on the first line, `b` on the
    /// second: [`EdgeLine::distance`], [`EdgeLine::along`]): the same result, bit for bit.
    #[inline(always)]
    pub fn keller_pair(
        &self,
        (a, a_on): (Vec3, (Real, Real)),
        (b, b_on): (Vec3, (Real, Real)),
    ) -> Result<KellerPair, NoKellerPair> {
        let (first, second) = self.lines;
        // The same test from either end (the crossing's subgradient condition is symmetric).
        if self
            .crossing
            .is_some_and(|c| through_crossing(a, self.lines, b, c))
        {
            return Err(NoKellerPair::Crossing);
        }
        let forward = || keller_pair_from((a, a_on), (first, second), (b, b_on));
        let backward = || {
            keller_pair_from((b, b_on), (second, first), (a, a_on)).map(
                |KellerPair {
                     at: (t2, t1),
                     residual,
                 }| {
                    KellerPair {
                        at: (t1, t2),
                        residual,
                    }
                },
            )
        };
        let key = |v: Vec3| [v.x, v.y, v.z];
        let from_b = key(b)
            .iter()
            .zip(key(a))
            .map(|(x, y)| x.total_cmp(&y))
            .find(|o| o.is_ne())
            == Some(std::cmp::Ordering::Less);
        let pair = if from_b {
            backward().or_else(forward)
        } else {
            forward().or_else(backward)
        };
        pair.ok_or(NoKellerPair::Unsettled)
    }
}

/// [`keller_pair`] solved from `a`'s end, the path not through the lines' crossing, each end
/// with its distance from its line and its parameter ([`focus`]).
fn keller_pair_from(
    (a, a_on): (Vec3, (Real, Real)),
    (first, second): (EdgeLine, EdgeLine),
    (b, b_on): (Vec3, (Real, Real)),
) -> Option<KellerPair> {
    // `b`'s Keller point on `second` from `p` (the closed form with its two points swapped
    // back, so the same operations as `second.keller(p, b)`).
    let to_b = |p: Vec3| keller_of(focus(&second, p), b_on);
    let round = |t2: Real| {
        let t1 = keller_of(a_on, focus(&first, second.point(t2)))?;
        Some((t1, to_b(first.point(t1))?))
    };
    let local = |t: (Real, Real)| local(a, (first, second), b, t);
    let t1 = keller_of(a_on, focus(&first, b))?;
    let (mut t1, mut t2) = round(to_b(first.point(t1))?)?;
    let mut here = local((t1, t2));
    let mut polished = 0;
    for done in 1..=MAX_ROUNDS {
        let (s1, s2) = here.step?.by;
        let there = local((t1 + s1, t2 + s2));
        let next = if there.length <= here.length {
            here = there;
            (t1 + s1, t2 + s2)
        } else {
            let next = round(t2)?;
            here = local(next);
            next
        };
        let moved = (next.0 - t1).abs().max((next.1 - t2).abs());
        (t1, t2) = next;
        if !(t1.is_finite() && t2.is_finite()) {
            return None;
        }
        // Settled: the points stopped moving and Keller's law holds to KELLER_RESIDUAL
        // (a short middle leg turns a tiny move into a larger angle: then a few more
        // rounds, never a lost solution).
        if moved <= KELLER_PAIR_TOL {
            let residual = here.step.map_or(0.0, |s| s.residual);
            let settled = residual <= KELLER_RESIDUAL || residual.is_nan();
            if settled || polished == POLISH_ROUNDS || done == MAX_ROUNDS {
                return Some(KellerPair {
                    at: (t1, t2),
                    residual: here.step.map_or(Real::INFINITY, |s| s.residual),
                });
            }
            polished += 1;
        }
    }
    None
}

/// A point's distance from `line` and its parameter on it (m).
#[inline(always)]
fn focus(line: &EdgeLine, p: Vec3) -> (Real, Real) {
    (line.distance(p), line.along(p))
}

/// [`EdgeLine::keller`] from both points' [`focus`]es: the same operations, so the same bits.
#[inline(always)]
fn keller_of((da, ta): (Real, Real), (db, tb): (Real, Real)) -> Option<Real> {
    let sum = da + db;
    (sum > 0.0 && sum.is_finite()).then(|| (db * ta + da * tb) / sum)
}

/// Lines closer than this (m) cross, for [`shortest_at_crossing`].
const CROSSING_M: Real = 1e-9;

/// Whether the two lines cross (edges meeting at a corner) and the shortest path lies through
/// the crossing, both points there: the length is not smooth there (the middle leg has no
/// length), where Newton's method and the coordinate rounds creep for tens of rounds. The
/// crossing `C` is the minimum when zero is a subgradient there: some `w`, |w| ≤ 1 (the middle
/// leg's), with `d1·w = d1·u1` and `d2·w = d2·u3` (`u1`, `u3` the unit legs from `a` to `C` and
/// from `C` to `b`); the shortest such `w` lies in the lines' plane.
#[cfg(test)]
fn shortest_at_crossing(a: Vec3, lines: (EdgeLine, EdgeLine), b: Vec3) -> bool {
    crossing(lines.0, lines.1).is_some_and(|c| through_crossing(a, lines, b, c))
}

/// The lines' part of [`shortest_at_crossing`]: their crossing, `c = d1·d2` and
/// `det = 1 − c²`, or `None` when they are (nearly) parallel or do not cross.
#[inline(always)]
fn crossing(first: EdgeLine, second: EdgeLine) -> Option<(Vec3, Real, Real)> {
    let (d1, d2) = (first.direction, second.direction);
    let c = d1.dot(d2);
    let det = 1.0 - c * c;
    if det <= 1e-12 {
        return None;
    }
    let w0 = first.start - second.start;
    let (d, e) = (d1.dot(w0), d2.dot(w0));
    let (p, q) = (
        first.point((c * e - d) / det),
        second.point((e - c * d) / det),
    );
    (p.distance(q) <= CROSSING_M).then(|| (0.5 * (p + q), c, det))
}

/// The ends' part of [`shortest_at_crossing`], the lines crossing at `corner`.
#[inline(always)]
fn through_crossing(
    a: Vec3,
    (first, second): (EdgeLine, EdgeLine),
    b: Vec3,
    (corner, c, det): (Vec3, Real, Real),
) -> bool {
    let (d1, d2) = (first.direction, second.direction);
    let (v1, v3) = (corner - a, b - corner);
    if v1.length() <= CROSSING_M || v3.length() <= CROSSING_M {
        return false;
    }
    let (alpha, beta) = (d1.dot(v1.normalize()), d2.dot(v3.normalize()));
    let (x, y) = ((alpha - c * beta) / det, (beta - c * alpha) / det);
    x * alpha + y * beta < 1.0 - 1e-9
}

/// The path length at (t1, t2) and Newton's step there ([`newton_step`]), from the same legs.
struct Local {
    /// |P1 − a| + |P2 − P1| + |b − P2| (m).
    length: Real,
    /// `None` when a leg has no length.
    step: Option<Step>,
}

#[inline(always)]
fn local(a: Vec3, lines: (EdgeLine, EdgeLine), b: Vec3, (t1, t2): (Real, Real)) -> Local {
    let (p, q) = (lines.0.point(t1), lines.1.point(t2));
    let legs = [p - a, q - p, b - q];
    let lengths = legs.map(|v| v.length());
    Local {
        length: lengths[0] + lengths[1] + lengths[2],
        step: newton_step(lines, legs, lengths),
    }
}

/// Newton's step (Δt1, Δt2) for the path length at the point whose three legs (from `a` to
/// P1, P1 to P2, P2 to `b`) and their lengths are given: −H⁻¹·∇f, with ∇|v| = J^T·u and
/// ∇²|v| = J^T·(I − u·u^T)·J/|v| for each leg v (unit u, Jacobian J); NaN (a step that
/// shortens nothing, so the caller takes a coordinate round) when the Hessian is not positive
/// definite. `None` when a leg has no length.
#[inline(always)]
fn newton_step(
    (first, second): (EdgeLine, EdgeLine),
    legs: [Vec3; 3],
    lengths: [Real; 3],
) -> Option<Step> {
    let unit = |k: usize| (lengths[k] > 0.0).then(|| (legs[k] / lengths[k], lengths[k]));
    let ((u1, l1), (u2, l2), (u3, l3)) = (unit(0)?, unit(1)?, unit(2)?);
    let (d1, d2) = (first.direction, second.direction);
    let (a1, a2, b2, b3) = (d1.dot(u1), d1.dot(u2), d2.dot(u2), d2.dot(u3));
    let (g1, g2) = (a1 - a2, b2 - b3);
    let h11 = (1.0 - a1 * a1) / l1 + (1.0 - a2 * a2) / l2;
    let h22 = (1.0 - b2 * b2) / l2 + (1.0 - b3 * b3) / l3;
    let h12 = (a2 * b2 - d1.dot(d2)) / l2;
    let det = h11 * h22 - h12 * h12;
    let residual = g1.abs().max(g2.abs());
    if !(det > 0.0 && det.is_finite()) {
        return Some(Step {
            by: (Real::NAN, Real::NAN),
            residual,
        });
    }
    Some(Step {
        by: (-(h22 * g1 - h12 * g2) / det, -(h11 * g2 - h12 * g1) / det),
        residual,
    })
}

/// A Newton step and the Keller residual where it starts.
#[derive(Clone, Copy)]
struct Step {
    /// (Δt1, Δt2), metres.
    by: (Real, Real),
    /// The larger of |cos β_in − cos β_out| at the two edges.
    residual: Real,
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A seeded stream of numbers in [−1, 1) (a 64-bit LCG: deterministic, no dependency).
    struct Stream(u64);
    impl Stream {
        fn next(&mut self) -> Real {
            self.0 = self
                .0
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (self.0 >> 11) as Real / (1u64 << 52) as Real - 1.0
        }
        fn vec(&mut self, scale: Real) -> Vec3 {
            Vec3::new(self.next(), self.next(), self.next()) * scale
        }
    }

    /// On random lines and points (skew, nearly parallel, crossing), the solution obeys
    /// Keller's law at both points to 1e-9 and no nearby pair of points is shorter: the
    /// stationary point of a convex length is its minimum.
    #[test]
    fn the_pair_obeys_keller_at_both_points_and_is_shortest() {
        let mut rng = Stream(7);
        for case in 0..2000 {
            let first = EdgeLine {
                start: rng.vec(5.0),
                direction: rng.vec(1.0).normalize(),
            };
            let tilt = if case % 4 == 0 { 1e-3 } else { 1.0 };
            let second = EdgeLine {
                start: rng.vec(5.0),
                direction: (first.direction + tilt * rng.vec(1.0)).normalize(),
            };
            let (a, b) = (rng.vec(20.0), rng.vec(20.0));
            let Some((t1, t2)) = keller_pair(a, first, second, b) else {
                panic!("case {case}: no solution");
            };
            // The settled pair is the same, with the residual where the solve stopped.
            let settled = keller_pair_settled(a, first, second, b).unwrap();
            assert_eq!(settled.at, (t1, t2), "case {case}");
            assert!(settled.residual < 1e-9, "case {case}: {}", settled.residual);
            let (p, q) = (first.point(t1), second.point(t2));
            let cos = |from: Vec3, to: Vec3, e: Vec3| (to - from).normalize().dot(e);
            assert!(
                (cos(a, p, first.direction) - cos(p, q, first.direction)).abs() < 1e-9,
                "case {case}: Keller at the first edge"
            );
            assert!(
                (cos(p, q, second.direction) - cos(q, b, second.direction)).abs() < 1e-9,
                "case {case}: Keller at the second edge"
            );
            let length = |t1: Real, t2: Real| {
                let (p, q) = (first.point(t1), second.point(t2));
                p.distance(a) + q.distance(p) + b.distance(q)
            };
            let best = length(t1, t2);
            for (d1, d2) in [
                (1e-3, 0.0),
                (-1e-3, 0.0),
                (0.0, 1e-3),
                (0.0, -1e-3),
                (1e-3, -1e-3),
            ] {
                assert!(length(t1 + d1, t2 + d2) >= best - 1e-12, "case {case}");
            }
        }
    }

    /// Lines that cross (edges meeting at a corner): where the subgradient test says the
    /// shortest path runs through the crossing, no small move of either point shortens it
    /// (so by convexity nothing does) and there is no pair; elsewhere the pair is found and
    /// is no longer than the path through the crossing. Both answers occur.
    #[test]
    fn through_a_crossing_there_is_no_pair_and_elsewhere_the_pair_is_shorter() {
        let mut rng = Stream(11);
        let mut seen = [0usize; 2];
        for case in 0..2000 {
            let corner = rng.vec(3.0);
            let (d1, d2) = (rng.vec(1.0).normalize(), rng.vec(1.0).normalize());
            let (s1, s2) = (rng.next() * 2.0, rng.next() * 2.0);
            let first = EdgeLine {
                start: corner - s1 * d1,
                direction: d1,
            };
            let second = EdgeLine {
                start: corner - s2 * d2,
                direction: d2,
            };
            let (a, b) = (rng.vec(6.0), rng.vec(6.0));
            let length = |t1: Real, t2: Real| {
                let (p, q) = (first.point(t1), second.point(t2));
                p.distance(a) + q.distance(p) + b.distance(q)
            };
            let through = length(s1, s2);
            if shortest_at_crossing(a, (first, second), b) {
                seen[0] += 1;
                assert_eq!(keller_pair(a, first, second, b), None, "case {case}");
                let why = keller_pair_checked(a, first, second, b);
                assert_eq!(why, Err(NoKellerPair::Crossing), "case {case}");
                for (e1, e2) in [(1e-4, 0.0), (0.0, 1e-4), (1e-4, 1e-4), (1e-4, -1e-4)] {
                    for sign in [1.0, -1.0] {
                        let moved = length(s1 + sign * e1, s2 + sign * e2);
                        assert!(moved >= through - 1e-12, "case {case}");
                    }
                }
            } else if let Some((t1, t2)) = keller_pair(a, first, second, b) {
                seen[1] += 1;
                assert!(length(t1, t2) <= through + 1e-12, "case {case}");
            }
        }
        assert!(seen.iter().all(|&n| n > 100), "{seen:?}");
    }

    /// The Keller points of a point and the points of a stretch of another line lie in
    /// [`EdgeLine::keller_range`]'s interval (sampled densely, ends included), and the
    /// interval is not much wider than the points' own spread on most cases.
    #[test]
    fn keller_points_over_a_stretch_lie_in_its_range() {
        let mut rng = Stream(23);
        let mut tight = 0;
        for case in 0..2000 {
            let line = EdgeLine {
                start: rng.vec(5.0),
                direction: rng.vec(1.0).normalize(),
            };
            let other = EdgeLine {
                start: rng.vec(5.0),
                direction: rng.vec(1.0).normalize(),
            };
            let a = if case % 5 == 0 {
                line.point(rng.next())
            } else {
                rng.vec(10.0)
            };
            let (t0, len) = (rng.next() * 5.0, (rng.next() + 1.0) * 2.0);
            let range = (t0, t0 + len);
            let focus = (line.distance(a), line.along(a));
            let Some((lo, hi)) = line.keller_range(focus, &other, range) else {
                assert_eq!(focus.0, 0.0, "case {case}");
                continue;
            };
            let (mut seen_lo, mut seen_hi) = (Real::INFINITY, Real::NEG_INFINITY);
            for k in 0..=200 {
                let q = other.point(range.0 + len * k as Real / 200.0);
                let Some(t) = line.keller(a, q) else { continue };
                assert!(
                    t >= lo - 1e-9 && t <= hi + 1e-9,
                    "case {case}: {t} not in {lo}..{hi}"
                );
                (seen_lo, seen_hi) = (seen_lo.min(t), seen_hi.max(t));
            }
            tight += usize::from(hi - lo <= 2.0 * (seen_hi - seen_lo) + 1e-9);
        }
        assert!(tight > 1000, "{tight}");
    }

    /// Parallel lines in a plane with the points: the path is the straight line's, bent where
    /// it crosses each line, and the parameters are the crossings' (a closed form).
    #[test]
    fn the_pair_on_parallel_lines_in_a_plane_is_the_crossings() {
        let first = EdgeLine {
            start: Vec3::new(0.0, 0.0, 1.0),
            direction: Vec3::Y,
        };
        let second = EdgeLine {
            start: Vec3::new(4.0, 0.0, 1.0),
            direction: Vec3::Y,
        };
        let (a, b) = (Vec3::new(-3.0, -2.0, 0.0), Vec3::new(9.0, 7.0, 0.0));
        // Unfolded about the lines the path is straight: y advances in proportion to the
        // distance travelled across the lines (each leg's length perpendicular to them).
        let (t1, t2) = keller_pair(a, first, second, b).unwrap();
        let across = [
            (3.0f64.powi(2) + 1.0).sqrt(),
            4.0,
            (5.0f64.powi(2) + 1.0).sqrt(),
        ];
        let total: Real = across.iter().sum();
        assert!((t1 - (-2.0 + 9.0 * across[0] / total)).abs() < 1e-9, "{t1}");
        assert!(
            (t2 - (-2.0 + 9.0 * (across[0] + across[1]) / total)).abs() < 1e-9,
            "{t2}"
        );
    }
}
