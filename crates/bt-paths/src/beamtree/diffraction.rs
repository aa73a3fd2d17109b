//! Diffracted candidates from two beam trees, one grown from TX and one from RX.
//!
//! A diffracted path `s1..sp → D on edge E → s(p+1)..sk → RX` unfolds, through the planes of
//! its reflections, into a straight line from the TX image `I` (TX mirrored through `s1..sp`)
//! to `D`, and another from `D` to the RX image `J` (RX mirrored through `sk..s(p+1)`). So
//! - `D` lies in the beam of the TX tree's node `s1..sp` (the root when p = 0): the segment
//!   `I → D` crosses every window of the prefix. The part of `E` inside that beam is the
//!   node's *reach* on `E` (an interval, the beam being convex);
//! - likewise `D` lies in the reach of the RX tree's node `sk..s(p+1)`;
//! - the segments next to `D` lie in the edge's exterior, and their directions are those of
//!   `I − D` and `J − D`: `I` and `J` lie in the exterior sector (a test independent of `D`);
//! - `D` is the Keller point of `I` and `J` on the edge line ([`bt_scene::Edge::keller`]).
//!
//! - the reflection next to `D` is not on a surface whose plane holds the edge line: `D` would
//!   lie on that plane, and validation calls such a path grazing
//!   ([`plane_holds_edge`]; a third of the living room's candidates before this rule).
//!
//! The join pairs, per edge, the TX reaches with the RX reaches whose depths fit the order,
//! and keeps a pair when the Keller point lies in both reaches and on the edge. Every test
//! keeps the tree's margins on the inclusive side, so no path validation accepts is lost
//! (property tests against [`crate::diffraction::enumerate_diffracted`]).

mod twice;

use super::{BeamTree, BuildProgress, BuildStage, EPS, GROW, Progress, ROOT, TreeError};
use crate::diffraction::{DiffractedSet, Diffracting};
use bt_geom::bvh::box_meets_halfspaces;
use bt_geom::{Plane, Real, Vec3};
use bt_scene::edges::EdgeLine;
use bt_scene::{Edge, EdgeId, Scene, SurfaceId};

/// Angular slack (rad) of the exterior test on images: far above round-off, far below any
/// sector a valid path could need.
const EXTERIOR_SLACK_RAD: Real = 1e-6;

/// The part of an edge a node's beam reaches.
#[derive(Debug, Clone, Copy)]
struct Reach {
    node: u32,
    depth: usize,
    image: Vec3,
    /// Parameter interval along the edge (m from its start).
    lo: Real,
    hi: Real,
}

/// At the RX tree's deepest level (depth `order − 1`) a reach pairs with the TX root alone
/// (the TX itself, whose reach is the whole edge): the join keeps it only when the Keller
/// point of TX and the node's image lies on the edge within the join's margin. [`BeamTree::reaches`]
/// tests that first and clips only the nodes that pass, so the join sees the same pairs.
#[derive(Debug, Clone, Copy)]
struct RootOnly {
    /// The depth (≥ 1) whose reaches pair with the TX root alone.
    depth: usize,
    /// TX (m, scene frame).
    tx: Vec3,
    /// The join's margin (m).
    margin: Real,
}

/// TX's half of the Keller point on an edge tested at a [`RootOnly`] level: its distance
/// from the edge line and its projection on it (m; the TX half of
/// [`bt_scene::edges::EdgeLine::keller`], bit for bit).
#[derive(Debug, Clone, Copy)]
struct Focus {
    tx_distance: Real,
    tx_along: Real,
    /// Whether [`on_edge`] may accept without the closed form when both projections lie on
    /// the edge: TX off the line (a positive, moderate distance), its projection finite and
    /// the margin above the closed form's rounding (a few ulps of the edge's length).
    shortcut: bool,
}

/// Nodes per task of [`BeamTree::reaches`] (tens of microseconds of a city's edges each).
const REACH_CHUNK: usize = 256;
/// Tasks of [`BeamTree::reaches`] run at once before their reaches are appended in order (it
/// bounds the reaches held twice, in the tasks' lists and the edges').
const REACH_BATCH: usize = 64;

