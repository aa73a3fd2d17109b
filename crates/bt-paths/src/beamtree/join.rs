//! The deferred level's (parent, reflector) pairs joined from RX's side (issue 29, "RX-side
//! pruning"): instead of clipping and probing every reflector `s` that meets a parent's beam,
//! the deferred level tries only the pairs this join yields.
//!
//! A node `(c, s)` of the deferred level gives a candidate when RX lies in its beam, or when a
//! leaf `t` passes the leaf test ([`super::Probe`]). Either way a ray from `c`'s apex `I`
//! (its image source) meets `s`'s plane at a point `p` of the node's window and goes on to RX
//! (through `t`'s polygon on the way). Unfolded through `s`, the ray is a straight line from
//! `I` through `p` to `J'`, RX mirrored through `s` (or through `t` and then `s`), with `p`
//! between them. So `I` lies in the *cone* of rays from `J'` through `p`'s region, beyond
//! `s`'s plane: RX's depth-1 node on `s`, or its depth-2 node `(t, s)` (the part of `s`'s
//! grown hull inside `t`'s mirror beam, [`super::reach`]). The join builds these cones once
//! per reflector `s` (`t` from the reach lists), grouped by the side of `s`'s plane their apex
//! lies on, each group with a box around its cones inside the parents' apexes' box; a child
//! `s` of a parent (found by the parent's box test as before) is then clipped and probed only
//! when the parent's apex lies in a group's box and in one of its cones: a few compares and
//! dot products instead of a clip and a probe for each of the pairs no cone holds. Used from
//! [`JOIN_FROM`] parents in large scenes, always in small ones ([`pays`]).
//!
//! Margins: `p`'s region is `s`'s hull grown by half the reach lists' margin (a
//! well-conditioned node's window, relaxed by the probe's one tolerance, lies within a
//! quarter of it, [`super::reach::Reach::answers`]), clipped by `t`'s mirror beam with the
//! whole margin; a cone's side plane is left out (widening the cone) when rounding could
//! orient it wrongly, every plane test keeps the margin, and an apex within the margin of
//! `s`'s plane joins every parent. A node whose beam is not well defined (a sliver window far
//! from its apex, or a sharp corner) can still
//! pass the probe outside these cones: such nodes give candidates only by rounding, and the
//! trace's paths do not depend on them (docs/beam-tree.md, "The deferred level's pairs from
//! RX's side").

use super::reach::Reach;
use super::{BeamTree, Facing, LINEAR_SCAN, Mirrored, Prepared, chunked, side_plane};
use bt_geom::{Plane, Real, Vec3, convex};
use bt_scene::SurfaceId;

/// Reflectors per parallel task of [`Joined::of`].
const CHUNK: usize = 64;

/// Per reflector `s`, the cones that a parent's apex must lie in for the node `(parent, s)`
/// to pass the probe (see the module).
pub(super) struct Joined {
    /// Per surface: its cones ([`Span`]), those whose apex lies on the positive side of its
    /// plane first, then the others, and a box around each group's cones inside the
    /// parents' apexes' box; `None`: every parent joins it.
    spans: Vec<Option<Span>>,
    /// The cones of each task of [`Joined::of`], where they were made (no copy).
    parts: Vec<Part>,
    margin: Real,
}

/// The cones of some reflectors: per cone, its side planes' range in `planes`.
#[derive(Default)]
struct Part {
    cones: Vec<(u32, u32)>,
    planes: Vec<Plane>,
}

/// One reflector's cones in [`Part::cones`] of part `part`, and a box (min, max) around each of its two
/// groups' cones within the parents' apexes' box (empty for an empty group), read first:
/// most parents' apexes lie outside it (one cache line instead of the cones' planes).
#[derive(Clone, Copy)]
struct Span {
    part: u32,
    cones: (u32, u32, u32),
    bounds: [(Vec3, Vec3); 2],
}

/// A box holding nothing (the identity of [`union`]).
const EMPTY: (Vec3, Vec3) = (Vec3::splat(Real::INFINITY), Vec3::splat(Real::NEG_INFINITY));

