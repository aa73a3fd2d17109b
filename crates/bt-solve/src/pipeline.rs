//! The pipeline under the [`crate::Tracer`]: candidates → solver → valid paths, and the types
//! every trace shares ([`TraceOptions`], [`Traced`], [`TraceError`]).
//!
//! Front ends trace through the `Tracer`; the candidate generator, its budget and the solver
//! dispatch live here, in one place. [`candidates`] stays public for the accelerator's host and
//! the studies, which solve the candidate set their own way.

use crate::partner::Partner;
use crate::{Solver, TraceResult};
use bt_geom::Vec3;
use bt_paths::beamtree::{
    BeamTree, DiffractionSide, TreeCache, TreeOptions, TreeStats, diffracted_with,
};
pub use bt_paths::beamtree::{BuildProgress, BuildStage, Progress};
use bt_paths::diffraction::Diffracting;
use bt_paths::{AllVisible, CandidateSet, CandidateStats};
use bt_scene::{Scene, SceneError};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::time::{Duration, Instant};

/// How candidate surface sequences are generated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum CandidateMode {
    /// Visibility-driven generation (the default): only sequences geometry allows.
    #[default]
    BeamTree,
    /// Every sequence over the weak visibility network (paper's WVRN).
    Wvrn,
    /// Every sequence up to the order (side test only): the reference for checking.
    Exhaustive,
}

/// Default budget on candidate sequences (see [`TraceOptions::max_candidates`]).
pub const DEFAULT_MAX_CANDIDATES: u64 = 2_000_000;

/// Default budget on the WVRN's pair tests (see [`TraceOptions::max_wvrn_tests`]).
pub const DEFAULT_MAX_WVRN_TESTS: u64 = bt_paths::wvrn::MAX_WVRN_TESTS.limit;

/// What to trace and how.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct TraceOptions {
    /// Highest number of reflections.
    pub max_order: usize,
    /// Solver for the candidates.
    pub solver: Solver,
    /// Candidate generator.
    pub candidates: CandidateMode,
    /// Spread the work over rayon's pool (output identical either way).
    pub parallel: bool,
    /// Budget: the trace stops with [`TraceError::Budget`] rather than generate more
    /// candidates (or beam-tree nodes) than this.
    pub max_candidates: u64,
    /// Budget: the WVRN generator stops with [`TraceError::OverBudget`] before building a
    /// network of more pair tests than this ([`bt_paths::wvrn::build_tests`]).
    pub max_wvrn_tests: u64,
    /// Thin-slab transmission through every reflector whose material is a slab (default off;
    /// a material's `"transmission": true` switches it on for that material either way):
    /// [`Tracer`](crate::Tracer) traces its scenes
    /// [`with_transmission`](Scene::with_transmission)`(transmission, max_order)`, so that a
    /// path's crossings count in `max_order`.
    pub transmission: bool,
    /// Edge diffraction (default off).
    pub diffraction: DiffractionOptions,
}

/// Which diffracted paths a trace looks for. A diffraction counts as one interaction of the
/// order: a path has at most `max_order` interactions, at most `max_diffractions` of them
/// diffractions.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct DiffractionOptions {
    /// Diffractions per path: 0 (off, the default), 1 or 2.
    pub max_diffractions: usize,
    /// Edges shorter than this (metres) do not diffract (default 0: every edge).
    pub min_edge_length: bt_geom::Real,
}

impl DiffractionOptions {
    /// One diffraction per path on every edge.
    pub fn first_order() -> Self {
        DiffractionOptions {
            max_diffractions: 1,
            min_edge_length: 0.0,
        }
    }
    /// What the candidates diffract on, when diffraction is on.
    pub fn enabled(&self) -> Option<Diffracting> {
        (self.max_diffractions > 0).then_some(Diffracting {
            min_edge_length: self.min_edge_length,
            max_diffractions: self.max_diffractions,
        })
    }
}