/// What every node's reaches read at one depth of [`BeamTree::reaches`].
struct ReachLevel<'a> {
    edges: &'a bt_scene::edges::Edges,
    depth: usize,
    limit: &'a [usize],
    /// Per edge, the surfaces whose planes hold it ([`plane_holds_edge`]).
    in_plane: &'a [Vec<u32>],
    sectors: &'a [Sector],
    /// At the root-only depth, TX's half of each edge's Keller point and the margin.
    focus: Option<(Vec<Focus>, Real)>,
    eps: Real,
}

impl BeamTree {
    /// The nodes (the root included) whose image lies in an edge's exterior and whose beam
    /// reaches the edge, per edge, each edge's in ascending depth: on edge `e` the nodes of
    /// depth below `limit[e]` (none when 0). At `root_only`'s depth, only the nodes whose
    /// Keller point with TX lies on the edge (within the margin). Each level's nodes are
    /// split into fixed chunks, on all cores when the tree's options say so, and their
    /// reaches appended in node order: the same lists on any number of threads.
    fn reaches(
        &self,
        scene: &Scene,
        (limit, root_only): (&[usize], Option<RootOnly>),
        progress: Progress<'_>,
    ) -> Vec<Vec<Reach>> {
        let max_depth = limit.iter().max().map_or(0, |m| m.saturating_sub(1));
        let edges = scene.edges();
        let in_plane: Vec<Vec<u32>> = edges
            .all()
            .iter()
            .map(|edge| plane_holds_edge(scene, edge))
            .collect();
        let sectors: Vec<Sector> = edges.all().iter().map(Sector::of).collect();
        let mut out: Vec<Vec<Reach>> = vec![Vec::new(); edges.len()];
        for (e, edge) in edges.all().iter().enumerate() {
            if limit[e] > 0 && in_sector(edge, self.tx) && !hidden_from(scene, self.tx, edge) {
                out[e].push(Reach {
                    node: ROOT,
                    depth: 0,
                    image: self.tx,
                    lo: 0.0,
                    hi: edge.length,
                });
            }
        }
        for (d, &(lo, hi)) in self.levels.iter().enumerate().take(max_depth) {
            let depth = d + 1;
            let level = ReachLevel {
                edges,
                depth,
                limit,
                in_plane: &in_plane,
                sectors: &sectors,
                focus: root_only
                    .filter(|r| r.depth == depth)
                    .map(|r| (focus(scene, r.tx, r.margin), r.margin)),
                eps: EPS * self.tol,
            };
            let chunks: Vec<std::ops::Range<usize>> = (lo..hi)
                .step_by(REACH_CHUNK)
                .map(|a| a..(a + REACH_CHUNK).min(hi))
                .collect();
            for batch in chunks.chunks(REACH_BATCH) {
                self.report_reaches((depth, batch[0].start - lo, hi - lo), progress);
                let parts = super::chunked::in_order_if(self.options.parallel, batch, |r| {
                    self.reaches_of(r.clone(), &level)
                });
                for (e, reach) in parts.into_iter().flatten() {
                    out[e as usize].push(reach);
                }
            }
            self.report_reaches((depth, hi - lo, hi - lo), progress);
        }
        out
    }

    /// Report `done` of the `nodes` nodes of depth `depth` whose reaches are found.
    fn report_reaches(&self, (depth, done, nodes): (usize, usize, usize), progress: Progress<'_>) {
        progress(BuildProgress {
            stage: BuildStage::Reaches,
            depth,
            max_order: self.max_order,
            parents_done: done,
            parents: nodes,
            nodes: self.nodes.len() as u64,
        });
    }

