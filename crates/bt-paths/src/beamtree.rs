//! The beam tree: visibility-driven candidate generation (docs/beam-tree.md).
//!
//! A node is a prefix `s1..sk` of reflecting surfaces with its *image source* `I_k` (TX
//! mirrored through the planes of `s1..sk`) and its *window* `W_k`: the part of `s_k`'s plane
//! that specular rays from TX can reach through every earlier window. Its *beam* is the set of
//! rays from `I_k` through `W_k`, beyond `s_k`'s plane: a convex cone given by one near plane
//! (the plane of `s_k`) and one side plane per window edge. A child `s` of the node exists only
//! where `s`'s polygon meets the beam; its window is `s`'s (convex hull, grown by a margin)
//! clipped by the beam's planes, so an empty clip proves that no specular path has that prefix.
//!
//! A sequence `s1..sk` is a candidate for a receiver exactly when RX lies in node `k`'s beam:
//! that is the condition for the image-method path to cross every window. The geometry is
//! exact, and every test keeps a margin of a few length tolerances on the inclusive side, so
//! the tree never drops a path that validation ([`bt_solve`'s `validate`]) would accept.
//!
//! *Occlusion culling.* A convex surface `O` between two consecutive windows that covers the
//! whole new window as seen from the image source (every ray crosses `O` strictly inside,
//! strictly between the two planes) blocks every path through it: the node is removed. When
//! `O` covers the window except across one of its edges, the window is clipped to the
//! uncovered part, which stays convex. Both tests need only the window's vertices, because
//! central projection maps convex sets to convex sets.

use crate::{CandidateSet, CandidateStats};
use bt_geom::bvh::box_meets_halfspaces;
use bt_geom::{Plane, Real, Vec3, convex};
use bt_scene::{Scene, SurfaceId, SurfaceKind};
use serde::{Deserialize, Serialize};
use std::sync::OnceLock;

mod diffraction;

use crate::diffraction::Diffracting;
mod chunked;
mod join;
mod reach;
mod rebuild;
mod receivers;
pub use diffraction::{DiffractionSide, join as join_diffracted};
pub use rebuild::RebuildStats;
pub use receivers::ReceiverNodes;

/// How the tree is built.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TreeOptions {
    /// Highest reflection order.
    pub max_order: usize,
    /// Budget on materialised nodes: the build stops with [`TreeError::Budget`] beyond it.
    pub max_nodes: u64,
    /// When to remove or shrink windows covered by convex occluders (exact either way).
    pub culling: Culling,
    /// Give each candidate its IPC start points (the centres of its windows). Solvers that do
    /// not read them (the image method) turn this off: a single-receiver trace then does not
    /// clip the last window of each candidate it emits.
    pub starts: bool,
    /// Grow the levels of a large scene's tree, and find which reflectors RX sees, on all
    /// cores (rayon). The tree and its candidates are the same either way: the work is done
    /// in fixed chunks, appended in order.
    pub parallel: bool,
    /// In a single-receiver trace ([`candidates_in`], without diffraction) of a scene culled
    /// as it is built, test a node of the last materialised level for occlusion only when it
    /// can end or lead to a candidate (RX lies in its beam, or in one of its children's):
    /// the others are never materialised. The reflectors RX sees are then always found first;
    /// with them, the candidates are those of culling every node (a beam clipped by an
    /// occluder lies inside the unclipped one). The statistics count only the nodes tested.
    /// Off: every node is culled as it is built, as in a kept tree.
    pub defer_culling: bool,
}

/// When the tree tests its nodes for occlusion (`occlude`). Culling never changes the paths
/// found, only how much the tree and the solver do: in a room most windows are visible and the
/// test costs more than the children it could save; in a city it removes most nodes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Culling {
    /// Never.
    Off,
    /// Every node as it is built.
    Always,
    /// Every node as it is built in scenes of more than 64 reflectors; in smaller ones a node
    /// only when it is about to get children and their count times the levels still to build
    /// reaches `min_work` (then leaves are never tested: validation rejects their blocked paths).
    Auto {
        /// Children × levels below which a small scene's node is not tested.
        min_work: usize,
    },
}

impl TreeOptions {
    /// Order `max_order`, 2 million nodes (about 1 GB), [`Culling::Auto`] (64), one thread,
    /// culling of the last materialised level deferred.
    pub fn new(max_order: usize) -> Self {
        TreeOptions {
            max_order,
            max_nodes: 2_000_000,
            culling: Culling::Auto { min_work: 64 },
            starts: true,
            parallel: false,
            defer_culling: true,
        }
    }
}

/// Why the tree could not be built.
#[derive(Debug, thiserror::Error)]
pub enum TreeError {
    /// The scene lacks the terminal the work needs: the TX for a build, both for
    /// [`candidates`] ([`bt_scene::SceneError::MissingTerminal`]).
    #[error(transparent)]
    Scene(#[from] bt_scene::SceneError),
    /// More nodes than the budget.
    #[error(
        "candidate budget exceeded: the beam tree holds more than {budget} nodes by depth {depth} \
         of {max_order} ({nodes} so far); lower the order or raise the budget with --max-candidates"
    )]
    Budget {
        /// Nodes built when the budget ran out.
        nodes: u64,
        /// Depth being built.
        depth: usize,
        /// The order asked for.
        max_order: usize,
        /// The budget.
        budget: u64,
    },
    /// More pairs of reaches to test for two diffractions than the budget allows
    /// ([`PAIR_TESTS_PER_CANDIDATE`] per candidate of the budget), counted before testing.
    #[error(
        "candidate budget exceeded: {pairs} pairs of edge reaches to test for two diffractions \
         at order {max_order}, more than {allowed} ({PAIR_TESTS_PER_CANDIDATE} per candidate of \
         --max-candidates {budget}); lower the order, use --max-diffractions 1, raise \
         --min-edge-length or raise --max-candidates"
    )]
    PairBudget {
        /// Pairs that would be tested.
        pairs: u64,
        /// Pairs allowed.
        allowed: u64,
        /// The candidate budget.
        budget: u64,
        /// The order asked for.
        max_order: usize,
    },
    /// More diffracted candidates than the budget.
    #[error(
        "candidate budget exceeded: more than {budget} diffracted candidates at order {max_order}; \
         lower the order, raise --min-edge-length or raise the budget with --max-candidates"
    )]
    DiffractedBudget {
        /// The budget.
        budget: u64,
        /// The order asked for.
        max_order: usize,
    },
}

/// Where a build stands, reported to a progress callback at each level's start and every
/// [`PROGRESS_EVERY`] parents: large trees (cities, high orders) take seconds. With
/// diffraction, a trace then reports the TX tree's reaches on the edges, the tree grown from
/// RX and its reaches ([`BuildStage`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BuildProgress {
    /// What is being built.
    pub stage: BuildStage,
    /// Depth being built (1 = first reflection).
    pub depth: usize,
    /// The order asked for.
    pub max_order: usize,
    /// Parents of this level whose children are done.
    pub parents_done: usize,
    /// Parents of this level.
    pub parents: usize,
    /// Nodes materialised so far (all levels).
    pub nodes: u64,
}

/// What a [`BuildProgress`] reports on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BuildStage {
    /// The beam tree from TX: `parents_done` of the `parents` of level `depth`.
    Tree,
    /// With diffraction, the tree grown from RX (the same fields).
    RxTree,
    /// With diffraction, the part of each edge each node's beam reaches, TX's tree and then
    /// RX's: `parents_done` of the `parents` nodes of depth `depth` done.
    Reaches,
}

/// Parents between two progress reports.
pub const PROGRESS_EVERY: usize = 256;

/// A progress callback ([`BuildProgress`]).
pub type Progress<'p> = &'p mut dyn FnMut(BuildProgress);

/// What the tree did, for `stats.tree` in the JSON output.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct TreeStats {
    /// Materialised nodes per depth (index 0 = depth 1).
    pub nodes_per_depth: Vec<u64>,
    /// Child sequences examined (each a surface meeting a beam's bounding test); a rebuilt
    /// tree ([`BeamTree::rebuild`]) counts its copied nodes too.
    pub tested: u64,
    /// Sequences whose window clipped to nothing (or grazing image sources).
    pub empty: u64,
    /// Nodes removed by occlusion culling.
    pub occluded: u64,
    /// Windows shrunk by an occluder.
    pub occluder_clips: u64,
    /// The surfaces that removed or shrank a node, ascending: the only non-reflectors the tree
    /// depends on. While none of them and no reflector moves (and TX, RX stay), the tree's
    /// candidates stay a superset of what a new tree would give, with the same valid paths.
    #[serde(skip)]
    pub occluders: Vec<u32>,
}

impl TreeStats {
    /// Add `other`'s counts and occluders (a chunk's, [`BeamTree::grow_level`]) to these.
    fn absorb(&mut self, other: &TreeStats) {
        self.tested += other.tested;
        self.empty += other.empty;
        self.occluded += other.occluded;
        self.occluder_clips += other.occluder_clips;
        self.occluders.extend_from_slice(&other.occluders);
    }
}

/// One node: a prefix ending on `surface`.
#[derive(Debug, Clone, Copy)]
struct Node {
    surface: u32,
    parent: u32,
    image: Vec3,
    window: (u32, u32),
    planes: (u32, u32),
    /// False once occlusion culling has removed the node (its beam is hidden).
    live: bool,
}

/// What occlusion culling did to a node.
enum Cull {
    Removed,
    Clipped,
    Kept,
}

/// Whether to test a parent of a small scene for occlusion before building its children
/// ([`Culling::Auto`]): `children` (by the bounding test) times the levels still to build
/// (`depth` is the children's) reach `min_work`.
fn worth_culling(prep: &Prepared<'_>, children: usize, depth: usize) -> bool {
    match prep.options.culling {
        Culling::Auto { min_work } if !prep.cull_at_build => {
            let levels = prep.options.max_order + 1 - depth;
            children.saturating_mul(levels) >= min_work
        }
        _ => false,
    }
}

const ROOT: u32 = u32::MAX;

/// A beam tree for a fixed TX, materialised to its full order: answers any RX by a walk
/// ([`BeamTree::candidates`]), the common beam-management case of a moving handset.
#[derive(Debug, Clone)]
pub struct BeamTree {
    max_order: usize,
    tol: Real,
    /// What the tree was built for: a rebuild ([`BeamTree::rebuild`]) reuses nodes only for
    /// the same options, TX, surfaces and reflectors.
    options: TreeOptions,
    tx: Vec3,
    reflectors: Vec<u32>,
    surfaces: usize,
    /// Nodes level by level; `levels[d]` = range of depth `d + 1`.
    nodes: Vec<Node>,
    levels: Vec<(usize, usize)>,
    verts: Vec<Vec3>,
    planes: Vec<Plane>,
    stats: TreeStats,
}

