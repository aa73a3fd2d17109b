//! Validation of a found path: points inside their polygons, neighbours on the reflecting side,
//! no segment blocked by another surface. A penetrable surface ([`Scene::penetrable`]) never
//! blocks: a segment crosses it (thin-slab transmission, no deflection), and a path's crossings
//! count in its interaction budget ([`Scene::max_interactions`]).

use bt_geom::{Real, Vec3};
use bt_scene::edges::FLAT_WEDGE_RAD;
use bt_scene::{Scene, SurfaceId, SurfaceKind};
use serde::Serialize;

/// Verdict on a path's geometry.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(tag = "verdict", rename_all = "kebab-case")]
pub enum Validity {
    /// A real specular path.
    Valid,
    /// Interaction point `index` lies outside its polygon.
    OutsidePolygon {
        /// Point index, 0-based from TX.
        index: usize,
    },
    /// The neighbours of point `index` lie on opposite sides of its surface.
    OppositeSides {
        /// Point index, 0-based from TX.
        index: usize,
    },
    /// A neighbour of point `index` lies on its plane: a grazing path, not counted as a reflection.
    Grazing {
        /// Point index, 0-based from TX.
        index: usize,
    },
    /// Segment `segment` (0 = TX to first point) crosses surface `by`.
    Blocked {
        /// Segment index, 0-based from TX.
        segment: usize,
        /// The occluding surface.
        by: SurfaceId,
    },
    /// A point is not finite (only reachable from a solver bug; never reported as valid).
    NonFinite,
    /// The diffraction point `index` lies off its edge (beyond an end, or at a corner).
    OffEdge {
        /// Point index, 0-based from TX.
        index: usize,
    },
    /// A neighbour of the diffraction point `index` lies inside the wedge or on a face: no
    /// diffraction (counted with `opposite_sides`).
    InsideWedge {
        /// Point index, 0-based from TX.
        index: usize,
    },
}

/// Validate the path TX -> points -> RX over the surface sequence `seq`.
#[inline(always)]
pub fn validate(scene: &Scene, seq: &[SurfaceId], tx: Vec3, rx: Vec3, points: &[Vec3]) -> Validity {
    if let Some(verdict) = point_verdict(scene, seq, tx, rx, points) {
        return verdict;
    }
    segment_verdict(scene, seq, tx, rx, points)
}

/// [`validate`] for a batch that only counts a blocked path (`trace`'s fold), given a `hint`:
/// a segment and the surface that blocked this candidate's path before (for a receiver
/// nearby: [`crate::hints`]). When the points pass their checks and that surface blocks that
/// segment now (by the rule of [`blocker_excluding`]), the verdict is
/// [`Validity::Blocked`] at once: [`validate`] gives `Blocked` too, since that segment's BVH
/// walk meets the surface, but its `segment` and `by` may differ (an earlier segment blocked
/// as well, another surface met first). The verdict's kind is exact, its fields are those of
/// a blocked segment. Otherwise (no hint, or it no longer blocks) [`validate`]'s verdict.
#[inline(always)]
pub(crate) fn validate_hinted(
    scene: &Scene,
    (seq, points): (&[SurfaceId], &[Vec3]),
    (tx, rx): (Vec3, Vec3),
    hint: Option<(usize, SurfaceId)>,
) -> Validity {
    if let Some(verdict) = point_verdict(scene, seq, tx, rx, points) {
        return verdict;
    }
    // A hint from another scene may name any segment and surface: only real ones are tested.
    let hint = hint
        .filter(|&(segment, by)| segment <= seq.len() && (by.0 as usize) < scene.surfaces().len());
    if let Some((segment, by)) = hint {
        let tol = scene.length_tolerance();
        let ((a, from), (b, to)) = segment_ends(seq, (tx, rx), points, segment);
        let ends = (from.as_slice(), to.as_slice());
        let t_min = tol / a.distance(b).max(tol);
        let through = may_cross(scene, seq.len());
        if stops(scene, by, ends, through, |polygon| {
            polygon.blocks_segment(a, b, t_min, tol)
        }) {
            return Validity::Blocked { segment, by };
        }
    }
    segment_verdict(scene, seq, tx, rx, points)
}