    /// The reaches of the live nodes `nodes` (all of `level`'s depth) as (edge, reach), in
    /// node order.
    fn reaches_of(
        &self,
        nodes: std::ops::Range<usize>,
        level: &ReachLevel<'_>,
    ) -> Vec<(u32, Reach)> {
        let mut out = Vec::new();
        let (edges, depth) = (level.edges, level.depth);
        for i in nodes.filter(|&i| self.nodes[i].live) {
            let node = &self.nodes[i];
            let planes = &self.planes[node.planes.0 as usize..node.planes.1 as usize];
            let test = |min, max| box_meets_halfspaces(min, max, planes, level.eps);
            edges.bvh().visit(test, |e| {
                let edge = &edges.all()[e as usize];
                if depth >= level.limit[e as usize]
                    || level.in_plane[e as usize].contains(&node.surface)
                    || level.focus.as_ref().is_some_and(|(focus, margin)| {
                        !on_edge(edge, focus[e as usize], node.image, *margin)
                    })
                    || !level.sectors[e as usize].holds(edge, node.image)
                {
                    return;
                }
                if let Some((lo, hi)) = clip(edge, planes, level.eps) {
                    let reach = Reach {
                        node: i as u32,
                        depth,
                        image: node.image,
                        lo,
                        hi,
                    };
                    out.push((e, reach));
                }
            });
        }
        out
    }

    /// Each node's (parent, surface) up to depth `max_depth` (node index order), what
    /// [`surfaces_of`] needs of the tree.
    fn prefixes(&self, max_depth: usize) -> Vec<(u32, u32)> {
        let end = self
            .levels
            .iter()
            .take(max_depth)
            .map(|l| l.1)
            .max()
            .unwrap_or(0);
        self.nodes[..end]
            .iter()
            .map(|n| (n.parent, n.surface))
            .collect()
    }
}
/// The surfaces of node `i` of a tree whose node `k` has (parent, surface) `node(k)`, root
/// side first (empty for the root).
fn surfaces_of(node: impl Fn(u32) -> (u32, u32), mut i: u32, out: &mut Vec<SurfaceId>) {
    out.clear();
    while i != ROOT {
        let (parent, surface) = node(i);
        out.push(SurfaceId(surface));
        i = parent;
    }
    out.reverse();
}

/// The surfaces touching `edge` whose plane holds its whole segment to half the scene's length
/// tolerance. A reflection on one of them next to the diffraction point `D` (on the segment,
/// so within that half tolerance of the plane, plus round-off) has a neighbour within the
/// tolerance of its plane, and validation rejects it as grazing
/// (`bt_solve::diffraction::validate`): no valid path starts or ends such a reach.
fn plane_holds_edge(scene: &Scene, edge: &Edge) -> Vec<u32> {
    let half = 0.5 * scene.length_tolerance();
    edge.touching
        .iter()
        .filter(|id| {
            let plane = scene.surface(**id).polygon.plane();
            plane.signed_distance(edge.start).abs() <= half
                && plane.signed_distance(edge.end).abs() <= half
        })
        .map(|id| id.0)
        .collect()
}

/// Whether `p` lies in `edge`'s exterior, φ ∈ (0, nπ), up to [`EXTERIOR_SLACK_RAD`] (as a
/// distance: the slack times p's distance r from the edge line; points on the line are in no
/// sector).
#[inline]
fn in_sector(edge: &Edge, p: Vec3) -> bool {
    Sector::of(edge).holds(edge, p)
}

/// The axes of an edge's exterior test ([`in_sector`]), computed once per edge for the tests
/// of many points: `e × t0` and `tn × e`, as [`Edge::about`] computes them.
#[derive(Debug, Clone, Copy)]
struct Sector {
    y0: Vec3,
    yn: Vec3,
}

impl Sector {
    fn of(edge: &Edge) -> Self {
        Sector {
            y0: edge.direction.cross(edge.t0),
            yn: edge.tn.cross(edge.direction),
        }
    }

