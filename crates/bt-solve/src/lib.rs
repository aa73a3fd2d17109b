//! Solvers for candidate paths and validation of what they find.
//!
//! - [`image`]: the image method, exact geometric optics, the reference;
//! - [`ipc`]: iterative path convergence (the paper's Algorithms 1-2), Gauss-Seidel or Jacobi,
//!   optionally finished by Newton steps ([`Acceleration::Newton`]);
//! - [`validate`]: the geometric checks every found path must pass;
//! - [`sbr`]: shooting and bouncing rays, the baseline (whole-scene, not per candidate);
//! - [`settings`]: a trace's settings by name (the CLI's flags, Python's keywords) → options.
//!
//! [`Tracer`] is the front door every consumer traces through: it holds a scene, the options,
//! the kept beam tree, the previous time step ([`steps`]) and the caches. [`trace`] runs a
//! solver over a [`CandidateSet`] and returns the valid paths plus a count of every outcome;
//! one bad candidate never aborts the batch.
#![warn(missing_docs)]

mod batch;
pub mod diffraction;
mod hints;
pub mod image;
pub mod ipc;
mod lanes;
mod newton;
pub mod partner;
pub mod pipeline;
pub mod sbr;
pub mod settings;
pub mod steps;
mod tracer;
pub mod validate;

use bt_geom::{Real, Vec3};
use bt_paths::CandidateSet;
use bt_scene::{Endpoints, Scene, SceneError, SurfaceId};
use serde::{Deserialize, Serialize};

use batch::{Batch, Todo, found_path, solve_batch};
pub use ipc::{Acceleration, DegenerateKind, IpcOptions, IpcOutcome, UpdateOrder};
pub use sbr::{SbrLaunch, SbrOptions};
pub use steps::{StepTrace, UpdateStats, max_point_distance};
pub use tracer::Tracer;
pub use validate::Validity;

/// Which solver computes the interaction points.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "solver", rename_all = "kebab-case")]
pub enum Solver {
    /// The image method.
    Image,
    /// Iterative path convergence.
    Ipc(IpcOptions),
    /// Shooting and bouncing rays: [`trace`] runs [`sbr::trace`] up to the longest candidate's
    /// order (the candidates themselves are not used); [`solve_candidate`] runs
    /// [`sbr::solve_sequence`].
    Sbr(SbrOptions),
}

/// A path's short list, held inline up to `N` items (no allocation for the paths of
/// ordinary orders), on the heap beyond: a slice to read.
pub type Inline<T, const N: usize> = smallvec::SmallVec<[T; N]>;

/// A valid path found by a solver: reflections, with up to two edge diffractions and any
/// slab crossings.
///
/// Its lists are [`Inline`]: up to order 4 a path costs no allocation (a trace finds hundreds).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FoundPath {
    /// Reflecting surfaces, TX side first (empty: line of sight, or a lone diffraction). With
    /// a diffraction or crossings, fewer than the points: [`FoundPath::interactions`] aligns
    /// them.
    pub surfaces: Inline<SurfaceId, 4>,
    /// Interaction points, TX side first, metres (TX and RX excluded).
    pub points: Inline<Vec3, 4>,
    /// The diffractions (none, one or two), in path order.
    pub diffractions: Inline<Diffraction, 2>,
    /// The penetrable surfaces the path crosses (thin-slab transmission), by point, in path
    /// order; empty without transmission.
    pub crossings: Inline<Crossing, 2>,
    /// IPC rounds used (IPC only).
    pub iterations: Option<u32>,
    /// Mean displacement of IPC's last round, metres (IPC only).
    pub residual: Option<Real>,
}

/// A path's diffraction: which of its points, on which edge.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct Diffraction {
    /// Index of the diffraction point in [`FoundPath::points`].
    pub index: usize,
    /// The edge ([`Scene::edges`]).
    pub edge: bt_scene::EdgeId,
}