/// The box around two boxes.
fn union(a: (Vec3, Vec3), b: (Vec3, Vec3)) -> (Vec3, Vec3) {
    (a.0.min(b.0), a.1.max(b.1))
}

/// The box (min, max; m) around the apexes of the nodes `tree.nodes[lo..hi]`.
pub(super) fn apex_box(tree: &BeamTree, (lo, hi): (usize, usize)) -> (Vec3, Vec3) {
    (tree.nodes[lo..hi].iter()).fold(EMPTY, |b, n| union(b, (n.image, n.image)))
}

/// From this many parents, a large scene's deferred level uses the join: its cones cost
/// about the same whatever the number of parents, the tries they spare grow with it
/// (order 3, one thread, CPU time of the whole trace: Florence's 9,139 parents −6 %, San
/// Francisco's 12,822 −6 %; Munich's 3,460 +2 %, Etoile's 3,057 +4 %).
const JOIN_FROM: usize = 8_192;

/// Whether the deferred level of a trace to `max_order` with `parents` parents uses the
/// join: at order 3 (its parents are the first level's nodes), in large scenes from
/// [`JOIN_FROM`] parents, always in small ones (so that the property tests exercise it).
pub(super) fn pays(prep: &Prepared<'_>, max_order: usize, parents: usize) -> bool {
    max_order == 3 && (prep.reflectors.len() <= LINEAR_SCAN || parents >= JOIN_FROM)
}

impl Joined {
    /// The cones of every reflector for the RX of `mirrored`, whose reach lists are `reach`,
    /// and the parents whose apexes lie in the box `area` (min, max; m).
    pub(super) fn of(
        prep: &Prepared<'_>,
        mirrored: &Mirrored,
        reach: &Reach,
        area: (Vec3, Vec3),
    ) -> Joined {
        let side = RxSide::new(prep, (mirrored, reach), area);
        let mut joined = Joined {
            spans: vec![None; prep.planes.len()],
            parts: Vec::new(),
            margin: side.margin,
        };
        let parts = chunked::map_chunks(prep, (&prep.reflectors, Some(CHUNK)), |chunk| {
            let (mut q, mut part, mut spans) = (Query::default(), Part::default(), Vec::new());
            for &s in chunk {
                if let Some(span) = side.cones_of(prep, s, &mut q, &mut part) {
                    spans.push((s, span));
                }
            }
            (part, spans)
        });
        for (part, spans) in parts {
            for (s, span) in spans {
                let part = joined.parts.len() as u32;
                joined.spans[s as usize] = Some(Span { part, ..span });
            }
            joined.parts.push(part);
        }
        joined
    }

    /// Whether the node of reflector `s` under a parent with apex `apex` may pass the probe:
    /// the apex lies in one of `s`'s cones (within the margin).
    pub(super) fn joins(&self, prep: &Prepared<'_>, s: u32, apex: Vec3) -> bool {
        let Some(Span {
            part,
            cones,
            bounds,
        }) = self.spans[s as usize]
        else {
            return true;
        };
        let part = &self.parts[part as usize];
        let (lo, mid, hi) = cones;
        let held = |(min, max): (Vec3, Vec3)| apex.cmpge(min).all() && apex.cmple(max).all();
        let [positive, negative] = bounds.map(held);
        if !positive && !negative {
            return false;
        }
        let d = prep.plane(s).signed_distance_unfused(apex);
        // A cone lies beyond the plane from its apex: a parent's apex on the negative side
        // can only lie in the cones from the positive side, and the reverse.
        let inside = |k: u32| {
            let (a, b) = part.cones[k as usize];
            (part.planes[a as usize..b as usize].iter())
                .all(|pl| pl.signed_distance_unfused(apex) >= -self.margin)
        };
        (positive && d <= self.margin && (lo..mid).any(inside))
            || (negative && d >= -self.margin && (mid..hi).any(inside))
    }
}