    /// Whether `p` lies in `edge`'s exterior: `Edge::about(p)`'s `r > 0` and
    /// `in_sector(EXTERIOR_SLACK_RAD · r)`, bit for bit, with the same products; the square
    /// root only when `p` lies behind both faces' planes (r > 0 makes the slack non-negative,
    /// so a point on the exterior side of either plane passes whatever r is).
    #[inline]
    fn holds(&self, edge: &Edge, p: Vec3) -> bool {
        let v = p - edge.start;
        let (sin0, cos0, sin_n) = (v.dot(self.y0), v.dot(edge.t0), v.dot(self.yn));
        let r2 = sin0 * sin0 + cos0 * cos0;
        // r = √r2 > 0 exactly when r2 > 0 (false for NaN).
        r2 > 0.0 && {
            sin0 >= 0.0 || sin_n >= 0.0 || {
                let slack = EXTERIOR_SLACK_RAD * r2.sqrt();
                sin0 >= -slack || sin_n >= -slack
            }
        }
    }
}

/// TX's half of the Keller point on every edge, by edge index, for [`on_edge`] with `margin`.
fn focus(scene: &Scene, tx: Vec3, margin: Real) -> Vec<Focus> {
    scene
        .edges()
        .all()
        .iter()
        .map(|edge| {
            let line = EdgeLine::of(edge);
            let (tx_distance, tx_along) = (line.distance(tx), line.along(tx));
            Focus {
                tx_distance,
                tx_along,
                shortcut: tx_distance > 0.0
                    && tx_distance < MODERATE
                    && tx_along.is_finite()
                    && 4.0 * Real::EPSILON * edge.length <= margin,
            }
        })
        .collect()
}

/// Lengths below this (m) are moderate: sums of two stay finite.
const MODERATE: Real = 1e150;

/// Whether the Keller point of TX and `image` on `edge` lies on the edge within `margin`
/// (what the join asks of a pair with the TX root, [`Pairing::once`]): the same closed form
/// as [`EdgeLine::keller`], TX's half from `f`. The point is a weighted mean of the two
/// projections, so when both lie beyond the same end by twice the margin (far above the
/// closed form's round-off) it does too, and no square root is needed.
///
/// When both projections lie on the edge, so does the point up to its rounding: with
/// non-negative weights and projections the closed form is non-negative, and it exceeds the
/// edge's length `L` by at most about 2 ε·L (four roundings), below the margin
/// ([`Focus::shortcut`]). It is defined when TX lies off the line and the image's offset is
/// moderate (the sum of distances then positive and finite). So the answer is the closed
/// form's, without its square root.
#[inline]
fn on_edge(edge: &Edge, f: Focus, image: Vec3, margin: Real) -> bool {
    let line = EdgeLine::of(edge);
    let v = image - edge.start;
    // `line.along(image)`, with the offset kept for the shortcut's test.
    let along = v.dot(edge.direction);
    let (near, far) = (f.tx_along.min(along), f.tx_along.max(along));
    if far < -2.0 * margin || near > edge.length + 2.0 * margin {
        return false;
    }
    if f.shortcut && near >= 0.0 && far <= edge.length && v.length_squared() < MODERATE {
        return true;
    }
    match line.keller_from(f.tx_distance, f.tx_along, image) {
        Some(t) => t >= -margin && t <= edge.length + margin,
        None => false,
    }
}

/// How far inside an occluder, and off its plane, the rays of [`hidden_from`] must cross it,
/// in length tolerances: above validation's blocking test's tolerance (one), so that what
/// this calls hidden, validation calls blocked.
const HIDDEN: Real = 4.0;

/// Whether one opaque convex surface hides all of `edge` from `apex` (TX or RX): the segments
/// from `apex` to both ends of the edge cross it, each end and `apex` off its plane on either
/// side and the crossings inside it, all by [`HIDDEN`] tolerances. Its shadow from `apex` is
/// convex, so it then holds the whole edge: the segment from `apex` to any diffraction point
/// crosses it inside, and validation finds that leg blocked. The surfaces touching the edge
/// (every diffraction point lies on them) and penetrable ones never hide it.
fn hidden_from(scene: &Scene, apex: Vec3, edge: &Edge) -> bool {
    let margin = HIDDEN * scene.length_tolerance();
    let crosses = |polygon: &bt_geom::Polygon, p: Vec3| {
        (polygon.plane().crossing_beyond(apex, p, margin))
            .is_some_and(|(crossing, _)| polygon.inside_by(crossing, margin))
    };
    let hides = |item: u32| {
        let id = SurfaceId(item);
        let polygon = &scene.surface(id).polygon;
        !scene.penetrable(id)
            && !edge.touching.contains(&id)
            && crosses(polygon, edge.start)
            && crosses(polygon, edge.end)
            && bt_geom::convex::is_convex(polygon)
    };
    scene
        .bvh()
        .any_hit(apex, edge.start, margin, hides)
        .is_some()
}

