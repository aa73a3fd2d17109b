//! The one batch-solve loop: every consumer that solves many candidates (the static
//! [`crate::trace`], the incremental steps of [`crate::Tracer`]) goes through [`solve_batch`], which
//! owns the chunking and parallelism, the FMA dispatch, the start points (a caller's warm start,
//! else the candidate set's window start, else the centroids) and the per-candidate buffers.
//! [`found_path`] turns a valid outcome into a [`FoundPath`].

use crate::hints::{self, Hints};
use crate::ipc::IpcOptions;
use crate::partner::Partner;
use crate::{
    CandidateOutcome, FoundPath, Inline, IpcOutcome, Solver, Validity, ipc_verdict, lanes,
    solve_candidate_from, solve_candidate_in,
};
use bt_geom::{Real, Vec3};
use bt_paths::CandidateSet;
use bt_scene::{Endpoints, Scene, SurfaceId};
use rayon::prelude::*;

/// Candidates per parallel chunk.
const CHUNK: usize = 128;
/// Below this many candidates a batch runs on the calling thread.
const PARALLEL_FROM: usize = 256;
/// From this many candidates a batch with a [`Partner`] (and not `parallel`) is split in two
/// halves, the second on the partner: below it, the hand-over (about a microsecond) would
/// take most of what the half saves. The halves' accumulators are allocated (and later freed)
/// by the calling thread: memory of one thread freed by the other makes glibc's allocator
/// lock the other's arena, and two threads allocating meanwhile then wait on each other
/// (a concurrent solve took 1.5 times as long; docs/performance.md).
const SPLIT_FROM: usize = 32;
/// Maximum order handled with stack buffers; longer sequences use heap buffers.
const STACK_ORDER: usize = 8;

/// Which candidates of a set a batch solves.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Todo<'t> {
    /// Every candidate, in set order.
    All,
    /// These indices into the set, in this order.
    Only(&'t [usize]),
}

impl Todo<'_> {
    fn len(&self, set: &CandidateSet) -> usize {
        match self {
            Todo::All => set.len(),
            Todo::Only(v) => v.len(),
        }
    }

    fn index(&self, k: usize) -> usize {
        match self {
            Todo::All => k,
            Todo::Only(v) => v[k],
        }
    }
}

/// What a batch solves: the scene, its candidates and the solver; `parallel` spreads chunks
/// over rayon's pool (the output is identical either way).
#[derive(Clone, Copy)]
pub(crate) struct Batch<'a> {
    /// The scene (TX, RX, surfaces).
    pub(crate) scene: &'a Scene,
    /// The scene's terminals, checked ([`Scene::terminals`]).
    pub(crate) ends: Endpoints,
    /// The candidate sequences (and their window start points, if any).
    pub(crate) candidates: &'a CandidateSet,
    /// The solver.
    pub(crate) solver: &'a Solver,
    /// Whether to use rayon's pool for large batches.
    pub(crate) parallel: bool,
    /// Without `parallel`: a partner thread that takes the second half of a batch of at
    /// least [`SPLIT_FROM`] candidates (a lone receiver's answer, `beamtrace serve`).
    pub(crate) partner: Option<&'a Partner>,
    /// Whether the fold only counts a blocked candidate (not which segment, not by what):
    /// then the image method's and SBR's paths are validated with the thread's hints first
    /// ([`crate::hints`], [`crate::validate::validate_hinted`]: the same kind of verdict,
    /// fewer BVH walks).
    pub(crate) counts_blocked: bool,
}

