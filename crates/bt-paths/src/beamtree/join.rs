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
//! grown hull inside `t`'s mirror beam, [`super::reach`]). Before the level, each parent's
//! box test finds its children `s` as before ([`BeamTree::child_candidates`]); the tries are
//! then gathered per reflector `s`, whose cones (`t` from the reach lists) are built, grouped
//! by the side of `s`'s plane their apex lies on, each group with a box around its cones
//! inside the parents' apexes' box, and tested against the apexes of all of `s`'s tries at
//! once: each cone's planes are read while they are in the cache, once per reflector instead
//! of once per try. A child `s` of a parent is then clipped and probed only when the parent's
//! apex lies in a group's box and in one of its cones: a few compares and dot products
//! instead of a clip and a probe for each of the pairs no cone holds. Its probe then tries
//! only the leaves `t` whose cones hold the apex, by the same argument, instead of every leaf
//! of `s`'s reach list (Etoile: 1.45 M of the probes' leaf tests spared). Used from [`JOIN_FROM`]
//! parents in large scenes, always in small ones ([`pays`]); in large scenes a reflector with
//! few tries for its cones keeps them all ([`TRIES_PER_CONE`]).
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
use super::{BeamTree, LINEAR_SCAN, Mirrored, Prepared, chunked, side_planes};
use bt_geom::{Plane, Points, Real, Vec3, convex};
use bt_scene::SurfaceId;

/// Reflectors per parallel task of [`Pairs::of`]'s joins.
const CHUNK: usize = 64;

/// The deferred level's (parent, reflector) pairs the join keeps: per parent, in the order of
/// the level, the reflectors (ascending) found by its box test ([`BeamTree::child_candidates`])
/// whose cones hold its apex (see the module).
pub(super) struct Pairs {
    /// The level's first parent (node index).
    first: u32,
    /// Per parent: its range in `children` (one more entry than parents).
    starts: Vec<u32>,
    children: Vec<Joined>,
    /// The leaves of the children's probes ([`Joined::leaves`]), each child's in a range.
    leaves: Vec<u32>,
    /// Per parent: the reflectors its box test found (all of them count as tested).
    tried: Vec<u32>,
}

/// A (parent, reflector) pair the join keeps.
#[derive(Clone, Copy)]
pub(super) struct Joined {
    /// The reflector `s`.
    pub(super) s: u32,
    /// The range in [`Pairs::leaves`] of the leaves `t` whose cone (RX's depth-2 node
    /// `(t, s)`) holds the parent's apex, ascending: the only leaves that can pass the
    /// node's probe when its beam is well defined (see the module). `None`: every leaf of
    /// `s`'s list (the reflector had no cones).
    leaves: Option<(u32, u32)>,
}