/// RX's side of the join: its mirror images and each visible reflector's mirror beam.
struct RxSide<'a> {
    mirrored: &'a Mirrored,
    reach: &'a Reach,
    /// Per surface: the planes of its mirror beam (empty: RX within the margin of its plane,
    /// or not visible).
    beams: Vec<Vec<Plane>>,
    margin: Real,
    /// The parents' apexes' box (min, max), grown by the margin.
    area: (Vec3, Vec3),
}

/// Scratch of one task of [`Joined::of`].
#[derive(Default)]
struct Query {
    window: Vec<Vec3>,
    tmp: Vec<Vec3>,
    ts: Vec<u32>,
    /// The cones whose apex lies on the negative side, before they join the part.
    negative: Part,
}

impl<'a> RxSide<'a> {
    fn new(
        prep: &Prepared<'_>,
        (mirrored, reach): (&'a Mirrored, &'a Reach),
        area: (Vec3, Vec3),
    ) -> Self {
        let margin = reach.margin();
        let mut beams = vec![Vec::new(); prep.planes.len()];
        if let Some(visible) = prep.rx_visible.as_ref() {
            for &t in &visible.ids {
                let (d_rx, image) = mirrored[t as usize];
                if d_rx.abs() > margin {
                    let beam = &mut beams[t as usize];
                    super::beam_planes(prep.plane(t), image, prep.hull(t), beam);
                }
            }
        }
        let grow = Vec3::splat(margin);
        RxSide {
            mirrored,
            reach,
            beams,
            margin,
            area: (area.0 - grow, area.1 + grow),
        }
    }

    /// Append the cones of reflector `s` to `part` and return their span (its part left
    /// unset), or `None` (and `part` as it was) when every parent joins `s`.
    fn cones_of(
        &self,
        prep: &Prepared<'_>,
        s: u32,
        q: &mut Query,
        part: &mut Part,
    ) -> Option<Span> {
        let (cones, planes) = (part.cones.len(), part.planes.len());
        let span = self.fill(prep, s, q, part);
        if span.is_none() {
            part.cones.truncate(cones);
            part.planes.truncate(planes);
        }
        span
    }

    /// [`RxSide::cones_of`], leaving `part` to the caller when it fails.
    fn fill(&self, prep: &Prepared<'_>, s: u32, q: &mut Query, part: &mut Part) -> Option<Span> {
        let plane = *prep.plane(s);
        let polygon = &prep.scene.surface(SurfaceId(s)).polygon;
        let hull = convex::grown_hull(polygon, 0.5 * self.margin);
        if hull.len() < 3 {
            // No window to bound the cones by.
            return None;
        }
        let lo = part.cones.len() as u32;
        q.negative.cones.clear();
        q.negative.planes.clear();
        let mut bounds = [EMPTY; 2];
        let negative = &mut q.negative;
        let mut push = |apex: Vec3, window: &[Vec3]| {
            let h = plane.signed_distance_unfused(apex);
            let into = if h < 0.0 { &mut *negative } else { &mut *part };
            let first = into.planes.len() as u32;
            cone(&plane, apex, window, self.margin, &mut into.planes)?;
            into.cones.push((first, into.planes.len() as u32));
            let b = &mut bounds[usize::from(h < 0.0)];
            *b = union(*b, self.cone_box((&plane, h), apex, window));
            Some(())
        };
        // RX in the node's beam: RX's depth-1 node on `s`.
        push(self.mirrored[s as usize].1, &hull)?;
        for list in 0..2 {
            // A node whose parent's apex lies on the positive side of `s`'s plane reads list 0
            // (its apex, mirrored, lies on the negative side), and its cones are those whose
            // apex lies on the negative side.
            q.ts.clear();
            q.ts.extend(self.reach.list(s, list).filter(|&t| t != s));
            q.ts.sort_unstable();
            q.ts.dedup();
            for &t in &q.ts {
                let image = plane.mirror(self.mirrored[t as usize].1);
                let h = plane.signed_distance_unfused(image);
                if (list == 0 && h > self.margin) || (list == 1 && h < -self.margin) {
                    continue;
                }
                // RX's depth-2 node (t, s): `s`'s grown hull inside `t`'s mirror beam.
                q.window.clone_from(&hull);
                for pl in &self.beams[t as usize] {
                    convex::clip_in_place(&mut q.window, pl, self.margin, &mut q.tmp);
                    if q.window.len() < 3 {
                        break;
                    }
                }
                if q.window.len() >= 3 {
                    push(image, &q.window)?;
                }
            }
        }
        let mid = part.cones.len() as u32;
        let shift = part.planes.len() as u32;
        part.planes.extend_from_slice(&q.negative.planes);
        (part.cones).extend(
            q.negative
                .cones
                .iter()
                .map(|&(a, b)| (a + shift, b + shift)),
        );
        Some(Span {
            part: 0,
            cones: (lo, mid, part.cones.len() as u32),
            bounds,
        })
    }

