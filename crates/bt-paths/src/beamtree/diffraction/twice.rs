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
use bt_geom::{Plane, Polygon, Real, Vec3};
use bt_scene::edges::{EdgeLine, KellerReach, LinePair, NoKellerPair};
use bt_scene::{Edge, EdgeId, Scene, SurfaceId};
use rustc_hash::FxHashMap;
use std::sync::{Arc, Mutex, OnceLock};

/// Angular slack (rad) of the prefilters: far above round-off, far below any angle a valid
/// path could need.
const SLACK: Real = 1e-6;

/// An interval on the first edge, as the prefilters read it: its line, its ends (grown by the
/// margin) and the range of cos β0 of the incident rays over it.
#[derive(Debug, Clone, Copy)]
struct Span {
    edge: usize,
    line: EdgeLine,
    /// The interval's parameters along the line, grown by the margin (m).
    t: (Real, Real),
    ends: [Vec3; 2],
    /// cos β0 at the interval's ends (increasing along the edge), or a range holding those of
    /// several reaches.
    incidence: (Real, Real),
}

impl Span {
    fn new(edge: usize, line: EdgeLine, t: (Real, Real), incidence: (Real, Real)) -> Self {
        Span {
            edge,
            line,
            t,
            ends: [line.point(t.0), line.point(t.1)],
            incidence,
        }
    }
}

/// A TX reach on the first edge and its [`Span`].
#[derive(Debug, Clone)]
struct Near {
    span: Span,
    reach: Reach,
    /// The TX image's distance from the edge line and its parameter (m).
    focus: (Real, Real),
}

/// The TX reaches of one edge and one depth (`members`, a range of the [`Near`] list) and a
/// span holding all of theirs: the smallest interval holding their intervals and the union of
/// their incidence ranges. Each prefilter of [`Pairing::may_pair`] fails for a member's span
/// when it fails for the group's (its bounds only widen as the interval and the range grow), so
/// one test of the group rejects all its members.
#[derive(Debug, Clone)]
struct Group {
    span: Span,
    depth: usize,
    members: std::ops::Range<usize>,
}

/// The [`Group`]s of `near` (ordered by edge, each edge's reaches by depth).
fn groups(near: &[Near]) -> Vec<Group> {
    let mut out: Vec<Group> = Vec::new();
    for (i, a) in near.iter().enumerate() {
        match out.last_mut() {
            Some(g) if g.span.edge == a.span.edge && g.depth == a.reach.depth => {
                let (lo, hi) = (g.span.t.0.min(a.span.t.0), g.span.t.1.max(a.span.t.1));
                let incidence = (
                    g.span.incidence.0.min(a.span.incidence.0),
                    g.span.incidence.1.max(a.span.incidence.1),
                );
                g.span = Span::new(a.span.edge, g.span.line, (lo, hi), incidence);
                g.members.end = i + 1;
            }
            _ => out.push(Group {
                span: a.span,
                depth: a.reach.depth,
                members: i..i + 1,
            }),
        }
    }
    out
}

/// An RX reach on the second edge and the middle reflections: the edge's wedge (its line
/// among it), interval ends and the RX image, unfolded through the middle into the first
/// edge's frame, and the range of cos β0 of rays leaving towards the image.
struct Far<'m> {
    edge: usize,
    reach: Reach,
    middle: &'m [SurfaceId],
    image: Vec3,
    /// The image's distance from the unfolded edge line and its parameter (m).
    focus: (Real, Real),
    ends: [Vec3; 2],
    /// cos β0 of the ray from the interval's ends towards the image.
    leaving: (Real, Real),
    /// The second edge's interior wedge and line, unfolded.
    wedge: Wedge,
    /// With one middle reflection: its plane and the signed distances from it of the
    /// interval's real ends (the unfolded ends mirrored back), negated.
    across: Option<(Plane, [Real; 2])>,
}

/// An edge's interior wedge as [`Wedge::deep_inside`] reads it: the edge line and the outward
/// normals of its two faces' planes (`e × t0` and `tn × e`), possibly mirrored through
/// reflections (a mirror keeps every distance, so a point's distances from the mirrored
/// planes are its mirror image's from the edge's own).
#[derive(Debug, Clone, Copy)]
struct Wedge {
    line: EdgeLine,
    normal0: Vec3,
    normal_n: Vec3,
}

impl Wedge {
    fn of(edge: &Edge) -> Self {
        Wedge {
            line: EdgeLine::of(edge),
            normal0: edge.direction.cross(edge.t0),
            normal_n: edge.tn.cross(edge.direction),
        }
    }

    fn mirrored(&self, plane: &Plane) -> Self {
        Wedge {
            line: self.line.mirrored(plane),
            normal0: plane.mirror_direction(self.normal0),
            normal_n: plane.mirror_direction(self.normal_n),
        }
    }