/// Solve the candidates of `todo`. IPC starts from `warm(i)` when it gives points for candidate
/// `i`, else from the set's start points, else from the centroids. `each(acc, i, seq,
/// outcome, points)` folds every candidate's result, in `todo` order within a chunk, into its chunk's
/// accumulator (`init(n)` to begin, for a chunk of `n` candidates); the accumulators come back
/// in chunk order.
pub(crate) fn solve_batch<'w, R, I, W, F>(
    batch: &Batch<'_>,
    todo: Todo<'_>,
    (init, warm): (I, W),
    each: F,
) -> Vec<R>
where
    R: Send,
    I: Fn(usize) -> R + Sync,
    W: Fn(usize) -> Option<&'w [Vec3]> + Sync,
    F: Fn(&mut R, usize, &[SurfaceId], &CandidateOutcome, &[Vec3]) + Sync,
{
    let total = todo.len(batch.candidates);
    let chunk = Chunk {
        batch,
        todo,
        warm: &warm,
        each: &each,
    };
    if let (false, Some(partner)) = (batch.parallel, batch.partner)
        && total >= SPLIT_FROM
    {
        let half = balanced_half(batch.candidates, todo, total);
        // Both accumulators are made here, so that the partner's is this thread's memory,
        // freed by this thread (see `SPLIT_FROM`).
        let (first, second) = (init(half), init(total - half));
        let (first, second) = partner.join(
            || chunk.run(0..half, first),
            || chunk.run(half..total, second),
        );
        return vec![first, second];
    }
    if !batch.parallel || total < PARALLEL_FROM {
        return vec![chunk.run(0..total, init(total))];
    }
    (0..total.div_ceil(CHUNK))
        .into_par_iter()
        .map(|c| {
            let range = c * CHUNK..((c + 1) * CHUNK).min(total);
            chunk.run(range.clone(), init(range.len()))
        })
        .collect()
}

/// Where the candidates of `todo` (`total` of them) split into a batch's two halves
/// ([`crate::partner::half_of_work`]): a candidate costs its order plus one (its segments to
/// validate); the image method's cost grows with the order, and a set's candidates come by
/// order, so half the count left the partner the longer half.
fn balanced_half(candidates: &CandidateSet, todo: Todo<'_>, total: usize) -> usize {
    crate::partner::half_of_work(total, |k| candidates.get(todo.index(k)).len() + 1)
}

/// What every chunk of a batch shares.
struct Chunk<'c, W, F> {
    batch: &'c Batch<'c>,
    todo: Todo<'c>,
    warm: &'c W,
    each: &'c F,
}

