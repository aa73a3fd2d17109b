//! The weak visibility relationship network (WVRN) of the paper (Section V, Fig. 11), in 3-D.
//!
//! Nodes are TX, RX and the reflecting surfaces; two nodes are *linked* when some point of one
//! may see some point of the other directly. The network is **conservative**: a link is removed
//! only when no segment of a valid path (as `bt_solve::validate` judges it, tolerances
//! included) can join the two nodes, so routing candidates over it loses no path. Two proofs
//! remove links:
//!
//! - **Coplanar** (facing test). At a reflection on `B` the neighbouring point must be more than
//!   the length tolerance `tol` off `B`'s plane (else the path is grazing). A path point on `A`
//!   lies within `tol` of `A`'s polygon in `A`'s plane, so its distance to `B`'s plane is at most
//!   `max_i |d_B(a_i)| + tol |n_A × n_B|` (plus round-off). When that bound is below `tol / 2`,
//!   `A` and `B` cannot be consecutive (either order). For TX/RX: `|d_B(tx)| <= tol / 2`.
//!   Surfaces reflect from both sides, so "in front" means "off the plane on either side"; side
//!   consistency over three nodes is the enumeration's side test, not a property of one link.
//! - **Occluded** by one convex surface `C` (any kind, other than `A` and `B`). If `C`'s plane
//!   strictly separates the vertices of `A` and `B`, every segment from `conv(A)` to `conv(B)`
//!   crosses it once, and the crossing points form exactly the convex hull of the `|A| × |B|`
//!   crossings of vertex-to-vertex segments (central projection of a polytope from a point is the
//!   hull of the projected vertices, applied once from each side). So if all those points lie
//!   inside the convex `C` with a margin, every segment is blocked. The margin covers the path
//!   points' tolerance (`δ = 2 tol` around each polygon): moving the ends of a segment by `δ`
//!   moves its crossing by at most `δ + (D + 2δ) δ / (m_A + m_B − 2δ)`, with `D` the largest
//!   vertex distance and `m_A`, `m_B` the smallest plane distances of `A`'s and `B`'s vertices.
//!
//! Non-convex occluders are skipped, as are unions of occluders: the network is complete
//! (never drops a real link) but not minimal. Sampling is never used to remove a link.

use crate::{Node, Visibility};
use bt_geom::convex::is_strictly_convex;
use bt_geom::{Budget, Polygon, Real, Vec3};
use bt_scene::{Endpoints, Scene, SceneError, SurfaceId, SurfaceKind};
use serde::{Deserialize, Serialize};

/// Budget on the pair tests of [`Wvrn::build`] ([`build_tests`]): each node pair is tested
/// against every surface (~100-150 ns each, measured on random quads), so the default of
/// 100,000,000 is ~10-15 s; it admits ~580 reflectors, and refuses Sionna's city scenes
/// (5,000-15,000 reflectors: 1e11-1e12 tests and a 1-6 GB pair table), which the beam tree
/// traces.
pub const MAX_WVRN_TESTS: Budget =
    Budget::new("visibility pair tests", "--max-wvrn-tests", 100_000_000);

/// The pair tests of building the network of `scene` (before any allocation): the unordered
/// pairs of its nodes (TX, RX and the reflectors) times its surfaces, saturating. It bounds the
/// memory too: the pair table holds nodes² links and nodes × surfaces sides.
pub fn build_tests(scene: &Scene) -> u64 {
    let nodes = scene.reflectors().count() as u64 + 2;
    let pairs = nodes.saturating_mul(nodes - 1) / 2;
    pairs.saturating_mul(scene.surfaces().len() as u64)
}

/// The state of a pair of nodes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(tag = "state", rename_all = "kebab-case")]
pub enum Link {
    /// Some point of one may see some point of the other (an edge of the network).
    Linked,
    /// One lies in the other's plane: no path reflects on one and continues to the other.
    Coplanar,
    /// Every segment between the two crosses the convex surface `by` (the first in scene order).
    Occluded {
        /// The occluding surface.
        by: SurfaceId,
    },
}

impl Link {
    /// Whether this is an edge of the network.
    #[inline]
    pub fn is_linked(self) -> bool {
        self == Link::Linked
    }
}

/// Counts over the unordered pairs of distinct nodes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct WvrnStats {
    /// Nodes: TX, RX and the reflectors.
    pub nodes: usize,
    /// Unordered pairs of distinct nodes.
    pub pairs: usize,
    /// Pairs linked (edges).
    pub linked: usize,
    /// Pairs removed by the coplanar test.
    pub coplanar: usize,
    /// Pairs removed by a convex occluder.
    pub occluded: usize,
}

