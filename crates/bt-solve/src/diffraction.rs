//! Paths with one edge diffraction: solving and validating a [`DiffractedCandidate`].
//!
//! **Image method (closed form).** TX is mirrored through the planes before the edge (`I`), RX
//! through those after it, from RX's side (`J`). The diffraction point `D` is the Keller point
//! of `I` and `J` on the edge line (equal angles with the edge, [`bt_scene::Edge::keller`]):
//! the stationary point of the unfolded length `|I − D| + |D − J|`. The reflection points are
//! then the image method's between TX and `D`, and between `D` and RX.
//!
//! **IPC.** Each point is updated in turn from its two neighbours by its own closed form: a
//! reflection point where the neighbour mirrored through its plane sees the other neighbour,
//! the diffraction point at the neighbours' Keller point. The rounds descend the path length,
//! a convex function of the points on their planes and line, and stop when a round moves the
//! points by at most the threshold on average.
//!
//! **Validation.** Reflection points as for specular paths ([`crate::validate`]); the
//! diffraction point strictly inside its edge (one length tolerance from either end: a corner
//! is not an edge); both neighbours of `D` in the edge's exterior ([`bt_scene::Edge::in_exterior`]:
//! a path on a face or inside the wedge does not diffract); the ray not along the edge (sin β0
//! at least `bt_channel::diffraction::MIN_SIN_BETA`, where UTD holds); no segment blocked (the segments
//! at `D` start on every surface touching the edge, which cannot block them).

use crate::image::ImageFailure;
use crate::validate::{self, Validity};
use crate::{CandidateOutcome, Diffraction, FoundPath, IpcOptions, IpcOutcome, TraceResult};
use bt_geom::{Real, Vec3};
use bt_paths::diffraction::DiffractedCandidate;
use bt_paths::diffraction::DiffractedSet;
use bt_scene::{Edge, Endpoints, Scene, SurfaceId};
use rayon::prelude::*;

/// The interaction points of `c` by the image method into `points` (length `c.order()`,
/// metres, TX side first, the diffraction point at index `c.position`).
#[inline(always)]
pub fn solve_image(
    scene: &Scene,
    ends: Endpoints,
    c: DiffractedCandidate<'_>,
    points: &mut [Vec3],
) -> Result<(), ImageFailure> {
    let p = c.position;
    let edge = scene.edges().get(c.edge);
    let mirror = |from: Vec3, seq: &mut dyn Iterator<Item = &SurfaceId>| {
        seq.fold(from, |image, id| {
            scene.surface(*id).polygon.plane().mirror(image)
        })
    };
    let i = mirror(ends.tx, &mut c.before().iter());
    let j = mirror(ends.rx, &mut c.after().iter().rev());
    let t = edge
        .keller(i, j)
        .ok_or(ImageFailure::Parallel { index: p })?;
    let d = edge.point(t);
    points[p] = d;
    crate::image::solve(scene, c.before(), ends.tx, d, &mut points[..p])?;
    crate::image::solve(scene, c.after(), d, ends.rx, &mut points[p + 1..]).map_err(|e| match e {
        ImageFailure::Parallel { index } => ImageFailure::Parallel {
            index: index + p + 1,
        },
    })
}

/// The interaction points of `c` by IPC rounds (module docs) from `points` (the start: e.g.
/// polygon centroids and the edge's midpoint), under `options`' threshold and round cap.
pub fn solve_ipc(
    scene: &Scene,
    ends: Endpoints,
    c: DiffractedCandidate<'_>,
    options: &IpcOptions,
    points: &mut [Vec3],
) -> IpcOutcome {
    let edge = scene.edges().get(c.edge);
    let n = points.len();
    let neighbour = |points: &[Vec3], k: usize| {
        let prev = if k == 0 { ends.tx } else { points[k - 1] };
        let next = if k + 1 == n { ends.rx } else { points[k + 1] };
        (prev, next)
    };
    let min_sum = crate::ipc::min_sum(scene);
    let degenerate = |index, iterations| IpcOutcome::Degenerate {
        kind: crate::DegenerateKind::NeighboursOnPlane,
        index,
        iterations,
    };
    let mut residual = Real::INFINITY;
    for round in 1..=options.max_iterations {
        let mut moved = 0.0;
        for k in 0..n {
            let (prev, next) = neighbour(points, k);
            let new = if k == c.position {
                edge.keller(prev, next).map(|t| edge.point(t))
            } else {
                let plane = scene.surface(reflection_at(c, k)).polygon.plane();
                crate::ipc::intersection_point(plane, prev, next, min_sum)
            };
            let Some(new) = new else {
                return degenerate(k, round);
            };
            moved += new.distance(points[k]);
            points[k] = new;
        }
        residual = moved / n as Real;
        if !residual.is_finite() {
            return degenerate(0, round);
        }
        if residual <= options.threshold {
            return IpcOutcome::Converged {
                iterations: round,
                residual,
            };
        }
    }
    IpcOutcome::NotConverged {
        iterations: options.max_iterations,
        residual,
    }
}