/// The verdict of the checks of `points` alone (inside their polygons, neighbours on the
/// reflecting side), `None` when they pass.
#[inline(always)]
fn point_verdict(
    scene: &Scene,
    seq: &[SurfaceId],
    tx: Vec3,
    rx: Vec3,
    points: &[Vec3],
) -> Option<Validity> {
    let tol = scene.length_tolerance();
    let n = seq.len();
    if points.iter().any(|p| !p.is_finite()) {
        return Some(Validity::NonFinite);
    }
    for k in 0..n {
        if let Some(verdict) = reflection_point(scene, seq[k], points[k], tol, k) {
            return Some(verdict);
        }
    }
    for k in 0..n {
        let (a, b) = neighbour_distances(scene, seq, (tx, rx), points, k);
        if a.abs() <= tol || b.abs() <= tol {
            return Some(Validity::Grazing { index: k });
        }
        if (a > 0.0) != (b > 0.0) {
            return Some(Validity::OppositeSides { index: k });
        }
    }
    None
}

/// The verdict of the segments of a path whose points passed [`point_verdict`]: the first
/// blocked segment, else the crossings' budget.
#[inline(always)]
fn segment_verdict(
    scene: &Scene,
    seq: &[SurfaceId],
    tx: Vec3,
    rx: Vec3,
    points: &[Vec3],
) -> Validity {
    let tol = scene.length_tolerance();
    let n = seq.len();
    let through = may_cross(scene, n);
    for segment in 0..=n {
        let ((a, from), (b, to)) = segment_ends(seq, (tx, rx), points, segment);
        let ends = (from.as_slice(), to.as_slice());
        if let Some(by) = blocker_excluding(scene, (a, b), ends, tol, through) {
            return Validity::Blocked { segment, by };
        }
    }
    if through {
        let vertex = |k: usize| match k {
            0 => tx,
            k if k == n + 1 => rx,
            k => points[k - 1],
        };
        let on = |k: usize| match k {
            0 => &[][..],
            k if k == n + 1 => &[][..],
            k => std::slice::from_ref(&seq[k - 1]),
        };
        let path = PathVertices {
            vertex: &vertex,
            on: &on,
            points: n,
        };
        return crossing_budget(scene, path, n);
    }
    Validity::Valid
}

/// A path as the crossing walks see it: `points` interaction points, vertex `k` at `vertex(k)`
/// for `k` in `0..=points + 1` (0 = TX, points + 1 = RX), lying on the surfaces `on(k)` (none
/// for a terminal, its surface for a reflection, the edge's faces for a diffraction).
#[derive(Clone, Copy)]
pub struct PathVertices<'a, 's> {
    /// Vertex `k`, metres, scene-local frame.
    pub vertex: &'a dyn Fn(usize) -> Vec3,
    /// The surfaces vertex `k` lies on.
    pub on: &'a dyn Fn(usize) -> &'s [SurfaceId],
    /// Interaction points (TX and RX excluded).
    pub points: usize,
}

/// The crossing verdict of `path`, which has `interactions` reflections and diffractions: [`Validity::Blocked`] by the first crossing (in path order)
/// beyond [`Scene::max_interactions`], else [`Validity::Valid`].
#[inline(always)]
pub fn crossing_budget<'s>(
    scene: &'s Scene,
    path: PathVertices<'_, 's>,
    interactions: usize,
) -> Validity {
    crossing_budget_recording(scene, path, interactions, |_| {})
}

/// [`crossing_budget`], calling `record` on each crossing (segment, point, surface) within
/// the budget, in path order: for a valid path, every crossing [`walk_crossings`] finds.
#[inline(always)]
pub(crate) fn crossing_budget_recording<'s>(
    scene: &'s Scene,
    path: PathVertices<'_, 's>,
    interactions: usize,
    mut record: impl FnMut((usize, Vec3, SurfaceId)),
) -> Validity {
    let mut allowed = scene.max_interactions().saturating_sub(interactions);
    let mut verdict = Validity::Valid;
    walk_crossings(scene, path, |segment, p, by| {
        if allowed == 0 {
            verdict = Validity::Blocked { segment, by };
            return false;
        }
        allowed -= 1;
        record((segment, p, by));
        true
    });
    verdict
}