/// The parameter interval of `edge` inside every half-space `{x : plane(x) ≥ −eps}`, or
/// `None` when empty.
fn clip(edge: &Edge, planes: &[Plane], eps: Real) -> Option<(Real, Real)> {
    let (mut lo, mut hi) = (0.0, edge.length);
    for plane in planes {
        let at_start = plane.signed_distance_unfused(edge.start) + eps;
        let slope = plane.normal.dot(edge.direction);
        if slope.abs() <= Real::EPSILON {
            if at_start < 0.0 {
                return None;
            }
            continue;
        }
        let t = -at_start / slope;
        if slope > 0.0 {
            lo = Real::max(lo, t);
        } else {
            hi = Real::min(hi, t);
        }
        if lo > hi {
            return None;
        }
    }
    Some((lo, hi))
}

/// What the diffracted candidates need of a TX tree, kept while only RX moves: its nodes'
/// reaches on the usable edges (those at least the minimum edge length long) and the
/// surfaces of those nodes. It holds no reference to the tree, so a trace can keep it
/// after the tree's arenas went back to their cache.
#[derive(Debug, Clone)]
pub struct DiffractionSide {
    reaches: Vec<Vec<Reach>>,
    max_order: usize,
    /// Per edge: at least the minimum edge length long.
    usable: Vec<bool>,
    max_diffractions: usize,
    /// (parent, surface) of the tree's nodes to depth `max_order − 1`.
    prefixes: Vec<(u32, u32)>,
    /// The tree's length tolerance (m), for the join's margin (and the cache's key).
    pub(super) tol: Real,
    /// TX (m, scene frame).
    tx: Vec3,
    /// The two-diffraction join's TX part, made by the first join that needs it.
    twice: std::sync::OnceLock<twice::TxPart>,
    /// The size of the last join's set before [`DiffractedSet::canonicalise`].
    last: LastSize,
}

/// The candidates and reflections of the last set a join made with a [`DiffractionSide`]:
/// the next join (the next RX, often close by) reserves that much at once instead of
/// growing its arrays (a hint only: any size works).
#[derive(Debug, Default)]
struct LastSize {
    candidates: std::sync::atomic::AtomicUsize,
    reflections: std::sync::atomic::AtomicUsize,
}

impl LastSize {
    fn get(&self) -> (usize, usize) {
        use std::sync::atomic::Ordering::Relaxed;
        (
            self.candidates.load(Relaxed),
            self.reflections.load(Relaxed),
        )
    }

    fn set(&self, set: &DiffractedSet) {
        use std::sync::atomic::Ordering::Relaxed;
        self.candidates.store(set.len(), Relaxed);
        self.reflections.store(set.reflection_count(), Relaxed);
    }
}

impl Clone for LastSize {
    fn clone(&self) -> Self {
        let (candidates, reflections) = self.get();
        LastSize {
            candidates: candidates.into(),
            reflections: reflections.into(),
        }
    }
}

impl DiffractionSide {
    /// The side of `tx` (materialised to depth `max_order − 1` at least) for paths of up to
    /// `max_order` interactions, as `diffracting` says.
    pub fn of(scene: &Scene, tx: &BeamTree, max_order: usize, diffracting: Diffracting) -> Self {
        Self::reporting(scene, (tx, max_order), diffracting, &mut |_| {})
    }