/// IPC's start points of `c`: each polygon's centroid, the edge's midpoint.
pub fn ipc_start(scene: &Scene, c: DiffractedCandidate<'_>, points: &mut [Vec3]) {
    for (k, p) in points.iter_mut().enumerate() {
        *p = if k == c.position {
            let edge = scene.edges().get(c.edge);
            edge.point(0.5 * edge.length)
        } else {
            scene.surface(reflection_at(c, k)).polygon.centroid()
        };
    }
}

/// The surface of interaction `k` (not the diffraction) of `c`.
#[inline(always)]
fn reflection_at(c: DiffractedCandidate<'_>, k: usize) -> SurfaceId {
    if k < c.position {
        c.reflections[k]
    } else {
        c.reflections[k - 1]
    }
}

/// Validate the path TX → `points` → RX of candidate `c` (module docs).
#[inline(always)]
pub fn validate(
    scene: &Scene,
    ends: Endpoints,
    c: DiffractedCandidate<'_>,
    points: &[Vec3],
) -> Validity {
    let tol = scene.length_tolerance();
    let edge = scene.edges().get(c.edge);
    let n = points.len();
    if points.iter().any(|p| !p.is_finite()) {
        return Validity::NonFinite;
    }
    let vertex = |k: usize| match k {
        0 => ends.tx,
        k if k == n + 1 => ends.rx,
        k => points[k - 1],
    };
    let t = edge.parameter(points[c.position]);
    if t <= tol || t >= edge.length - tol {
        return Validity::OffEdge { index: c.position };
    }
    for k in (0..n).filter(|&k| k != c.position) {
        if let Some(verdict) =
            validate::reflection_point(scene, reflection_at(c, k), points[k], tol, k)
        {
            return verdict;
        }
    }
    for k in (0..n).filter(|&k| k != c.position) {
        let plane = scene.surface(reflection_at(c, k)).polygon.plane();
        let (a, b) = (
            plane.signed_distance(vertex(k)),
            plane.signed_distance(vertex(k + 2)),
        );
        if a.abs() <= tol || b.abs() <= tol {
            return Validity::Grazing { index: k };
        }
        if (a > 0.0) != (b > 0.0) {
            return Validity::OppositeSides { index: k };
        }
    }
    if !edge.in_exterior(vertex(c.position), tol) || !edge.in_exterior(vertex(c.position + 2), tol)
    {
        return Validity::InsideWedge { index: c.position };
    }
    // A ray (nearly) along the edge has no UTD coefficient (sin β0 → 0): grazing.
    let incoming = (points[c.position] - vertex(c.position)).normalize();
    if incoming.cross(edge.direction).length() < bt_channel::diffraction::MIN_SIN_BETA {
        return Validity::Grazing { index: c.position };
    }
    blocked(scene, c, (vertex, n), edge)
}

/// The blocking verdict of the segments of the path with vertices `vertex(0..=n + 1)`.
#[inline(always)]
fn blocked(
    scene: &Scene,
    c: DiffractedCandidate<'_>,
    (vertex, n): (impl Fn(usize) -> Vec3, usize),
    edge: &Edge,
) -> Validity {
    let tol = scene.length_tolerance();
    let on = |k: usize| -> &[SurfaceId] {
        // Vertex k (0 = TX) lies on: nothing for the terminals, the edge's surfaces for D.
        match k {
            0 => &[],
            k if k == n + 1 => &[],
            k if k - 1 == c.position => &edge.touching,
            k => std::slice::from_ref(if k - 1 < c.position {
                &c.reflections[k - 1]
            } else {
                &c.reflections[k - 2]
            }),
        }
    };
    let through = validate::may_cross(scene, n);
    for segment in 0..=n {
        let (a, b) = (vertex(segment), vertex(segment + 1));
        let (from, to) = (on(segment), on(segment + 1));
        if let Some(by) = validate::blocker_excluding(scene, (a, b), (from, to), tol, through) {
            return Validity::Blocked { segment, by };
        }
    }
    if through {
        let path = validate::PathVertices {
            vertex: &vertex,
            on: &on,
            points: n,
        };
        return validate::crossing_budget(scene, path, n);
    }
    Validity::Valid
}