    /// Whether `p` lies strictly inside the wedge (not in the edge's exterior, by more than
    /// [`SLACK`] of its distance from the line): a convex region, so a segment with both ends
    /// there lies in it.
    #[inline(always)]
    fn deep_inside(&self, p: Vec3) -> bool {
        let v = p - self.line.start;
        let r = self.line.distance(p);
        r > 0.0 && v.dot(self.normal0) < -SLACK * r && v.dot(self.normal_n) < -SLACK * r
    }
}

/// cos of the angle between unit `direction` and the ray from the point at parameter `t` of
/// `line` to `p`: (t_p − t)/√((t_p − t)² + r²), monotone in t.
fn cos_towards(line: &EdgeLine, t: Real, p: Vec3) -> Real {
    let v = p - line.point(t);
    v.dot(line.direction) / v.length()
}

/// The ranges of cos β between `q − p` and each of the unit `directions`, for `p` on segment
/// `ps` and `q` on segment `qs` (conservative: each numerator's and the length's ranges taken
/// apart; the corners and the length bounds shared).
#[inline(always)]
fn cos_ranges(ps: [Vec3; 2], qs: [Vec3; 2], directions: [Vec3; 2]) -> [(Real, Real); 2] {
    let corners = [qs[0] - ps[0], qs[0] - ps[1], qs[1] - ps[0], qs[1] - ps[1]];
    let d_hi = corners.iter().map(|v| v.length()).fold(0.0, Real::max);
    if d_hi.is_nan() || d_hi <= 0.0 {
        return [(-1.0, 1.0); 2];
    }
    let d_lo = segment_distance_bound(ps, qs);
    // Written out, not `array::map`: that one is a call, compiled without the FMA feature.
    let along = |d: Vec3| {
        [
            corners[0].dot(d),
            corners[1].dot(d),
            corners[2].dot(d),
            corners[3].dot(d),
        ]
    };
    let bounds = (d_lo, d_hi);
    [
        cos_bounds(&along(directions[0]), bounds),
        cos_bounds(&along(directions[1]), bounds),
    ]
}

/// The range of cos β = n/|v| over vectors `v` whose numerators `n` lie between the least and
/// the greatest of `along` (the extreme corners of a convex set of vectors) and whose lengths
/// lie in `(d_lo, d_hi)`, d_hi > 0 (conservative: each taken apart).
#[inline(always)]
fn cos_bounds(along: &[Real], (d_lo, d_hi): (Real, Real)) -> (Real, Real) {
    let ratio = |n: Real, d: Real| {
        if d > 0.0 {
            (n / d).clamp(-1.0, 1.0)
        } else {
            n.signum()
        }
    };
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
}

/// The range of cos β between `m − p` and the unit `direction`, for `p` on segment `ends` and
/// `m` in the box `(lo, hi)` (conservative, as [`cos_ranges`]; the whole range when the box
/// may touch the segment).
#[inline(always)]
fn cos_range_to_box(ends: [Vec3; 2], (lo, hi): (Vec3, Vec3), direction: Vec3) -> (Real, Real) {
    let corner = |k: usize| {
        Vec3::new(
            if k & 1 == 0 { lo.x } else { hi.x },
            if k & 2 == 0 { lo.y } else { hi.y },
            if k & 4 == 0 { lo.z } else { hi.z },
        )
    };
    let mut along = [0.0; 16];
    let mut d_hi: Real = 0.0;
    for k in 0..8 {
        for (j, p) in ends.iter().enumerate() {
            let v = corner(k) - *p;
            along[2 * k + j] = v.dot(direction);
            d_hi = d_hi.max(v.length());
        }
    }
    if d_hi.is_nan() || d_hi <= 0.0 {
        return (-1.0, 1.0);
    }
    let (center, radius) = (0.5 * (lo + hi), 0.5 * (hi - lo).length());
    let d_lo = (point_segment_distance(center, ends) - radius).max(0.0);
    cos_bounds(&along, (d_lo, d_hi))
}