/// What one task of [`Pairs::of`]'s joins keeps: per pair, the parent's position and the
/// pair (its leaves' range in `leaves`), in the order of the reflectors and then of their
/// tries.
#[derive(Default)]
struct Kept {
    pairs: Vec<(u32, Joined)>,
    leaves: Vec<u32>,
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

/// From this many parents, a large scene's deferred level uses the join: its fixed costs (the
/// mirror beams of the reflectors RX sees, the cones of reflectors with few tries) are
/// spread over more tries. Order 3, one thread, CPU time of the whole trace against the old
/// path: Etoile's 3,057 parents −16 %, Munich's 3,460 −16 %; Munich with TX in the street
/// (`--tx 45,90,1.5 --rx 8.5,21,27`): 723 parents +1-4 %.
const JOIN_FROM: usize = 2_048;

/// A large scene's reflector `s` gets its cones only when it has more tries than a third of
/// its reach lists' entries (about its cones): a cone costs about as much as the clip of a
/// try it could spare, so a reflector with fewer tries lets them all through (Munich with
/// TX in the street, 723 parents: 2,835 → 2,744 M instructions, the old path's 2,727 M;
/// the cities' counts do not move).
const TRIES_PER_CONE: usize = 3;

/// Whether the deferred level of a trace to `max_order` with `parents` parents uses the
/// join: at order 3 (its parents are the first level's nodes), in large scenes from
/// [`JOIN_FROM`] parents, always in small ones (so that the property tests exercise it).
pub(super) fn pays(prep: &Prepared<'_>, max_order: usize, parents: usize) -> bool {
    max_order == 3 && (prep.reflectors.len() <= LINEAR_SCAN || parents >= JOIN_FROM)
}

impl Pairs {
    /// The pairs of the parents `tree.nodes[lo..hi]` for the RX of `mirrored`, whose reach
    /// lists are `reach`. Each parent's box test runs first (on all cores, in chunks); the
    /// tries are then gathered per reflector, whose cones are built and tested against all
    /// of its tries' apexes at once (each cone's planes read once per reflector, not once
    /// per try), and the pairs kept are handed back per parent.
    pub(super) fn of(
        tree: &BeamTree,
        prep: &Prepared<'_>,
        (mirrored, reach): (&Mirrored, &Reach),
        (lo, hi): (usize, usize),
    ) -> Pairs {
        let positions: Vec<u32> = (0..(hi - lo) as u32).collect();
        let found = chunked::map_chunks(prep, (&positions, Some(chunked::CHUNK_PARENTS)), |ps| {
            let (mut children, mut all, mut tried) = (Vec::new(), Vec::new(), Vec::new());
            for &i in ps {
                let parent = tree.parent_ref(prep, lo as u32 + i);
                tree.child_candidates(prep, &parent, false, &mut children);
                all.extend_from_slice(&children);
                tried.push(children.len() as u32);
            }
            (all, tried)
        });
        let tries = Tries::of(prep.planes.len(), &found);
        let tried: Vec<u32> = found.into_iter().flat_map(|(_, t)| t).collect();
        let apexes: Vec<Vec3> = tree.nodes[lo..hi].iter().map(|n| n.image).collect();
        let side = RxSide::new(prep, (mirrored, reach), apex_box(tree, (lo, hi)));
        let kept = chunked::map_chunks(prep, (&prep.reflectors, Some(CHUNK)), |chunk| {
            let (mut q, mut out) = (Query::default(), Kept::default());
            for &s in chunk {
                let of_s = tries.of_surface(s);
                if !of_s.is_empty() {
                    side.join_surface(prep, (s, of_s), &apexes, &mut q, &mut out);
                }
            }
            out
        });
        Pairs::by_parent(lo as u32, tried, &kept)
    }

    /// The pairs `kept` (per task, reflectors ascending) per parent, each parent's
    /// reflectors ascending.
    fn by_parent(first: u32, tried: Vec<u32>, kept: &[Kept]) -> Pairs {
        let (mut all, mut leaves) = (Vec::new(), Vec::new());
        for task in kept {
            let shift = leaves.len() as u32;
            leaves.extend_from_slice(&task.leaves);
            all.extend(task.pairs.iter().map(|&(i, j)| {
                let leaves = j.leaves.map(|(a, b)| (a + shift, b + shift));
                (i, Joined { leaves, ..j })
            }));
        }
        let by = || all.iter().enumerate().map(|(k, &(i, _))| (i, k as u32));
        let (starts, order) = super::by_key(tried.len(), by);
        Pairs {
            first,
            starts,
            children: order.iter().map(|&k| all[k as usize].1).collect(),
            leaves,
            tried,
        }
    }

    /// The pairs the join keeps for parent `p` (a node of the level), reflectors ascending,
    /// and the number of reflectors its box test found.
    pub(super) fn of_parent(&self, p: u32) -> (&[Joined], u64) {
        let i = (p - self.first) as usize;
        let (a, b) = (self.starts[i] as usize, self.starts[i + 1] as usize);
        (&self.children[a..b], u64::from(self.tried[i]))
    }

    /// The leaves `child`'s probe tries ([`Joined::leaves`]; `None`: all of them).
    pub(super) fn leaves(&self, child: &Joined) -> Option<&[u32]> {
        child
            .leaves
            .map(|(a, b)| &self.leaves[a as usize..b as usize])
    }
}

/// Per reflector, the parents (positions in the level, ascending) whose box test found it.
struct Tries {
    starts: Vec<u32>,
    parents: Vec<u32>,
}

impl Tries {
    /// The tries of `found` (per chunk of parents in order: their reflectors, and how many
    /// each parent found) over `surfaces` surfaces.
    fn of(surfaces: usize, found: &[(Vec<u32>, Vec<u32>)]) -> Tries {
        let firsts = found.iter().scan(0, |first, (_, tried)| {
            let this = *first;
            *first += tried.len() as u32;
            Some(this)
        });
        let pairs = || {
            (found.iter().zip(firsts.clone())).flat_map(|((all, tried), first)| {
                let ends = tried.iter().scan(0, |end, &n| {
                    *end += n as usize;
                    Some(*end)
                });
                (ends.enumerate()).flat_map(move |(k, end)| {
                    let parent = first + k as u32;
                    all[end - tried[k] as usize..end]
                        .iter()
                        .map(move |&s| (s, parent))
                })
            })
        };
        let (starts, parents) = super::by_key(surfaces, pairs);
        Tries { starts, parents }
    }