    /// [`DiffractionSide::of`], reporting the reaches ([`BuildStage::Reaches`]) to `progress`.
    pub(crate) fn reporting(
        scene: &Scene,
        (tx, max_order): (&BeamTree, usize),
        diffracting: Diffracting,
        progress: Progress<'_>,
    ) -> Self {
        let mut usable = vec![false; scene.edges().len()];
        for e in crate::diffraction::usable_edges(scene, diffracting.min_edge_length) {
            usable[e.index()] = true;
        }
        let limit: Vec<usize> = usable
            .iter()
            .map(|&u| if u { max_order } else { 0 })
            .collect();
        let reaches = tx.reaches(scene, (&limit, None), progress);
        DiffractionSide {
            reaches,
            max_order,
            usable,
            max_diffractions: diffracting.max_diffractions,
            prefixes: tx.prefixes(max_order.saturating_sub(1)),
            tol: tx.tol,
            tx: tx.tx,
            twice: std::sync::OnceLock::new(),
            last: LastSize::default(),
        }
    }
}

/// The diffracted candidates of one TX and one RX up to `side`'s order, from the TX tree's
/// `side` and the RX tree `rx` (materialised to depth `max_order − 1` at least).
/// Stops with [`TreeError::Budget`] beyond `budget`.
pub fn join(
    scene: &Scene,
    side: &DiffractionSide,
    rx: &BeamTree,
    budget: u64,
) -> Result<DiffractedSet, TreeError> {
    join_reporting(scene, side, (rx, budget), &mut |_| {})
}

/// [`join`], reporting the RX tree's reaches ([`BuildStage::Reaches`]) to `progress`.
pub(crate) fn join_reporting(
    scene: &Scene,
    side: &DiffractionSide,
    (rx, budget): (&BeamTree, u64),
    progress: Progress<'_>,
) -> Result<DiffractedSet, TreeError> {
    let (candidates, reflections) = side.last.get();
    let mut set = DiffractedSet::with_capacity(candidates, reflections);
    let max_order = side.max_order;
    if max_order == 0 {
        return Ok(set);
    }
    let from_tx = &side.reaches;
    // An RX reach on an edge fits the order only with the shallowest TX reach there at most;
    // with two diffractions, with the TX root on another edge.
    let twice = side.max_diffractions >= 2 && max_order >= 2;
    let limit: Vec<usize> = from_tx
        .iter()
        .zip(&side.usable)
        .map(|(r, &usable)| {
            let once = r.first().map_or(0, |a| max_order - a.depth);
            if twice && usable {
                once.max(max_order - 1)
            } else {
                once
            }
        })
        .collect();
    let margin = GROW * side.tol.max(rx.tol);
    let root_only = RootOnly {
        depth: max_order - 1,
        tx: side.tx,
        margin,
    };
    let root_only = (max_order >= 2).then_some(root_only);
    let from_rx = rx.reaches(scene, (&limit, root_only), progress);
    let pairing = Pairing {
        side,
        rx,
        from_rx: &from_rx,
        margin,
        budget,
    };
    pairing.once(scene, &mut set)?;
    if twice {
        pairing.twice(scene, &mut set)?;
    }
    side.last.set(&set);
    set.canonicalise();
    Ok(set)
}

/// What the join pairs: the TX side's reaches and the RX tree's, per edge.
struct Pairing<'a> {
    side: &'a DiffractionSide,
    rx: &'a BeamTree,
    from_rx: &'a [Vec<Reach>],
    /// Slack of the tests that a Keller point lies in a reach, metres.
    margin: Real,
    budget: u64,
}