impl<'w, W, F> Chunk<'_, W, F>
where
    W: Fn(usize) -> Option<&'w [Vec3]>,
{
    /// Positions `range` of the batch's `todo`.
    ///
    /// Compiled twice: with the `fma` target feature when the CPU has it (checked at run
    /// time), and without. The solvers use `mul_add` for robust side tests; without the
    /// feature every `mul_add` is a call into the software-dispatched `fma` of
    /// compiler-builtins, which also spills every live float register (a third of the
    /// instructions of an IPC round). FMA is correctly rounded either way, and Rust never
    /// contracts a separate multiply and add, so both versions give bit-identical results.
    /// The solvers and validation are `inline(always)` down to the BVH walk so that they are
    /// compiled into the FMA version.
    fn run<R>(&self, range: std::ops::Range<usize>, acc: R) -> R
    where
        F: Fn(&mut R, usize, &[SurfaceId], &CandidateOutcome, &[Vec3]),
    {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("fma") {
            // SAFETY: the CPU supports FMA (checked just above).
            return unsafe { self.run_fma(range, acc) };
        }
        self.run_impl(range, acc)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "fma")]
    fn run_fma<R>(&self, range: std::ops::Range<usize>, acc: R) -> R
    where
        F: Fn(&mut R, usize, &[SurfaceId], &CandidateOutcome, &[Vec3]),
    {
        self.run_impl(range, acc)
    }

    #[inline(always)]
    fn run_impl<R>(&self, range: std::ops::Range<usize>, mut acc: R) -> R
    where
        F: Fn(&mut R, usize, &[SurfaceId], &CandidateOutcome, &[Vec3]),
    {
        let Batch {
            scene,
            ends,
            candidates,
            solver,
            ..
        } = *self.batch;
        if let Solver::Ipc(options) = solver {
            return self.run_ipc(range, options, acc);
        }
        let mut stack_points = [Vec3::ZERO; STACK_ORDER];
        let mut stack_scratch = [Vec3::ZERO; STACK_ORDER];
        let mut heap_points = Vec::new();
        let mut heap_scratch = Vec::new();
        // Taken out of the thread-local store, not used in a closure: a closure's body would
        // be compiled without this function's FMA feature.
        let mut hints = self.batch.counts_blocked.then(Hints::take);
        for k in range {
            let i = self.todo.index(k);
            let seq = candidates.get(i);
            let n = seq.len();
            let (points, scratch) = if n <= STACK_ORDER {
                (&mut stack_points[..n], &mut stack_scratch[..n])
            } else {
                heap_points.resize(n, Vec3::ZERO);
                heap_scratch.resize(n, Vec3::ZERO);
                (&mut heap_points[..], &mut heap_scratch[..])
            };
            let start = (self.warm)(i).or_else(|| candidates.start(i));
            let key = hints.as_ref().and_then(|_| hints::key(seq));
            let hint = key.and_then(|key| hints.as_ref()?.get(key));
            let buffers = (start, &mut *points, scratch);
            let outcome = solve_candidate_in(scene, ends, seq, solver, buffers, hint);
            let blocked = blocked_at(&outcome);
            if let (Some(hints), Some(key), true) = (&mut hints, key, blocked != hint) {
                hints.record(key, blocked);
            }
            (self.each)(&mut acc, i, seq, &outcome, points);
        }
        if let Some(hints) = hints {
            hints.give_back();
        }
        acc
    }
}

impl<'w, W, F> Chunk<'_, W, F>
where
    W: Fn(usize) -> Option<&'w [Vec3]>,
{
    /// [`Chunk::run_impl`] for IPC: the candidates of each order up to
    /// [`lanes::MAX_ORDER`] run [`lanes::LANES`] at a time ([`lanes::solve_group`]); longer
    /// ones, and Newton acceleration, take the one-by-one path. The outcomes are kept and
    /// folded in `todo` order at the end, so the accumulator sees exactly what the one-by-one
    /// loop gives.
    #[inline(always)]
    fn run_ipc<R>(&self, range: std::ops::Range<usize>, options: &IpcOptions, mut acc: R) -> R
    where
        F: Fn(&mut R, usize, &[SurfaceId], &CandidateOutcome, &[Vec3]),
    {
        let (scene, terminals, candidates) =
            (self.batch.scene, self.batch.ends, self.batch.candidates);
        let index = |k: usize| self.todo.index(range.start + k);
        let seq_at = |k: usize| candidates.get(index(k));
        let start_at = |k: usize| (self.warm)(index(k)).or_else(|| candidates.start(index(k)));
        let len = range.len();
        // Each candidate's points at `offsets[k]..offsets[k + 1]` of `points`.
        let mut offsets = Vec::with_capacity(len + 1);
        offsets.push(0);
        for k in 0..len {
            offsets.push(offsets[k] + seq_at(k).len());
        }
        let mut points = vec![Vec3::ZERO; offsets[len]];
        let mut outcomes: Vec<Option<CandidateOutcome>> = vec![None; len];
        let mut ends: Vec<Option<crate::IpcOutcome>> = vec![None; len];
        let mut by_order: Vec<usize> = (0..len).collect();
        // By order, and within an order the likely long runs first, so that the lanes' last
        // rounds are not one long run alone ([`likely_slow`]).
        by_order.sort_by_cached_key(|&k| (seq_at(k).len(), !likely_slow(scene, seq_at(k))));
        let lanes = lanes::handles(options);
        for group in by_order.chunk_by(|&a, &b| seq_at(a).len() == seq_at(b).len()) {
            let n = seq_at(group[0]).len();
            if lanes && n <= lanes::MAX_ORDER {
                let items = group.iter().map(|&k| (k, seq_at(k), start_at(k)));
                // The callback only records each run's end: a closure is compiled without the
                // FMA feature of this function, so validation (whose fused plane distances
                // would each be a software `fma` call there) runs below, in this body.
                lanes::solve_group(
                    (scene, terminals),
                    options,
                    n,
                    items,
                    |k, _, end, solved| {
                        points[offsets[k]..offsets[k + 1]].copy_from_slice(solved);
                        ends[k] = Some(end);
                    },
                );
                for &k in group {
                    let end = ends[k].take().expect("every run of the group ended");
                    let solved = &points[offsets[k]..offsets[k + 1]];
                    outcomes[k] = Some(ipc_verdict(scene, terminals, seq_at(k), end, solved));
                }
                continue;
            }
            let solver = Solver::Ipc(*options);
            let mut scratch = vec![Vec3::ZERO; n];
            for &k in group {
                let out = &mut points[offsets[k]..offsets[k + 1]];
                let (seq, start) = (seq_at(k), start_at(k));
                let outcome =
                    solve_candidate_from(scene, terminals, seq, &solver, start, out, &mut scratch);
                outcomes[k] = Some(outcome);
            }
        }
        for (k, outcome) in outcomes.iter().enumerate() {
            let outcome = outcome
                .as_ref()
                .expect("every candidate of the chunk was solved");
            let solved = &points[offsets[k]..offsets[k + 1]];
            (self.each)(&mut acc, index(k), seq_at(k), outcome, solved);
        }
        acc
    }
}