/// A path's crossing of a penetrable surface ([`Scene::penetrable`]): which of its points,
/// through which surface. The wave goes straight through (a thin slab deflects nothing).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct Crossing {
    /// Index of the crossing point in [`FoundPath::points`].
    pub index: usize,
    /// The surface crossed.
    pub surface: SurfaceId,
}

/// One interaction of a path, aligned with its points.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum Interaction {
    /// A specular reflection on a surface.
    Reflection(SurfaceId),
    /// A diffraction on an edge.
    Diffraction(bt_scene::EdgeId),
    /// A crossing of a penetrable surface (thin-slab transmission).
    Transmission(SurfaceId),
}

impl FoundPath {
    /// The interactions, aligned with [`FoundPath::points`].
    pub fn interactions(&self) -> Vec<Interaction> {
        let mut interactions = Vec::with_capacity(self.points.len());
        self.interactions_into(&mut interactions);
        interactions
    }

    /// [`FoundPath::interactions`] into `interactions` (cleared first), whose memory a report
    /// of many paths reuses.
    pub fn interactions_into(&self, interactions: &mut Vec<Interaction>) {
        interactions.clear();
        if self.crossings.is_empty() && self.diffractions.is_empty() {
            // Reflections only (most of a room's paths): the merge below, without its tests.
            let reflections = self.surfaces.iter().take(self.points.len());
            interactions.extend(reflections.map(|&s| Interaction::Reflection(s)));
            return;
        }
        let mut reflections = self.surfaces.iter();
        let mut crossings = self.crossings.iter().peekable();
        let mut diffractions = self.diffractions.iter().peekable();
        interactions.extend((0..self.points.len()).filter_map(|i| {
            match crossings.next_if(|c| c.index == i) {
                Some(c) => Some(Interaction::Transmission(c.surface)),
                None => match diffractions.next_if(|d| d.index == i) {
                    Some(d) => Some(Interaction::Diffraction(d.edge)),
                    None => reflections.next().map(|s| Interaction::Reflection(*s)),
                },
            }
        }));
    }

    /// The path with the penetrable surfaces its segments cross in `scene` (between `ends`)
    /// inserted as crossing points ([`validate::walk_crossings`]); the diffractions' indices
    /// move with them. A path found without transmission comes back unchanged, and so does
    /// one whose reflections and diffractions spend the scene's interaction budget: its
    /// validation let no penetrable surface cross it ([`validate::may_cross`]).
    pub fn with_crossings(self, scene: &Scene, ends: Endpoints) -> FoundPath {
        let n = self.points.len();
        if !validate::may_cross(scene, n) {
            return self;
        }
        let interactions = self.interactions();
        let edges = scene.edges();
        let vertex = |k: usize| match k {
            0 => ends.tx,
            k if k == n + 1 => ends.rx,
            k => self.points[k - 1],
        };
        let on = |k: usize| -> &[SurfaceId] {
            match k.checked_sub(1).and_then(|i| interactions.get(i)) {
                Some(Interaction::Reflection(s) | Interaction::Transmission(s)) => {
                    std::slice::from_ref(s)
                }
                Some(Interaction::Diffraction(e)) => &edges.get(*e).touching,
                None => &[],
            }
        };
        let mut found: Vec<(usize, Vec3, SurfaceId)> = Vec::new();
        let path = validate::PathVertices {
            vertex: &vertex,
            on: &on,
            points: n,
        };
        validate::walk_crossings(scene, path, |segment, p, id| {
            found.push((segment, p, id));
            true
        });
        self.with_found_crossings(&found)
    }