impl TraceOptions {
    /// The image method over the default generator, in parallel, default budget.
    pub fn new(max_order: usize) -> Self {
        TraceOptions {
            max_order,
            solver: Solver::Image,
            candidates: CandidateMode::default(),
            parallel: true,
            max_candidates: DEFAULT_MAX_CANDIDATES,
            max_wvrn_tests: DEFAULT_MAX_WVRN_TESTS,
            transmission: false,
            diffraction: DiffractionOptions::default(),
        }
    }

    /// What a user should know before tracing `scene` under these options: with
    /// transmission, the reflector materials that stay opaque (half-spaces and constant-loss
    /// materials have no thickness to cross), by name.
    pub fn warnings(&self, scene: &Scene) -> Vec<String> {
        let opaque = scene.opaque_materials();
        if !self.transmission || opaque.is_empty() {
            return Vec::new();
        }
        let names: Vec<String> = (opaque.iter().take(8))
            .map(|m| format!("\"{}\"", bt_scene::name::shown(m)))
            .collect();
        let more = opaque.len().saturating_sub(names.len());
        let more = if more > 0 {
            format!(" and {more} more")
        } else {
            String::new()
        };
        vec![format!(
            "--transmission: surfaces of {}{more} stay opaque: a half-space (or a material \
             without a radio model) has no thickness to cross; give one with --thickness or \
             the material's \"thickness\"",
            names.join(", ")
        )]
    }

    /// `scene` as traces under these options see it: its penetrable surfaces
    /// ([`Scene::with_transmission`]) and a path's interaction budget, `max_order`.
    pub fn scene_of(&self, scene: &Scene) -> Scene {
        scene.with_transmission(self.transmission, self.max_order)
    }
}

/// Why a trace could not run.
#[derive(Debug, thiserror::Error)]
pub enum TraceError {
    /// The work would exceed the candidate budget.
    #[error(
        "candidate budget exceeded: {} candidates at order {max_order} (budget {budget}); \
         lower the order or raise the budget with --max-candidates",
        bt_geom::Count(*.estimate)
    )]
    Budget {
        /// Candidates (or tree nodes) counted or estimated (saturating: `u64::MAX` means more).
        estimate: u64,
        /// The budget.
        budget: u64,
        /// The order asked for.
        max_order: usize,
    },
    /// Other work over its budget (the WVRN's pair tests).
    #[error(transparent)]
    OverBudget(#[from] bt_geom::OverBudget),
    /// The beam tree ran out of its node budget (a tree's scene error, such as a missing
    /// terminal, converts to [`TraceError::Scene`] instead: one shape per cause).
    #[error(transparent)]
    Tree(bt_paths::beamtree::TreeError),
    /// A receiver (or transmitter) position is not valid in the scene.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// SBR asked for in a scene with penetrable surfaces: it does not transmit.
    #[error(
        "the SBR solver does not transmit, and {penetrable} surface(s) of this scene are \
         penetrable (the first: \"{first}\"; --transmission, or a material's \
         \"transmission\": true): use --solver image or ipc"
    )]
    SbrTransmission {
        /// Penetrable surfaces in the scene.
        penetrable: usize,
        /// The first one's name, as messages show names ([`bt_scene::name::shown`]).
        first: String,
    },
}

impl From<bt_paths::beamtree::TreeError> for TraceError {
    fn from(e: bt_paths::beamtree::TreeError) -> Self {
        match e {
            bt_paths::beamtree::TreeError::Scene(e) => TraceError::Scene(e),
            e => TraceError::Tree(e),
        }
    }
}

/// Wall time of each stage of one trace.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct StageTimes {
    /// Candidate generation.
    pub candidates: Duration,
    /// Solving and validation.
    pub solve: Duration,
}