    /// The tries of reflector `s`.
    fn of_surface(&self, s: u32) -> &[u32] {
        &self.parents[self.starts[s as usize] as usize..self.starts[s as usize + 1] as usize]
    }
}

/// The cones of one reflector: per cone, its side planes' range in `planes` and its leaf.
#[derive(Default)]
struct Cones {
    cones: Vec<(u32, u32, u32)>,
    planes: Vec<Plane>,
}

/// The leaf of RX's depth-1 cone (RX itself in the node's beam: no leaf).
const NO_LEAF: u32 = u32::MAX;

impl Cones {
    fn clear(&mut self) {
        self.cones.clear();
        self.planes.clear();
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

/// Scratch of one task of [`Pairs::of`]'s joins.
#[derive(Default)]
struct Query {
    window: Vec<Vec3>,
    tmp: Vec<Vec3>,
    ts: Vec<u32>,
    /// The reflector's cones whose apex lies on the positive side of its plane, and the others.
    groups: [Cones; 2],
    /// Per try: whether it joins.
    joined: Vec<bool>,
    /// The tries to test against a group's cones: apexes, tagged with their index.
    pending: Points,
    /// Per pending try: whether the cone at hand holds its apex.
    inside: Vec<bool>,
    /// (try, leaf) of each leaf's cone that holds the try's apex.
    hits: Vec<(u32, u32)>,
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

    /// Append to `out` the tries `tries` of reflector `s` (parents' positions; their apexes
    /// in `apexes`) whose apex lies in one of `s`'s cones (within the margin), in the order
    /// of `tries`, each with the leaves whose cones hold it; all of them, with every leaf,
    /// when every parent joins `s`.
    fn join_surface(
        &self,
        prep: &Prepared<'_>,
        (s, tries): (u32, &[u32]),
        apexes: &[Vec3],
        q: &mut Query,
        out: &mut Kept,
    ) {
        let worth = prep.reflectors.len() <= LINEAR_SCAN
            || tries.len() * TRIES_PER_CONE > self.reach.lists_len(s);
        let Some(bounds) = worth.then(|| self.cones(prep, s, q)).flatten() else {
            let every = Joined { s, leaves: None };
            out.pairs.extend(tries.iter().map(|&i| (i, every)));
            return;
        };
        self.hold(prep.plane(s), (tries, apexes), bounds, q);
        q.hits.sort_unstable();
        q.hits.dedup();
        let mut hits = q.hits.iter().peekable();
        for (k, &i) in tries.iter().enumerate() {
            let lo = out.leaves.len() as u32;
            while let Some(&(_, t)) = hits.next_if(|&&(h, _)| h == k as u32) {
                out.leaves.push(t);
            }
            if q.joined[k] {
                let leaves = Some((lo, out.leaves.len() as u32));
                out.pairs.push((i, Joined { s, leaves }));
            }
        }
    }

    /// Which tries (parents' positions `tries`, apexes in `apexes`) the cones of `q.groups`
    /// (boxes `bounds`) of the reflector with plane `plane` hold, in `q.joined`, and in
    /// `q.hits` (try, leaf) of each leaf cone that holds one: every cone is tested against
    /// every try in its group's box, cone by cone (its planes read once while in the cache).
    fn hold(
        &self,
        plane: &Plane,
        (tries, apexes): (&[u32], &[Vec3]),
        bounds: [(Vec3, Vec3); 2],
        q: &mut Query,
    ) {
        q.joined.clear();
        q.joined.resize(tries.len(), false);
        q.hits.clear();
        for (g, &(min, max)) in bounds.iter().enumerate() {
            // A cone lies beyond the plane from its apex: a parent's apex on the negative side
            // can only lie in the cones from the positive side (group 0), and the reverse.
            q.pending.clear();
            for (k, &i) in tries.iter().enumerate() {
                let apex = apexes[i as usize];
                let d = plane.signed_distance_unfused(apex);
                let side = if g == 0 {
                    d <= self.margin
                } else {
                    d >= -self.margin
                };
                let held = apex.cmpge(min).all() && apex.cmple(max).all();
                if held && side {
                    q.pending.push(apex, k as u32);
                }
            }
            let group = &q.groups[g];
            if q.pending.is_empty() {
                continue;
            }
            for &(a, b, leaf) in &group.cones {
                let planes = &group.planes[a as usize..b as usize];
                if !q.pending.inside_all(planes, self.margin, &mut q.inside) {
                    continue;
                }
                for (&k, _) in
                    (q.pending.tags().iter().zip(&q.inside)).filter(|(_, inside)| **inside)
                {
                    q.joined[k as usize] = true;
                    if leaf != NO_LEAF {
                        q.hits.push((k, leaf));
                    }
                }
            }
        }
    }

    /// The cones of reflector `s` in `q.groups` (those whose apex lies on the positive side
    /// of its plane, then the others) and a box around each group's cones within the
    /// parents' apexes' box (empty for an empty group), or `None` when every parent joins `s`.
    fn cones(&self, prep: &Prepared<'_>, s: u32, q: &mut Query) -> Option<[(Vec3, Vec3); 2]> {
        let plane = *prep.plane(s);
        let polygon = &prep.scene.surface(SurfaceId(s)).polygon;
        let hull = convex::grown_hull(polygon, 0.5 * self.margin);
        if hull.len() < 3 {
            // No window to bound the cones by.
            return None;
        }
        q.groups.iter_mut().for_each(Cones::clear);
        let mut bounds = [EMPTY; 2];
        let beyond = self.beyond(&plane);
        let groups = &mut q.groups;
        let mut push = |apex: Vec3, window: &[Vec3], leaf: u32| {
            let h = plane.signed_distance_unfused(apex);
            let g = usize::from(h < 0.0);
            let into = &mut groups[g];
            let first = into.planes.len() as u32;
            cone(&plane, apex, window, self.margin, &mut into.planes)?;
            into.cones.push((first, into.planes.len() as u32, leaf));
            bounds[g] = union(bounds[g], self.cone_box((beyond, h), apex, window));
            Some(())
        };
        // RX in the node's beam: RX's depth-1 node on `s`.
        push(self.mirrored[s as usize].1, &hull, NO_LEAF)?;
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
                    push(image, &q.window, t)?;
                }
            }
        }
        Some(bounds)
    }