/// Margins in units of the scene's length tolerance: windows grow by `GROW` (validation accepts
/// points within 1 tolerance of a polygon), plane tests keep `EPS`, occluders must cover with
/// `COVER` to spare.
const GROW: Real = 4.0;

/// Pair tests of the two-diffraction join allowed per candidate of the budget
/// ([`TreeError::PairBudget`]): a test costs a small fraction of a candidate's solve.
pub const PAIR_TESTS_PER_CANDIDATE: u64 = 64;
const EPS: Real = 1.0;
const COVER: Real = 4.0;

/// Up to this many reflectors, a parent's children are found by testing every reflector's box
/// against its beam (already in index order) rather than by walking the BVH: in a room every
/// beam meets most boxes, so the walk only adds its inner nodes and a sort.
const LINEAR_SCAN: usize = 64;

/// Per-surface data of one build. Hulls and convexity are computed on first use: a city
/// trace at order 1 tests 19,846 reflectors and needs the hull of a handful.
struct Prepared<'a> {
    scene: &'a Scene,
    /// The scene's TX (checked: a bare scene builds no tree), the root's apex.
    tx: Vec3,
    tol: Real,
    /// Each surface's plane, contiguous (the leaf test reads one per child).
    planes: Vec<Plane>,
    /// Hulls and convexity, from and back to the caller's [`TreeCache`].
    shapes: Shapes,
    reflectors: Vec<u32>,
    /// Whether each surface reflects (children are reflectors only).
    is_reflector: Vec<bool>,
    options: TreeOptions,
    /// Test every node for occlusion as it is built (see [`Culling`]).
    cull_at_build: bool,
    /// Single-receiver traces of large scenes: the reflectors RX can see, the only ones that
    /// can end a valid path, so the only ones tried as leaves ([`rx_visibility`]).
    rx_visible: Option<RxVisible>,
}

/// The reflectors some part of which RX sees (no convex occluder covers them as seen from RX).
struct RxVisible {
    /// Per surface.
    visible: Vec<bool>,
    /// The visible reflectors, ascending, and a BVH over their boxes (item `i` = `ids[i]`).
    ids: Vec<u32>,
    bvh: bt_geom::bvh::Bvh,
    /// For the probes of a deferred level: per reflector, the visible ones that can end a
    /// candidate through it ([`reach::Reach`]).
    reach: Option<reach::Reach>,
}

impl<'a> Prepared<'a> {
    /// The data of one build, taking the shapes out of `cache` when they are `scene`'s (hand
    /// them back with [`Prepared::keep_in`]).
    /// Fails when the scene has no TX.
    fn new(
        scene: &'a Scene,
        options: TreeOptions,
        cache: &mut TreeCache,
    ) -> Result<Self, TreeError> {
        let tx = scene.terminal(bt_scene::Terminal::Tx)?;
        let surfaces = scene.surfaces();
        let reflectors: Vec<u32> = scene.reflectors().map(|id| id.0).collect();
        let cull_at_build = match options.culling {
            Culling::Off => false,
            Culling::Always => true,
            Culling::Auto { .. } => reflectors.len() > LINEAR_SCAN,
        };
        let tol = scene.length_tolerance();
        Ok(Prepared {
            planes: surfaces.iter().map(|s| *s.polygon.plane()).collect(),
            shapes: Shapes::take(&mut cache.shapes, scene, GROW * tol),
            is_reflector: surfaces
                .iter()
                .map(|s| s.kind == SurfaceKind::Reflector)
                .collect(),
            cull_at_build,
            rx_visible: None,
            scene,
            tx,
            tol,
            reflectors,
            options,
        })
    }

    fn plane(&self, s: u32) -> &Plane {
        &self.planes[s as usize]
    }

    /// The grown convex hull of surface `s` (empty for a blocker).
    fn hull(&self, s: u32) -> &[Vec3] {
        self.shapes.hulls[s as usize].get_or_init(|| {
            let surface = self.scene.surface(SurfaceId(s));
            match surface.kind {
                SurfaceKind::Reflector => convex::grown_hull(&surface.polygon, self.shapes.margin),
                SurfaceKind::Blocker => Vec::new(),
            }
        })
    }

    /// Occluder `s`'s edges as [`shadow`] reads them, moved inward by the cover margin.
    fn shadow_edges(&self, s: u32) -> &[ShadowEdge] {
        self.shapes.shadow_edges[s as usize].get_or_init(|| {
            shadow_edges(&self.scene.surface(SurfaceId(s)).polygon, COVER * self.tol)
        })
    }

    /// The surfaces whose boxes the segment `a -> q` touches (grown by the tolerance) among
    /// those that may occlude, each at most once and in no particular order: the scene's
    /// BVH, or with penetrable surfaces the opaque ones' ([`Opaque`]). Callers still test
    /// [`Prepared::is_occluder`].
    fn visit_opaque(&self, (a, q): (Vec3, Vec3), mut visit: impl FnMut(u32)) {
        match self.opaque() {
            None => self.scene.bvh().visit_segment(a, q, self.tol, visit),
            Some(o) => o
                .bvh
                .visit_segment(a, q, self.tol, |i| visit(o.ids[i as usize])),
        }
    }

    /// [`Opaque`]'s index of the scene, made on first use.
    fn opaque(&self) -> Option<&Opaque> {
        self.shapes
            .opaque
            .get_or_init(|| Opaque::of(self.scene))
            .as_ref()
    }

    /// Whether no surface of the scene can occlude (every one penetrable).
    fn nothing_occludes(&self) -> bool {
        self.opaque().is_some_and(|o| o.ids.is_empty())
    }

    /// Whether surface `s` may occlude: convex and opaque (a penetrable surface,
    /// [`Scene::penetrable`], lets every beam through).
    fn is_occluder(&self, s: u32) -> bool {
        !self.scene.penetrable(SurfaceId(s))
            && *self.shapes.convex[s as usize]
                .get_or_init(|| convex::is_convex(&self.scene.surface(SurfaceId(s)).polygon))
    }
}

impl Prepared<'_> {
    /// Hand the shapes back to `cache` for its next build of the same geometry.
    fn keep_in(self, cache: &mut TreeCache) {
        cache.shapes = self.shapes;
    }
}

/// What the beam tree keeps between builds, only for speed, owned by the caller (the
/// `bt_solve` tracer keeps one; a build given a fresh cache computes everything anew and gives
/// bit-identical trees): the per-surface shapes (grown hulls, convexity) of the last geometry built, reused while
/// [`bt_scene::GeometryKey`] says the next scene has the same surfaces (a stream of receivers,
/// a sweep, a benchmark), and the arenas (nodes, windows, beam planes) of the last single-receiver walk
/// ([`candidates_in`]). Cloning gives an empty cache.
#[derive(Default)]
pub struct TreeCache {
    shapes: Shapes,
    arenas: Option<Arenas>,
    side: Option<KeptSide>,
}

impl Clone for TreeCache {
    fn clone(&self) -> Self {
        TreeCache::default()
    }
}

impl std::fmt::Debug for TreeCache {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("TreeCache")
            .field("shapes", &self.shapes.hulls.len())
            .field("arenas", &self.arenas.is_some())
            .finish()
    }
}

/// Per-surface shapes derived from the geometry alone: each surface's box, and, computed on
/// first use, each reflector's convex hull grown by `margin` (m), each surface's convexity,
/// each occluder's shadow edges and the index of the opaque surfaces ([`Opaque`]). A
/// [`TreeCache`] keeps the
/// last build's for its next one of the same geometry, so that hulls are not rebuilt every
/// trace. Unlike the [`Arenas`], they are kept whatever their size: they grow with the scene,
/// not with a tree.
#[derive(Default)]
struct Shapes {
    geometry: Option<bt_scene::GeometryKey>,
    margin: Real,
    /// Each surface's box `(min, max)` (its polygon's bounds, m), contiguous: the reach
    /// lists' and small scenes' box tests read one per surface a walk reaches.
    boxes: Vec<(Vec3, Vec3)>,
    hulls: Vec<OnceLock<Vec<Vec3>>>,
    convex: Vec<OnceLock<bool>>,
    /// Per occluder, its edges as [`shadow`] reads them ([`shadow_edges`]), made on first use.
    shadow_edges: Vec<OnceLock<Box<[ShadowEdge]>>>,
    opaque: OnceLock<Option<Opaque>>,
}

/// Where occlusion's walks ([`occlude`]) look for occluders in a scene with penetrable
/// surfaces, which never occlude: a BVH over the opaque surfaces only (item `i` is surface
/// `ids[i]`), so that a walk does not visit every wall a beam passes through. With none
/// opaque (transmission everywhere), nothing occludes and no walk is made.
struct Opaque {
    ids: Vec<u32>,
    bvh: bt_geom::bvh::Bvh,
}

impl Opaque {
    /// The index of `scene`'s opaque surfaces, or `None` when every surface is opaque (the
    /// scene's own BVH then serves).
    fn of(scene: &Scene) -> Option<Opaque> {
        if !scene.transmits() {
            return None;
        }
        let ids: Vec<u32> = (0..scene.surfaces().len() as u32)
            .filter(|&s| !scene.penetrable(SurfaceId(s)))
            .collect();
        Some(Opaque {
            bvh: bvh_over(scene, &ids),
            ids,
        })
    }
}

impl Shapes {
    /// The `kept` shapes (taken out) when they are `scene`'s with the same `margin`, else
    /// fresh ones.
    fn take(kept: &mut Shapes, scene: &Scene, margin: Real) -> Shapes {
        let kept = std::mem::take(kept);
        let n = scene.surfaces().len();
        if kept.margin == margin
            && kept.hulls.len() == n
            && kept.geometry.as_ref().is_some_and(|g| g.matches(scene))
        {
            return kept;
        }
        Shapes {
            geometry: Some(scene.geometry_key()),
            margin,
            boxes: (scene.surfaces().iter())
                .map(|s| s.polygon.bounds())
                .collect(),
            hulls: (0..n).map(|_| OnceLock::new()).collect(),
            convex: (0..n).map(|_| OnceLock::new()).collect(),
            shadow_edges: (0..n).map(|_| OnceLock::new()).collect(),
            opaque: OnceLock::new(),
        }
    }
}

/// `plane`, flipped if needed so that `inner` is on its non-negative side.
fn orient_towards(plane: Plane, inner: Vec3) -> Plane {
    if plane.signed_distance_unfused(inner) < 0.0 {
        flip(plane)
    } else {
        plane
    }
}