/// The outcome of one trace: candidate statistics, valid paths and outcome counts.
#[derive(Debug, Clone, Default)]
pub struct Traced {
    /// How many candidates each stage produced.
    pub candidates: CandidateStats,
    /// What the beam tree did (beam-tree mode only).
    pub tree: Option<TreeStats>,
    /// Valid paths (in candidate order) and outcome counts.
    pub result: TraceResult,
    /// Stage wall times.
    pub time: StageTimes,
}

/// Generate the candidates of `scene` under `options` (with the budget checked). A scene
/// without both terminals fails with [`TraceError::Scene`]
/// ([`bt_scene::SceneError::MissingTerminal`] names the missing ones).
pub fn candidates(scene: &Scene, options: &TraceOptions) -> Result<CandidateSet, TraceError> {
    candidates_with_progress(scene, options, &mut |_| {})
}

/// [`candidates`], reporting the beam tree's build to `progress` (the enumerating modes report
/// nothing: their budget is checked before they start).
pub fn candidates_with_progress(
    scene: &Scene,
    options: &TraceOptions,
    progress: Progress<'_>,
) -> Result<CandidateSet, TraceError> {
    let tree = tree_options(options);
    generate(scene, options, tree, &mut TreeCache::default(), progress)
}

/// The candidates of `options.candidates`, the beam tree built with `tree` and `cache`.
fn generate(
    scene: &Scene,
    options: &TraceOptions,
    tree: TreeOptions,
    cache: &mut TreeCache,
    progress: Progress<'_>,
) -> Result<CandidateSet, TraceError> {
    scene.terminals()?;
    if matches!(options.solver, Solver::Sbr(_)) && scene.transmits() {
        let ids: Vec<bt_scene::SurfaceId> = (0..scene.surfaces().len() as u32)
            .map(bt_scene::SurfaceId)
            .filter(|&id| scene.penetrable(id))
            .collect();
        return Err(TraceError::SbrTransmission {
            penetrable: ids.len(),
            first: bt_scene::name::shown(&scene.surface(ids[0]).name),
        });
    }
    check_budget(scene, options)?;
    let diffraction = options.diffraction.enabled();
    let mut set = match options.candidates {
        CandidateMode::Exhaustive => bt_paths::enumerate(scene, options.max_order, &AllVisible)?,
        CandidateMode::BeamTree => {
            return Ok(bt_paths::beamtree::candidates_and_diffracted_in(
                scene,
                tree,
                diffraction,
                cache,
                progress,
            )?);
        }
        CandidateMode::Wvrn => {
            wvrn_budget(scene, options.max_wvrn_tests)?;
            let wvrn = bt_paths::wvrn::Wvrn::build(scene)?;
            bt_paths::enumerate(scene, options.max_order, &wvrn)?
        }
    };
    // The enumerating modes diffract blindly (the WVRN relates surfaces, not edges).
    if let Some(diffracting) = diffraction {
        set.diffracted =
            bt_paths::diffraction::enumerate_diffracted(scene, options.max_order, diffracting);
        set.stats.diffracted = set.diffracted.len() as u64;
    }
    Ok(set)
}

/// The beam-tree options of a trace: its order, and its candidate budget as the node budget.
pub(crate) fn tree_options(options: &TraceOptions) -> TreeOptions {
    TreeOptions {
        max_nodes: options.max_candidates,
        parallel: options.parallel,
        ..TreeOptions::new(options.max_order)
    }
}

/// [`tree_options`] for a trace that solves the candidates itself: start points only for the
/// solver that reads them (IPC).
pub(crate) fn solver_tree_options(options: &TraceOptions) -> TreeOptions {
    TreeOptions {
        starts: matches!(options.solver, Solver::Ipc(_)),
        ..tree_options(options)
    }
}