/// What an incremental update recomputed and changed (the paper's red and green edges: pairs
/// touching moved objects are recomputed, the rest are static).
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct WvrnDelta {
    /// Whether the whole network was rebuilt (surfaces or the tolerance changed).
    pub rebuilt: bool,
    /// Pairs with a moved node, recomputed from scratch ("red" pairs).
    pub recomputed_pairs: usize,
    /// Pairs of unmoved nodes re-tested against the moved occluders only.
    pub retested_pairs: usize,
    /// Pairs whose linked-ness changed: `(a, b, linked now)`, `a < b` in node order.
    pub changed: Vec<(Node, Node, bool)>,
    /// Every pair whose state (including the reason) differs from the previous step.
    pub state_changes: usize,
}

/// The weak visibility relationship network of one scene (or time step).
#[derive(Debug, Clone, PartialEq)]
pub struct Wvrn {
    nodes: Vec<Node>,
    /// Node index of each surface (reflectors only), `NONE` for blockers.
    slot: Vec<u32>,
    /// `links[a * n + b]`, symmetric, `Linked` on the diagonal.
    links: Vec<Link>,
    /// Whether each surface (by id) is usable as an occluder ([`may_occlude`]).
    convex: Vec<bool>,
    /// `sides[node * surfaces + surface]`: on which side of the surface's plane all the node's
    /// points lie beyond the separation margin (+1 / -1, 0 when not strictly on one side), and
    /// their smallest distance to it. Only convex surfaces' entries are filled.
    sides: Vec<(i8, Real)>,
    tx: Vec3,
    rx: Vec3,
    tol: Real,
}

const NONE: u32 = u32::MAX;

impl Wvrn {
    /// Build the network of `scene`: O(nodes² × surfaces) pair tests. TX and RX are nodes: a
    /// scene without both fails ([`SceneError::MissingTerminal`]).
    pub fn build(scene: &Scene) -> Result<Self, SceneError> {
        let Endpoints { tx, rx } = scene.terminals()?;
        let mut nodes = vec![Node::Tx, Node::Rx];
        let mut slot = vec![NONE; scene.surfaces().len()];
        for id in scene.reflectors() {
            slot[id.index()] = nodes.len() as u32;
            nodes.push(Node::Surface(id));
        }
        let n = nodes.len();
        let m = scene.surfaces().len();
        let mut wvrn = Wvrn {
            nodes,
            slot,
            links: vec![Link::Linked; n * n],
            convex: (0..m)
                .map(|i| may_occlude(scene, SurfaceId(i as u32)))
                .collect(),
            sides: vec![(0, 0.0); n * m],
            tx,
            rx,
            tol: scene.length_tolerance(),
        };
        for node in 0..n {
            for surface in 0..m {
                wvrn.fill_side(scene, node, surface);
            }
        }
        for a in 0..n {
            for b in a + 1..n {
                let link = wvrn.compute(scene, a, b);
                wvrn.set(a, b, link);
            }
        }
        Ok(wvrn)
    }