fn flip(plane: Plane) -> Plane {
    Plane {
        normal: -plane.normal,
        offset: -plane.offset,
    }
}

/// Scratch buffers reused across children.
#[derive(Default)]
struct Scratch {
    a: Vec<Vec3>,
    b: Vec<Vec3>,
    items: Vec<u32>,
    /// Occlusion: ray starts and ends (the window on entry) per window vertex, and the
    /// surfaces one ray crosses.
    starts: Vec<Vec3>,
    rays: Vec<Vec3>,
    /// The occluder that covered the last culled window: siblings behind the same wall are
    /// tried against it before any BVH walk.
    last_cover: Option<u32>,
    hits: Vec<(Real, u32)>,
    /// Occlusion: the surfaces whose box one ray's BVH walk reached, in walk order.
    reached: Vec<u32>,
    /// The parent's beam plane that emptied the last empty window: siblings beyond the same
    /// plane are told empty before any clipping ([`hull_beyond`]).
    last_empty: usize,
}

/// The arenas of a tree (nodes, window vertices, beam planes), kept in a [`TreeCache`] between
/// single-receiver traces ([`candidates_in`]): a stream of traces (receivers, time steps,
/// benchmarks) reuses them instead of allocating them afresh, which with glibc can mean a
/// page fault per touched page of every call. Only arenas of at most [`POOLED_BYTES`] are
/// kept, so a city-sized tree's memory is returned.
#[derive(Default)]
struct Arenas {
    nodes: Vec<Node>,
    verts: Vec<Vec3>,
    planes: Vec<Plane>,
}

/// Candidates a walk makes room for at once (a room at order 3 has about a hundred): the set
/// then grows once or not at all instead of doubling from one.
const RESERVED_CANDIDATES: usize = 256;

/// The largest arenas a [`TreeCache`] keeps between traces, bytes.
const POOLED_BYTES: usize = 4 << 20;

impl Arenas {
    /// The cache's kept arenas (empty), or new ones.
    fn take(cache: &mut TreeCache) -> Arenas {
        let mut a = cache.arenas.take().unwrap_or_default();
        a.nodes.clear();
        a.verts.clear();
        a.planes.clear();
        a
    }

    /// Keep `self` in `cache` for its next trace, unless too large.
    fn give_back(self, cache: &mut TreeCache) {
        let bytes = self.nodes.capacity() * size_of::<Node>()
            + self.verts.capacity() * size_of::<Vec3>()
            + self.planes.capacity() * size_of::<Plane>();
        if bytes <= POOLED_BYTES {
            cache.arenas = Some(self);
        }
    }
}

/// A parent's view for generating children: apex, near plane and beam planes.
struct Parent<'n> {
    index: u32,
    surface: Option<u32>,
    apex: Vec3,
    /// Beam planes (near plane first); empty at the root.
    planes: &'n [Plane],
}

impl BeamTree {
    /// A tree with no node yet, for the scene and options of `prep`.
    fn empty(prep: &Prepared<'_>) -> Self {
        BeamTree {
            max_order: prep.options.max_order,
            tol: prep.tol,
            options: prep.options,
            tx: prep.tx,
            reflectors: prep.reflectors.clone(),
            surfaces: prep.planes.len(),
            nodes: Vec::new(),
            levels: Vec::new(),
            verts: Vec::new(),
            planes: Vec::new(),
            stats: TreeStats::default(),
        }
    }

    /// Build the tree of `scene`'s TX to `options.max_order`; a scene without a TX fails with
    /// [`TreeError::Scene`].
    pub fn build(scene: &Scene, options: TreeOptions) -> Result<Self, TreeError> {
        Self::build_with_progress(scene, options, &mut |_| {})
    }

    /// [`BeamTree::build`], reporting to `progress`.
    pub fn build_with_progress(
        scene: &Scene,
        options: TreeOptions,
        progress: Progress<'_>,
    ) -> Result<Self, TreeError> {
        Self::build_in(scene, options, &mut TreeCache::default(), progress)
    }

    /// [`BeamTree::build_with_progress`], reusing and refilling `cache`.
    pub fn build_in(
        scene: &Scene,
        options: TreeOptions,
        cache: &mut TreeCache,
        progress: Progress<'_>,
    ) -> Result<Self, TreeError> {
        let prep = Prepared::new(scene, options, cache)?;
        let mut tree = BeamTree::empty(&prep);
        let mut scratch = Scratch::default();
        for depth in 1..=options.max_order {
            tree.grow_level(&prep, depth, &mut scratch, None, progress)?;
        }
        prep.keep_in(cache);
        Ok(tree)
    }

    /// Statistics of the build.
    pub fn stats(&self) -> &TreeStats {
        &self.stats
    }

    /// The length tolerance (m) the tree's margins were built with: a receiver scene with a
    /// larger tolerance needs a new tree.
    pub fn tolerance(&self) -> Real {
        self.tol
    }

    /// Number of materialised nodes.
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    /// Whether the tree has no node.
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// The candidates for a receiver at `rx`: line of sight and every sequence whose beam holds
    /// `rx`, by order then lexicographically, with IPC start points inside the windows (when
    /// the tree's options ask for them).
    pub fn candidates(&self, rx: Vec3) -> CandidateSet {
        self.candidates_among(rx, self.levels.iter().flat_map(|&(lo, hi)| lo..hi))
    }

    /// [`BeamTree::candidates`], testing only `nodes` (ascending indices, a superset of the
    /// live nodes holding `rx`, such as [`ReceiverNodes::of`] gives): the same set.
    pub fn candidates_among(
        &self,
        rx: Vec3,
        nodes: impl IntoIterator<Item = usize>,
    ) -> CandidateSet {
        let hits = nodes
            .into_iter()
            .filter(|&i| self.nodes[i].live && self.holds(i, rx));
        self.candidates_of(hits)
    }

    /// Nodes of the tree in the order [`BeamTree::candidates`] tests them (by depth, then
    /// index): [`BeamTree::holding`] takes ranges of it.
    pub fn walk_len(&self) -> usize {
        self.levels.iter().map(|&(lo, hi)| hi - lo).sum()
    }

    /// The live nodes at positions `part` of the walk ([`BeamTree::walk_len`]) whose beams
    /// hold `rx`, in walk order, appended to `hits`: a part of [`BeamTree::candidates`]'s
    /// tests, so that parts may be tested on different threads and their hits given, in
    /// order, to [`BeamTree::candidates_of`].
    pub fn holding(&self, rx: Vec3, part: std::ops::Range<usize>, hits: &mut Vec<usize>) {
        let walk = self.levels.iter().flat_map(|&(lo, hi)| lo..hi);
        let nodes = walk.skip(part.start).take(part.len());
        hits.extend(nodes.filter(|&i| self.nodes[i].live && self.holds(i, rx)));
    }

    /// The candidate set of `hits`, the live nodes holding a receiver in walk order
    /// ([`BeamTree::holding`]): line of sight and each node's sequence, as
    /// [`BeamTree::candidates`] gives it.
    pub fn candidates_of(&self, hits: impl IntoIterator<Item = usize>) -> CandidateSet {
        let mut set = CandidateSet::with_starts();
        set.reserve(
            RESERVED_CANDIDATES,
            RESERVED_CANDIDATES * self.max_order,
            self.options.starts,
        );
        set.push_with_starts(&[], &[]);
        let mut seq = Vec::with_capacity(self.max_order);
        let mut starts = Vec::with_capacity(self.max_order);
        for i in hits {
            self.prefix(i as u32, &mut seq, &mut starts);
            push(&mut set, &seq, &starts);
        }
        set.stats = self.candidate_stats(set.len() as u64);
        set.tree = Some(self.stats.clone());
        set
    }

    fn candidate_stats(&self, candidates: u64) -> CandidateStats {
        let generated = self.stats.tested + 1;
        CandidateStats {
            generated,
            pruned_visibility: generated.saturating_sub(candidates),
            pruned_side: 0,
            candidates,
            diffracted: 0,
        }
    }

    /// Whether `p` lies in node `i`'s beam (inclusive, with the tree's margin).
    fn holds(&self, i: usize, p: Vec3) -> bool {
        let (lo, hi) = self.nodes[i].planes;
        let eps = EPS * self.tol;
        self.planes[lo as usize..hi as usize]
            .iter()
            .all(|pl| pl.signed_distance_unfused(p) >= -eps)
    }

    /// The surface sequence and, when the options ask for start points, the window centres of
    /// node `i`, TX side first.
    fn prefix(&self, mut i: u32, seq: &mut Vec<SurfaceId>, starts: &mut Vec<Vec3>) {
        seq.clear();
        starts.clear();
        while i != ROOT {
            let node = &self.nodes[i as usize];
            seq.push(SurfaceId(node.surface));
            if self.options.starts {
                let (lo, hi) = node.window;
                starts.push(convex::vertex_mean(&self.verts[lo as usize..hi as usize]));
            }
            i = node.parent;
        }
        seq.reverse();
        starts.reverse();
    }

    /// Build the nodes of `depth` from those of `depth - 1` (the root when `depth == 1`). With
    /// `leaf_rx`, the level is not materialised: children holding RX are emitted into `out`.
    fn grow_level(
        &mut self,
        prep: &Prepared<'_>,
        depth: usize,
        scratch: &mut Scratch,
        mut leaf: Option<&mut Leaf<'_>>,
        progress: Progress<'_>,
    ) -> Result<(), TreeError> {
        let materialised = leaf.is_none();
        if prep.cull_at_build {
            // Nodes are culled as they are built, so no parent changes: chunks of parents
            // can grow apart.
            return match leaf {
                None => self.grow_level_chunked(prep, depth, (None, None), progress),
                Some(leaf) => self.grow_leaves_chunked(prep, depth, leaf, progress),
            };
        }
        if materialised {
            // A fresh level (a rebuild instead keeps the old tree's arenas, already sized).
            let parents = match depth {
                1 => 1,
                _ => self.levels[depth - 2].1 - self.levels[depth - 2].0,
            };
            self.reserve_level(prep, parents);
        }
        self.for_each_parent(prep, (depth, materialised), progress, |tree, p, bufs| {
            tree.grow_children(prep, p, depth, scratch, leaf.as_deref_mut(), bufs);
        })
    }

    /// The parents of level `depth`: the root, or the nodes of the level above.
    fn parents_of(&self, depth: usize) -> Vec<u32> {
        match depth {
            1 => vec![ROOT],
            _ => {
                let (lo, hi) = self.levels[depth - 2];
                (lo as u32..hi as u32).collect()
            }
        }
    }