/// Check the budget before enumerating: the exhaustive and WVRN generators are refused when
/// the sequence count [`exhaustive_count`] exceeds it (the beam tree counts its nodes as it
/// builds them instead).
pub(crate) fn check_budget(scene: &Scene, options: &TraceOptions) -> Result<(), TraceError> {
    if options.candidates == CandidateMode::BeamTree {
        return Ok(());
    }
    options_budget(scene, options)
}

/// Stop before enumerating every sequence of `scene` up to `max_order` (no surface twice in a
/// row) when their count [`exhaustive_count`] exceeds `budget` (`--max-candidates`): for
/// consumers that enumerate exhaustively (the WVRN view, the fixed-point host).
pub fn exhaustive_budget(scene: &Scene, max_order: usize, budget: u64) -> Result<(), TraceError> {
    let reflectors = scene.reflectors().count() as u64;
    let estimate = exhaustive_count(reflectors, max_order);
    check_estimate(estimate, budget, max_order)
}

/// Stop before building the WVRN of `scene` when its pair tests
/// ([`bt_paths::wvrn::build_tests`]) exceed `budget` (`--max-wvrn-tests`).
pub fn wvrn_budget(scene: &Scene, budget: u64) -> Result<(), TraceError> {
    let tests = bt_paths::wvrn::build_tests(scene);
    Ok(bt_paths::wvrn::MAX_WVRN_TESTS
        .with_limit(budget)
        .check(tests)?)
}

/// [`exhaustive_budget`] for the candidates of `options`: the sequences, and the diffracted
/// ones when diffraction is on ([`bt_paths::diffraction::diffracted_count`]).
fn options_budget(scene: &Scene, options: &TraceOptions) -> Result<(), TraceError> {
    let reflectors = scene.reflectors().count() as u64;
    let mut estimate = exhaustive_count(reflectors, options.max_order);
    if let Some(diffracting) = options.diffraction.enabled() {
        let edges =
            bt_paths::diffraction::usable_edges(scene, diffracting.min_edge_length).count() as u64;
        estimate = estimate.saturating_add(bt_paths::diffraction::diffracted_count(
            reflectors,
            edges,
            options.max_order,
            diffracting.max_diffractions,
        ));
    }
    check_estimate(estimate, options.max_candidates, options.max_order)
}

/// Refuse `estimate` candidates over `budget`.
fn check_estimate(estimate: u64, budget: u64, max_order: usize) -> Result<(), TraceError> {
    if estimate > budget {
        return Err(TraceError::Budget {
            estimate,
            budget,
            max_order,
        });
    }
    Ok(())
}

/// Number of sequences of order `0..=max_order` over `n` reflectors with no surface twice in
/// a row (saturating): `1 + Σ n (n-1)^(k-1)`.
pub fn exhaustive_count(n: u64, max_order: usize) -> u64 {
    let mut total = 1u64;
    let mut level = n;
    for _ in 0..max_order {
        total = total.saturating_add(level);
        level = level.saturating_mul(n.saturating_sub(1));
    }
    total
}

/// Trace `scene` from its TX to its RX, the beam tree built with `cache`, reporting the
/// candidate generation to `progress`.
pub(crate) fn trace_scene_in(
    scene: &Scene,
    options: &TraceOptions,
    cache: &mut TreeCache,
    progress: Progress<'_>,
) -> Result<Traced, TraceError> {
    let t0 = Instant::now();
    let set = generate(
        scene,
        options,
        solver_tree_options(options),
        cache,
        progress,
    )?;
    let t1 = Instant::now();
    solve_set(scene, set, options, t1 - t0, None)
}

/// Solve a generated candidate set (the second half of [`trace_scene_in`]).
pub(crate) fn solve_set(
    scene: &Scene,
    set: CandidateSet,
    options: &TraceOptions,
    generation: Duration,
    partner: Option<&Partner>,
) -> Result<Traced, TraceError> {
    let t1 = Instant::now();
    let result = crate::trace_on(scene, &set, &options.solver, options.parallel, partner)?;
    let t2 = Instant::now();
    Ok(Traced {
        candidates: set.stats,
        tree: set.tree,
        result,
        time: StageTimes {
            candidates: generation,
            solve: t2 - t1,
        },
    })
}