/// Calls `each(segment, point, surface)` for every crossing of a penetrable surface on
/// `path`, in path order, until `each` returns false. A segment crosses a penetrable surface that it would be
/// blocked by were it opaque (the rule of [`blocker_excluding`]); where it crosses a seam
/// between coplanar faces (normals within [`FLAT_WEDGE_RAD`], crossing points within the
/// tolerance), it crosses once: the first face along the segment (the lower id at a tie).
#[inline(always)]
pub fn walk_crossings<'s>(
    scene: &'s Scene,
    path: PathVertices<'_, 's>,
    mut each: impl FnMut(usize, Vec3, SurfaceId) -> bool,
) {
    let PathVertices {
        vertex,
        on,
        points: n,
    } = path;
    let mut found: Vec<(Real, SurfaceId)> = Vec::new();
    for segment in 0..=n {
        let (a, b) = (vertex(segment), vertex(segment + 1));
        segment_crossings(scene, (a, b), (on(segment), on(segment + 1)), &mut found);
        for &(t, id) in &found {
            if !each(segment, a + t * (b - a), id) {
                return;
            }
        }
    }
}

/// The penetrable surfaces the segment `a -> b` crosses, other than those its ends lie on
/// (`from`, `to`), into `out` as (parameter along the segment, surface), ordered along it,
/// seams crossed once (see [`walk_crossings`]).
#[inline(always)]
fn segment_crossings(
    scene: &Scene,
    (a, b): (Vec3, Vec3),
    (from, to): (&[SurfaceId], &[SurfaceId]),
    out: &mut Vec<(Real, SurfaceId)>,
) {
    out.clear();
    let tol = scene.length_tolerance();
    let length = a.distance(b);
    let t_min = tol / length.max(tol);
    // `any_hit` rejecting every item: the items `first_blocking` tests (in a small scene
    // the boxes the segment touches, scanned several at once), inlined into the caller.
    scene.bvh().any_hit(a, b, 2.0 * tol, |i| {
        let id = SurfaceId(i);
        if !scene.penetrable(id) || from.contains(&id) || to.contains(&id) {
            return false;
        }
        let polygon = &scene.surface(id).polygon;
        if !polygon.blocks_segment(a, b, t_min, tol) {
            return false;
        }
        let plane = polygon.plane();
        let (da, db) = (plane.signed_distance(a), plane.signed_distance(b));
        if let Some(t) = bt_geom::Plane::crossing_parameter(da, db, a, b) {
            out.push((t, id));
        }
        false
    });
    out.sort_unstable_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
    let normal = |id: SurfaceId| scene.surface(id).polygon.plane().normal;
    let mut kept = 0;
    for k in 0..out.len() {
        let seam = out[..kept].iter().any(|&(t, id)| {
            (out[k].0 - t).abs() * length <= tol
                && normal(id).dot(normal(out[k].1)).abs() >= FLAT_WEDGE_RAD.cos()
        });
        if !seam {
            out[kept] = out[k];
            kept += 1;
        }
    }
    out.truncate(kept);
}

/// Why `p` is not a reflection point of surface `id` (point `index` of a path), or `None`
/// when it is: outside the polygon by more than `tol` is [`Validity::OutsidePolygon`]; within
/// `tol` of a diffracting edge of it (a wedge's or a free edge, [`bt_scene::Scene::edges`]) is
/// [`Validity::Grazing`]. The one rule for points on a boundary: at an edge or a corner a path
/// does not reflect (it touches the edge; with diffraction on, it is found as a diffraction,
/// whose point lies strictly inside its edge); on a seam between coplanar faces, which is no
/// edge, it reflects once, on the face of the lowest id that holds the point
/// (`seam_owner_below`); for the other faces it is [`Validity::OutsidePolygon`]. Edges and
/// seams are looked at only for points within `tol` of the boundary.
#[inline(always)]
pub fn reflection_point(
    scene: &Scene,
    id: SurfaceId,
    p: Vec3,
    tol: Real,
    index: usize,
) -> Option<Validity> {
    let polygon = &scene.surface(id).polygon;
    // Most points lie well inside: one test decides them.
    if polygon.inside_by(p, tol) {
        return None;
    }
    if !polygon.contains(p, tol) {
        return Some(Validity::OutsidePolygon { index });
    }
    if on_edge_of(scene, id, p, tol) {
        return Some(Validity::Grazing { index });
    }
    seam_owner_below(scene, id, p, tol).then_some(Validity::OutsidePolygon { index })
}