    /// Update the network after the surfaces `moved` (ids) of the previous step moved to their
    /// places in `scene`; TX/RX moves are detected here. The result equals
    /// [`Wvrn::build`]`(scene)` exactly. `scene` must be the next step of the scene this network
    /// was built for (same surfaces by id); otherwise the network is rebuilt.
    /// A scene without both terminals fails and leaves the network as it was.
    pub fn update(&mut self, scene: &Scene, moved: &[SurfaceId]) -> Result<WvrnDelta, SceneError> {
        let Endpoints { tx, rx } = scene.terminals()?;
        let same_surfaces = self.slot.len() == scene.surfaces().len()
            && scene
                .surfaces()
                .iter()
                .enumerate()
                .all(|(i, s)| (self.slot[i] != NONE) == (s.kind == SurfaceKind::Reflector));
        if !same_surfaces || self.tol != scene.length_tolerance() {
            let old = std::mem::replace(self, Wvrn::build(scene)?);
            let mut delta = WvrnDelta {
                rebuilt: true,
                recomputed_pairs: self.nodes.len() * (self.nodes.len() - 1) / 2,
                ..WvrnDelta::default()
            };
            if old.nodes == self.nodes {
                self.diff_into(&old, &mut delta);
            }
            return Ok(delta);
        }
        let n = self.nodes.len();
        let mut dirty = vec![false; n];
        dirty[0] = self.tx != tx;
        dirty[1] = self.rx != rx;
        self.tx = tx;
        self.rx = rx;
        let mut moved_mask = vec![false; self.slot.len()];
        for id in moved {
            moved_mask[id.index()] = true;
            self.convex[id.index()] = may_occlude(scene, *id);
            if self.slot[id.index()] != NONE {
                dirty[self.slot[id.index()] as usize] = true;
            }
        }
        let m = self.slot.len();
        for (node, &is_dirty) in dirty.iter().enumerate() {
            if is_dirty {
                (0..m).for_each(|surface| self.fill_side(scene, node, surface));
            } else {
                moved
                    .iter()
                    .for_each(|id| self.fill_side(scene, node, id.index()));
            }
        }
        let first_moved = moved.iter().map(|id| id.0).min();
        let old = self.clone();
        let mut delta = WvrnDelta::default();
        for a in 0..n {
            for b in a + 1..n {
                let before = self.get(a, b);
                let recompute = if dirty[a] || dirty[b] {
                    delta.recomputed_pairs += 1;
                    true
                } else {
                    match before {
                        Link::Coplanar => false,
                        // Still occluded by `by` unless it moved; an earlier moved occluder
                        // would now be the first one: recompute then to keep the reason exact.
                        Link::Occluded { by } => {
                            let again =
                                moved_mask[by.index()] || first_moved.is_some_and(|m| m < by.0);
                            delta.retested_pairs += again as usize;
                            again
                        }
                        Link::Linked => {
                            if moved.is_empty() {
                                false
                            } else {
                                delta.retested_pairs += 1;
                                let (pa, pb) = (self.points(scene, a), self.points(scene, b));
                                let (sa, sb) = (self.surface_of(a), self.surface_of(b));
                                moved.iter().any(|c| {
                                    Some(*c) != sa
                                        && Some(*c) != sb
                                        && self.occludes_pair(scene, c.index(), a, b, &pa, &pb)
                                })
                            }
                        }
                    }
                };
                if recompute {
                    let link = self.compute(scene, a, b);
                    self.set(a, b, link);
                }
            }
        }
        self.diff_into(&old, &mut delta);
        Ok(delta)
    }

    /// The nodes: TX, RX, then the reflectors in scene order.
    pub fn nodes(&self) -> &[Node] {
        &self.nodes
    }

    /// The state of the pair `(a, b)`. Nodes that are not in the network (blockers) are
    /// reported linked, the conservative answer.
    pub fn link(&self, a: Node, b: Node) -> Link {
        match (self.index(a), self.index(b)) {
            (Some(i), Some(j)) => self.get(i, j),
            _ => Link::Linked,
        }
    }