    /// The path with the crossings `found` ((segment, point, surface), in path order, as
    /// [`validate::walk_crossings`] gives them) inserted as crossing points.
    pub(crate) fn with_found_crossings(self, found: &[(usize, Vec3, SurfaceId)]) -> FoundPath {
        if found.is_empty() {
            return self;
        }
        let n = self.points.len();
        let mut points = Inline::with_capacity(n + found.len());
        let mut crossings = Inline::with_capacity(found.len());
        let mut diffractions = self.diffractions.clone();
        let mut next = found.iter().peekable();
        for segment in 0..=n {
            while let Some((_, p, id)) = next.next_if(|c| c.0 == segment) {
                crossings.push(Crossing {
                    index: points.len(),
                    surface: *id,
                });
                points.push(*p);
            }
            for (d, old) in diffractions.iter_mut().zip(&self.diffractions) {
                if old.index == segment {
                    d.index = points.len();
                }
            }
            points.extend(self.points.get(segment).copied());
        }
        FoundPath {
            points,
            crossings,
            diffractions,
            ..self
        }
    }
}

/// What happened to one candidate.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub enum CandidateOutcome {
    /// The solver produced points, judged by validation.
    Solved {
        /// Geometric verdict.
        validity: Validity,
        /// IPC outcome when IPC ran.
        ipc: Option<IpcOutcome>,
    },
    /// The image method found a line parallel to a plane.
    ImageDegenerate(image::ImageFailure),
    /// IPC did not converge within the round cap.
    NotConverged(IpcOutcome),
    /// IPC degenerated (m + n = 0, opposite sides).
    Degenerate(IpcOutcome),
    /// IPC stopped early: a point was leaving its polygon for good.
    LeftPolygon(IpcOutcome),
    /// IPC stopped early: a segment was blocked for good (counted as blocked).
    Blocked(IpcOutcome),
    /// SBR: no launched ray reached RX through this sequence.
    Missed,
}

/// Counts of candidate outcomes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct OutcomeCounts {
    /// Valid paths.
    pub valid: u64,
    /// Rejected: a point outside its polygon.
    pub outside_polygon: u64,
    /// Rejected: neighbours on opposite sides of a surface.
    pub opposite_sides: u64,
    /// Rejected: a neighbour on the plane (grazing).
    pub grazing: u64,
    /// Rejected: a segment blocked.
    pub blocked: u64,
    /// IPC: round cap reached.
    pub not_converged: u64,
    /// IPC or image method: degenerate geometry.
    pub degenerate: u64,
    /// SBR per candidate: no ray reached RX through the sequence.
    pub missed: u64,
}

impl OutcomeCounts {
    /// Count one candidate's outcome.
    pub fn add(&mut self, outcome: &CandidateOutcome) {
        match outcome {
            CandidateOutcome::Solved { validity, .. } => match validity {
                Validity::Valid => self.valid += 1,
                Validity::OutsidePolygon { .. } => self.outside_polygon += 1,
                Validity::OppositeSides { .. } => self.opposite_sides += 1,
                Validity::Grazing { .. } => self.grazing += 1,
                Validity::Blocked { .. } => self.blocked += 1,
                Validity::NonFinite => self.degenerate += 1,
                Validity::OffEdge { .. } => self.outside_polygon += 1,
                Validity::InsideWedge { .. } => self.opposite_sides += 1,
            },
            CandidateOutcome::ImageDegenerate(_) | CandidateOutcome::Degenerate(_) => {
                self.degenerate += 1
            }
            CandidateOutcome::NotConverged(_) => self.not_converged += 1,
            CandidateOutcome::LeftPolygon(_) => self.outside_polygon += 1,
            CandidateOutcome::Blocked(_) => self.blocked += 1,
            CandidateOutcome::Missed => self.missed += 1,
        }
    }

    /// Add the counts of another batch.
    pub fn merge(&mut self, other: &OutcomeCounts) {
        self.valid += other.valid;
        self.outside_polygon += other.outside_polygon;
        self.opposite_sides += other.opposite_sides;
        self.grazing += other.grazing;
        self.blocked += other.blocked;
        self.not_converged += other.not_converged;
        self.degenerate += other.degenerate;
        self.missed += other.missed;
    }
}

/// Result of a trace.
#[derive(Debug, Clone, Default, Serialize)]
pub struct TraceResult {
    /// Valid paths, in candidate order.
    pub paths: Vec<FoundPath>,
    /// Outcome counts over all candidates.
    pub counts: OutcomeCounts,
}