/// The segment and blocker of a blocked verdict.
#[inline(always)]
fn blocked_at(outcome: &CandidateOutcome) -> Option<(usize, SurfaceId)> {
    match outcome {
        CandidateOutcome::Solved {
            validity: Validity::Blocked { segment, by },
            ..
        } => Some((*segment, *by)),
        _ => None,
    }
}

/// Whether IPC on `seq` is likely to need many rounds: its chain holds two (nearly) parallel
/// planes. A path bouncing between parallel mirrors moves its points least per round (in the
/// living room the four longest runs, 320-1,408 rounds against a median of 40, all do). The
/// lanes start such runs first: how runs are grouped never changes their outcome, but four
/// lanes that end with one long run alone idle three quarters of their last rounds.
fn likely_slow(scene: &Scene, seq: &[SurfaceId]) -> bool {
    let normal = |s: &SurfaceId| scene.surface(*s).polygon.plane().normal;
    seq.iter().enumerate().any(|(i, a)| {
        seq[i + 1..]
            .iter()
            .any(|b| normal(a).dot(normal(b)).abs() > PARALLEL_COS)
    })
}

/// |cos| of the angle between two normals above which their planes count as parallel for
/// [`likely_slow`] (2.6°).
const PARALLEL_COS: Real = 0.999;

/// The path of a valid outcome (`None` for any other outcome): `seq` and its solved `points`,
/// with IPC's rounds and residual when IPC converged.
pub(crate) fn found_path(
    seq: &[SurfaceId],
    outcome: &CandidateOutcome,
    points: &[Vec3],
) -> Option<FoundPath> {
    let CandidateOutcome::Solved {
        validity: Validity::Valid,
        ipc,
    } = outcome
    else {
        return None;
    };
    let (iterations, residual) = match ipc {
        Some(IpcOutcome::Converged {
            iterations,
            residual,
        }) => (Some(*iterations), Some(*residual)),
        _ => (None, None),
    };
    Some(FoundPath {
        surfaces: Inline::from_slice(seq),
        points: Inline::from_slice(points),
        diffractions: Inline::new(),
        crossings: Inline::new(),
        iterations,
        residual,
    })
}

#[cfg(test)]
mod tests;
