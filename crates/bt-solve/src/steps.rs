//! Tracing dynamic scenes step by step, incrementally: between two time steps only what the
//! moving objects can have changed is recomputed, and the result equals a from-scratch trace.
//!
//! The state lives in the [`crate::Tracer`] (its previous step); one step of
//! [`crate::Tracer::update`]:
//! 1. *Moved surfaces*: vertex lists compared exactly with the previous step
//!    ([`bt_scene::dynamic::moved_surfaces`]); TX/RX compared too.
//! 2. *WVRN*: [`Wvrn::update`] recomputes the pairs touching moved nodes and re-tests the other
//!    links against the moved occluders only (the paper's red vs green edges).
//! 3. *Candidates*: in beam-tree mode (the default) the tracer keeps a beam tree of the full
//!    order. While no reflector and none of the tree's occluders moved (a person walking), the
//!    tree stays and only a moved RX needs a walk; a moved reflector rebuilds only the subtrees
//!    it touches ([`BeamTree::rebuild`]): nodes whose prefix avoids it are copied, and it is
//!    tested afresh as a child of each copied parent. In WVRN and exhaustive mode the
//!    candidate set depends only on the links and the side masks of reflectors and
//!    terminals, so it is reused when no reflector or terminal moved and no link changed;
//!    otherwise the enumeration runs again.
//! 4. *Paths*: a candidate's outcome is reused when it existed in the previous step, none of its
//!    surfaces moved, the terminals and the length tolerance are unchanged, and its outcome does
//!    not depend on other surfaces, or no moved surface's bounding box (before or after the
//!    move, padded by 4 × the length tolerance) meets the bounding box of one of its previous
//!    segments. Why that is exact: the solvers use only the candidate's own planes and the
//!    terminals, so its points are the same; validation then differs only in occlusion, and a
//!    surface can block a segment (within the validation's tolerance band) only if its box,
//!    padded by the tolerance, meets the segment's box. Everything else is solved again, IPC
//!    warm-started from the previous step's points.
//!
//! For the image method the incremental result is bit-identical to [`trace_scratch`]; for IPC
//! reused and warm-started points agree with a cold start to the IPC threshold.
//!
//! (This was the crate bt-dynamic, a second pipeline beside bt-solve's; it is now the
//! [`crate::Tracer`]'s time-step half.)

use crate::batch::{Batch, Todo, found_path, solve_batch};
use crate::pipeline::{CandidateMode, TraceError, TraceOptions};
use crate::{CandidateOutcome, FoundPath, IpcOutcome, Solver, TraceResult, Validity};
use bt_geom::{Real, Vec3};
use bt_paths::beamtree::{BeamTree, TreeCache};
use bt_paths::wvrn::{Wvrn, WvrnStats};
use bt_paths::{CandidateSet, CandidateStats};
use bt_scene::dynamic::moved_surfaces;
use bt_scene::{Endpoints, Scene, SurfaceId};
use serde::{Deserialize, Serialize};
use std::cmp::Ordering;

/// What an incremental step recomputed.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct UpdateStats {
    /// Computed from scratch (first step, or the scene is not the next step of the previous).
    pub full: bool,
    /// Surfaces whose geometry changed since the previous step.
    pub moved_surfaces: usize,
    /// TX or RX moved (every candidate is then solved again).
    pub terminals_moved: bool,
    /// WVRN pairs with a moved node, recomputed ("red" pairs).
    pub wvrn_recomputed_pairs: usize,
    /// WVRN links re-tested against the moved occluders only.
    pub wvrn_retested_pairs: usize,
    /// WVRN pairs whose linked-ness changed.
    pub wvrn_links_changed: usize,
    /// The candidate enumeration ran again, or the beam tree was walked for a new RX (else
    /// the previous set was reused).
    pub candidates_rederived: bool,
    /// Beam-tree nodes copied from the previous step's tree (a moved reflector rebuilds only
    /// the subtrees it touches).
    pub tree_nodes_reused: u64,
    /// Beam-tree nodes built this step.
    pub tree_nodes_built: u64,
    /// Candidates solved and validated this step.
    pub solved: usize,
    /// Of those, IPC runs warm-started from the previous step's points.
    pub warm_started: usize,
    /// Candidates whose previous outcome was reused.
    pub reused: usize,
}