    /// A box around the part inside [`RxSide::area`] of the cone from `apex` (at signed
    /// distance `h` from `plane`, beyond the margin) through `window`, grown by the margin:
    /// a point of the cone is `apex + λ·(v − apex)` for a point `v` of the window and
    /// `λ ≥ 1`, and `λ = 1 + (its distance beyond the plane) / |h|`, at most `Λ` inside the
    /// area; so the part lies in the hull of the window and its copy scaled by `Λ` from the
    /// apex.
    fn cone_box(&self, (plane, h): (&Plane, Real), apex: Vec3, window: &[Vec3]) -> (Vec3, Vec3) {
        let (lo, hi) = self.area;
        let away = if h > 0.0 { -1.0 } else { 1.0 };
        let corners = (0..8).map(|k| {
            let pick = |bit: u32, a: Real, b: Real| if k & bit == 0 { a } else { b };
            Vec3::new(
                pick(1, lo.x, hi.x),
                pick(2, lo.y, hi.y),
                pick(4, lo.z, hi.z),
            )
        });
        let beyond = corners
            .map(|c| away * plane.signed_distance_unfused(c))
            .fold(0.0, Real::max);
        let scale = 1.0 + (beyond + self.margin) / h.abs();
        let mut b = EMPTY;
        for &v in window {
            let far = apex + scale * (v - apex);
            b = union(b, (v.min(far), v.max(far)));
        }
        let grow = Vec3::splat(self.margin);
        let (min, max) = ((b.0 - grow).max(lo), (b.1 + grow).min(hi));
        if min.cmple(max).all() {
            (min, max)
        } else {
            EMPTY
        }
    }
}

/// The side planes of the cone of rays from `apex` through the convex `window` lying in
/// `plane`, appended to `out` (the cone also lies beyond the plane from the apex: the caller
/// tests that side). A side plane per window edge, kept only when rounding cannot have
/// turned it ([`side_plane`], the rule of the beams; facing the window's inside by the
/// apex's side of the plane); leaving a plane out only widens the cone. `None` (the whole space) for an apex within `margin` of the plane.
fn cone(
    plane: &Plane,
    apex: Vec3,
    window: &[Vec3],
    margin: Real,
    out: &mut Vec<Plane>,
) -> Option<()> {
    let h = plane.signed_distance_unfused(apex);
    if h.is_nan() || h.abs() <= margin {
        return None;
    }
    let facing = Facing::of(plane, apex);
    let mut w = window[window.len() - 1];
    for &v in window {
        out.extend(side_plane(apex, (w, v), &facing));
        w = v;
    }
    Some(())
}

#[cfg(test)]
mod tests {
    use super::super::{
        BeamTree, Culling, Probe, Scratch, TreeCache, TreeOptions, TreeStats, beam_planes,
        mirrored, rx_visibility, window_in_beam,
    };
    use super::*;

    /// Whether the beam of a node with apex `apex` and window `window` (in `s`'s plane) is
    /// well defined: each window edge at least a millionth of the window's distance from the
    /// apex (shorter ones give side planes that rounding orients at random), and the reach
    /// lists' conditioning holds ([`Reach::answers`]: no degenerate side plane, the apex
    /// well off the plane, no sharp corner or grazing side plane).
    fn well_defined(prep: &Prepared<'_>, (s, apex): (u32, Vec3), window: &[Vec3]) -> bool {
        let reach = prep
            .rx_visible
            .as_ref()
            .and_then(|v| v.reach.as_ref())
            .unwrap();
        let mut planes = Vec::new();
        beam_planes(prep.plane(s), apex, window, &mut planes);
        let far = (convex::vertex_mean(window) - apex).length();
        let n = window.len();
        (0..n).all(|i| (window[(i + 1) % n] - window[i]).length() >= 1e-6 * far)
            && reach.answers(prep, (s, apex), window, &planes)
    }