impl Pairing<'_> {
    /// The surfaces of TX node `a` (TX side first) and of RX node `b` (RX side last) into
    /// `before` and `after`.
    fn surfaces(
        &self,
        (a, b): (u32, u32),
        (before, after): (&mut Vec<SurfaceId>, &mut Vec<SurfaceId>),
    ) {
        let tx_node = |k: u32| self.side.prefixes[k as usize];
        let rx_node = |k: u32| {
            let node = &self.rx.nodes[k as usize];
            (node.parent, node.surface)
        };
        surfaces_of(tx_node, a, before);
        surfaces_of(rx_node, b, after);
        after.reverse();
    }

    fn check_budget(&self, set: &DiffractedSet) -> Result<(), TreeError> {
        if set.len() as u64 > self.budget {
            return Err(TreeError::DiffractedBudget {
                budget: self.budget,
                max_order: self.side.max_order,
            });
        }
        Ok(())
    }

    /// The candidates with one diffraction: per edge, the TX and RX reaches whose depths fit
    /// the order and whose Keller point lies in both.
    fn once(&self, scene: &Scene, set: &mut DiffractedSet) -> Result<(), TreeError> {
        let max_order = self.side.max_order;
        let margin = self.margin;
        let (mut before, mut after) = (Vec::new(), Vec::new());
        for (e, edge) in scene.edges().all().iter().enumerate() {
            for a in &self.side.reaches[e] {
                // Reaches come in ascending depth: stop at the first too deep to fit the order.
                let fits = |b: &&Reach| a.depth + b.depth < max_order;
                for b in self.from_rx[e].iter().take_while(fits) {
                    if a.lo.max(b.lo) > a.hi.min(b.hi) + margin {
                        continue;
                    }
                    let Some(t) = edge.keller(a.image, b.image) else {
                        continue;
                    };
                    let inside = |r: &Reach| t >= r.lo - margin && t <= r.hi + margin;
                    if inside(a) && inside(b) {
                        self.surfaces((a.node, b.node), (&mut before, &mut after));
                        set.push(&before, EdgeId(e as u32), &after);
                        self.check_budget(set)?;
                    }
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The exterior test as [`Edge::about`] states it, with its square root.
    fn in_sector_by_about(edge: &Edge, p: Vec3) -> bool {
        let about = edge.about(p);
        about.r > 0.0 && about.in_sector(EXTERIOR_SLACK_RAD * about.r)
    }

    /// [`on_edge`] by the closed form alone ([`EdgeLine::keller_from`]).
    fn on_edge_by_keller(edge: &Edge, f: Focus, image: Vec3, margin: Real) -> bool {
        EdgeLine::of(edge)
            .keller_from(f.tx_distance, f.tx_along, image)
            .is_some_and(|t| t >= -margin && t <= edge.length + margin)
    }

    /// A point on a coarse grid (many on faces' planes, on edge lines and at the ends), or
    /// off it by a small offset.
    fn point(c: [i8; 3], off: [i8; 3]) -> Vec3 {
        let v = |c: [i8; 3]| Vec3::new(c[0] as Real, c[1] as Real, c[2] as Real);
        0.5 * v(c) + 1e-9 * v(off)
    }

    proptest! {
        /// The sector test with its axes computed once, and the Keller test with its
        /// shortcut, answer as the formulas they replace, on every edge of a box room and a
        /// screen, for points on and near their faces, lines and ends.
        #[test]
        fn the_per_edge_tests_answer_as_their_formulas(
            c in proptest::array::uniform3(-4i8..9),
            off in proptest::array::uniform3(-3i8..4),
            t in proptest::array::uniform3(-4i8..9),
            margin_exp in -12i32..0,
        ) {
            let room = bt_testkit::box_room([4.0, 3.0, 2.5], [1.0, 1.0, 1.0], [3.0, 2.0, 1.5]);
            let p = point(c, off);
            let tx = point(t, [0; 3]);
            let margin = (10.0 as Real).powi(margin_exp);
            for edge in room.edges().all() {
                prop_assert_eq!(Sector::of(edge).holds(edge, p), in_sector_by_about(edge, p));
                let f = focus(&room, tx, margin)
                    .into_iter()
                    .zip(room.edges().all())
                    .find(|(_, e)| *e == edge)
                    .unwrap()
                    .0;
                prop_assert_eq!(on_edge(edge, f, p, margin), on_edge_by_keller(edge, f, p, margin));
            }
        }
    }
}