/// Whether a reflector of lower id than `id`, parallel to it (normals within
/// [`FLAT_WEDGE_RAD`], the junctions that are seams and not edges), holds `p` (within `tol` of
/// its plane and of its polygon): `p` lies on a seam of coplanar faces, and that face reflects
/// the path, so that it is found once.
#[inline(never)]
fn seam_owner_below(scene: &Scene, id: SurfaceId, p: Vec3, tol: Real) -> bool {
    let normal = scene.surface(id).polygon.plane().normal;
    let mut below = false;
    scene.bvh().visit_near(p, 2.0 * tol, |s| {
        if below || s >= id.0 {
            return;
        }
        let other = scene.surface(SurfaceId(s));
        let plane = other.polygon.plane();
        below = other.kind == SurfaceKind::Reflector
            && plane.normal.dot(normal).abs() >= FLAT_WEDGE_RAD.cos()
            && plane.signed_distance(p).abs() <= tol
            && other.polygon.contains(p, tol);
    });
    below
}

/// Whether `p` lies within `tol` of a diffracting edge that surface `id` touches.
#[inline(never)]
fn on_edge_of(scene: &Scene, id: SurfaceId, p: Vec3, tol: Real) -> bool {
    let edges = scene.edges();
    let mut near = false;
    edges.bvh().visit_near(p, 2.0 * tol, |e| {
        let edge = edges.get(bt_scene::EdgeId(e));
        let t = edge.parameter(p).clamp(0.0, edge.length);
        near |= edge.touching.contains(&id) && edge.point(t).distance(p) <= tol;
    });
    near
}

/// Signed distances (m) of point `k`'s two neighbours on the path TX -> `points` -> RX (TX or
/// the previous point, RX or the next) from its surface's plane.
#[inline(always)]
fn neighbour_distances(
    scene: &Scene,
    seq: &[SurfaceId],
    (tx, rx): (Vec3, Vec3),
    points: &[Vec3],
    k: usize,
) -> (Real, Real) {
    let plane = scene.surface(seq[k]).polygon.plane();
    let prev = if k == 0 { tx } else { points[k - 1] };
    let next = if k + 1 == seq.len() {
        rx
    } else {
        points[k + 1]
    };
    (plane.signed_distance(prev), plane.signed_distance(next))
}

/// The ends of segment `segment` (0 = TX to the first point) of the path TX -> `points` -> RX
/// over `seq`, each with the surface it lies on (`None` for TX and RX).
#[inline(always)]
fn segment_ends(
    seq: &[SurfaceId],
    (tx, rx): (Vec3, Vec3),
    points: &[Vec3],
    segment: usize,
) -> ((Vec3, Option<SurfaceId>), (Vec3, Option<SurfaceId>)) {
    let n = seq.len();
    let start = match segment {
        0 => (tx, None),
        _ => (points[segment - 1], Some(seq[segment - 1])),
    };
    let end = match segment {
        s if s == n => (rx, None),
        _ => (points[segment], Some(seq[segment])),
    };
    (start, end)
}

/// The first surface that blocks (an opaque one; a penetrable one too unless `through`: then it
/// is crossed, see [`walk_crossings`]), other than those the segment's ends lie on (`from`, `to`: none for a
/// terminal, one for a reflection point, every surface touching the edge for a diffraction
/// point), whose box grown by twice the scene's length tolerance (`blocks` may accept
/// crossings within the tolerance outside a polygon) the segment `a -> b` touches and whose
/// polygon passes `blocks`.
#[inline(always)]
fn first_blocking(
    scene: &Scene,
    (a, b): (Vec3, Vec3),
    (from, to): (&[SurfaceId], &[SurfaceId]),
    through: bool,
    mut blocks: impl FnMut(&bt_geom::Polygon) -> bool,
) -> Option<SurfaceId> {
    let margin = 2.0 * scene.length_tolerance();
    let bvh = scene.bvh();
    // A small scene's boxes are scanned at once: their items are tested in this loop, not in
    // `any_hit`'s closure, whose body would be compiled apart from a batch's FMA code.
    if let Some(mut touched) = bvh.touched_by(a, b, margin) {
        while touched != 0 {
            let id = SurfaceId(touched.trailing_zeros());
            if stops(scene, id, (from, to), through, &mut blocks) {
                return Some(id);
            }
            touched &= touched - 1;
        }
        return None;
    }
    bvh.any_hit(a, b, margin, |i| {
        stops(scene, SurfaceId(i), (from, to), through, &mut blocks)
    })
    .map(SurfaceId)
}