/// The result of one time step.
#[derive(Debug, Clone, Serialize)]
pub struct StepTrace {
    /// Time step, 0-based.
    pub step: usize,
    /// Valid paths (candidate order) and outcome counts.
    pub trace: TraceResult,
    /// Candidate enumeration counts.
    pub candidates: CandidateStats,
    /// WVRN counts when the WVRN is used.
    pub wvrn: Option<WvrnStats>,
    /// What the incremental update did (all zeros but `full` for a from-scratch trace).
    pub update: UpdateStats,
}

/// The step's candidates: over `wvrn` when given (WVRN mode, which keeps its incremental link
/// update), else from the pipeline's generator (beam tree or exhaustive), under the budget.
fn step_candidates(
    options: &TraceOptions,
    scene: &Scene,
    wvrn: Option<&Wvrn>,
) -> Result<CandidateSet, TraceError> {
    match wvrn {
        // The WVRN relates surfaces, not edges: with diffraction the pipeline enumerates.
        Some(w) if options.diffraction.enabled().is_none() => {
            crate::pipeline::check_budget(scene, options)?;
            Ok(bt_paths::enumerate(scene, options.max_order, w)?)
        }
        _ => crate::pipeline::candidates(scene, options),
    }
}

/// The WVRN of `scene` in WVRN mode.
fn step_wvrn(options: &TraceOptions, scene: &Scene) -> Result<Option<Wvrn>, TraceError> {
    Ok(match options.candidates {
        CandidateMode::Wvrn => {
            crate::pipeline::wvrn_budget(scene, options.max_wvrn_tests)?;
            Some(Wvrn::build(scene)?)
        }
        _ => None,
    })
}

/// A first step's generator and candidates: the WVRN, or the beam tree materialised to the
/// full order (kept for the next steps: a new RX is a walk, a moved reflector rebuilds only its
/// subtrees), or exhaustive enumeration.
fn generate(
    options: &TraceOptions,
    (scene, ends): (&Scene, Endpoints),
    cache: &mut TreeCache,
) -> Result<(Generator, CandidateSet), TraceError> {
    if options.candidates == CandidateMode::BeamTree {
        let tree_options = crate::pipeline::tree_options(options);
        let tree = BeamTree::build_in(scene, tree_options, cache, &mut |_| {})?;
        let candidates = tree.candidates(ends.rx);
        let generator = Generator {
            wvrn: None,
            tree: Some(tree),
        };
        return Ok((generator, candidates));
    }
    let wvrn = step_wvrn(options, scene)?;
    let candidates = step_candidates(options, scene, wvrn.as_ref())?;
    Ok((Generator { wvrn, tree: None }, candidates))
}

/// What the tracer keeps of a step's candidate generator: the WVRN (WVRN mode) or the beam
/// tree (beam-tree mode), or nothing (exhaustive).
#[derive(Clone, Default)]
struct Generator {
    wvrn: Option<Wvrn>,
    tree: Option<BeamTree>,
}

/// Trace one scene from scratch: candidates ([`crate::pipeline::candidates`], or the WVRN),
/// then [`crate::trace`]. The reference the incremental tracer must reproduce. A scene without
/// both terminals fails ([`bt_scene::SceneError::MissingTerminal`]).
pub fn trace_scratch(
    scene: &Scene,
    step: usize,
    options: &TraceOptions,
) -> Result<StepTrace, TraceError> {
    scene.terminals()?;
    let wvrn = step_wvrn(options, scene)?;
    let candidates = step_candidates(options, scene, wvrn.as_ref())?;
    let trace = crate::trace(scene, &candidates, &options.solver, options.parallel)?;
    Ok(StepTrace {
        step,
        trace,
        candidates: candidates.stats,
        wvrn: wvrn.map(|w| w.stats()),
        update: UpdateStats {
            full: true,
            solved: candidates.len(),
            ..UpdateStats::default()
        },
    })
}

/// One candidate's outcome and the points its solver produced (meaningful when solved).
#[derive(Debug, Clone)]
struct Record {
    outcome: CandidateOutcome,
    /// Offset of its points in `State::points`.
    start: u32,
}

#[derive(Clone)]
struct State {
    scene: Scene,
    generator: Generator,
    candidates: CandidateSet,
    records: Vec<Record>,
    points: Vec<Vec3>,
    step: usize,
}