impl TraceResult {
    /// No paths yet, with room for the paths of `candidates` candidates, up to
    /// [`TraceResult::MAX_ROOM`] (a large batch's paths, a few of its candidates, grow as
    /// they come instead of taking memory for every candidate up front).
    pub(crate) fn with_room(candidates: usize) -> TraceResult {
        TraceResult {
            paths: Vec::with_capacity(candidates.min(Self::MAX_ROOM)),
            counts: OutcomeCounts::default(),
        }
    }

    /// The most paths [`TraceResult::with_room`] makes room for (about 1 MB).
    const MAX_ROOM: usize = 4096;

    /// The results of consecutive parts as one, in order: the paths moved once into a
    /// vector of their total length (a path holds its lists inline, so it is worth not
    /// moving twice), or, when a single part has paths (a trace on one thread: a room's),
    /// that part's vector as it is (no move at all).
    pub fn concat(parts: impl IntoIterator<Item = TraceResult>) -> TraceResult {
        let mut parts: Vec<TraceResult> = parts.into_iter().collect();
        if parts.iter().filter(|p| !p.paths.is_empty()).count() <= 1 {
            let mut counts = OutcomeCounts::default();
            for part in &parts {
                counts.merge(&part.counts);
            }
            let paths = parts.iter_mut().find(|p| !p.paths.is_empty());
            return TraceResult {
                paths: paths
                    .map(|p| std::mem::take(&mut p.paths))
                    .unwrap_or_default(),
                counts,
            };
        }
        let mut out = TraceResult {
            paths: Vec::with_capacity(parts.iter().map(|p| p.paths.len()).sum()),
            counts: OutcomeCounts::default(),
        };
        for part in parts {
            out.paths.extend(part.paths);
            out.counts.merge(&part.counts);
        }
        out
    }
}

/// Solve and validate one candidate from `ends.tx` to `ends.rx` (the scene's, from
/// [`Scene::terminals`]). `points` and `scratch` must have the sequence's length; on return
/// `points` holds the solver's points (meaningful when `Solved`).
#[inline(always)]
pub fn solve_candidate(
    scene: &Scene,
    ends: Endpoints,
    seq: &[SurfaceId],
    solver: &Solver,
    points: &mut [Vec3],
    scratch: &mut [Vec3],
) -> CandidateOutcome {
    solve_candidate_from(scene, ends, seq, solver, None, points, scratch)
}

/// [`solve_candidate`], with IPC starting from `warm` (e.g. the previous time step's points)
/// instead of the polygon centroids when given; other solvers ignore `warm`.
#[inline(always)]
pub fn solve_candidate_from(
    scene: &Scene,
    ends: Endpoints,
    seq: &[SurfaceId],
    solver: &Solver,
    warm: Option<&[Vec3]>,
    points: &mut [Vec3],
    scratch: &mut [Vec3],
) -> CandidateOutcome {
    solve_candidate_in(scene, ends, seq, solver, (warm, points, scratch), None)
}

/// [`solve_candidate_from`] (its `warm`, `points` and `scratch` as `buffers`), a path of the
/// image method or SBR validated with a `hint` of where it was blocked before, if any
/// ([`validate::validate_hinted`]: a blocked verdict's kind is exact, not its fields;
/// without a hint, [`validate::validate`]'s verdict).
#[inline(always)]
pub(crate) fn solve_candidate_in(
    scene: &Scene,
    ends: Endpoints,
    seq: &[SurfaceId],
    solver: &Solver,
    (warm, points, scratch): (Option<&[Vec3]>, &mut [Vec3], &mut [Vec3]),
    hint: Option<(usize, SurfaceId)>,
) -> CandidateOutcome {
    let Endpoints { tx, rx } = ends;
    match solver {
        Solver::Image => {
            if let Err(e) = image::solve(scene, seq, tx, rx, points) {
                return CandidateOutcome::ImageDegenerate(e);
            }
        }
        Solver::Ipc(options) => {
            ipc_start(scene, seq, warm, points);
            let outcome = ipc::solve(scene, seq, tx, rx, options, points, scratch);
            return ipc_verdict(scene, ends, seq, outcome, points);
        }
        Solver::Sbr(options) => match sbr::solve_sequence(scene, ends, seq, options) {
            Some(path) => points.copy_from_slice(&path.points),
            None => return CandidateOutcome::Missed,
        },
    }
    CandidateOutcome::Solved {
        validity: validate::validate_hinted(scene, (seq, points), (tx, rx), hint),
        ipc: None,
    }
}