    /// Report `done` of `parents` parents of level `depth` to `progress`.
    fn report(
        &self,
        prep: &Prepared<'_>,
        depth: usize,
        (done, parents): (usize, usize),
        progress: Progress<'_>,
    ) {
        progress(BuildProgress {
            stage: BuildStage::Tree,
            depth,
            max_order: prep.options.max_order,
            parents_done: done.min(parents),
            parents,
            nodes: self.nodes.len() as u64,
        });
    }

    /// Run `grow(tree, p, bufs)` for every parent `p` of depth `depth` (the root at depth 1),
    /// in order, reporting to `progress` and checking the node budget after each; then close
    /// the level (recorded when `materialised`). `bufs`: scratch for a parent's planes and
    /// children, reused across parents.
    fn for_each_parent(
        &mut self,
        prep: &Prepared<'_>,
        (depth, materialised): (usize, bool),
        progress: Progress<'_>,
        mut grow: impl FnMut(&mut Self, u32, (&mut Vec<Plane>, &mut Vec<u32>)),
    ) -> Result<(), TreeError> {
        let start = self.nodes.len();
        let ids = self.parents_of(depth);
        let (mut planes, mut children) = (Vec::new(), Vec::new());
        for (done, &p) in ids.iter().enumerate() {
            if done % PROGRESS_EVERY == 0 {
                self.report(prep, depth, (done, ids.len()), progress);
            }
            grow(self, p, (&mut planes, &mut children));
            self.check_budget(prep, depth)?;
        }
        self.end_level(start, materialised);
        Ok(())
    }

    /// Build the children of parent `p` (a node of depth `depth - 1`, or the root): the
    /// reflectors meeting its beam, after occlusion culling of `p` where it pays. With `leaf`,
    /// children holding RX are emitted instead of materialised. `bufs`: scratch for the
    /// parent's planes and its children.
    fn grow_children(
        &mut self,
        prep: &Prepared<'_>,
        p: u32,
        depth: usize,
        scratch: &mut Scratch,
        leaf: Option<&mut Leaf<'_>>,
        (plane_copy, children): (&mut Vec<Plane>, &mut Vec<u32>),
    ) {
        let leaf_level = leaf.is_some();
        self.child_candidates(prep, &self.parent_ref(prep, p), leaf_level, children);
        if p != ROOT && worth_culling(prep, children.len(), depth) {
            match self.cull(prep, p, scratch) {
                Cull::Removed => return,
                Cull::Kept => {}
                Cull::Clipped => {
                    self.child_candidates(prep, &self.parent_ref(prep, p), leaf_level, children);
                }
            }
        }
        self.stats.tested += children.len() as u64;
        match leaf {
            // Leaves only read the tree: the parent's planes are borrowed in place.
            Some(leaf) => {
                let parent = self.parent_ref(prep, p);
                leaf.test.apex_distances(&parent);
                for &s in children.iter() {
                    self.leaf_child(prep, &parent, s, leaf);
                }
            }
            // Children grow the arenas: the parent's planes are copied out first.
            None => {
                let parent = self.parent_view(prep, p, plane_copy);
                for &s in children.iter() {
                    self.child(prep, &parent, s, scratch);
                }
            }
        }
    }

    /// In small scenes, room for the level's nodes at most (every parent times every
    /// reflector, within the budget), so that the arenas grow once instead of doubling; large
    /// scenes keep growing as they go (their bound is far above what culling leaves).
    fn reserve_level(&mut self, prep: &Prepared<'_>, parents: usize) {
        if prep.reflectors.len() > LINEAR_SCAN {
            return;
        }
        let room = (parents * prep.reflectors.len()).min(prep.options.max_nodes as usize);
        self.nodes.reserve(room);
        // A window has a hull's vertices plus at most one per clipping plane; a beam one plane
        // more than its window has edges. Typical room windows have 4-6.
        self.verts.reserve(room * 6);
        self.planes.reserve(room * 7);
    }

    /// Stop with [`TreeError::Budget`] once the tree holds more nodes than the budget.
    fn check_budget(&self, prep: &Prepared<'_>, depth: usize) -> Result<(), TreeError> {
        if self.nodes.len() as u64 > prep.options.max_nodes {
            return Err(TreeError::Budget {
                nodes: self.nodes.len() as u64,
                depth,
                max_order: prep.options.max_order,
                budget: prep.options.max_nodes,
            });
        }
        Ok(())
    }

    /// Close the level whose nodes start at `start`: record it when `materialised`.
    fn end_level(&mut self, start: usize, materialised: bool) {
        self.stats.occluders.sort_unstable();
        self.stats.occluders.dedup();
        if materialised {
            self.levels.push((start, self.nodes.len()));
            self.stats
                .nodes_per_depth
                .push((self.nodes.len() - start) as u64);
        }
    }

    /// Node `p` (or the root) as a parent, its beam planes borrowed from the arena.
    fn parent_ref(&self, prep: &Prepared<'_>, p: u32) -> Parent<'_> {
        let (apex, surface, range) = self.parent_parts(prep, p);
        Parent {
            index: p,
            surface,
            apex,
            planes: &self.planes[range.0 as usize..range.1 as usize],
        }
    }

    /// Apex, surface and beam-plane range of node `p` (the root: TX, none, empty).
    fn parent_parts(&self, prep: &Prepared<'_>, p: u32) -> (Vec3, Option<u32>, (u32, u32)) {
        if p == ROOT {
            (prep.tx, None, (0, 0))
        } else {
            let n = &self.nodes[p as usize];
            (n.image, Some(n.surface), n.planes)
        }
    }

    /// Node `p` (or the root) as a parent, its beam planes copied into `planes` (for growing
    /// levels, which push to the arena while the parent is in use).
    fn parent_view<'b>(
        &self,
        prep: &Prepared<'_>,
        p: u32,
        planes: &'b mut Vec<Plane>,
    ) -> Parent<'b> {
        let (apex, surface, range) = self.parent_parts(prep, p);
        planes.clear();
        planes.extend_from_slice(&self.planes[range.0 as usize..range.1 as usize]);
        Parent {
            index: p,
            surface,
            apex,
            planes,
        }
    }

    /// Occlusion culling of node `i` (see [`occlude`]): removes it, or shrinks its window and
    /// beam, or leaves it as it is.
    fn cull(&mut self, prep: &Prepared<'_>, i: u32, scratch: &mut Scratch) -> Cull {
        let node = self.nodes[i as usize];
        let mut no_planes = Vec::new();
        let parent = self.parent_view(prep, node.parent, &mut no_planes);
        scratch.a.clear();
        scratch
            .a
            .extend_from_slice(&self.verts[node.window.0 as usize..node.window.1 as usize]);
        let clips = self.stats.occluder_clips;
        if occlude(prep, &parent, node.surface, scratch, &mut self.stats) {
            self.stats.occluded += 1;
            self.nodes[i as usize].live = false;
            return Cull::Removed;
        }
        if self.stats.occluder_clips == clips {
            return Cull::Kept;
        }
        let planes = beam_planes(
            prep.plane(node.surface),
            node.image,
            &scratch.a,
            &mut self.planes,
        );
        let n = &mut self.nodes[i as usize];
        n.window = push_range(&mut self.verts, &scratch.a);
        n.planes = planes;
        Cull::Clipped
    }

    /// Reflectors that may meet the parent's beam, in increasing index order. On the last level
    /// of a single-receiver trace (`leaf_level`) of a small scene, every reflector: the leaf
    /// test costs about as much as the box test it would save.
    fn child_candidates(
        &self,
        prep: &Prepared<'_>,
        parent: &Parent<'_>,
        leaf_level: bool,
        out: &mut Vec<u32>,
    ) {
        out.clear();
        if parent.index == ROOT {
            out.extend_from_slice(&prep.reflectors);
            return;
        }
        let eps = EPS * prep.tol;
        // On the last level, only surfaces RX can see can end a valid path.
        let last = prep.rx_visible.as_ref().filter(|_| leaf_level);
        let may_end = |s: u32| last.is_none_or(|v| v.visible[s as usize]);
        if prep.reflectors.len() <= LINEAR_SCAN && leaf_level && last.is_none() {
            // Every reflector but the parent's own (`reflectors` is ascending).
            out.extend_from_slice(&prep.reflectors);
            if let Some(own) = parent.surface.and_then(|p| out.binary_search(&p).ok()) {
                out.remove(own);
            }
            return;
        }
        if prep.reflectors.len() <= LINEAR_SCAN {
            out.extend(prep.reflectors.iter().copied().filter(|&s| {
                let (lo, hi) = prep.shapes.boxes[s as usize];
                Some(s) != parent.surface
                    && may_end(s)
                    && (leaf_level || box_meets_halfspaces(lo, hi, parent.planes, eps))
            }));
            return;
        }
        if let Some(last) = last {
            last.bvh.visit(
                |lo, hi| box_meets_halfspaces(lo, hi, parent.planes, eps),
                |i| {
                    let s = last.ids[i as usize];
                    if Some(s) != parent.surface {
                        out.push(s);
                    }
                },
            );
            ascending(out, prep.is_reflector.len());
            return;
        }
        let scene = prep.scene;
        scene.bvh().visit(
            |lo, hi| box_meets_halfspaces(lo, hi, parent.planes, eps),
            |item| {
                if Some(item) != parent.surface && prep.is_reflector[item as usize] {
                    out.push(item);
                }
            },
        );
        ascending(out, prep.is_reflector.len());
    }

    /// Try child `s` of `parent`; push it when its window is not empty and not occluded.
    fn child(&mut self, prep: &Prepared<'_>, parent: &Parent<'_>, s: u32, scratch: &mut Scratch) {
        self.child_probed(prep, parent, s, scratch, None);
    }

    /// [`BeamTree::child`]; with `probe`, the child is tested for occlusion and pushed only
    /// when it can end or lead to a candidate ([`Probe::ends_a_candidate`], trying only the
    /// leaves given with it, when given).
    fn child_probed(
        &mut self,
        prep: &Prepared<'_>,
        parent: &Parent<'_>,
        s: u32,
        scratch: &mut Scratch,
        probe: Option<(&mut Probe, Option<&[u32]>)>,
    ) {
        let plane = *prep.plane(s);
        if plane.signed_distance_unfused(parent.apex).abs() <= prep.tol {
            // Every ray from the apex to this plane runs in it: all such paths graze.
            self.stats.empty += 1;
            return;
        }
        if hull_beyond(prep, parent, s, scratch.last_empty) {
            debug_assert!(
                window_in_beam(prep, parent, s, (&mut scratch.a, &mut scratch.b)).is_some(),
                "a hull beyond a beam plane leaves a window"
            );
            self.stats.empty += 1;
            return;
        }
        if let Some(k) = window_in_beam(prep, parent, s, (&mut scratch.a, &mut scratch.b)) {
            scratch.last_empty = k;
            self.stats.empty += 1;
            return;
        }
        let image = plane.mirror(parent.apex);
        if let Some((probe, only)) = probe
            && !probe.ends_a_candidate(self, prep, (s, image), &scratch.a, only)
        {
            return;
        }
        if prep.cull_at_build && occlude(prep, parent, s, scratch, &mut self.stats) {
            self.stats.occluded += 1;
            return;
        }
        let planes = beam_planes(&plane, image, &scratch.a, &mut self.planes);
        let window = push_range(&mut self.verts, &scratch.a);
        self.nodes.push(Node {
            surface: s,
            parent: parent.index,
            image,
            window,
            planes,
            live: true,
        });
    }

    /// The last level of a single-receiver trace: emit child `s` when RX lies in its beam,
    /// without building its window. RX lies in the beam exactly when the image-method point
    /// (where the ray from the parent's apex to RX's mirror image crosses `s`'s plane) lies in
    /// the parent's beam and in `s`'s polygon. Only an emitted child's window is clipped: its
    /// centre is the IPC start on `s`, like every other window's. (The image-method point
    /// itself, though inside the window, is a worse start for the accelerator's Jacobi
    /// rounds: a third-order path of the dynamic living room then missed its 256-round cap.)
    fn leaf_child(&self, prep: &Prepared<'_>, parent: &Parent<'_>, s: u32, leaf: &mut Leaf<'_>) {
        if !leaf.test.hit(prep, parent, s) {
            return;
        }
        self.prefix(parent.index, &mut leaf.seq, &mut leaf.starts);
        leaf.seq.push(SurfaceId(s));
        if prep.options.starts {
            window_in_beam(prep, parent, s, (&mut leaf.window, &mut leaf.tmp));
            leaf.starts.push(if leaf.window.len() >= 3 {
                convex::vertex_mean(&leaf.window)
            } else {
                prep.scene.surface(SurfaceId(s)).polygon.centroid()
            });
        }
        push(leaf.out, &leaf.seq, &leaf.starts);
    }
}