/// The distance (m) from `p` to the segment `ends`.
#[inline(always)]
fn point_segment_distance(p: Vec3, ends: [Vec3; 2]) -> Real {
    let u = ends[1] - ends[0];
    let l2 = u.length_squared();
    let t = if l2 > 0.0 {
        ((p - ends[0]).dot(u) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    p.distance(ends[0] + t * u)
}

/// A lower bound on the distance between two segments: the larger of their lines' distance
/// and their midpoints' distance less both half-lengths (0 at worst).
#[inline(always)]
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
#[inline(always)]
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

/// What the join takes from the TX side alone, for one margin (m): its reaches that may
/// start a twice-diffracted path, their [`Group`]s and the reflector index ([`Toward`]).
/// Kept with the [`DiffractionSide`](super::DiffractionSide) while only RX moves.
#[derive(Debug, Clone)]
pub(super) struct TxPart {
    margin: Real,
    near: Vec<Near>,
    groups: Vec<Group>,
    index: Toward,
    /// Every edge's [`Wedge`], by edge index (the scene's alone, made once with the rest).
    wedges: Vec<Wedge>,
}

impl TxPart {
    fn of(pairing: &Pairing<'_>, scene: &Scene, deepest: usize) -> Self {
        let near = pairing.near(scene, deepest);
        let groups = groups(&near);
        let index = Toward::of(scene, pairing.margin, deepest);
        TxPart {
            margin: pairing.margin,
            near,
            groups,
            index,
            wedges: scene.edges().all().iter().map(Wedge::of).collect(),
        }
    }
}

/// The join's working state for one TX side: its reaches, their groups and scratch.
struct Pairs<'a> {
    near: &'a [Near],
    groups: &'a [Group],
    /// The most reflections a path with two diffractions has room for.
    deepest: usize,
    /// Per far interval, per first edge: whether the interval leaves that edge's interior.
    seen: Vec<Option<bool>>,
    /// Every edge's wedge ([`TxPart::wedges`]).
    wedges: &'a [Wedge],
    before: Vec<SurfaceId>,
    after: Vec<SurfaceId>,
}

/// A group in a [`Toward`] list: its index into the groups and, in the lists per second
/// edge, its interval (grown as [`Pairing::beyond`] reads it, [`widened`]) seen from that
/// edge's line as the far intervals on it unfold it ([`EdgeLine::keller_reach`]): the part
/// of `beyond`'s Keller range that the TX side and the scene give, the same bits as made
/// there.
#[derive(Debug, Clone, Copy)]
struct Listed {
    group: u32,
    seen: Option<KellerReach>,
}

impl Listed {
    /// Group `group` of `groups` seen from the (unfolded) second edge line `line`.
    fn seen_from(line: &EdgeLine, groups: &[Group], group: u32) -> Self {
        let span = &groups[group as usize].span;
        Listed {
            group,
            seen: Some(line.keller_reach(&span.line, widened(span))),
        }
    }
}

/// A span's interval grown by [`APART_SLACK`] (m), as [`Pairing::beyond`] reads it.
#[inline(always)]
fn widened(span: &Span) -> (Real, Real) {
    (span.t.0 - APART_SLACK, span.t.1 + APART_SLACK)
}

/// Per reflector, the groups of TX reaches whose diffracted rays may head into its box: a
/// path `D1 → M → ...` reflecting at `M` right after `D1` leaves `D1` along `M − D1`, whose
/// cos β0 with the first edge equals the incident ray's (Keller), and `M` lies in the
/// reflector's polygon, within the margin of its box. A group whose range of that cosine
/// ([`cos_range_to_box`]) misses its incidence range pairs with no interval beyond that
/// reflector, so the join never looks at those pairs. Likewise per second edge, for paths
/// with no middle reflection: `D1 → D2` leaves `D1` towards the second edge's segment
/// ([`heads_into`]), and per (reflector, second edge) for paths with that one middle
/// reflection: the reflector's groups whose rays may head into the second edge's segment
/// mirrored through it.
/// Each list holds its groups by depth (ascending), so that a far interval takes the
/// prefix whose depths fit; the lists per second edge hold with each group its interval seen
/// from that edge's (unfolded) line ([`Listed`]).
#[derive(Debug, Clone)]
struct Toward {
    /// Per surface id: the groups for a middle starting there, made when first asked for
    /// ([`Toward::starting_at`]).
    groups: Vec<OnceLock<Vec<Listed>>>,
    /// Per surface id: a reflector's polygon box grown by the margin (m).
    boxes: Vec<(Vec3, Vec3)>,
    /// Per second edge: the groups for paths with no middle reflection, made when first
    /// asked for ([`Toward::straight`]).
    straight: Vec<OnceLock<Vec<Listed>>>,
    /// Per (surface id, second edge) asked for: the groups for a middle of that one
    /// reflection, made when first asked for ([`Toward::across`]). A map, not a table of
    /// every pair: a city has ~10⁹ pairs (a table of empty slots was 10-20 GB).
    across: Across,
    /// The margin (m).
    margin: Real,
    /// The most reflections a path with two diffractions has room for.
    deepest: usize,
}

/// [`Toward::across`]'s lists by (surface id, second edge), shared with the callers (the
/// lock is held only to look up or insert).
#[derive(Debug, Default)]
struct Across(Mutex<FxHashMap<(u32, u32), Shared>>);

/// A list of [`Across`], shared.
type Shared = Arc<[Listed]>;

impl Clone for Across {
    fn clone(&self) -> Self {
        let map = self.0.lock().unwrap_or_else(|e| e.into_inner());
        Across(Mutex::new(map.clone()))
    }
}

/// A list of groups that the join reads: borrowed from a [`Toward`] or shared with its map.
enum Lists<'a> {
    Borrowed(&'a [Listed]),
    Shared(Shared),
}

impl std::ops::Deref for Lists<'_> {
    type Target = [Listed];

    fn deref(&self) -> &[Listed] {
        match self {
            Lists::Borrowed(list) => list,
            Lists::Shared(list) => list,
        }
    }
}