/// IPC's start points for `seq` into `points`: `warm` when given, else the polygon centroids.
#[inline(always)]
pub(crate) fn ipc_start(
    scene: &Scene,
    seq: &[SurfaceId],
    warm: Option<&[Vec3]>,
    points: &mut [Vec3],
) {
    match warm {
        Some(warm) => points.copy_from_slice(warm),
        None => {
            for (p, id) in points.iter_mut().zip(seq) {
                *p = scene.surface(*id).polygon.centroid();
            }
        }
    }
}

/// The candidate outcome of an IPC run on `seq` that ended as `outcome` with `points`: a
/// converged run is validated, any other end is the outcome itself.
#[inline(always)]
pub(crate) fn ipc_verdict(
    scene: &Scene,
    ends: Endpoints,
    seq: &[SurfaceId],
    outcome: IpcOutcome,
    points: &[Vec3],
) -> CandidateOutcome {
    match outcome {
        IpcOutcome::Converged { .. } => CandidateOutcome::Solved {
            validity: validate::validate(scene, seq, ends.tx, ends.rx, points),
            ipc: Some(outcome),
        },
        IpcOutcome::NotConverged { .. } => CandidateOutcome::NotConverged(outcome),
        IpcOutcome::Degenerate { .. } => CandidateOutcome::Degenerate(outcome),
        IpcOutcome::LeftPolygon { .. } => CandidateOutcome::LeftPolygon(outcome),
        IpcOutcome::Blocked { .. } => CandidateOutcome::Blocked(outcome),
    }
}

/// The [`solve_batch`] fold of [`trace`]: count every outcome, keep the valid paths.
#[inline(always)]
fn keep_valid(
    out: &mut TraceResult,
    _: usize,
    seq: &[SurfaceId],
    outcome: &CandidateOutcome,
    points: &[Vec3],
) {
    out.counts.add(outcome);
    out.paths.extend(found_path(seq, outcome, points));
}

/// Run `solver` on every candidate. `parallel` spreads candidates over rayon's pool; the
/// output is identical either way (order-preserving). A scene without both terminals fails
/// ([`SceneError::MissingTerminal`]).
pub fn trace(
    scene: &Scene,
    candidates: &CandidateSet,
    solver: &Solver,
    parallel: bool,
) -> Result<TraceResult, SceneError> {
    trace_on(scene, candidates, solver, parallel, None)
}