/// The leaf test of a single-receiver trace: RX, each surface's signed distance to RX and
/// RX's mirror image in it (computed once, read by every leaf test).
struct LeafTest {
    /// Per surface: (signed distance of RX, m; RX mirrored through the plane), shared by the
    /// chunks of a level grown in parallel.
    mirrored: Mirrored,
    /// The current parent's apex's signed distance to each of its beam planes, m (read by
    /// each of its leaf tests).
    apex_d: Vec<Real>,
}

/// Per surface: RX's signed distance to the plane (m) and RX mirrored through it.
type Mirrored = std::sync::Arc<[(Real, Vec3)]>;

impl LeafTest {
    fn new(mirrored: Mirrored) -> Self {
        LeafTest {
            mirrored,
            apex_d: Vec::new(),
        }
    }

    /// Prepare the leaf tests of `parent`'s children ([`LeafTest::apex_d`]).
    fn apex_distances(&mut self, parent: &Parent<'_>) {
        self.apex_d.clear();
        self.apex_d.extend(
            parent
                .planes
                .iter()
                .map(|p| p.signed_distance_unfused(parent.apex)),
        );
    }

    /// Whether child `s` of `parent` ends a candidate: RX lies in its beam (see
    /// [`BeamTree::leaf_child`]); [`LeafTest::apex_distances`] must have been given `parent`.
    fn hit(&self, prep: &Prepared<'_>, parent: &Parent<'_>, s: u32) -> bool {
        let plane = prep.plane(s);
        let tol = prep.tol;
        let eps = EPS * tol;
        let d_apex = plane.signed_distance_unfused(parent.apex);
        let (d_rx, rx_image) = self.mirrored[s as usize];
        // RX must be on the apex's side of the plane (the reflected side) and off it.
        let d_rx_same_side = if d_apex > 0.0 { d_rx } else { -d_rx };
        if d_apex.abs() <= tol || d_rx_same_side < -eps {
            return false;
        }
        // The point is x = apex + t·(rx_image − apex) with t = num / den > 0 (den > 0: |d_apex|
        // > tol ≥ eps ≥ −d_rx_same_side). A beam plane's distance is affine along the line,
        // d(x) = a + t·(r − a) for a = d(apex), r = d(rx_image), so d(x) ≥ −eps is tested as
        // a·den + num·(r − a) ≥ −eps·den: no division for the pairs the beam rejects.
        let (num, den) = (d_apex.abs(), d_apex.abs() + d_rx_same_side);
        if !parent.planes.iter().zip(&self.apex_d).all(|(p, &a)| {
            let r = p.signed_distance_unfused(rx_image);
            a * den + num * (r - a) >= -eps * den
        }) {
            return false;
        }
        let t = num / den;
        if !t.is_finite() {
            return false;
        }
        let x = parent.apex + t * (rx_image - parent.apex);
        prep.scene
            .surface(SurfaceId(s))
            .polygon
            .contains(x, GROW * tol)
    }
}

/// RX's signed distance to each surface's plane and its mirror image in it ([`Mirrored`]).
fn mirrored(prep: &Prepared<'_>, rx: Vec3) -> Mirrored {
    prep.planes
        .iter()
        .map(|pl| {
            let d = pl.signed_distance_unfused(rx);
            (d, rx - (2.0 * d) * pl.normal)
        })
        .collect()
}

/// The last level of a single-receiver trace: the leaf test and the candidates emitted.
struct Leaf<'o> {
    test: LeafTest,
    out: &'o mut CandidateSet,
    /// Scratch for one candidate's sequence, start points and last window.
    seq: Vec<SurfaceId>,
    starts: Vec<Vec3>,
    window: Vec<Vec3>,
    tmp: Vec<Vec3>,
}

impl<'o> Leaf<'o> {
    /// Leaf tests against the RX of `mirrored` (see [`LeafTest::mirrored`]), emitting into `out`.
    fn with_mirrored(mirrored: Mirrored, out: &'o mut CandidateSet) -> Self {
        Leaf {
            test: LeafTest::new(mirrored),
            out,
            seq: Vec::new(),
            starts: Vec::new(),
            window: Vec::new(),
            tmp: Vec::new(),
        }
    }
}

/// Whether a node of the last materialised level of a single-receiver trace can end or lead to
/// a candidate ([`TreeOptions::defer_culling`]): its beam, from its window before occlusion
/// culling, and its children's leaf tests.
struct Probe {
    rx: Vec3,
    test: LeafTest,
    planes: Vec<Plane>,
    children: Vec<u32>,
}

/// The index of a node tried before it is materialised (never a parent in the arenas).
const PENDING: u32 = u32::MAX - 1;

impl Probe {
    fn new(rx: Vec3, mirrored: Mirrored) -> Self {
        Probe {
            rx,
            test: LeafTest::new(mirrored),
            planes: Vec::new(),
            children: Vec::new(),
        }
    }

    /// Whether RX lies in the beam of surface `s`'s node (image `image`, window `window`), or
    /// in the beam of one of its children ([`LeafTest::hit`]); counts the children tested in
    /// `tree`'s statistics. Occlusion culling only shrinks a window, and the beam of a smaller
    /// window lies inside the larger's: a node for which this is false holds no candidate and
    /// has no child that does, culled or not. With `only` (the leaves whose cones hold the
    /// parent's apex, [`join::Joined`]), a node whose reach lists answer tries those leaves
    /// instead of its list: the others cannot pass when its beam is well defined.
    fn ends_a_candidate(
        &mut self,
        tree: &mut BeamTree,
        prep: &Prepared<'_>,
        (s, image): (u32, Vec3),
        window: &[Vec3],
        only: Option<&[u32]>,
    ) -> bool {
        self.planes.clear();
        beam_planes(prep.plane(s), image, window, &mut self.planes);
        let eps = EPS * prep.tol;
        if self
            .planes
            .iter()
            .all(|pl| pl.signed_distance_unfused(self.rx) >= -eps)
        {
            return true;
        }
        let node = Parent {
            index: PENDING,
            surface: Some(s),
            apex: image,
            planes: &self.planes,
        };
        self.test.apex_distances(&node);
        let mut tested = 0;
        let reach = prep.rx_visible.as_ref().and_then(|v| v.reach.as_ref());
        if let Some(reach) = reach.filter(|r| r.answers(prep, (s, image), window, &self.planes)) {
            if let Some(only) = only {
                tree.stats.tested += only.len() as u64;
                return only.iter().any(|&c| self.test.hit(prep, &node, c));
            }
            // Only the reflectors whose mirror beam reaches `s` can pass.
            let found = reach.of_surface(prep, s, image).any(|c| {
                tested += u64::from(c != s);
                c != s && self.test.hit(prep, &node, c)
            });
            tree.stats.tested += tested;
            return found;
        }
        let visible = prep.rx_visible.as_ref();
        let Some(visible) = visible.filter(|_| prep.reflectors.len() > LINEAR_SCAN) else {
            tree.child_candidates(prep, &node, true, &mut self.children);
            tree.stats.tested += self.children.len() as u64;
            return self.children.iter().any(|&c| self.test.hit(prep, &node, c));
        };
        // The first child that passes is enough: no list, no sort, and the walk stops there.
        let found = visible.bvh.find(
            |lo, hi| box_meets_halfspaces(lo, hi, node.planes, eps),
            |i| {
                let c = visible.ids[i as usize];
                tested += u64::from(c != s);
                c != s && self.test.hit(prep, &node, c)
            },
        );
        tree.stats.tested += tested;
        found.is_some()
    }
}

/// Child `s`'s window, its grown hull clipped by `parent`'s beam planes, into `window`
/// (`tmp`: scratch; fewer than 3 vertices: empty, and the index of the plane that emptied it
/// is returned).
fn window_in_beam(
    prep: &Prepared<'_>,
    parent: &Parent<'_>,
    s: u32,
    (window, tmp): (&mut Vec<Vec3>, &mut Vec<Vec3>),
) -> Option<usize> {
    window.clear();
    window.extend_from_slice(prep.hull(s));
    for (k, pl) in parent.planes.iter().enumerate() {
        convex::clip_in_place(window, pl, EPS * prep.tol, tmp);
        if window.len() < 3 {
            return Some(k);
        }
    }
    (window.len() < 3).then_some(0)
}