/// Solve and validate `c` with `solver` (the image method or IPC; SBR does not diffract and
/// gives `Missed`). `points` must have `c.order()` entries.
#[inline(always)]
pub fn solve_candidate(
    scene: &Scene,
    ends: Endpoints,
    c: DiffractedCandidate<'_>,
    solver: &crate::Solver,
    points: &mut [Vec3],
) -> CandidateOutcome {
    match solver {
        crate::Solver::Image => {
            if let Err(e) = solve_image(scene, ends, c, points) {
                return CandidateOutcome::ImageDegenerate(e);
            }
            CandidateOutcome::Solved {
                validity: validate(scene, ends, c, points),
                ipc: None,
            }
        }
        crate::Solver::Ipc(options) => {
            ipc_start(scene, c, points);
            match solve_ipc(scene, ends, c, options, points) {
                outcome @ IpcOutcome::Converged { .. } => CandidateOutcome::Solved {
                    validity: validate(scene, ends, c, points),
                    ipc: Some(outcome),
                },
                outcome @ IpcOutcome::NotConverged { .. } => {
                    CandidateOutcome::NotConverged(outcome)
                }
                outcome => CandidateOutcome::Degenerate(outcome),
            }
        }
        crate::Solver::Sbr(_) => CandidateOutcome::Missed,
    }
}

/// Solve and validate every candidate of `set` (in parallel when `parallel`; the output is
/// the same either way): the valid paths in set order, and every outcome counted.
pub fn trace_set(
    scene: &Scene,
    ends: Endpoints,
    set: &DiffractedSet,
    solver: &crate::Solver,
    parallel: bool,
) -> TraceResult {
    let chunks: Vec<std::ops::Range<usize>> = (0..set.len())
        .step_by(CHUNK)
        .map(|start| start..(start + CHUNK).min(set.len()))
        .collect();
    let run = |range: &std::ops::Range<usize>| {
        solve_range(
            &Work {
                scene,
                ends,
                set,
                solver,
            },
            range.clone(),
        )
    };
    let parts: Vec<TraceResult> = if parallel && set.len() >= 2 * CHUNK {
        chunks.par_iter().map(run).collect()
    } else {
        chunks.iter().map(run).collect()
    };
    let mut out = TraceResult::default();
    for part in parts {
        out.counts.merge(&part.counts);
        out.paths.extend(part.paths);
    }
    out
}

/// Diffracted candidates per parallel chunk.
const CHUNK: usize = 128;

/// What [`trace_set`] solves.
struct Work<'a> {
    scene: &'a Scene,
    ends: Endpoints,
    set: &'a DiffractedSet,
    solver: &'a crate::Solver,
}

/// Solve candidates `range` of the set: compiled with the `fma` target feature when the CPU
/// has it (as the specular batch, `crate::batch`: the side and inside tests use `mul_add`,
/// a software call without the feature; results are bit-identical either way).
fn solve_range(work: &Work<'_>, range: std::ops::Range<usize>) -> TraceResult {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("fma") {
        // SAFETY: the CPU supports FMA (checked just above).
        return unsafe { solve_range_fma(work, range) };
    }
    solve_range_impl(work, range)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "fma")]
fn solve_range_fma(work: &Work<'_>, range: std::ops::Range<usize>) -> TraceResult {
    solve_range_impl(work, range)
}

#[inline(always)]
fn solve_range_impl(work: &Work<'_>, range: std::ops::Range<usize>) -> TraceResult {
    let mut out = TraceResult::default();
    let mut buffer = [Vec3::ZERO; 8];
    let mut heap = Vec::new();
    for i in range {
        let c = work.set.get(i);
        let points: &mut [Vec3] = if c.order() <= buffer.len() {
            &mut buffer[..c.order()]
        } else {
            heap.resize(c.order(), Vec3::ZERO);
            &mut heap[..]
        };
        let outcome = solve_candidate(work.scene, work.ends, c, work.solver, points);
        out.counts.add(&outcome);
        out.paths.extend(found(c, &outcome, points));
    }
    out
}

/// The found path of a valid outcome: the specular batch's ([`crate::batch::found_path`])
/// with its diffraction.
fn found(
    c: DiffractedCandidate<'_>,
    outcome: &CandidateOutcome,
    points: &[Vec3],
) -> Option<FoundPath> {
    crate::batch::found_path(c.reflections, outcome, points).map(|path| FoundPath {
        diffraction: Some(Diffraction {
            index: c.position,
            edge: c.edge,
        }),
        ..path
    })
}