    /// The edges `(a, b)`, `a` before `b` in node order.
    pub fn edges(&self) -> impl Iterator<Item = (Node, Node)> + '_ {
        self.pairs()
            .filter(|(_, _, l)| l.is_linked())
            .map(|(a, b, _)| (a, b))
    }

    /// Every unordered pair of distinct nodes with its state, `a` before `b` in node order.
    pub fn pairs(&self) -> impl Iterator<Item = (Node, Node, Link)> + '_ {
        let n = self.nodes.len();
        (0..n).flat_map(move |a| {
            (a + 1..n).map(move |b| (self.nodes[a], self.nodes[b], self.get(a, b)))
        })
    }

    /// Counts of pair states.
    pub fn stats(&self) -> WvrnStats {
        let mut s = WvrnStats {
            nodes: self.nodes.len(),
            ..WvrnStats::default()
        };
        for (_, _, l) in self.pairs() {
            s.pairs += 1;
            match l {
                Link::Linked => s.linked += 1,
                Link::Coplanar => s.coplanar += 1,
                Link::Occluded { .. } => s.occluded += 1,
            }
        }
        s
    }

    fn index(&self, node: Node) -> Option<usize> {
        match node {
            Node::Tx => Some(0),
            Node::Rx => Some(1),
            Node::Surface(id) => match self.slot.get(id.index()) {
                Some(&s) if s != NONE => Some(s as usize),
                _ => None,
            },
        }
    }

    #[inline]
    fn get(&self, a: usize, b: usize) -> Link {
        self.links[a * self.nodes.len() + b]
    }

    fn set(&mut self, a: usize, b: usize, link: Link) {
        let n = self.nodes.len();
        self.links[a * n + b] = link;
        self.links[b * n + a] = link;
    }

    fn surface_of(&self, i: usize) -> Option<SurfaceId> {
        match self.nodes[i] {
            Node::Surface(id) => Some(id),
            _ => None,
        }
    }

    fn points<'s>(&self, scene: &'s Scene, i: usize) -> std::borrow::Cow<'s, [Vec3]> {
        match self.nodes[i] {
            Node::Tx => std::borrow::Cow::Owned(vec![self.tx]),
            Node::Rx => std::borrow::Cow::Owned(vec![self.rx]),
            Node::Surface(id) => std::borrow::Cow::Borrowed(scene.surface(id).polygon.vertices()),
        }
    }

    /// The state of the pair of node indices `(a, b)` from scratch.
    fn compute(&self, scene: &Scene, a: usize, b: usize) -> Link {
        let (sa, sb) = (self.surface_of(a), self.surface_of(b));
        let (pa, pb) = (self.points(scene, a), self.points(scene, b));
        let half = 0.5 * self.tol;
        let in_plane = |s: Option<SurfaceId>, other: Option<SurfaceId>, pts: &[Vec3]| match s {
            None => false,
            Some(s) => {
                let plane = scene.surface(s).polygon.plane();
                let far = pts
                    .iter()
                    .map(|p| plane.signed_distance(*p).abs())
                    .fold(0.0, Real::max);
                // In-plane slack of the other node's path points (terminals are exact).
                let slack = other.map_or(0.0, |o| {
                    self.tol
                        * scene
                            .surface(o)
                            .polygon
                            .plane()
                            .normal
                            .cross(plane.normal)
                            .length()
                });
                far + slack <= half
            }
        };
        if in_plane(sb, sa, &pa) || in_plane(sa, sb, &pb) {
            return Link::Coplanar;
        }
        for i in 0..scene.surfaces().len() {
            let id = SurfaceId(i as u32);
            if Some(id) == sa || Some(id) == sb {
                continue;
            }
            if self.occludes_pair(scene, i, a, b, &pa, &pb) {
                return Link::Occluded { by: id };
            }
        }
        Link::Linked
    }

    /// Fill the side-table entry of `node` against `surface`.
    fn fill_side(&mut self, scene: &Scene, node: usize, surface: usize) {
        let m = self.slot.len();
        self.sides[node * m + surface] = if self.convex[surface] {
            let plane = scene.surface(SurfaceId(surface as u32)).polygon.plane();
            side_class(plane, &self.points(scene, node), separation(self.tol))
        } else {
            (0, 0.0)
        };
    }

    /// [`occludes`] for node indices, rejecting by the side table first.
    fn occludes_pair(
        &self,
        scene: &Scene,
        c: usize,
        a: usize,
        b: usize,
        pa: &[Vec3],
        pb: &[Vec3],
    ) -> bool {
        let m = self.slot.len();
        let (side_a, min_a) = self.sides[a * m + c];
        let (side_b, min_b) = self.sides[b * m + c];
        if !self.convex[c] || side_a == 0 || side_b == 0 || side_a == side_b {
            return false;
        }
        crossings_inside(
            &scene.surface(SurfaceId(c as u32)).polygon,
            pa,
            pb,
            min_a,
            min_b,
            self.tol,
        )
    }

    fn diff_into(&self, old: &Wvrn, delta: &mut WvrnDelta) {
        let n = self.nodes.len();
        for a in 0..n {
            for b in a + 1..n {
                let (before, after) = (old.get(a, b), self.get(a, b));
                if before != after {
                    delta.state_changes += 1;
                    if before.is_linked() != after.is_linked() {
                        delta
                            .changed
                            .push((self.nodes[a], self.nodes[b], after.is_linked()));
                    }
                }
            }
        }
    }
}

impl Visibility for Wvrn {
    fn linked(&self, a: Node, b: Node) -> bool {
        self.link(a, b).is_linked()
    }
}

/// Separation from an occluder's plane required of both nodes' points: room for the path
/// points' uncertainty (`2 tol`) and the validation's tolerance band, so that perturbed
/// segments still cross the plane strictly inside (`t` in `[t_min, 1 - t_min]`).
fn separation(tol: Real) -> Real {
    4.0 * tol
}