/// Whether child `s`'s window is empty because every vertex of its grown hull lies beyond
/// `parent`'s beam plane `k` by more than twice the clipping margin (false when there is no
/// plane `k`). Then [`window_in_beam`] leaves nothing either: whatever the planes before `k`
/// cut, the window's vertices stay within the hull (up to rounding far below the margin), so
/// plane `k` drops them all, if an earlier plane has not already.
fn hull_beyond(prep: &Prepared<'_>, parent: &Parent<'_>, s: u32, k: usize) -> bool {
    let Some(pl) = parent.planes.get(k) else {
        return false;
    };
    let clearly = -2.0 * EPS * prep.tol;
    (prep.hull(s).iter()).all(|&v| pl.signed_distance_unfused(v) < clearly)
}

/// Append candidate `seq` to `set` with its start points (`starts`, empty when the options
/// ask for none: the set then has no start points).
fn push(set: &mut CandidateSet, seq: &[SurfaceId], starts: &[Vec3]) {
    if starts.len() == seq.len() {
        set.push_with_starts(seq, starts);
    } else {
        set.push(seq);
    }
}

fn push_range<T: Copy>(arena: &mut Vec<T>, items: &[T]) -> (u32, u32) {
    let lo = arena.len() as u32;
    arena.extend_from_slice(items);
    (lo, arena.len() as u32)
}

/// The beam of rays from `apex` through the convex `window` lying in `plane`, appended to the
/// arena `out`: the near plane (oriented away from the apex) and one side plane per edge
/// (oriented inward, [`Facing`]); returns their range in `out`. Side planes that rounding
/// could have turned ([`side_plane`]: the apex on or near an edge's line) are left out, which
/// only widens the beam.
fn beam_planes(plane: &Plane, apex: Vec3, window: &[Vec3], out: &mut Vec<Plane>) -> (u32, u32) {
    let lo = out.len() as u32;
    let near = if plane.signed_distance_unfused(apex) > 0.0 {
        flip(*plane)
    } else {
        *plane
    };
    out.push(near);
    side_planes(plane, apex, window, out);
    (lo, out.len() as u32)
}

/// The side planes of the rays from `apex` through the convex `window` lying in `plane`,
/// one per window edge, appended to `out`: each facing the window's inside ([`Facing`]) and
/// kept only when rounding cannot have turned it ([`side_plane`]). Shared by the beams
/// ([`beam_planes`]) and the join's cones ([`join`]).
pub(super) fn side_planes(plane: &Plane, apex: Vec3, window: &[Vec3], out: &mut Vec<Plane>) {
    debug_assert!(
        counter_clockwise(plane, window),
        "a window runs clockwise about its plane: its side planes would face out"
    );
    let facing = Facing::of(plane, apex);
    let mut w = window[window.len() - 1];
    for &v in window {
        out.extend(side_plane(apex, (w, v), &facing));
        w = v;
    }
}

/// Whether `window` runs counter-clockwise about `plane`'s normal, as [`Facing`] assumes:
/// its Newell area vector does not point against the normal, beyond the rounding of a window
/// too thin to have an orientation (a relative 1e-9 of its squared size).
fn counter_clockwise(plane: &Plane, window: &[Vec3]) -> bool {
    let twice_area = bt_geom::poly2::newell(window).dot(plane.normal);
    let size2 = (window.iter().zip(window.iter().skip(1)))
        .map(|(a, b)| a.distance_squared(*b))
        .sum::<Real>();
    twice_area >= -1e-9 * size2
}

/// A side plane is kept only when its normal's rounding (about `ε / sin θ` radians, `θ` the
/// angle between the edge and the ray from the apex to it, [`side_plane`]) is below this:
/// then it moves a point at distance `r` from the apex by at most `1e-10 · r`, a tenth of the
/// tree's margin (one length tolerance, `1e-9` of the scene's extent) for points within the
/// scene's extent.
pub(super) const MAX_NORMAL_ERROR: Real = 1e-10;

/// Which way a window's side planes face ([`side_plane`]): windows are convex hulls
/// counter-clockwise in their polygon's frame (about its plane's normal), clipped in order,
/// so an edge's plane `(w − apex) × (v − w)` faces inward exactly when the apex lies on the
/// negative side of the window's plane. This reads one signed distance, which the tree keeps
/// beyond a tolerance (a child whose plane passes within one of the apex is never built),
/// instead of a point inside the window: for a window thinner than the rounding, the vertex
/// mean left the orientation to chance, and a sliver clipped from a window could get a wider
/// beam than the window's.
struct Facing {
    outward: bool,
}

impl Facing {
    /// The facing of a window lying in `plane`, seen from `apex`.
    fn of(plane: &Plane, apex: Vec3) -> Self {
        Facing {
            outward: plane.signed_distance_unfused(apex) > 0.0,
        }
    }
}

/// The plane through `apex` and the window edge from `w` to `v` (the window's edges in
/// order), facing the window's inside ([`Facing`]), or `None` when rounding could have
/// turned it by more than [`MAX_NORMAL_ERROR`] (its relative error, about
/// `1.2e-16·|a|·|e| / |a × e|`, large when the apex lies near the edge's line). Its normal is
/// `(w − apex) × (v − w)`: the edge vector is exact for nearby vertices (Sterbenz), so a short
/// edge far from the apex keeps its plane through its own ends. The cross product of the two
/// rays, `(w − apex) × (v − apex)`, nearly parallel, moved it by about `ε·R² / e` at the
/// window for an edge of length `e` at distance `R` (5 µm for 1 nm at 5 m, beyond the
/// margin: a path just inside the edge was lost). Leaving a plane out only widens a beam or
/// cone. Shared by the beams ([`beam_planes`]) and the join's cones ([`join`]).
fn side_plane(apex: Vec3, (w, v): (Vec3, Vec3), facing: &Facing) -> Option<Plane> {
    let (a, e) = (w - apex, v - w);
    let normal = a.cross(e);
    let (len, ae) = (normal.length(), a.length() * e.length());
    // The error's bound, false for NaN and for a zero normal.
    if !(len > 0.0 && 1.2e-16 * ae <= MAX_NORMAL_ERROR * len) {
        return None;
    }
    let side = Plane::from_point_normal_of_length(apex, normal, len);
    Some(if facing.outward { flip(side) } else { side })
}

/// A counting sort of `(key, value)` pairs (each key below `keys`) by key: the start of each
/// key's run (one more entry than keys, the last the number of pairs) and the values in key
/// order, each key's in the order `pairs` gives them (it is walked twice).
fn by_key<I: Iterator<Item = (u32, u32)>>(
    keys: usize,
    pairs: impl Fn() -> I,
) -> (Vec<u32>, Vec<u32>) {
    let mut starts = vec![0u32; keys + 1];
    for (k, _) in pairs() {
        starts[k as usize + 1] += 1;
    }
    for i in 0..keys {
        starts[i + 1] += starts[i];
    }
    let mut next = starts.clone();
    let mut values = vec![0u32; starts[keys] as usize];
    for (k, v) in pairs() {
        values[next[k as usize] as usize] = v;
        next[k as usize] += 1;
    }
    (starts, values)
}

/// Put `ids` (distinct, each below `n`, as a BVH walk finds them) in increasing order. A long
/// list goes through a bit set of `n` bits (a parent's few hundred children of a city's
/// 18,000 surfaces: a tenth of a sort's instructions), a short one is sorted.
fn ascending(ids: &mut Vec<u32>, n: usize) {
    if ids.len() < 64 {
        ids.sort_unstable();
        return;
    }
    let mut seen = vec![0u64; n.div_ceil(64)];
    for &i in ids.iter() {
        debug_assert!(
            seen[i as usize / 64] & (1 << (i % 64)) == 0,
            "ids are distinct"
        );
        seen[i as usize / 64] |= 1 << (i % 64);
    }
    ids.clear();
    for (w, mut bits) in seen.into_iter().enumerate() {
        while bits != 0 {
            ids.push(w as u32 * 64 + bits.trailing_zeros());
            bits &= bits - 1;
        }
    }
}

/// Whether a cross product of squared length `len2` from two vectors whose squared lengths
/// multiply to `scale2` spans a plane (its length above 1e-12 times the lengths' product):
/// false for (nearly) parallel vectors, and for NaN. Squares spare the square roots.
fn spans_a_plane(len2: Real, scale2: Real) -> bool {
    len2 > 1e-24 * scale2
}

/// Occlusion culling of the window in `scratch.a` (child `s` of `parent`): returns true when a
/// convex surface between the parent's window (or TX) and the new window covers all of it;
/// shrinks the window when one covers all of it but the part beyond one edge.
fn occlude(
    prep: &Prepared<'_>,
    parent: &Parent<'_>,
    s: u32,
    scratch: &mut Scratch,
    stats: &mut TreeStats,
) -> bool {
    if prep.nothing_occludes() {
        return false;
    }
    let scene = prep.scene;
    let mut starts = std::mem::take(&mut scratch.starts);
    ray_starts(prep, parent, &scratch.a, &mut starts);
    let margin = COVER * prep.tol;
    if let Some(o) = scratch
        .last_cover
        .filter(|&o| Some(o) != parent.surface && o != s)
    {
        let polygon = &scene.surface(SurfaceId(o)).polygon;
        if between(polygon.plane(), &starts, &scratch.a, margin)
            && matches!(
                shadow(prep.shadow_edges(o), parent.apex, &scratch.a),
                Shadow::Covers
            )
        {
            stats.occluders.push(o);
            scratch.starts = starts;
            return true;
        }
    }
    // Only a surface that the ray to some window vertex crosses can cover or clip the window
    // (the covered part of a convex window contains a vertex). Ray by ray, nearest first, so a
    // window hidden by the first wall in front costs one BVH walk.
    let mut tested = std::mem::take(&mut scratch.items);
    tested.clear();
    let mut hits = std::mem::take(&mut scratch.hits);
    let mut reached = std::mem::take(&mut scratch.reached);
    let mut covered = false;
    // The rays are those of the window as it was on entry (a clip below only shrinks it).
    let rays = scratch.a.len();
    let mut window_rays = std::mem::take(&mut scratch.rays);
    window_rays.clear();
    window_rays.extend_from_slice(&scratch.a);
    'rays: for k in 0..rays {
        let (a, q) = (starts[k], window_rays[k]);
        // The walk gathers, then the segment tests run in a build with FMA.
        reached.clear();
        prep.visit_opaque((a, q), |item| {
            if Some(item) != parent.surface
                && item != s
                && prep.is_occluder(item)
                && !tested.contains(&item)
            {
                reached.push(item);
            }
        });
        segment_hits(scene, &reached, (a, q), parent.apex, &mut hits);
        hits.sort_unstable_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
        for &(_, o) in &hits {
            tested.push(o);
            let polygon = &scene.surface(SurfaceId(o)).polygon;
            if !between(polygon.plane(), &starts, &scratch.a, margin) {
                continue;
            }
            match shadow(prep.shadow_edges(o), parent.apex, &scratch.a) {
                Shadow::Covers => {
                    stats.occluders.push(o);
                    scratch.last_cover = Some(o);
                    covered = true;
                    break 'rays;
                }
                Shadow::AllBut(plane) => {
                    stats.occluders.push(o);
                    convex::clip(&scratch.a, &plane, EPS * prep.tol, &mut scratch.b);
                    std::mem::swap(&mut scratch.a, &mut scratch.b);
                    stats.occluder_clips += 1;
                    if scratch.a.len() < 3 {
                        covered = true;
                        break 'rays;
                    }
                }
                Shadow::None => {}
            }
        }
    }
    scratch.items = tested;
    scratch.hits = hits;
    scratch.reached = reached;
    scratch.starts = starts;
    scratch.rays = window_rays;
    covered
}