impl Toward {
    fn of(scene: &Scene, margin: Real, deepest: usize) -> Self {
        let mut boxes = vec![(Vec3::ZERO, Vec3::ZERO); scene.surfaces().len()];
        for m in scene.reflectors() {
            let (lo, hi) = scene.surface(m).polygon.bounds();
            boxes[m.index()] = (lo - Vec3::splat(margin), hi + Vec3::splat(margin));
        }
        Toward {
            groups: vec![OnceLock::new(); scene.surfaces().len()],
            boxes,
            straight: vec![OnceLock::new(); scene.edges().len()],
            across: Across::default(),
            margin,
            deepest,
        }
    }

    /// The groups whose diffracted rays may head into reflector `m`'s box (see the type), by
    /// depth.
    fn starting_at(&self, groups: &[Group], m: SurfaceId) -> &[Listed] {
        self.groups[m.index()].get_or_init(|| {
            let bounds = self.boxes[m.index()];
            let mut list: Vec<u32> = (0..groups.len() as u32)
                .filter(|&g| {
                    let span = &groups[g as usize].span;
                    let range = cos_range_to_box(span.ends, bounds, span.line.direction);
                    overlap(range, span.incidence)
                })
                .collect();
            list.sort_by_key(|&g| (groups[g as usize].depth, g));
            (list.into_iter())
                .map(|group| Listed { group, seen: None })
                .collect()
        })
    }

    /// The groups for paths with no middle reflection to edge `e2` of `scene` ([`heads_into`]
    /// its segment grown by the margin), by depth.
    fn straight(&self, scene: &Scene, groups: &[Group], e2: usize) -> &[Listed] {
        self.straight[e2].get_or_init(|| {
            let edge = &scene.edges().all()[e2];
            let line = EdgeLine::of(edge);
            let whole = [
                line.point(-self.margin),
                line.point(edge.length + self.margin),
            ];
            let mut list: Vec<u32> = (0..groups.len() as u32)
                .filter(|&g| {
                    let span = &groups[g as usize].span;
                    span.edge != e2 && heads_into(span, whole)
                })
                .collect();
            list.sort_by_key(|&g| (groups[g as usize].depth, g));
            (list.into_iter())
                .map(|g| Listed::seen_from(&line, groups, g))
                .collect()
        })
    }

    /// The groups for paths with the one middle reflection `m` to edge `e2` of `scene`: those
    /// of `m`'s list ([`Toward::groups`], by depth) with room for the middle (depth below
    /// `deepest`), not [`surely_apart`] from the edge across `m`'s plane, that [`heads_into`]
    /// the edge's segment,
    /// grown by the margin, mirrored through `m`'s plane as [`Pairing::far`] unfolds it (the
    /// far intervals on the edge behind `m` are parts of that segment, as for
    /// [`Toward::straight`]).
    fn across(&self, scene: &Scene, groups: &[Group], m: SurfaceId, e2: usize) -> Shared {
        let key = (m.0, e2 as u32);
        let lock = || self.across.0.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(list) = lock().get(&key) {
            return list.clone();
        }
        let list = self.across_anew(scene, groups, m, e2);
        lock().entry(key).or_insert(list).clone()
    }

    /// [`Toward::across`]'s list, made.
    fn across_anew(&self, scene: &Scene, groups: &[Group], m: SurfaceId, e2: usize) -> Shared {
        let edge = &scene.edges().all()[e2];
        let line = EdgeLine::of(edge).mirrored(scene.surface(m).polygon.plane());
        let whole = [
            line.point(-self.margin),
            line.point(edge.length + self.margin),
        ];
        // The second edge's real ends' side of the plane (the unfolded ends mirrored back).
        let plane = scene.surface(m).polygon.plane();
        let behind = whole.map(|p| -plane.signed_distance(p));
        let list = self.starting_at(groups, m);
        let fit = list.partition_point(|l| groups[l.group as usize].depth < self.deepest);
        (list[..fit].iter())
            .filter(|l| {
                let span = &groups[l.group as usize].span;
                heads_into(span, whole)
                    && !surely_apart(span.ends.map(|p| plane.signed_distance(p)), behind)
            })
            .map(|l| Listed::seen_from(&line, groups, l.group))
            .collect()
    }