/// `(+1 | -1, min distance)` when all `points` are beyond `sep` on one side of `plane`,
/// `(0, 0)` otherwise.
fn side_class(plane: &bt_geom::Plane, points: &[Vec3], sep: Real) -> (i8, Real) {
    let mut sign = 0;
    let mut min = Real::INFINITY;
    for p in points {
        let d = plane.signed_distance(*p);
        let s = if d > sep {
            1
        } else if d < -sep {
            -1
        } else {
            return (0, 0.0);
        };
        if sign != 0 && s != sign {
            return (0, 0.0);
        }
        sign = s;
        min = min.min(d.abs());
    }
    (sign, min)
}

/// Whether the convex polygon `c` provably blocks every segment of a valid path between a point
/// near `conv(a)` and a point near `conv(b)` (within `2 tol`), under the validation rule
/// ([`Polygon::blocks_segment`] with tolerance `tol`). See the module docs for the proof.
/// `c` must be convex ([`is_strictly_convex`]); for a non-convex `c` the answer means nothing.
pub fn occludes(c: &Polygon, a: &[Vec3], b: &[Vec3], tol: Real) -> bool {
    let sep = separation(tol);
    let (side_a, min_a) = side_class(c.plane(), a, sep);
    let (side_b, min_b) = side_class(c.plane(), b, sep);
    side_a != 0 && side_b != 0 && side_a != side_b && crossings_inside(c, a, b, min_a, min_b, tol)
}

/// The second half of [`occludes`], for point sets already known to lie strictly on opposite
/// sides of `c`'s plane, at least `min_a` and `min_b` from it.
fn crossings_inside(
    c: &Polygon,
    a: &[Vec3],
    b: &[Vec3],
    min_a: Real,
    min_b: Real,
    tol: Real,
) -> bool {
    let delta = 2.0 * tol;
    let plane = c.plane();
    let mut far: Real = 0.0;
    for p in a {
        for q in b {
            far = far.max(p.distance(*q));
        }
    }
    let shift = delta + (far + 2.0 * delta) * delta / (min_a + min_b - 2.0 * delta);
    // Inside by the shift plus the validation's own band, doubled for round-off.
    let need = 2.0 * (shift + tol);
    for p in a {
        let dp = plane.signed_distance(*p);
        for q in b {
            let dq = plane.signed_distance(*q);
            let x = *p + (dp / (dp - dq)) * (*q - *p);
            if c.signed_boundary_distance(x) < need {
                return false;
            }
        }
    }
    true
}