/// The previous step of a [`crate::Tracer`]: its scene, WVRN or beam tree, candidates and
/// outcomes, reused where the motion provably changed nothing. Cloning keeps the state (to
/// branch, or to time one step).
#[derive(Clone, Default)]
pub(crate) struct Incremental {
    state: Option<State>,
}

impl Incremental {
    /// Trace `scene` as step `step`, the next step after the kept one. Scenes that are not a
    /// next step of the previous one (other surfaces) are traced from scratch. A scene without
    /// both terminals fails and leaves the previous step kept.
    pub(crate) fn step(
        &mut self,
        options: &TraceOptions,
        scene: &Scene,
        step: usize,
        cache: &mut TreeCache,
    ) -> Result<StepTrace, TraceError> {
        let ends = scene.terminals()?;
        let options = *options;
        let prev = self.state.take();
        if matches!(options.solver, Solver::Sbr(_))
            || options.diffraction.enabled().is_some()
            || scene.transmits()
        {
            // SBR traces the whole scene at once, not per candidate: nothing to reuse. The
            // reuse of the steps covers specular candidates through opaque surfaces: with
            // diffraction (edges derived from each step's own surfaces) or transmission (a
            // moved slab changes crossings, not blockers) every step is traced in full.
            let result = trace_scratch(scene, step, &options)?;
            self.state = Some(State {
                scene: scene.clone(),
                generator: Generator::default(),
                candidates: CandidateSet::default(),
                records: Vec::new(),
                points: Vec::new(),
                step,
            });
            return Ok(result);
        }
        let moved = prev.as_ref().and_then(|p| moved_surfaces(&p.scene, scene));
        let (Some(mut prev), Some(moved)) = (prev, moved) else {
            let generated = generate(&options, (scene, ends), cache)?;
            return Ok(self.full(&options, (scene, ends), step, generated));
        };
        let mut update = UpdateStats {
            moved_surfaces: moved.len(),
            terminals_moved: prev.scene.tx() != scene.tx() || prev.scene.rx() != scene.rx(),
            ..UpdateStats::default()
        };
        let everything =
            update.terminals_moved || scene.length_tolerance() != prev.scene.length_tolerance();
        let generator = std::mem::take(&mut prev.generator);
        let (generator, candidates) = next_candidates(
            &options,
            (generator, &prev),
            scene,
            &moved,
            everything,
            &mut update,
        )?;
        let plans = plan(&prev, (scene, ends), &candidates, &moved, everything);

        // Solve the affected candidates (in parallel, order preserved).
        let (solved, solved_points) = solve_planned(
            (scene, ends),
            &options,
            &candidates,
            &plans,
            (&prev.records, &prev.points),
        );
        update.solved = solved.len();
        update.warm_started = solved.iter().filter(|s| s.1).count();
        update.reused = candidates.len() - solved.len();

        let (records, points) = assemble(
            &candidates,
            &plans,
            (&prev.records, &prev.points),
            solved,
            &solved_points,
        );
        let solved = (candidates, records, points);
        Ok(self.keep(scene, step, generator, solved, update))
    }

    /// Keep step `step` of `scene` (its WVRN or beam tree, candidates, records and points) for
    /// the next step and return its result.
    fn keep(
        &mut self,
        scene: &Scene,
        step: usize,
        generator: Generator,
        (candidates, records, points): (CandidateSet, Vec<Record>, Vec<Vec3>),
        update: UpdateStats,
    ) -> StepTrace {
        let state = State {
            scene: scene.clone(),
            generator,
            candidates,
            records,
            points,
            step,
        };
        let result = state.result(update);
        self.state = Some(state);
        result
    }

    /// Step `step` solved in full over the candidates `generate` gave.
    fn full(
        &mut self,
        options: &TraceOptions,
        (scene, ends): (&Scene, Endpoints),
        step: usize,
        (generator, candidates): (Generator, CandidateSet),
    ) -> StepTrace {
        let batch = Batch {
            scene,
            ends,
            candidates: &candidates,
            solver: &options.solver,
            parallel: options.parallel,
            partner: None,
            counts_blocked: false,
        };
        let (records, points) = concat(solve_batch(
            &batch,
            Todo::All,
            (no_room, |_| None),
            keep_all,
        ));
        let records: Vec<Record> = records
            .into_iter()
            .map(|(outcome, start, _)| Record { outcome, start })
            .collect();
        let update = UpdateStats {
            full: true,
            solved: records.len(),
            candidates_rederived: true,
            tree_nodes_built: generator.tree.as_ref().map_or(0, |t| t.len() as u64),
            ..UpdateStats::default()
        };
        let solved = (candidates, records, points);
        self.keep(scene, step, generator, solved, update)
    }
}