    /// The groups that may pair with `far`, or `None` when none may: with one middle
    /// reflection, the ray arriving at the far interval from the reflector's box must obey
    /// Keller's law there too (cos β0 of `q − M` against the leaving range).
    fn groups(&self, scene: &Scene, groups: &[Group], far: &Far<'_>) -> Option<Lists<'_>> {
        let Some(&m) = far.middle.first() else {
            return Some(Lists::Borrowed(self.straight(scene, groups, far.edge)));
        };
        if far.middle.len() == 1 {
            let direction = far.wedge.line.direction;
            let (lo, hi) = cos_range_to_box(far.ends, self.boxes[m.index()], direction);
            if !overlap((-hi, -lo), far.leaving) {
                return None;
            }
            return Some(Lists::Shared(self.across(scene, groups, m, far.edge)));
        }
        Some(Lists::Borrowed(self.starting_at(groups, m)))
    }
}

/// Whether rays from `span`'s interval to the segment `whole` (a second edge grown by the
/// margin, or that mirrored through one middle reflection: every far interval on that edge,
/// with that middle, is a part of it, on the same line) may
/// obey Keller's law at the first edge, with twice [`SLACK`]. When this fails, so does
/// [`Pairing::may_pair`]'s first test for every far interval on the edge: a part's
/// numerators lie between `whole`'s corners' and its lengths between the bounds taken here
/// (the distance bound of the segments' enclosing spheres, less [`NEAR`], is below the
/// part's), up to round-off; the distance bound of at least [`NEAR`] keeps that round-off's
/// effect on the cosines far below the slack (closer segments always pass).
fn heads_into(span: &Span, whole: [Vec3; 2]) -> bool {
    let ps = span.ends;
    let corners = [
        whole[0] - ps[0],
        whole[0] - ps[1],
        whole[1] - ps[0],
        whole[1] - ps[1],
    ];
    let d_hi = corners.iter().map(|v| v.length()).fold(0.0, Real::max);
    let (u, v) = (ps[1] - ps[0], whole[1] - whole[0]);
    let spheres = (0.5 * (ps[0] + ps[1])).distance(0.5 * (whole[0] + whole[1]))
        - 0.5 * (u.length() + v.length());
    let d_lo = spheres - NEAR;
    // Also false for NaN.
    if !(d_lo >= NEAR && d_hi > 0.0) {
        return true;
    }
    let direction = span.line.direction;
    let along = [
        corners[0].dot(direction),
        corners[1].dot(direction),
        corners[2].dot(direction),
        corners[3].dot(direction),
    ];
    let at = cos_bounds(&along, (d_lo, d_hi));
    at.0 <= span.incidence.1 + 2.0 * SLACK && span.incidence.0 <= at.1 + 2.0 * SLACK
}

/// Whether the span with signed distances `first` from a middle reflection's plane and every
/// part of the second edge's segment whose real ends have the signed distances `whole` lie
/// strictly on opposite sides of it, as [`Pairing::may_pair`] tests a part (its ends'
/// distances lie between the whole's up to round-off, far below [`NEAR`], which the whole's
/// must exceed).
fn surely_apart(first: [Real; 2], whole: [Real; 2]) -> bool {
    let beyond = |x: [Real; 2], sign: Real| x.iter().all(|d| sign * d > NEAR);
    let on = |x: [Real; 2], sign: Real| x.iter().all(|d| sign * d > 0.0);
    (on(first, 1.0) && beyond(whole, -1.0)) || (on(first, -1.0) && beyond(whole, 1.0))
}

/// Length (m) below which [`heads_into`] takes two segments as close (and passes them).
const NEAR: Real = 1e-6;

/// Length slack (m) of [`Pairing::apart`]'s intervals: far above their round-off and the
/// Keller pair's tolerance, far below any reach.
const APART_SLACK: Real = 1e-6;

/// Rounds of [`Pairing::apart`].
const APART_ROUNDS: usize = 2;

/// `into` cut to a range of Keller points `by` grown by [`APART_SLACK`]: whether it is now
/// empty, or `None` (`into` unchanged) when there is no range.
#[inline(always)]
fn shrink(into: &mut (Real, Real), by: Option<(Real, Real)>) -> Option<bool> {
    let (lo, hi) = by?;
    *into = (into.0.max(lo - APART_SLACK), into.1.min(hi + APART_SLACK));
    Some(into.0 > into.1)
}

/// Whether a Keller pair inside both reaches (within the margin), solved to `residual`,
/// proves that [`Pairing::obeys_keller`] holds for its group and far interval: its points
/// lie on the intervals the test reads (the span's and the far interval's, both grown by
/// the margin as the inside test is), so the test's conservative cos β0 ranges hold the
/// diffracted rays' cosines there and the incidence and leaving ranges the incident
/// rays' (each monotone along its edge, so held between its ends' values). Those differ by
/// at most the residual at each point, so with a residual of at most half of [`SLACK`]
/// the ranges overlap, the other half far above the tests' round-off.
#[inline(always)]
fn vouches(residual: Real) -> bool {
    residual <= 0.5 * SLACK
}

/// Whether the ranges overlap, up to [`SLACK`].
fn overlap(a: (Real, Real), b: (Real, Real)) -> bool {
    a.0 <= b.1 + SLACK && b.0 <= a.1 + SLACK
}

impl Pairing<'_> {
    /// The candidates with two diffractions: every TX reach, RX reach and middle sequence
    /// whose depths fit the order (two edges in a row differ) and whose Keller pair lies in
    /// both reaches. Cheap necessary tests come first ([`Pairing::may_pair`] on each group of
    /// TX reaches, then [`Pairing::apart`] on each reach).
    /// Compiled with the `fma` target feature when the CPU has it (checked at run time; the
    /// plane tests use `mul_add`, a software call without it; bit-identical either way, as
    /// in `bt_solve`'s batches).
    pub(super) fn twice(&self, scene: &Scene, set: &mut DiffractedSet) -> Result<(), TreeError> {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("fma") {
            // SAFETY: the CPU supports FMA (checked just above).
            return unsafe { self.twice_fma(scene, set) };
        }
        self.twice_impl(scene, set)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "fma")]
    fn twice_fma(&self, scene: &Scene, set: &mut DiffractedSet) -> Result<(), TreeError> {
        self.twice_impl(scene, set)
    }

    #[inline(always)]
    fn twice_impl(&self, scene: &Scene, set: &mut DiffractedSet) -> Result<(), TreeError> {
        let deepest = self.side.max_order - 2;
        let reflectors: Vec<SurfaceId> = scene.reflectors().collect();
        let middles: Vec<Vec<Vec<SurfaceId>>> = (0..=deepest)
            .map(|q| crate::diffraction::sequences(&reflectors, q))
            .collect();
        // The TX side's part, kept with the side for the next receiver (built anew for
        // another margin, which a kept side's RX trees in one scene do not give).
        let kept = self
            .side
            .twice
            .get_or_init(|| TxPart::of(self, scene, deepest));
        let fresh;
        let tx = if kept.margin == self.margin {
            kept
        } else {
            fresh = TxPart::of(self, scene, deepest);
            &fresh
        };
        let (near, index) = (&tx.near, &tx.index);
        self.check_pairs(near, middles.iter().map(Vec::len).collect(), deepest)?;
        let mut pairs = Pairs {
            near,
            groups: &tx.groups,
            deepest,
            seen: Vec::new(),
            wedges: &tx.wedges,
            before: Vec::new(),
            after: Vec::new(),
        };
        for (e2, on_edge) in self.from_rx.iter().enumerate() {
            for b in on_edge.iter().filter(|b| b.depth <= deepest) {
                for middle in middles[..=deepest - b.depth].iter().flatten() {
                    let far = self.far(scene, (e2, *b), middle, pairs.wedges[e2]);
                    let Some(first) = index.groups(scene, &tx.groups, &far) else {
                        continue;
                    };
                    self.pair_with(scene, &far, &first, &mut pairs, set)?;
                }
            }
        }
        Ok(())
    }

    /// The candidates of `far` with the groups `first` (indices into `pairs.groups`, with
    /// their intervals seen from `far`'s line when known) whose depths fit.
    #[inline(always)]
    fn pair_with(
        &self,
        scene: &Scene,
        far: &Far<'_>,
        first: &[Listed],
        pairs: &mut Pairs<'_>,
        set: &mut DiffractedSet,
    ) -> Result<(), TreeError> {
        let b = &far.reach;
        pairs.seen.clear();
        pairs.seen.resize(scene.edges().len(), None);
        // The lists hold their groups by depth: those that fit come first.
        let room = pairs.deepest - b.depth - far.middle.len();
        let fit = first.partition_point(|l| pairs.groups[l.group as usize].depth <= room);
        for listed in &first[..fit] {
            let g = &pairs.groups[listed.group as usize];
            let seen = (&mut pairs.seen[..], pairs.wedges);
            if self.beyond(&g.span, far, listed.seen) || !self.may_pair(scene, (&g.span, far), seen)
            {
                continue;
            }
            // The members go straight to the Keller pair: their own prefilters, run again,
            // dropped no candidate on the living room that the pair keeps and cost more
            // than the pair's own first test ([`Pairing::apart`]).
            // The first test of each member's `apart`, less its own point: one for the group.
            let toward = g
                .span
                .line
                .keller_reach(&far.wedge.line, self.grown(&far.reach));
            // The group's Keller-law test ([`Pairing::obeys_keller`]), made at its first
            // candidate whose pair does not vouch for it ([`vouches`]): when it fails, the
            // group has none (and no pair that vouches).
            let mut keller_law = None;
            // The two edge lines' part of the Keller pairs' solves, made for the group's
            // first pair (the members share the group's edge line).
            let mut lines = None;
            for a in &pairs.near[g.members.clone()] {
                let Some((keller, vouched)) = self.may_join(a, far, (toward, &mut lines)) else {
                    continue;
                };
                if !vouched && !*keller_law.get_or_insert_with(|| self.obeys_keller(&g.span, far)) {
                    break;
                }
                let (before, after) = (&mut pairs.before, &mut pairs.after);
                self.surfaces((a.reach.node, b.node), (before, after));
                let edges = (EdgeId(a.span.edge as u32), EdgeId(far.edge as u32));
                set.push_twice(before, edges, far.middle, after, Some(keller));
                self.check_budget(set)?;
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
                let incidence = (
                    -cos_towards(&line, lo, r.image),
                    -cos_towards(&line, hi, r.image),
                );
                out.push(Near {
                    span: Span::new(e, line, (lo, hi), incidence),
                    reach: *r,
                    focus: (line.distance(r.image), line.along(r.image)),
                });
            }
        }
        out
    }

    /// RX reach `b` on edge `e2` (whose [`Wedge`] is `wedge`) with the `middle` reflections,
    /// unfolded ([`Far`]).
    fn far<'m>(
        &self,
        scene: &Scene,
        (e2, b): (usize, Reach),
        middle: &'m [SurfaceId],
        mut wedge: Wedge,
    ) -> Far<'m> {
        let mut image = b.image;
        for id in middle.iter().rev() {
            let plane = scene.surface(*id).polygon.plane();
            wedge = wedge.mirrored(plane);
            image = plane.mirror(image);
        }
        let line = wedge.line;
        let (lo, hi) = (b.lo - self.margin, b.hi + self.margin);
        let ends = [line.point(lo), line.point(hi)];
        let across = match middle {
            [m] => {
                let plane = *scene.surface(*m).polygon.plane();
                Some((plane, ends.map(|p| -plane.signed_distance(p))))
            }
            _ => None,
        };
        Far {
            edge: e2,
            reach: b,
            middle,
            image,
            focus: (line.distance(image), line.along(image)),
            ends,
            leaving: (cos_towards(&line, hi, image), cos_towards(&line, lo, image)),
            wedge,
            across,
        }
    }

    /// Necessary conditions of a valid path through `a`'s and `far`'s intervals, each
    /// conservative: two edges in a row differ; across one middle reflection both points may
    /// lie on one side of its plane and the stretch may cross its window; the stretch between
    /// the edges leaves each into its exterior (the other interval is not wholly inside its
    /// interior wedge; `seen` caches, per first edge, the test of `far`'s interval against
    /// it, `wedges` the edges' wedges). The join also asks [`Pairing::obeys_keller`] of a
    /// group, but only once one of its members has a candidate.
    #[inline(always)]
    fn may_pair(
        &self,
        scene: &Scene,
        (a, far): (&Span, &Far<'_>),
        (seen, wedges): (&mut [Option<bool>], &[Wedge]),
    ) -> bool {
        if far.middle.is_empty() && a.edge == far.edge {
            return false;
        }
        if let (Some((plane, second)), [m]) = (&far.across, far.middle) {
            // Both points on one side of the middle reflection's plane: the second's real
            // place is its unfolded one mirrored back, on the other side of the plane.
            let first = [
                plane.signed_distance(a.ends[0]),
                plane.signed_distance(a.ends[1]),
            ];
            let opposite = |x: [Real; 2], y: [Real; 2]| {
                x.iter().all(|d| *d > 0.0) && y.iter().all(|d| *d < 0.0)
            };
            if opposite(first, *second) || opposite(*second, first) {
                return false;
            }
            let unfolded = [-second[0], -second[1]];
            let polygon = &scene.surface(*m).polygon;
            if misses_window(polygon, (a.ends, far.ends), (first, unfolded), self.margin) {
                return false;
            }
        }
        let inside = |wedge: &Wedge, ends: [Vec3; 2]| ends.iter().all(|p| wedge.deep_inside(*p));
        // The far interval against the first edge: one answer per edge for all its reaches.
        if !*seen[a.edge].get_or_insert_with(|| !inside(&wedges[a.edge], far.ends)) {
            return false;
        }
        // The first edge's interval against the second edge's wedge, unfolded into this frame.
        if inside(&far.wedge, a.ends) {
            return false;
        }
        true
    }

    /// Whether Keller's law may hold at both points of a path through `a`'s and `far`'s
    /// intervals: the cos β0 ranges of the incident and diffracted rays over the intervals
    /// overlap (conservative). After the per-edge and per-reflector lists ([`Toward`], whose
    /// [`heads_into`] is this test's first half against a whole second edge) and
    /// [`Pairing::beyond`] it fails for few groups (under 4 % in the living room), so the
    /// join makes it only for a group with a candidate, and drops the group's candidates
    /// when it fails: the candidates this test made first would have given.
    #[inline(always)]
    fn obeys_keller(&self, a: &Span, far: &Far<'_>) -> bool {
        let directions = [a.line.direction, far.wedge.line.direction];
        let [at_first, at_second] = cos_ranges(a.ends, far.ends, directions);
        overlap(at_first, a.incidence) && overlap(at_second, far.leaving)
    }

    /// Whether the Keller pair of `a` and `far` surely lies outside their reaches (grown by
    /// the margin): the pair `(t1, t2)` has `t1` at the Keller point of the TX image and
    /// the point `t2`, and `t2` at that of the point `t1` and the RX image. So if `t2` lies in
    /// its interval, `t1` lies in the range of Keller points over that interval
    /// ([`EdgeLine::keller_range`]), and in turn for `t2`: each interval shrinks to its
    /// intersection with that range, and an empty one proves the pair outside. `toward` is
    /// the far reach (grown) seen from `a`'s line ([`EdgeLine::keller_reach`]), the first
    /// range's part shared by a group's members.
    #[inline(always)]
    fn apart(&self, a: &Near, far: &Far<'_>, toward: KellerReach) -> bool {
        let mut near = self.grown(&a.reach);
        let mut away = self.grown(&far.reach);
        let (first, second) = (&a.span.line, &far.wedge.line);
        for round in 0..APART_ROUNDS {
            let range = if round == 0 {
                toward.range(a.focus)
            } else {
                first.keller_range(a.focus, second, away)
            };
            match shrink(&mut near, range) {
                Some(true) => return true,
                Some(false) => {}
                None => return false,
            }
            match shrink(&mut away, second.keller_range(far.focus, first, near)) {
                Some(true) => return true,
                Some(false) => {}
                None => return false,
            }
        }
        false
    }

    /// Whether no reach of `span` (a group's) can pair with `far`: the second point of a pair
    /// is the Keller point of the first and the RX image, so it lies in the range of those
    /// over the span's interval ([`EdgeLine::keller_range`]); when that range misses the far
    /// reach (grown as in [`Pairing::apart`]), so does every pair. `seen`: the span's
    /// interval seen from `far`'s line ([`Listed`]), made here when not given.
    #[inline(always)]
    fn beyond(&self, span: &Span, far: &Far<'_>, seen: Option<KellerReach>) -> bool {
        let seen = seen.unwrap_or_else(|| far.wedge.line.keller_reach(&span.line, widened(span)));
        shrink(&mut self.grown(&far.reach), seen.range(far.focus)) == Some(true)
    }

    /// `reach`'s interval grown by the margin and [`APART_SLACK`] (m), as [`Pairing::apart`]
    /// and [`Pairing::beyond`] test it.
    #[inline(always)]
    fn grown(&self, reach: &Reach) -> (Real, Real) {
        let grow = self.margin + APART_SLACK;
        (reach.lo - grow, reach.hi + grow)
    }

    /// `Some` when the Keller pair of `a` and `far` lies in both reaches (within the margin),
    /// with the pair, or its solve did not settle (`Some(None)`); `None` when it lies outside
    /// or there is none, the shortest path through the lines' crossing.
    /// The pair's inputs are the image method's for the candidate
    /// ([`DiffractedSet::keller`]), so the solve reuses it. `toward` as for
    /// [`Pairing::apart`]; `lines`, the two edge lines' part of the solve
    /// ([`LinePair`]), made here when not yet made. The ends' distances and parameters
    /// are the ones `a` and `far` keep (`focus`: [`EdgeLine::distance`] and
    /// [`EdgeLine::along`] of the same points on the same lines, so the same bits as
    /// [`bt_scene::edges::keller_pair_checked`] makes). With the pair, whether it vouches
    /// for the group's Keller-law test ([`vouches`]).
    #[inline(always)]
    fn may_join(
        &self,
        a: &Near,
        far: &Far<'_>,
        (toward, lines): (KellerReach, &mut Option<LinePair>),
    ) -> Option<(Option<(Real, Real)>, bool)> {
        if self.apart(a, far, toward) {
            return None;
        }
        let lines = lines.get_or_insert_with(|| LinePair::new(a.span.line, far.wedge.line));
        let pair = match lines.keller_pair((a.reach.image, a.focus), (far.image, far.focus)) {
            Ok(pair) => pair,
            // No path over both edges at all ([`NoKellerPair::Crossing`]): the image method
            // would count the candidate degenerate, and IPC could only meet the crossing.
            Err(NoKellerPair::Crossing) => return None,
            Err(NoKellerPair::Unsettled) => return Some((None, false)),
        };
        let (t1, t2) = pair.at;
        let m = self.margin;
        let (a, b) = (&a.reach, &far.reach);
        let inside = t1 >= a.lo - m && t1 <= a.hi + m && t2 >= b.lo - m && t2 <= b.hi + m;
        inside.then_some((Some((t1, t2)), vouches(pair.residual)))
    }
}