/// Nodes of a kept tree from which a lone receiver's walk is split over a [`Partner`].
const SPLIT_WALK: usize = 256;

thread_local! {
    /// The two halves' hits of a split walk ([`KeptTx::candidates`]), kept from answer to
    /// answer by the serving thread: the partner fills the second in place, so no buffer is
    /// allocated on one thread and freed on the other (glibc's allocator then locks the
    /// other thread's arena, a few microseconds an answer when both threads allocate).
    static WALK_HITS: std::cell::RefCell<[Vec<usize>; 2]> = std::cell::RefCell::default();
}

/// Receivers from which a many-receiver trace narrows the kept tree's nodes for boxes of
/// receivers ([`BeamTree::receiver_nodes`]) before walking it for each.
const BATCHED_RECEIVERS: usize = 16;

/// Trace `base`'s TX to each of `receivers` (metres, world frame: converted into the scene's
/// local frame here; the paths found are local, see [`Scene::to_world`]), one outcome per
/// receiver: a receiver on a surface or at the TX gets its own [`TraceError::Scene`] and the
/// others are still traced. Receivers run in parallel when `options.parallel`; each one's own
/// trace is then single-threaded. `tree` is the beam tree of `base`'s TX when the caller has
/// one (a fixed TX: every receiver is a walk); `cache` serves a single receiver's trace.
/// `then` turns each receiver's trace, beside the scene it was traced in, into its outcome,
/// in the task that traced it.
pub(crate) fn trace_each_receiver<T: Send>(
    base: &Scene,
    receivers: &[Vec3],
    options: &TraceOptions,
    (tree, cache): (Option<&KeptTx>, &mut TreeCache),
    partner: Option<&Partner>,
    then: &(impl Fn(&Scene, Traced) -> T + Sync),
) -> Vec<Result<T, TraceError>> {
    // A lone receiver's walk may take the partner; receivers in parallel use the cores.
    let partner = partner.filter(|_| receivers.len() == 1);
    let inner = TraceOptions {
        parallel: false,
        ..*options
    };
    if let ([rx], None) = (receivers, tree) {
        let one = base.with_receiver(*rx).map_err(TraceError::from);
        return vec![one.and_then(|moved| {
            let traced = trace_scene_in(&moved, &inner, cache, &mut |_| {})?;
            Ok(then(&moved, traced))
        })];
    }
    // Which of the tree's nodes may hold each receiver, found for boxes of nearby receivers
    // at once (a superset: the candidates are the same as testing every node). A few
    // receivers (a stream of moves, `beamtrace serve`) test every node instead.
    let nodes = tree
        .filter(|_| receivers.len() >= BATCHED_RECEIVERS)
        .map(|kept| {
            let local: Vec<Vec3> = receivers.iter().map(|&rx| base.to_local(rx)).collect();
            kept.tree.receiver_nodes(&local, options.parallel)
        });
    let one = |(k, rx): (usize, &Vec3)| -> Result<T, TraceError> {
        let moved = base.with_receiver(*rx)?;
        let traced = match tree {
            // The tree's margins hold for receivers whose scene tolerance is no larger.
            Some(kept) if moved.length_tolerance() <= kept.tree.tolerance() => {
                let t0 = Instant::now();
                let among = nodes.as_ref().map(|n| n.of(k));
                let set = kept.candidates(&moved, among, &inner, partner)?;
                solve_set(&moved, set, &inner, t0.elapsed(), partner)?
            }
            // Receivers traced in parallel cannot share one cache (`tree` is built in beam-tree
            // mode, so this is a receiver that grows the scene, or another mode: no tree).
            _ => trace_scene_in(&moved, &inner, &mut TreeCache::default(), &mut |_| {})?,
        };
        Ok(then(&moved, traced))
    };
    // One receiver runs on the caller's thread: handing it to the pool only adds a wake-up
    // (a whole scheduler slice, ~4 ms, when the cores are busy: serve's p99).
    if options.parallel && receivers.len() > 1 {
        receivers.par_iter().enumerate().map(one).collect()
    } else {
        receivers.iter().enumerate().map(one).collect()
    }
}