/// Into `starts` (cleared first): the start points of the rays from `parent`'s apex through
/// the `window`'s vertices, on the parent's plane (or the apex itself at the root).
fn ray_starts(prep: &Prepared<'_>, parent: &Parent<'_>, window: &[Vec3], starts: &mut Vec<Vec3>) {
    let start_plane = parent.surface.map(|p| *prep.plane(p));
    starts.clear();
    starts.extend(window.iter().map(|&q| match &start_plane {
        None => parent.apex,
        Some(pl) => match pl.line_parameter(parent.apex, q) {
            Some(t) => parent.apex + t * (q - parent.apex),
            None => q,
        },
    }));
}

/// The surfaces of `reached` (in order) that the segment `a -> q` crosses
/// ([`bt_geom::Polygon::blocks_segment`], no tolerance), into `hits` as (squared distance from
/// `apex` to the surface's centroid, surface), after clearing it. Compiled with the `fma`
/// target feature when the CPU has it (checked at run time): the test's
/// `Plane::signed_distance` uses `mul_add`, a software call without it (seven million calls
/// in Munich at order 3). Bit-identical either way, as in `bt_solve`'s batches.
fn segment_hits(
    scene: &Scene,
    reached: &[u32],
    (a, q): (Vec3, Vec3),
    apex: Vec3,
    hits: &mut Vec<(Real, u32)>,
) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("fma") {
        // SAFETY: the CPU supports FMA (checked just above).
        return unsafe { segment_hits_fma(scene, reached, (a, q), apex, hits) };
    }
    segment_hits_impl(scene, reached, (a, q), apex, hits)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "fma")]
fn segment_hits_fma(
    scene: &Scene,
    reached: &[u32],
    segment: (Vec3, Vec3),
    apex: Vec3,
    hits: &mut Vec<(Real, u32)>,
) {
    segment_hits_impl(scene, reached, segment, apex, hits)
}

/// [`segment_hits`]' body, inlined into both of its builds.
#[inline(always)]
fn segment_hits_impl(
    scene: &Scene,
    reached: &[u32],
    (a, q): (Vec3, Vec3),
    apex: Vec3,
    hits: &mut Vec<(Real, u32)>,
) {
    hits.clear();
    for &item in reached {
        let polygon = &scene.surface(SurfaceId(item)).polygon;
        if polygon.blocks_segment(a, q, 0.0, 0.0) {
            hits.push((polygon.centroid().distance_squared(apex), item));
        }
    }
}

/// Whether every segment start lies strictly on one side of `plane` and every window vertex
/// strictly on the other, by `margin`: then each ray crosses the plane strictly between them.
fn between(plane: &Plane, starts: &[Vec3], window: &[Vec3], margin: Real) -> bool {
    let side = |p: &Vec3| plane.signed_distance_unfused(*p);
    let front = starts.iter().all(|p| side(p) > margin) && window.iter().all(|q| side(q) < -margin);
    let back = starts.iter().all(|p| side(p) < -margin) && window.iter().all(|q| side(q) > margin);
    front || back
}

enum Shadow {
    /// Every ray through the window crosses the occluder at least `margin` inside its edges.
    Covers,
    /// Every ray crosses it inside, except across one edge: clip the window to this half-space
    /// (the uncovered side).
    AllBut(Plane),
    None,
}

/// An occluder's edge as [`shadow`] reads it: its start moved inward by the cover margin in
/// the occluder's plane, its direction (start to end, m) and the inward unit normal.
type ShadowEdge = (Vec3, Vec3, Vec3);

/// The [`ShadowEdge`]s of the convex `occluder`, its edges moved inward by `margin` (m): what
/// [`shadow`] needs of the occluder alone, made once per occluder and trace.
fn shadow_edges(occluder: &bt_geom::Polygon, margin: Real) -> Box<[ShadowEdge]> {
    let v = occluder.vertices();
    let n = v.len();
    let normal = occluder.plane().normal;
    (0..n)
        .map(|i| {
            let (a, b) = (v[i], v[if i + 1 == n { 0 } else { i + 1 }]);
            let dir = b - a;
            let mut inward = normal.cross(dir).normalize_or_zero();
            if (occluder.centroid() - a).dot(inward) < 0.0 {
                inward = -inward;
            }
            (a + margin * inward, dir, inward)
        })
        .collect()
}

/// The shadow from `apex` on the window's vertices of a convex occluder, given by its
/// [`shadow_edges`]: each edge, moved inward, spans a plane with the apex.
fn shadow(edges: &[ShadowEdge], apex: Vec3, window: &[Vec3]) -> Shadow {
    let mut open: Option<Plane> = None;
    for &(moved, dir, inward) in edges {
        let pn = (moved - apex).cross(dir);
        let (len2, scale2) = (
            pn.length_squared(),
            (moved - apex).length_squared() * dir.length_squared(),
        );
        if !spans_a_plane(len2, scale2) {
            return Shadow::None;
        }
        let plane = Plane::from_point_normal_of_length(apex, pn, len2.sqrt());
        let plane = orient_towards(plane, moved + inward);
        if window
            .iter()
            .all(|q| plane.signed_distance_unfused(*q) > 0.0)
        {
            continue;
        }
        if open.is_some()
            || window
                .iter()
                .all(|q| plane.signed_distance_unfused(*q) <= 0.0)
        {
            return Shadow::None;
        }
        open = Some(flip(plane));
    }
    match open {
        None => Shadow::Covers,
        Some(plane) => Shadow::AllBut(plane),
    }
}

/// Whether to find the reflectors RX sees before the last level of a single-receiver trace:
/// in large scenes, when the last level's parents number at least an eighth of the reflectors
/// (the visibility test costs about one occlusion test per reflector; in the city it removes
/// most leaf tests at order 3 but would cost more than it saves at orders 1 and 2).
fn worth_rx_visibility(prep: &Prepared<'_>, tree: &BeamTree) -> bool {
    let parents = tree.levels.last().map_or(1, |&(lo, hi)| hi - lo);
    prep.cull_at_build && 8 * parents >= prep.reflectors.len()
}

/// Per surface, whether a reflector is (partly) visible from `rx`: the occlusion test of a
/// first-level node ([`occlude`]) with RX as the apex and the reflector's grown hull as the
/// window. A reflector that a convex occluder covers entirely as seen from RX ends no valid
/// path: its last segment would cross the occluder (the reverse of culling a first
/// reflection from TX). Blockers are `false`.
fn rx_visibility(prep: &Prepared<'_>, rx: Vec3, stats: &mut TreeStats) -> RxVisible {
    let mut visible = vec![false; prep.planes.len()];
    for (part, seen) in chunked::map_chunks(prep, (&prep.reflectors, None), |chunk| {
        rx_sees(prep, rx, chunk)
    }) {
        stats.absorb(&part);
        for s in seen {
            visible[s as usize] = true;
        }
    }
    let ids: Vec<u32> = prep
        .reflectors
        .iter()
        .copied()
        .filter(|&s| visible[s as usize])
        .collect();
    RxVisible {
        visible,
        bvh: bvh_over(prep.scene, &ids),
        ids,
        reach: None,
    }
}

/// A BVH over the polygons of `scene`'s surfaces `ids` (item `i` is surface `ids[i]`): the
/// reflectors RX sees ([`rx_visibility`]), the opaque surfaces ([`Opaque`]).
fn bvh_over(scene: &Scene, ids: &[u32]) -> bt_geom::bvh::Bvh {
    let polygons: Vec<&bt_geom::Polygon> = ids
        .iter()
        .map(|&s| &scene.surface(SurfaceId(s)).polygon)
        .collect();
    bt_geom::bvh::Bvh::build(&polygons)
}

/// The reflectors of `chunk` that RX sees (see [`rx_visibility`]), and the occlusion tests'
/// statistics.
fn rx_sees(prep: &Prepared<'_>, rx: Vec3, chunk: &[u32]) -> (TreeStats, Vec<u32>) {
    let from_rx = Parent {
        index: ROOT,
        surface: None,
        apex: rx,
        planes: &[],
    };
    let (mut stats, mut scratch) = (TreeStats::default(), Scratch::default());
    let seen = chunk.iter().copied().filter(|&s| {
        if prep.plane(s).signed_distance_unfused(rx).abs() <= prep.tol {
            // RX in the surface's plane: every path ending there grazes; keep it (validation
            // decides), as the tree keeps what it cannot prove.
            return true;
        }
        scratch.a.clear();
        scratch.a.extend_from_slice(prep.hull(s));
        !occlude(prep, &from_rx, s, &mut scratch, &mut stats)
    });
    let seen = seen.collect();
    (stats, seen)
}

/// The candidates of `scene` for its own RX up to `options.max_order`: the tree is built to
/// order `max_order - 1` and the last level is tested against RX without being materialised.
/// A scene without both terminals fails ([`TreeError::Scene`]).
pub fn candidates(scene: &Scene, options: TreeOptions) -> Result<CandidateSet, TreeError> {
    candidates_with_progress(scene, options, &mut |_| {})
}

/// [`candidates`], reporting to `progress`.
pub fn candidates_with_progress(
    scene: &Scene,
    options: TreeOptions,
    progress: Progress<'_>,
) -> Result<CandidateSet, TreeError> {
    candidates_in(scene, options, &mut TreeCache::default(), progress)
}

/// [`candidates_with_progress`], reusing and refilling `cache` (the same set as with a fresh
/// cache; a stream of traces of one geometry skips the hulls and the arenas' allocation).
pub fn candidates_in(
    scene: &Scene,
    options: TreeOptions,
    cache: &mut TreeCache,
    progress: Progress<'_>,
) -> Result<CandidateSet, TreeError> {
    candidates_and_diffracted_in(scene, options, None, cache, progress)
}