    /// How far beyond `plane` the farthest corner of [`RxSide::area`] lies (m, at least 0),
    /// seen from an apex on each side: `[0]` for an apex on the positive side, `[1]` for one
    /// on the negative side ([`RxSide::cone_box`]).
    fn beyond(&self, plane: &Plane) -> [Real; 2] {
        let (lo, hi) = self.area;
        let corners = || {
            (0..8).map(move |k| {
                let pick = |bit: u32, a: Real, b: Real| if k & bit == 0 { a } else { b };
                Vec3::new(
                    pick(1, lo.x, hi.x),
                    pick(2, lo.y, hi.y),
                    pick(4, lo.z, hi.z),
                )
            })
        };
        [-1.0, 1.0].map(|away: Real| {
            corners()
                .map(|c| away * plane.signed_distance_unfused(c))
                .fold(0.0, Real::max)
        })
    }

    /// A box around the part inside [`RxSide::area`] of the cone from `apex` (at signed
    /// distance `h` from the plane, beyond the margin) through `window`, grown by the margin;
    /// `beyond` is [`RxSide::beyond`] of the plane. A point of the cone is
    /// `apex + λ·(v − apex)` for a point `v` of the window and `λ ≥ 1`, and
    /// `λ = 1 + (its distance beyond the plane) / |h|`, at most `Λ` inside the area; so the
    /// part lies in the hull of the window and its copy scaled by `Λ` from the apex.
    fn cone_box(
        &self,
        (beyond, h): ([Real; 2], Real),
        apex: Vec3,
        window: &[Vec3],
    ) -> (Vec3, Vec3) {
        let (lo, hi) = self.area;
        let beyond = beyond[usize::from(h <= 0.0)];
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
/// tests that side): the beams' side planes ([`side_planes`]); leaving a plane out only
/// widens the cone. `None` (the whole space) for an apex within `margin` of the plane.
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
    side_planes(plane, apex, window, out);
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
    /// beam, those the join holds, the pairs tried in all, and the leaf tests of the joined
    /// pairs' probes with every leaf of the reach lists and with the join's leaves. Fails
    /// when the join misses a well-defined accepted pair, or the probe with the join's leaves
    /// rejects one.
    fn accepted_and_joined(scene: &bt_scene::Scene) -> [u64; 6] {
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
        let pairs = Pairs::of(&tree, &prep, (&m, reach.unwrap()), tree.levels[0]);
        let (mut probe, mut part) = (Probe::new(rx, m.clone()), tree.part());
        let (mut children, mut window, mut tmp) = (Vec::new(), Vec::new(), Vec::new());
        let mut counts = [0u64; 6];
        for c in tree.levels[0].0 as u32..tree.levels[0].1 as u32 {
            let parent = tree.parent_ref(&prep, c);
            tree.child_candidates(&prep, &parent, false, &mut children);
            let (kept, tried) = pairs.of_parent(c);
            assert_eq!(tried, children.len() as u64);
            assert!(kept.iter().all(|j| children.contains(&j.s)));
            for &s in &children {
                let before = (part.nodes.len(), part.stats.occluded, part.stats.tested);
                part.child_probed(&prep, &parent, s, &mut scratch, Some((&mut probe, None)));
                let accepted = before.0 != part.nodes.len() || before.1 != part.stats.occluded;
                let joined = kept.iter().find(|j| j.s == s);
                counts[3] += 1;
                counts[2] += u64::from(joined.is_some());
                if let Some(j) = joined {
                    let tested = part.stats.tested;
                    let only = Some((&mut probe, pairs.leaves(j)));
                    part.child_probed(&prep, &parent, s, &mut scratch, only);
                    counts[4] += tested - before.2;
                    counts[5] += part.stats.tested - tested;
                }
                if !accepted {
                    continue;
                }
                counts[0] += 1;
                window_in_beam(&prep, &parent, s, (&mut window, &mut tmp));
                let image = prep.plane(s).mirror(parent.apex);
                if !well_defined(&prep, (s, image), &window) {
                    continue;
                }
                counts[1] += 1;
                let apex = parent.apex;
                let j =
                    joined.unwrap_or_else(|| panic!("node {c} ({apex:?}), child {s}: not joined"));
                let only = pairs.leaves(j);
                assert!(
                    probe.ends_a_candidate(&mut part, &prep, (s, image), &window, only),
                    "node {c} ({apex:?}), child {s}: rejected with the join's leaves {only:?}"
                );
            }
        }
        counts
    }

    /// On random scenes with the nasty cases (shared edges, coplanar neighbours, concave
    /// panels, grazing terminals, RX on mirror rays through edges and corners), the join holds
    /// every pair the probe accepts with a well-defined beam, and its probe with only the
    /// join's leaves accepts it too; the join leaves out most pairs, and most leaf tests.
    /// (The trace's paths with the join against exhaustive enumeration: the beam-tree property
    /// tests of bt-solve, whose order-3 traces culled at build go through it.)
    #[test]
    fn the_join_holds_every_pair_the_probe_accepts() {
        let mut total = [0u64; 6];
        for seed in 0..400u64 {
            let (n, terminals) = (1 + (seed % 8) as usize, (seed % 3) as u8);
            let Some(scene) = bt_testkit::nasty_scene(seed * 7_919, n, terminals) else {
                continue;
            };
            let counts = accepted_and_joined(&scene);
            for k in 0..6 {
                total[k] += counts[k];
            }
        }
        let [accepted, defined, joined, tried, every_leaf, joined_leaves] = total;
        assert!(defined > 100 && defined * 10 > accepted * 9, "{total:?}");
        assert!(joined < tried / 2, "{total:?}");
        assert!(joined_leaves < every_leaf / 2, "{total:?}");
    }
}