/// Whether a many-receiver trace of `receivers` under `options` walks one beam tree of the TX
/// (beam-tree mode, more than one receiver, or any number when the tree is `kept` for the
/// next call) instead of tracing each receiver alone.
pub(crate) fn walks_one_tree(options: &TraceOptions, receivers: &[Vec3], kept: bool) -> bool {
    options.candidates == CandidateMode::BeamTree && (receivers.len() > 1 || kept)
}

/// The beam tree of a TX kept for many receivers ([`trace_each_receiver`]), with the reaches
/// of its nodes on the edges when diffraction is on: each receiver then only grows its own
/// side (a tree from RX) and joins it.
#[derive(Clone)]
pub(crate) struct KeptTx {
    pub tree: BeamTree,
    pub side: Option<DiffractionSide>,
}

impl KeptTx {
    /// The tree of `scene`'s TX under `options` (the solver's tree options), built with
    /// `cache`, and its diffraction side when `options` diffract.
    pub fn build(
        scene: &Scene,
        options: &TraceOptions,
        cache: &mut TreeCache,
    ) -> Result<KeptTx, TraceError> {
        let tree = BeamTree::build_in(scene, solver_tree_options(options), cache, &mut |_| {})?;
        let side = options
            .diffraction
            .enabled()
            .map(|diffracting| DiffractionSide::of(scene, &tree, options.max_order, diffracting));
        Ok(KeptTx { tree, side })
    }

    /// The candidates of `scene`'s RX (`scene` has this tree's TX): a walk of the tree (of
    /// the nodes `among`, when given: a superset of those holding RX from
    /// [`BeamTree::receiver_nodes`]), and the diffracted ones joined with a tree grown from RX.
    /// With a `partner`, the walk's second half of the nodes is tested on it.
    fn candidates(
        &self,
        scene: &Scene,
        among: Option<&[u32]>,
        options: &TraceOptions,
        partner: Option<&Partner>,
    ) -> Result<CandidateSet, TraceError> {
        let rx = scene.terminals()?.rx;
        let tree = &self.tree;
        let walk = tree.walk_len();
        let mut set = match (among, partner) {
            (Some(nodes), _) => tree.candidates_among(rx, nodes.iter().map(|&i| i as usize)),
            (None, Some(partner)) if walk >= SPLIT_WALK => WALK_HITS.with_borrow_mut(|hits| {
                let [first, second] = hits;
                first.clear();
                second.clear();
                let k = walk / 2;
                partner.join(
                    || tree.holding(rx, 0..k, first),
                    || tree.holding(rx, k..walk, second),
                );
                tree.candidates_of(first.iter().chain(second.iter()).copied())
            }),
            (None, _) => tree.candidates(rx),
        };
        if let Some(side) = &self.side {
            let tree_options = solver_tree_options(options);
            // Receivers in parallel cannot share one cache: each RX tree gets its own.
            let cache = &mut TreeCache::default();
            set.diffracted = diffracted_with(scene, side, tree_options, cache)?;
            set.stats.diffracted = set.diffracted.len() as u64;
        }
        Ok(set)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exhaustive_count_matches_the_formula() {
        // 1 + 6 + 6*5 + 6*5*5 for a box room at order 3
        assert_eq!(exhaustive_count(6, 3), 1 + 6 + 30 + 150);
        assert_eq!(exhaustive_count(0, 3), 1);
        assert_eq!(exhaustive_count(u64::MAX, 3), u64::MAX);
    }
}