/// Whether surface `id` stops a segment by the rule of [`first_blocking`]: not a
/// surface an end lies on (`from`, `to`), not a penetrable one it may cross (`through`), and
/// its polygon passes `blocks`.
#[inline(always)]
fn stops(
    scene: &Scene,
    id: SurfaceId,
    (from, to): (&[SurfaceId], &[SurfaceId]),
    through: bool,
    mut blocks: impl FnMut(&bt_geom::Polygon) -> bool,
) -> bool {
    let crossed = through && scene.penetrable(id);
    !(from.contains(&id) || to.contains(&id) || crossed) && blocks(&scene.surface(id).polygon)
}

/// The first surface crossing the segment `a -> b` other than those its ends lie on (`from`,
/// `to`: several at a diffraction point, which lies on every surface touching its edge):
/// opaque surfaces only when `through` (the path may still cross penetrable ones), every
/// surface otherwise.
#[inline(always)]
pub fn blocker_excluding(
    scene: &Scene,
    (a, b): (Vec3, Vec3),
    (from, to): (&[SurfaceId], &[SurfaceId]),
    tol: Real,
    through: bool,
) -> Option<SurfaceId> {
    let length = a.distance(b);
    let t_min = tol / length.max(tol);
    first_blocking(scene, (a, b), (from, to), through, |polygon| {
        polygon.blocks_segment(a, b, t_min, tol)
    })
}

/// The first opaque surface (other than the segment's own end surfaces) crossing the segment
/// `a -> b`.
#[inline(always)]
pub fn blocker(
    scene: &Scene,
    a: Vec3,
    b: Vec3,
    from: Option<SurfaceId>,
    to: Option<SurfaceId>,
    tol: Real,
) -> Option<SurfaceId> {
    blocker_excluding(scene, (a, b), (from.as_slice(), to.as_slice()), tol, true)
}

/// Whether a path with `interactions` reflections and diffractions may still cross penetrable
/// surfaces (the scene has some, and the interaction budget is not spent): if not, a
/// penetrable surface blocks it like an opaque one, and one early-exit test decides.
#[inline(always)]
pub fn may_cross(scene: &Scene, interactions: usize) -> bool {
    scene.transmits() && scene.max_interactions() > interactions
}