/// [`trace`], its specular candidates split over `partner` (when not `parallel`): a lone
/// receiver's solve on two cores, the same result.
pub(crate) fn trace_on(
    scene: &Scene,
    candidates: &CandidateSet,
    solver: &Solver,
    parallel: bool,
    partner: Option<&partner::Partner>,
) -> Result<TraceResult, SceneError> {
    let ends = scene.terminals()?;
    if let Solver::Sbr(options) = solver {
        let max_order = candidates.iter().map(<[SurfaceId]>::len).max().unwrap_or(0);
        let result = sbr::trace_detailed(scene, options, max_order, parallel)?;
        return Ok(sbr::to_trace_result(&result));
    }
    // `keep_valid` counts a blocked candidate and keeps nothing else of it.
    let batch = Batch {
        scene,
        ends,
        candidates,
        solver,
        parallel,
        partner,
        counts_blocked: true,
    };
    let room = |n| TraceResult::with_room(n);
    let mut parts = solve_batch(&batch, Todo::All, (room, |_| None), keep_valid);
    if scene.transmits() {
        for part in &mut parts {
            part.paths = (std::mem::take(&mut part.paths).into_iter())
                .map(|p| p.with_crossings(scene, ends))
                .collect();
        }
    }
    // The diffracted paths come with their crossings: validation walked them.
    let mut out = TraceResult::concat(parts);
    diffraction::trace_set(
        scene,
        ends,
        &candidates.diffracted,
        solver,
        parallel,
        &mut out,
    );
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// [`TraceResult::concat`] keeps a lone part's paths as they are, and otherwise moves
    /// them: either way the paths of every part in order and the summed counts, also with
    /// empty parts before, between and after.
    #[test]
    fn concat_gives_every_part_in_order() {
        let path = |i: u32| FoundPath {
            surfaces: [SurfaceId(i)].into_iter().collect(),
            points: [Vec3::splat(Real::from(i))].into_iter().collect(),
            diffractions: Inline::new(),
            crossings: Inline::new(),
            iterations: Some(i),
            residual: None,
        };
        let part = |ids: std::ops::Range<u32>, blocked: u64| TraceResult {
            paths: ids.clone().map(path).collect(),
            counts: OutcomeCounts {
                valid: ids.len() as u64,
                blocked,
                ..OutcomeCounts::default()
            },
        };
        // Each part's path ids as (first, end).
        let layouts: [&[(u32, u32)]; 6] = [
            &[],
            &[(0, 0)],
            &[(0, 3)],
            &[(0, 0), (0, 3), (3, 3)],
            &[(0, 2), (2, 5)],
            &[(0, 0), (0, 2), (2, 2), (2, 5), (5, 6)],
        ];
        for layout in layouts {
            let parts: Vec<TraceResult> = (layout.iter().enumerate())
                .map(|(k, &(a, b))| part(a..b, k as u64 + 1))
                .collect();
            let expected: Vec<u32> = layout.iter().flat_map(|&(a, b)| a..b).collect();
            let blocked: u64 = (1..=layout.len() as u64).sum();
            let out = TraceResult::concat(parts);
            let got: Vec<u32> = out.paths.iter().map(|p| p.iterations.unwrap()).collect();
            assert_eq!(got, expected, "{layout:?}");
            assert_eq!(out.counts.valid, expected.len() as u64, "{layout:?}");
            assert_eq!(out.counts.blocked, blocked, "{layout:?}");
            assert!(
                out.paths
                    .iter()
                    .all(|p| p.surfaces[0].0 == p.iterations.unwrap())
            );
        }
    }

    /// A path of reflections only takes the short way through
    /// [`FoundPath::interactions_into`]: the same interactions as the merge of reflections,
    /// crossings and diffractions (written out here as it runs for the others), also when
    /// its surfaces and points disagree in number.
    #[test]
    fn reflections_alone_give_the_merged_interactions() {
        let merged = |p: &FoundPath| -> Vec<Interaction> {
            let mut reflections = p.surfaces.iter();
            (0..p.points.len())
                .filter_map(|_| reflections.next().map(|s| Interaction::Reflection(*s)))
                .collect()
        };
        for (surfaces, points) in [(0, 0), (1, 1), (3, 3), (6, 6), (2, 4), (4, 2)] {
            let path = FoundPath {
                surfaces: (0..surfaces).map(|i| SurfaceId(7 * i + 1)).collect(),
                points: (0..points).map(|i| Vec3::splat(i as Real)).collect(),
                diffractions: Inline::new(),
                crossings: Inline::new(),
                iterations: None,
                residual: None,
            };
            let mut kept = vec![Interaction::Transmission(SurfaceId(99))];
            path.interactions_into(&mut kept);
            assert_eq!(kept, merged(&path), "{surfaces} surfaces, {points} points");
        }
    }
}