impl State {
    fn result(&self, update: UpdateStats) -> StepTrace {
        let mut trace = TraceResult::default();
        for (i, r) in self.records.iter().enumerate() {
            let seq = self.candidates.get(i);
            trace.counts.add(&r.outcome);
            let points = &self.points[r.start as usize..r.start as usize + seq.len()];
            trace.paths.extend(found_path(seq, &r.outcome, points));
        }
        StepTrace {
            step: self.step,
            trace,
            candidates: self.candidates.stats,
            wvrn: self.generator.wvrn.as_ref().map(Wvrn::stats),
            update,
        }
    }
}

/// The step's generator (the previous one, taken out of `prev`, updated for the moved
/// surfaces) and candidates: the previous ones while nothing they depend on moved, else
/// generated anew (counted in `update`).
fn next_candidates(
    options: &TraceOptions,
    (generator, prev): (Generator, &State),
    scene: &Scene,
    moved: &[SurfaceId],
    everything: bool,
    update: &mut UpdateStats,
) -> Result<(Generator, CandidateSet), TraceError> {
    if let Some(tree) = generator.tree {
        return next_from_tree(tree, prev, scene, moved, update);
    }
    let mut wvrn = generator.wvrn;
    let mut links_changed = false;
    if let Some(w) = &mut wvrn {
        let delta = w.update(scene, moved)?;
        update.wvrn_recomputed_pairs = delta.recomputed_pairs;
        update.wvrn_retested_pairs = delta.retested_pairs;
        update.wvrn_links_changed = delta.changed.len();
        links_changed = delta.rebuilt || !delta.changed.is_empty();
    }
    let reflector_moved = moved
        .iter()
        .any(|id| scene.surface(*id).kind == bt_scene::SurfaceKind::Reflector);
    let generator = Generator { wvrn, tree: None };
    if everything || reflector_moved || links_changed {
        update.candidates_rederived = true;
        let candidates = step_candidates(options, scene, generator.wvrn.as_ref())?;
        return Ok((generator, candidates));
    }
    Ok((generator, prev.candidates.clone()))
}

/// The beam-tree step: the tree is kept while no reflector and no occluder of it moved (a
/// blocker walking through the room changes validation only), else rebuilt, reusing every
/// subtree the motion cannot have changed ([`BeamTree::rebuild`]); its walk for RX gives the
/// candidates (the previous ones when neither the tree nor RX changed).
fn next_from_tree(
    tree: BeamTree,
    prev: &State,
    scene: &Scene,
    moved: &[SurfaceId],
    update: &mut UpdateStats,
) -> Result<(Generator, CandidateSet), TraceError> {
    let (tree, rebuilt) = if tree.unchanged_by(scene, moved) {
        (tree, false)
    } else {
        let (tree, stats) = tree.rebuild(scene, moved)?;
        update.tree_nodes_reused = stats.reused;
        update.tree_nodes_built = stats.built;
        (tree, true)
    };
    let rx = scene.terminal(bt_scene::Terminal::Rx)?;
    let candidates = if rebuilt || Some(rx) != prev.scene.rx() {
        update.candidates_rederived = true;
        tree.candidates(rx)
    } else {
        prev.candidates.clone()
    };
    Ok((
        Generator {
            wvrn: None,
            tree: Some(tree),
        },
        candidates,
    ))
}