/// Early stopping of IPC (`IpcOptions::early_reject`): the first segment of the path TX ->
/// `points` -> RX that stays blocked, with its blocker, when every point may still move by up
/// to `reach` metres — or `None` when that is not certain. Certain means: every point lies
/// inside its polygon by more than `reach` plus the tolerance and both its neighbours lie off
/// its plane, on its side, by as much (so validation reaches the blocking test whatever the
/// final points), and the segment's crossing with the blocker stays strictly inside it. For a
/// segment `a -> b` at distances `da`, `db` from the blocker's plane on either side
/// (`S = |da| + |db|`, length `L`), moving both ends by up to `r` moves the crossing point by
/// at most `r (1 + L / (S - 2r))` (its parameter moves by at most `r / (S - 2r)`).
#[inline(always)]
pub fn blocked_for_good(
    scene: &Scene,
    seq: &[SurfaceId],
    (tx, rx): (Vec3, Vec3),
    points: &[Vec3],
    reach: Real,
) -> Option<(usize, SurfaceId)> {
    let tol = scene.length_tolerance();
    let margin = reach + tol;
    let n = seq.len();
    for k in 0..n {
        let (a, b) = neighbour_distances(scene, seq, (tx, rx), points, k);
        let sides = (a > margin && b > margin) || (a < -margin && b < -margin);
        let polygon = &scene.surface(seq[k]).polygon;
        if !sides || !polygon.inside_by(points[k], margin) {
            return None;
        }
    }
    // A loop, not `find_map`: a closure would be compiled apart from the caller's FMA body.
    for segment in 0..=n {
        let ((a, from), (b, to)) = segment_ends(seq, (tx, rx), points, segment);
        let length = a.distance(b);
        let ends = (from.as_slice(), to.as_slice());
        let by = first_blocking(scene, (a, b), ends, true, |polygon| {
            // Unfused distances: the margins are far above their round-off, and the closure
            // may be compiled without the FMA feature (a software `fma` per call).
            let Some((crossing, span)) = polygon.plane().crossing_beyond(a, b, margin) else {
                return false;
            };
            let shift = reach * (1.0 + length / (span - 2.0 * reach));
            polygon.inside_by(crossing, tol + shift)
        });
        if let Some(by) = by {
            return Some((segment, by));
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use bt_paths::{AllVisible, enumerate};

    /// Every candidate of `scene` up to `max_order` (exhaustive: every kind of verdict),
    /// solved by the image method and validated fully, then with every segment and surface
    /// as the hint (and hints out of range): the same kind of verdict every time, and a
    /// blocked one that differs from the full test's only when it is the hint. Returns
    /// (blocked candidates, verdicts the hint gave with other fields than the full test's).
    fn check(scene: &Scene, max_order: usize) -> (usize, usize) {
        let ends = scene.terminals().unwrap();
        let set = enumerate(scene, max_order, &AllVisible).unwrap();
        let surfaces = scene.surfaces().len() as u32;
        let (mut blocked, mut differing) = (0, 0);
        for i in 0..set.len() {
            let seq = set.get(i);
            let mut points = vec![Vec3::ZERO; seq.len()];
            if crate::image::solve(scene, seq, ends.tx, ends.rx, &mut points).is_err() {
                continue;
            }
            let full = validate(scene, seq, ends.tx, ends.rx, &points);
            blocked += usize::from(matches!(full, Validity::Blocked { .. }));
            let hints = (0..=seq.len() + 1)
                .flat_map(|segment| (0..=surfaces).map(move |s| Some((segment, SurfaceId(s)))));
            for hint in std::iter::once(None).chain(hints) {
                let got = validate_hinted(scene, (seq, &points), (ends.tx, ends.rx), hint);
                let what = format!("{seq:?} with {hint:?}: {got:?}, fully {full:?}");
                assert_eq!(
                    std::mem::discriminant(&got),
                    std::mem::discriminant(&full),
                    "{what}"
                );
                if got != full {
                    let Validity::Blocked { segment, by } = got else {
                        panic!("{what}");
                    };
                    assert_eq!(Some((segment, by)), hint, "{what}");
                    differing += 1;
                }
            }
        }
        (blocked, differing)
    }

    #[test]
    fn hints_give_the_same_kind_of_verdict_in_the_living_room() {
        let scene = bt_import::builtin_scene("living-room", bt_scene::Terminals::default())
            .unwrap()
            .unwrap();
        let mut totals = (0, 0);
        for rx in [[2.0, 2.0, 1.2], [4.5, 1.0, 0.5], [1.0, 3.5, 1.7]] {
            let scene = scene.with_receiver(Vec3::from(rx)).unwrap();
            let (blocked, differing) = check(&scene, 3);
            totals = (totals.0 + blocked, totals.1 + differing);
        }
        assert!(totals.0 > 0 && totals.1 > 0, "{totals:?}");
    }

    /// Penetrable surfaces: a surface the path may cross is no blocker, even as a hint.
    #[test]
    fn hints_give_the_same_kind_of_verdict_with_penetrable_surfaces() {
        let mut totals = (0, 0);
        let mut transmitting = 0;
        for seed in 0..16 {
            let Some(scene) = bt_testkit::nasty_penetrable_scene(seed, 2, (seed % 3) as u8) else {
                continue;
            };
            transmitting += usize::from(may_cross(&scene, 2));
            let (blocked, differing) = check(&scene, 2);
            totals = (totals.0 + blocked, totals.1 + differing);
        }
        assert!(
            transmitting > 0 && totals.0 > 0 && totals.1 > 0,
            "{totals:?}"
        );
    }
}