/// Whether surface `id` may occlude pairs: strictly convex and opaque (a penetrable surface,
/// [`Scene::penetrable`], is crossed, not blocking).
fn may_occlude(scene: &Scene, id: SurfaceId) -> bool {
    !scene.penetrable(id) && is_strictly_convex(&scene.surface(id).polygon)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{AllVisible, enumerate};
    use bt_testkit::scene_from_json as scene;

    fn quad(c: [Real; 3], u: [Real; 3], v: [Real; 3]) -> Vec<Vec3> {
        let (c, u, v) = (Vec3::from(c), Vec3::from(u), Vec3::from(v));
        vec![c - u - v, c + u - v, c + u + v, c - u + v]
    }

    #[test]
    fn occlusion_is_exact_on_the_hull_not_only_vertex_pairs() {
        let wall = Polygon::new(quad([0., 0., 1.], [2., 0., 0.], [0., 2., 0.])).unwrap();
        let small = quad([0., 0., 0.], [0.5, 0., 0.], [0., 0.5, 0.]);
        let above = quad([0., 0., 2.], [0.5, 0., 0.], [0., 0.5, 0.]);
        assert!(occludes(&wall, &small, &above, 1e-9));
        // Crossing points just outside: not provable.
        let wide = quad([0., 0., 2.], [3.6, 0., 0.], [0., 0.5, 0.]);
        assert!(!occludes(&wall, &small, &wide, 1e-9));
        // Touching the occluder's plane: not separated.
        let touching = quad([0., 0., 1.0], [0.5, 0., 0.], [0., 0.5, 0.]);
        assert!(!occludes(&wall, &small, &touching, 1e-9));
        // Same side: never occluded.
        let below = quad([0., 0., -1.], [0.5, 0., 0.], [0., 0.5, 0.]);
        assert!(!occludes(&wall, &small, &below, 1e-9));
    }

    #[test]
    fn build_tests_count_node_pairs_times_surfaces() {
        // a box room: 6 reflectors, 8 nodes, 28 pairs, 6 surfaces
        let s = scene(
            r#"{ "tx": [1, 1, 1], "rx": [3, 1, 1.5],
            "boxes": [ { "name": "room", "min": [0, 0, 0], "max": [4, 3, 2.5] } ] }"#,
        );
        assert_eq!(build_tests(&s), 28 * 6);
        let e = MAX_WVRN_TESTS.with_limit(100).check(build_tests(&s));
        let e = e.unwrap_err().to_string();
        assert!(e.contains("168 visibility pair tests") && e.contains("--max-wvrn-tests"));
    }

    #[test]
    fn partition_cuts_links_and_keeps_everything_else() {
        // A room split by a partition at x = 2 with a gap at y in [2.5, 3]; a small plate in a
        // corner of each half, out of view of each other through the gap.
        let s = scene(
            r#"{ "tx": [1, 1, 1], "rx": [3, 1, 1.5],
            "boxes": [ { "name": "room", "min": [0, 0, 0], "max": [4, 3, 2.5] } ],
            "surfaces": [
              { "name": "partition", "vertices": [[2, 0, 0], [2, 2.5, 0], [2, 2.5, 2.5], [2, 0, 2.5]] },
              { "name": "plate-w", "vertices": [[0.5, 0.2, 0.5], [1.5, 0.2, 0.5], [1.5, 0.2, 1.5], [0.5, 0.2, 1.5]] },
              { "name": "plate-e", "vertices": [[2.5, 0.3, 0.5], [3.5, 0.3, 0.5], [3.5, 0.3, 1.5], [2.5, 0.3, 1.5]] },
              { "name": "shelf-w", "vertices": [[0.5, 0.5, 0.8], [1.5, 0.5, 0.8], [1.5, 1.5, 0.8], [0.5, 1.5, 0.8]] },
              { "name": "shelf-e", "vertices": [[2.5, 0.5, 0.8], [3.5, 0.5, 0.8], [3.5, 1.5, 0.8], [2.5, 1.5, 0.8]] }
            ] }"#,
        );
        let w = Wvrn::build(&s).unwrap();
        let id = |n: &str| Node::Surface(s.find(n).unwrap());
        let partition = s.find("partition").unwrap();
        assert_eq!(w.link(Node::Tx, Node::Rx), Link::Occluded { by: partition });
        assert_eq!(
            w.link(id("plate-w"), id("plate-e")),
            Link::Occluded { by: partition }
        );
        assert_eq!(
            w.link(id("shelf-w"), id("plate-e")),
            Link::Occluded { by: partition }
        );
        // Coplanar: the two shelves lie in one plane z = 0.8 (the first reason found wins).
        assert_eq!(w.link(id("shelf-w"), id("shelf-e")), Link::Coplanar);
        // Walls span both halves: linked.
        assert!(w.link(id("room.south"), id("plate-e")).is_linked());
        assert!(w.link(Node::Tx, id("room.top")).is_linked());
        let stats = w.stats();
        assert_eq!(stats.pairs, stats.linked + stats.coplanar + stats.occluded);
        assert!(stats.occluded >= 4, "{stats:?}");
        let all = enumerate(&s, 2, &AllVisible).unwrap();
        let routed = enumerate(&s, 2, &w).unwrap();
        assert!(routed.len() < all.len());
    }

    #[test]
    fn update_equals_rebuild() {
        let json = |x: Real| {
            format!(
                r#"{{ "tx": [1, 1, 1], "rx": [3, 1, 1.5],
                "boxes": [ {{ "name": "room", "min": [0, 0, 0], "max": [4, 3, 2.5] }},
                           {{ "name": "crate", "kind": "blocker", "min": [{x}, 0.1, 0.1], "max": [{}, 2.9, 2.4] }} ],
                "surfaces": [ {{ "name": "plate-w", "vertices": [[0.5, 0.2, 0.5], [1.5, 0.2, 0.5], [1.5, 0.2, 1.5], [0.5, 0.2, 1.5]] }} ] }}"#,
                x + 0.2
            )
        };
        let steps: Vec<Scene> = [1.8, 2.5, 3.6, 1.8]
            .iter()
            .map(|x| scene(&json(*x)))
            .collect();
        let mut w = Wvrn::build(&steps[0]).unwrap();
        for k in 1..steps.len() {
            let moved: Vec<SurfaceId> = (0..steps[k].surfaces().len() as u32)
                .map(SurfaceId)
                .filter(|id| {
                    steps[k].surface(*id).polygon.vertices()
                        != steps[k - 1].surface(*id).polygon.vertices()
                })
                .collect();
            let delta = w.update(&steps[k], &moved).unwrap();
            assert!(!delta.rebuilt);
            assert_eq!(w, Wvrn::build(&steps[k]).unwrap(), "step {k}");
        }
    }
}