/// [`candidates_in`], with `diffraction: Some(..)` also the candidates with one or two
/// diffractions it allows in [`CandidateSet::diffracted`]: the TX tree's levels below the last
/// are joined with a tree grown from RX ([`join_diffracted`]).
pub fn candidates_and_diffracted_in(
    scene: &Scene,
    options: TreeOptions,
    diffraction: Option<Diffracting>,
    cache: &mut TreeCache,
    progress: Progress<'_>,
) -> Result<CandidateSet, TreeError> {
    let rx = scene.terminals()?.rx;
    let mut prep = Prepared::new(scene, options, cache)?;
    let mut tree = BeamTree::empty(&prep);
    let arenas = Arenas::take(cache);
    (tree.nodes, tree.verts, tree.planes) = (arenas.nodes, arenas.verts, arenas.planes);
    let mut scratch = Scratch::default();
    // Deferred culling: the last materialised level keeps only the nodes that can end or lead
    // to a candidate, culled as they are kept; RX's view is needed to tell them.
    let defer = options.defer_culling
        && diffraction.is_none()
        && prep.cull_at_build
        && options.max_order >= 2;
    let eager = options.max_order.saturating_sub(if defer { 2 } else { 1 });
    for depth in 1..=eager {
        tree.grow_level(&prep, depth, &mut scratch, None, progress)?;
    }
    let rx_mirrored = mirrored(&prep, rx);
    if defer {
        let mut visible = rx_visibility(&prep, rx, &mut tree.stats);
        // The join reads the reach lists (and the probes then read them too).
        let parents = tree.levels.last().copied().unwrap_or_default();
        let join = join::pays(&prep, options.max_order, parents.1 - parents.0);
        if join || reach::Reach::pays(&prep, &visible.ids) {
            visible.reach = Some(reach::Reach::of(&prep, &visible.ids, &rx_mirrored));
        }
        prep.rx_visible = Some(visible);
        let reach = prep.rx_visible.as_ref().and_then(|v| v.reach.as_ref());
        let joined = (reach.filter(|_| join))
            .map(|reach| join::Pairs::of(&tree, &prep, (&rx_mirrored, reach), parents));
        let probe = (rx, rx_mirrored.clone());
        let level = (Some(&probe), joined.as_ref());
        tree.grow_level_chunked(&prep, options.max_order - 1, level, progress)?;
    }
    // The materialised levels' candidates first, then the last level's, tested against RX
    // without being materialised, straight into the same set.
    let mut set = tree.candidates(rx);
    if options.max_order > 0 {
        if !defer && worth_rx_visibility(&prep, &tree) {
            prep.rx_visible = Some(rx_visibility(&prep, rx, &mut tree.stats));
        }
        let mut leaf = Leaf::with_mirrored(rx_mirrored, &mut set);
        tree.grow_level(
            &prep,
            options.max_order,
            &mut scratch,
            Some(&mut leaf),
            progress,
        )?;
    }
    set.stats = tree.candidate_stats(set.len() as u64);
    set.tree = Some(tree.stats.clone());
    let side = diffraction
        .map(|diffracting| KeptSide::take(cache, scene, (&tree, diffracting), &mut *progress));
    Arenas {
        nodes: tree.nodes,
        verts: tree.verts,
        planes: tree.planes,
    }
    .give_back(cache);
    prep.keep_in(cache);
    if let Some(side) = side {
        set.diffracted = diffracted_reporting(scene, &side.side, (options, cache), progress)?;
        set.stats.diffracted = set.diffracted.len() as u64;
        cache.side = Some(side);
    }
    Ok(set)
}

/// A TX tree's [`DiffractionSide`] kept in a [`TreeCache`] with what it was built from, so
/// that the next trace from the same TX (a moving receiver) skips the TX side's reaches.
struct KeptSide {
    geometry: bt_scene::GeometryKey,
    /// The TX (scene-local frame, m), the tree's options, the diffraction options and (in
    /// `side`) the tree's tolerance: equal bit for bit, or the side is built anew.
    tx: Vec3,
    options: TreeOptions,
    diffracting: Diffracting,
    side: DiffractionSide,
}

impl KeptSide {
    /// `cache`'s kept side when it was built for `tx`'s tree in `scene`, or a new one (its
    /// reaches reported to `progress`).
    fn take(
        cache: &mut TreeCache,
        scene: &Scene,
        (tx, diffracting): (&BeamTree, Diffracting),
        progress: Progress<'_>,
    ) -> Self {
        let same = |k: &KeptSide| {
            k.geometry.matches(scene)
                && k.tx == tx.tx
                && k.options == tx.options
                && k.side.tol == tx.tol
                && k.diffracting == diffracting
        };
        match cache.side.take() {
            Some(kept) if same(&kept) => kept,
            _ => KeptSide {
                geometry: scene.geometry_key(),
                tx: tx.tx,
                options: tx.options,
                diffracting,
                side: DiffractionSide::reporting(
                    scene,
                    (tx, tx.options.max_order),
                    diffracting,
                    progress,
                ),
            },
        }
    }
}

/// The diffracted candidates of `scene`'s RX with a kept TX tree's side
/// ([`DiffractionSide::of`], same order): the RX side from a tree grown from RX to depth
/// `options.max_order − 1` with `cache`. Stops beyond `options.max_nodes` candidates.
pub fn diffracted_with(
    scene: &Scene,
    tx: &DiffractionSide,
    options: TreeOptions,
    cache: &mut TreeCache,
) -> Result<crate::diffraction::DiffractedSet, TreeError> {
    diffracted_reporting(scene, tx, (options, cache), &mut |_| {})
}

/// [`diffracted_with`], reporting the RX tree's build ([`BuildStage::RxTree`]) and its
/// reaches to `progress`.
fn diffracted_reporting(
    scene: &Scene,
    tx: &DiffractionSide,
    (options, cache): (TreeOptions, &mut TreeCache),
    progress: Progress<'_>,
) -> Result<crate::diffraction::DiffractedSet, TreeError> {
    if options.max_order == 0 {
        return Ok(Default::default());
    }
    let ends = scene.terminals()?;
    let swapped = scene.with_terminals(scene.to_world(ends.rx), scene.to_world(ends.tx))?;
    let depth = TreeOptions {
        max_order: options.max_order - 1,
        starts: false,
        ..options
    };
    let rx = BeamTree::build_in(&swapped, depth, cache, &mut |p| {
        progress(BuildProgress {
            stage: BuildStage::RxTree,
            ..p
        })
    })?;
    diffraction::join_reporting(scene, tx, (&rx, options.max_nodes), progress)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// A trace with diffraction reports each stage of its work to the progress callback, in
    /// order: TX's tree, the edges its nodes reach, RX's tree and the edges its nodes reach;
    /// each depth's reaches end with all of its nodes done.
    #[test]
    fn a_diffracting_trace_reports_every_stage() {
        let scene = bt_testkit::random_scene(3, 40);
        let diffracting = Diffracting {
            min_edge_length: 0.0,
            max_diffractions: 1,
        };
        let mut reports = Vec::new();
        let mut cache = TreeCache::default();
        let options = TreeOptions::new(3);
        let diffraction = Some(diffracting);
        candidates_and_diffracted_in(&scene, options, diffraction, &mut cache, &mut |p| {
            reports.push(p)
        })
        .unwrap();
        let mut stages: Vec<BuildStage> = reports.iter().map(|p| p.stage).collect();
        stages.dedup();
        use BuildStage::*;
        assert_eq!(stages, [Tree, Reaches, RxTree, Reaches], "{reports:?}");
        let reaches = reports.iter().filter(|p| p.stage == Reaches);
        let ends = reaches.clone().filter(|p| p.parents_done == p.parents);
        let depths = |it: &mut dyn Iterator<Item = &BuildProgress>| {
            let mut d: Vec<usize> = it.map(|p| p.depth).collect();
            d.dedup();
            d
        };
        assert!(!depths(&mut reaches.clone()).is_empty());
        assert_eq!(
            depths(&mut reaches.clone()).len(),
            depths(&mut ends.clone()).len()
        );
        assert!(reaches.clone().all(|p| p.parents_done <= p.parents));
    }

    /// The occluders (convex, opaque) that the segment `a -> q` crosses, among `ids`.
    fn crossed(
        prep: &Prepared<'_>,
        ids: impl Iterator<Item = u32>,
        (a, q): (Vec3, Vec3),
    ) -> Vec<u32> {
        let mut out: Vec<u32> = ids
            .filter(|&s| prep.is_occluder(s))
            .filter(|&s| {
                prep.scene
                    .surface(SurfaceId(s))
                    .polygon
                    .blocks_segment(a, q, 0.0, 0.0)
            })
            .collect();
        out.sort_unstable();
        out.dedup();
        out
    }

    proptest! {
        #![proptest_config(ProptestConfig {
            cases: 256,
            rng_seed: proptest::test_runner::RngSeed::Fixed(0x0b5c_0001),
            ..ProptestConfig::default()
        })]

        /// With penetrable surfaces, occlusion's walks search the index of the opaque ones
        /// ([`Opaque`]): along any segment they find exactly the occluders that a scan of
        /// every surface finds crossing it (so culling removes and clips the same windows as
        /// with the scene's BVH), and no walk at all only when every surface is penetrable.
        #[test]
        fn occlusion_walks_find_every_crossed_occluder(
            seed in 0u64..1_000_000, n in 1usize..9, everywhere in any::<bool>(),
            ends in proptest::array::uniform6(0.0..1.0f64),
        ) {
            let Some(scene) = bt_testkit::nasty_penetrable_scene(seed, n, 0) else {
                return Ok(());
            };
            let scene = scene.with_transmission(everywhere, 3);
            let mut cache = TreeCache::default();
            let prep = Prepared::new(&scene, TreeOptions::new(3), &mut cache).unwrap();
            let (lo, hi) = scene.bvh().bounds().unwrap();
            let at = |f: &[f64]| lo + Vec3::new(f[0], f[1], f[2]) * (hi - lo);
            let segment = (at(&ends[..3]), at(&ends[3..]));
            let n_surfaces = scene.surfaces().len() as u32;
            let mut walked = Vec::new();
            prep.visit_opaque(segment, |s| walked.push(s));
            prop_assert_eq!(
                crossed(&prep, walked.into_iter(), segment),
                crossed(&prep, 0..n_surfaces, segment)
            );
            let every_one_penetrable = (0..n_surfaces).all(|s| scene.penetrable(SurfaceId(s)));
            prop_assert_eq!(prep.nothing_occludes(), every_one_penetrable);
        }
    }
}