/// Per candidate of the step: reuse the previous outcome, or solve (warm-started from the
/// previous candidate with the same sequence, if any). Both sets are walked in their common
/// order (by length, then by ids).
fn plan(
    prev: &State,
    (scene, ends): (&Scene, Endpoints),
    candidates: &CandidateSet,
    moved: &[SurfaceId],
    everything: bool,
) -> Vec<Plan> {
    // Moved surfaces' boxes before and after, padded by the validation's tolerance band.
    let tol = scene.length_tolerance();
    let pad = Vec3::splat(4.0 * tol.max(prev.scene.length_tolerance()));
    let mut is_moved = vec![false; scene.surfaces().len()];
    let mut boxes: Vec<(Vec3, Vec3)> = Vec::with_capacity(2 * moved.len());
    for id in moved {
        is_moved[id.index()] = true;
        for s in [&prev.scene, scene] {
            let (lo, hi) = s.surface(*id).polygon.bounds();
            boxes.push((lo - pad, hi + pad));
        }
    }
    let union = boxes
        .iter()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), (a, b)| {
            (lo.min(*a), hi.max(*b))
        });
    let Endpoints { tx, rx } = ends;
    let mut plans = Vec::with_capacity(candidates.len());
    let mut j = 0;
    for seq in candidates.iter() {
        while j < prev.candidates.len() && canonical(prev.candidates.get(j), seq) == Ordering::Less
        {
            j += 1;
        }
        let old = (j < prev.candidates.len() && prev.candidates.get(j) == seq).then_some(j);
        let plan = match old {
            None => Plan::Solve(None),
            Some(_) if everything || seq.iter().any(|id| is_moved[id.index()]) => Plan::Solve(old),
            Some(o) => {
                let record = &prev.records[o];
                let pts = &prev.points[record.start as usize..record.start as usize + seq.len()];
                if depends_on_others(&record.outcome) && touches(&boxes, union, tx, rx, pts) {
                    Plan::Solve(old)
                } else {
                    Plan::Reuse(o)
                }
            }
        };
        plans.push(plan);
    }
    plans
}

/// What the incremental step does with one candidate: reuse the previous outcome at this index,
/// or solve it (warm-started from the previous step's candidate at this index, if any).
enum Plan {
    Reuse(usize),
    Solve(Option<usize>),
}

/// Solve the candidates planned for solving, in parallel with order preserved: their outcomes
/// (and whether IPC was warm-started from the previous step) and their points, concatenated.
fn solve_planned(
    (scene, ends): (&Scene, Endpoints),
    options: &TraceOptions,
    candidates: &CandidateSet,
    plans: &[Plan],
    prev: (&[Record], &[Vec3]),
) -> (Vec<(CandidateOutcome, bool)>, Vec<Vec3>) {
    let (prev_records, prev_points) = prev;
    let todo: Vec<usize> = plans
        .iter()
        .enumerate()
        .filter_map(|(i, p)| matches!(p, Plan::Solve(_)).then_some(i))
        .collect();
    // The previous step's converged points of the candidate planned at `i`, if any.
    let warm = |i: usize| {
        let Plan::Solve(Some(o)) = plans[i] else {
            return None;
        };
        let r = &prev_records[o];
        let n = candidates.get(i).len();
        warm_start(
            &r.outcome,
            &prev_points[r.start as usize..r.start as usize + n],
        )
    };
    let is_ipc = matches!(options.solver, Solver::Ipc(_));
    let batch = Batch {
        scene,
        ends,
        candidates,
        solver: &options.solver,
        parallel: options.parallel,
        partner: None,
        counts_blocked: false,
    };
    let (records, points) = concat(solve_batch(
        &batch,
        Todo::Only(&todo),
        (no_room, warm),
        keep_all,
    ));
    let outcomes = records
        .into_iter()
        .map(|(outcome, _, i)| (outcome, is_ipc && warm(i).is_some()))
        .collect();
    (outcomes, points)
}

/// Per chunk: each solved candidate's outcome, the offset of its points in the chunk's points,
/// and its index; the points concatenated.
type Solved = (Vec<(CandidateOutcome, u32, usize)>, Vec<Vec3>);

/// The [`solve_batch`] fold that keeps every outcome and every point.
#[inline(always)]
fn keep_all(
    acc: &mut Solved,
    i: usize,
    _: &[SurfaceId],
    outcome: &CandidateOutcome,
    points: &[Vec3],
) {
    acc.0.push((*outcome, acc.1.len() as u32, i));
    acc.1.extend_from_slice(points);
}

/// An empty [`keep_all`] accumulator, whatever the chunk's size.
fn no_room(_: usize) -> Solved {
    Solved::default()
}