    /// For `scene` at order 3, culled as built (so its second level is deferred): the
    /// (first-level node, reflector) pairs the probe accepts, those of them with a well-defined
    /// beam, those the join holds, and the pairs tried in all. Fails when the join misses a
    /// well-defined accepted pair.
    fn accepted_and_joined(scene: &bt_scene::Scene) -> [u64; 4] {
        let options = TreeOptions {
            culling: Culling::Always,
            ..TreeOptions::new(3)
        };
        let mut cache = TreeCache::default();
        let mut prep = Prepared::new(scene, options, &mut cache).unwrap();
        let rx = scene.rx().unwrap();
        let mut tree = BeamTree::empty(&prep);
        let mut scratch = Scratch::default();
        tree.grow_level(&prep, 1, &mut scratch, None, &mut |_| {})
            .unwrap();
        let m = mirrored(&prep, rx);
        let mut visible = rx_visibility(&prep, rx, &mut TreeStats::default());
        visible.reach = Some(Reach::of(&prep, &visible.ids, &m));
        prep.rx_visible = Some(visible);
        let reach = prep.rx_visible.as_ref().and_then(|v| v.reach.as_ref());
        let joined = Joined::of(&prep, &m, reach.unwrap(), apex_box(&tree, tree.levels[0]));
        let (mut probe, mut part) = (Probe::new(rx, m.clone()), tree.part());
        let (mut children, mut window, mut tmp) = (Vec::new(), Vec::new(), Vec::new());
        let mut counts = [0u64; 4];
        for c in tree.levels[0].0 as u32..tree.levels[0].1 as u32 {
            let parent = tree.parent_ref(&prep, c);
            tree.child_candidates(&prep, &parent, false, &mut children);
            for &s in &children {
                let before = (part.nodes.len(), part.stats.occluded);
                part.child_probed(&prep, &parent, s, &mut scratch, Some(&mut probe));
                let joins = joined.joins(&prep, s, parent.apex);
                counts[3] += 1;
                counts[2] += u64::from(joins);
                if before == (part.nodes.len(), part.stats.occluded) {
                    continue;
                }
                counts[0] += 1;
                window_in_beam(&prep, &parent, s, (&mut window, &mut tmp));
                let image = prep.plane(s).mirror(parent.apex);
                if well_defined(&prep, (s, image), &window) {
                    counts[1] += 1;
                    assert!(
                        joins,
                        "node {c} (apex {:?}), child {s}: accepted, not joined",
                        parent.apex
                    );
                }
            }
        }
        counts
    }

    /// On random scenes with the nasty cases (shared edges, coplanar neighbours, concave
    /// panels, grazing terminals, RX on mirror rays through edges and corners), the join holds
    /// every pair the probe accepts with a well-defined beam, and leaves out most pairs.
    /// (The trace's paths with the join against exhaustive enumeration: the beam-tree property
    /// tests of bt-solve, whose order-3 traces culled at build go through it.)
    #[test]
    fn the_join_holds_every_pair_the_probe_accepts() {
        let mut total = [0u64; 4];
        for seed in 0..400u64 {
            let (n, terminals) = (1 + (seed % 8) as usize, (seed % 3) as u8);
            let Some(scene) = bt_testkit::nasty_scene(seed * 7_919, n, terminals) else {
                continue;
            };
            let counts = accepted_and_joined(&scene);
            for k in 0..4 {
                total[k] += counts[k];
            }
        }
        let [accepted, defined, joined, tried] = total;
        assert!(defined > 100 && defined * 10 > accepted * 9, "{total:?}");
        assert!(joined < tried / 2, "{total:?}");
    }
}