/// The chunks of [`keep_all`] joined in order, with point offsets into the joined points.
fn concat(parts: Vec<Solved>) -> Solved {
    let mut out: Solved = Default::default();
    for (records, points) in parts {
        let base = out.1.len() as u32;
        out.0.extend(
            records
                .into_iter()
                .map(|(o, start, i)| (o, start + base, i)),
        );
        out.1.extend(points);
    }
    out
}

/// The step's records and points in candidate order: reused ones copied from the previous
/// step, solved ones taken in order from `solved` / `solved_points`.
fn assemble(
    candidates: &CandidateSet,
    plans: &[Plan],
    prev: (&[Record], &[Vec3]),
    solved: Vec<(CandidateOutcome, bool)>,
    solved_points: &[Vec3],
) -> (Vec<Record>, Vec<Vec3>) {
    let (prev_records, prev_points) = prev;
    let mut records = Vec::with_capacity(candidates.len());
    let mut points = Vec::with_capacity(prev_points.len());
    let mut fresh = solved.into_iter();
    let mut fresh_points = 0;
    for (i, plan) in plans.iter().enumerate() {
        let n = candidates.get(i).len();
        let start = points.len() as u32;
        match plan {
            Plan::Reuse(o) => {
                let r = &prev_records[*o];
                points.extend_from_slice(&prev_points[r.start as usize..r.start as usize + n]);
                records.push(Record {
                    outcome: r.outcome,
                    start,
                });
            }
            Plan::Solve(_) => {
                let (outcome, _) = fresh.next().expect("one result per planned solve");
                points.extend_from_slice(&solved_points[fresh_points..fresh_points + n]);
                fresh_points += n;
                records.push(Record { outcome, start });
            }
        }
    }
    (records, points)
}

/// The order of [`bt_paths::enumerate`]'s output: by length, then lexicographically by id
/// (reflectors are enumerated in scene order, so by increasing id).
fn canonical(a: &[SurfaceId], b: &[SurfaceId]) -> Ordering {
    a.len().cmp(&b.len()).then_with(|| a.cmp(b))
}

/// Whether an outcome can change when surfaces other than the candidate's own move: only
/// occlusion looks at other surfaces, and validation reaches it only for paths that passed
/// the inside and side checks, i.e. verdicts `Valid` and `Blocked`.
fn depends_on_others(outcome: &CandidateOutcome) -> bool {
    matches!(
        outcome,
        CandidateOutcome::Solved {
            validity: Validity::Valid | Validity::Blocked { .. },
            ..
        }
    )
}

/// Whether any box meets the bounding box of a segment of the path `tx -> points -> rx`;
/// `union` bounds all the boxes (a quick rejection).
fn touches(
    boxes: &[(Vec3, Vec3)],
    union: (Vec3, Vec3),
    tx: Vec3,
    rx: Vec3,
    points: &[Vec3],
) -> bool {
    let meets = |(blo, bhi): (Vec3, Vec3), lo: Vec3, hi: Vec3| {
        !(bhi.cmplt(lo).any() || blo.cmpgt(hi).any())
    };
    let n = points.len();
    (0..=n).any(|k| {
        let a = if k == 0 { tx } else { points[k - 1] };
        let b = if k == n { rx } else { points[k] };
        let (lo, hi) = (a.min(b), a.max(b));
        meets(union, lo, hi) && boxes.iter().any(|bx| meets(*bx, lo, hi))
    })
}

/// Previous points usable as an IPC warm start: those of a converged run.
fn warm_start<'a>(outcome: &CandidateOutcome, points: &'a [Vec3]) -> Option<&'a [Vec3]> {
    match outcome {
        CandidateOutcome::Solved {
            ipc: Some(IpcOutcome::Converged { .. }),
            ..
        } if points.iter().all(|p| p.is_finite()) => Some(points),
        _ => None,
    }
}

/// Largest distance between corresponding points of two path lists with the same surface
/// sequences, metres; `None` when the sequences differ. For comparing steps in tests and tools.
pub fn max_point_distance(a: &[FoundPath], b: &[FoundPath]) -> Option<Real> {
    if a.len() != b.len() {
        return None;
    }
    let mut worst: Real = 0.0;
    for (p, q) in a.iter().zip(b) {
        if p.surfaces != q.surfaces {
            return None;
        }
        for (x, y) in p.points.iter().zip(&q.points) {
            worst = worst.max(x.distance(*y));
        }
    }
    Some(worst)
}
