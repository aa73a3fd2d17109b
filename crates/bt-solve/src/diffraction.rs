//! Paths with one or two edge diffractions: solving and validating a [`DiffractedCandidate`].
//!
//! **Image method (closed form).** TX is mirrored through the planes before the edge (`I`), RX
//! through those after it, from RX's side (`J`). The diffraction point `D` is the Keller point
//! of `I` and `J` on the edge line (equal angles with the edge, [`bt_scene::Edge::keller`]):
//! the stationary point of the unfolded length `|I − D| + |D − J|`. The reflection points are
//! then the image method's between TX and `D`, and between `D` and RX. With two diffractions
//! the second edge and `J` are also mirrored through the reflections between the edges, and
//! the two points are the stationary point of the unfolded length over both edge lines
//! ([`bt_scene::edges::keller_pair`]: Newton's method from the one-edge closed forms, to
//! 1e-10 m); the reflection points are the image method's on the three stretches.
//!
//! **IPC.** Each point is updated in turn from its two neighbours by its own closed form: a
//! reflection point where the neighbour mirrored through its plane sees the other neighbour,
//! the diffraction point at the neighbours' Keller point. The rounds descend the path length,
//! a convex function of the points on their planes and line, and stop when a round moves the
//! points by at most the threshold on average.
//!
//! **Validation.** Reflection points as for specular paths ([`crate::validate`]); each
//! diffraction point strictly inside its edge (one length tolerance from either end: a corner
//! is not an edge); both neighbours of `D` in the edge's exterior ([`bt_scene::Edge::in_exterior`]:
//! a path on a face or inside the wedge does not diffract); the ray not along the edge (sin β0
//! at least `bt_channel::diffraction::MIN_SIN_BETA`, where UTD holds); no segment blocked (the segments
//! at `D` start on every surface touching the edge, which cannot block them).

use crate::image::ImageFailure;
use crate::validate::{self, Validity};
use crate::{CandidateOutcome, Diffraction, FoundPath, IpcOptions, IpcOutcome, TraceResult};
use bt_geom::{Real, Vec3};
use bt_paths::diffraction::DiffractedSet;
use bt_paths::diffraction::{DiffractedCandidate, Site};
use bt_scene::edges::{EdgeLine, keller_pair};
use bt_scene::{Edge, Endpoints, Scene, SurfaceId};
use rayon::prelude::*;

/// The interaction points of `c` by the image method into `points` (length `c.order()`,
/// metres, TX side first, the diffraction points at their indices). With two diffractions,
/// `keller` may give the points' parameters already solved from the same inputs
/// ([`DiffractedSet::keller`]: the beam tree's join solves them; `Some(None)` when that
/// solve found none); they are solved here otherwise.
#[inline(always)]
pub fn solve_image(
    scene: &Scene,
    ends: Endpoints,
    c: DiffractedCandidate<'_>,
    keller: Option<Option<(Real, Real)>>,
    points: &mut [Vec3],
) -> Result<(), ImageFailure> {
    let p = c.position;
    let plane = |id: &SurfaceId| scene.surface(*id).polygon.plane();
    let mirror = |from: Vec3, seq: &mut dyn Iterator<Item = &SurfaceId>| {
        seq.fold(from, |image, id| plane(id).mirror(image))
    };
    let i = mirror(ends.tx, &mut c.before().iter());
    let j = mirror(ends.rx, &mut c.after().iter().rev());
    let edge = scene.edges().get(c.edge);
    let Some((second, q)) = c.second else {
        let t = edge
            .keller(i, j)
            .ok_or(ImageFailure::Parallel { index: p })?;
        let d = edge.point(t);
        points[p] = d;
        return stretches(
            scene,
            &[(c.before(), ends.tx), (c.after(), d)],
            ends.rx,
            points,
        );
    };
    let other = scene.edges().get(second);
    let mut line = EdgeLine::of(other);
    let mut j = j;
    for id in c.between().iter().rev() {
        line = line.mirrored(plane(id));
        j = plane(id).mirror(j);
    }
    let (t1, t2) = keller
        .unwrap_or_else(|| keller_pair(i, EdgeLine::of(edge), line, j))
        .ok_or(ImageFailure::Parallel { index: p })?;
    let (d1, d2) = (edge.point(t1), other.point(t2));
    (points[p], points[p + q + 1]) = (d1, d2);
    let parts = [(c.before(), ends.tx), (c.between(), d1), (c.after(), d2)];
    stretches(scene, &parts, ends.rx, points)
}

/// The reflection points of each stretch `(surfaces, from)` of a path whose diffraction
/// points are already in `points`: each stretch runs from `from` to the next stretch's start
/// (the last to `to`), its points right after the previous stretch's and its diffraction.
/// Inlined into the caller's FMA body (`solve_range`): compiled apart, each plane's fused
/// distance would be a software call.
#[inline(always)]
fn stretches(
    scene: &Scene,
    parts: &[(&[SurfaceId], Vec3)],
    to: Vec3,
    points: &mut [Vec3],
) -> Result<(), ImageFailure> {
    let mut start = 0;
    for (k, (surfaces, from)) in parts.iter().enumerate() {
        let end = parts.get(k + 1).map_or(to, |next| next.1);
        let range = start..start + surfaces.len();
        crate::image::solve(scene, surfaces, *from, end, &mut points[range]).map_err(
            |e| match e {
                ImageFailure::Parallel { index } => ImageFailure::Parallel {
                    index: index + start,
                },
            },
        )?;
        start += surfaces.len() + 1;
    }
    Ok(())
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
            let new = match c.site(k) {
                Site::Diffraction(e) => {
                    let edge = scene.edges().get(e);
                    edge.keller(prev, next).map(|t| edge.point(t))
                }
                Site::Reflection(id) => {
                    let plane = scene.surface(id).polygon.plane();
                    crate::ipc::intersection_point(plane, prev, next, min_sum)
                }
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

/// IPC's start points of `c`: each polygon's centroid, each edge's midpoint.
pub fn ipc_start(scene: &Scene, c: DiffractedCandidate<'_>, points: &mut [Vec3]) {
    for (k, p) in points.iter_mut().enumerate() {
        *p = match c.site(k) {
            Site::Diffraction(e) => {
                let edge = scene.edges().get(e);
                edge.point(0.5 * edge.length)
            }
            Site::Reflection(id) => scene.surface(id).polygon.centroid(),
        };
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
    validate_recording(scene, ends, c, points, &mut Vec::new())
}

/// The crossings of penetrable surfaces that validation walked: (segment, point, surface),
/// in path order ([`validate::walk_crossings`]); all of a valid path's.
type Crossings = Vec<(usize, Vec3, SurfaceId)>;

/// [`validate`], with the crossings walked into `crossings` (cleared first).
#[inline(always)]
fn validate_recording(
    scene: &Scene,
    ends: Endpoints,
    c: DiffractedCandidate<'_>,
    points: &[Vec3],
    crossings: &mut Crossings,
) -> Validity {
    crossings.clear();
    let tol = scene.length_tolerance();
    let n = points.len();
    if points.iter().any(|p| !p.is_finite()) {
        return Validity::NonFinite;
    }
    // TX, the points and RX in one array (a short path's on the stack): vertex k is
    // `all[k]`, without asking which of the three it is at each call.
    let (mut stack, mut heap) = ([Vec3::ZERO; 10], Vec::new());
    let all: &mut [Vec3] = if n + 2 <= stack.len() {
        &mut stack[..n + 2]
    } else {
        heap.resize(n + 2, Vec3::ZERO);
        &mut heap
    };
    all[0] = ends.tx;
    all[1..=n].copy_from_slice(points);
    all[n + 1] = ends.rx;
    let all: &[Vec3] = all;
    let vertex = |k: usize| all[k];
    for (k, e) in c.edges() {
        let edge = scene.edges().get(e);
        let t = edge.parameter(points[k]);
        if t <= tol || t >= edge.length - tol {
            return Validity::OffEdge { index: k };
        }
    }
    // The reflections with their points' indices, in path order: the r-th reflection is
    // point r plus the diffractions before it (the same pairs as [`DiffractedCandidate::site`]
    // gives, without asking each point).
    let (p, second) = (c.position, c.second.map(|(_, q)| c.position + q));
    let reflections = || {
        let before =
            move |r: usize| usize::from(r >= p) + usize::from(second.is_some_and(|s| r >= s));
        (c.reflections.iter().enumerate()).map(move |(r, &id)| (r + before(r), id))
    };
    for (k, id) in reflections() {
        if let Some(verdict) = validate::reflection_point(scene, id, points[k], tol, k) {
            return verdict;
        }
    }
    for (k, id) in reflections() {
        let plane = scene.surface(id).polygon.plane();
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
    for (k, e) in c.edges() {
        if let Some(verdict) = diffraction_point(
            scene.edges().get(e),
            (vertex(k), points[k], vertex(k + 2)),
            k,
            tol,
        ) {
            return verdict;
        }
    }
    blocked(scene, c, (vertex, n), crossings)
}

/// The verdict on a diffraction point `d` (point `index`) of `edge` between its neighbours
/// `prev` and `next`, when it fails: both neighbours in the edge's exterior, the ray not
/// along the edge (sin β0 at least `bt_channel::diffraction::MIN_SIN_BETA`, where UTD holds).
#[inline(always)]
fn diffraction_point(
    edge: &Edge,
    (prev, d, next): (Vec3, Vec3, Vec3),
    index: usize,
    tol: Real,
) -> Option<Validity> {
    if !edge.in_exterior(prev, tol) || !edge.in_exterior(next, tol) {
        return Some(Validity::InsideWedge { index });
    }
    // A ray (nearly) along the edge has no UTD coefficient (sin β0 → 0): grazing.
    let incoming = (d - prev).normalize();
    if incoming.cross(edge.direction).length() < bt_channel::diffraction::MIN_SIN_BETA {
        return Some(Validity::Grazing { index });
    }
    None
}

/// The blocking verdict of the segments of the path with vertices `vertex(0..=n + 1)`.
#[inline(always)]
fn blocked(
    scene: &Scene,
    c: DiffractedCandidate<'_>,
    (vertex, n): (impl Fn(usize) -> Vec3, usize),
    crossings: &mut Crossings,
) -> Validity {
    let tol = scene.length_tolerance();
    // Vertex k (0 = TX) lies on: nothing for the terminals, its edge's surfaces for a
    // diffraction point, its surface for a reflection (the j-th point's reflection is
    // `reflections[j − the diffractions before j]`). Worked out once for the candidate, not
    // from [`DiffractedCandidate::site`] at each call.
    let p = c.position;
    let first: &[SurfaceId] = &scene.edges().get(c.edge).touching;
    let (d2, second): (usize, &[SurfaceId]) = match c.second {
        Some((edge, q)) => (p + q + 1, &scene.edges().get(edge).touching),
        None => (usize::MAX, &[]),
    };
    let on = |k: usize| -> &[SurfaceId] {
        match k {
            0 => &[],
            k if k == n + 1 => &[],
            k if k - 1 == p => first,
            k if k - 1 == d2 => second,
            k => {
                let j = k - 1;
                let r = j - usize::from(j > p) - usize::from(j > d2);
                std::slice::from_ref(&c.reflections[r])
            }
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
        return validate::crossing_budget_recording(scene, path, n, |c| crossings.push(c));
    }
    Validity::Valid
}

/// Solve and validate `c` with `solver` (the image method or IPC; SBR does not diffract and
/// gives `Missed`), the image method reading `keller` as [`solve_image`] does. `points` must
/// have `c.order()` entries. IPC starts from [`ipc_start`]; when it converges to two
/// consecutive points within the length tolerance (a spurious fixed point where an edge
/// pierces a neighbouring reflection's plane), it runs again from the image method's points.
#[inline(always)]
pub fn solve_candidate(
    scene: &Scene,
    ends: Endpoints,
    c: DiffractedCandidate<'_>,
    keller: Option<Option<(Real, Real)>>,
    solver: &crate::Solver,
    points: &mut [Vec3],
) -> CandidateOutcome {
    let mut crossings = Vec::new();
    solve_candidate_recording(scene, ends, c, (keller, solver), points, &mut crossings)
}

/// [`solve_candidate`], with the crossings validation walked into `crossings`
/// ([`validate_recording`]).
#[inline(always)]
fn solve_candidate_recording(
    scene: &Scene,
    ends: Endpoints,
    c: DiffractedCandidate<'_>,
    (keller, solver): (Option<Option<(Real, Real)>>, &crate::Solver),
    points: &mut [Vec3],
    crossings: &mut Crossings,
) -> CandidateOutcome {
    match solver {
        crate::Solver::Image => {
            if let Err(e) = solve_image(scene, ends, c, keller, points) {
                return CandidateOutcome::ImageDegenerate(e);
            }
            CandidateOutcome::Solved {
                validity: validate_recording(scene, ends, c, points, crossings),
                ipc: None,
            }
        }
        crate::Solver::Ipc(options) => {
            ipc_start(scene, c, points);
            match solve_ipc(scene, ends, c, options, points) {
                outcome @ IpcOutcome::Converged { .. } => {
                    let again = collapsed(scene, ends, points).then(|| {
                        ipc_from_image(scene, ends, c, (keller, options), (outcome, points))
                    });
                    CandidateOutcome::Solved {
                        validity: validate_recording(scene, ends, c, points, crossings),
                        ipc: Some(again.flatten().unwrap_or(outcome)),
                    }
                }
                outcome @ IpcOutcome::NotConverged { .. } => {
                    CandidateOutcome::NotConverged(outcome)
                }
                outcome => CandidateOutcome::Degenerate(outcome),
            }
        }
        crate::Solver::Sbr(_) => CandidateOutcome::Missed,
    }
}

/// Whether two consecutive points of the path TX → `points` → RX lie within the scene's
/// length tolerance of each other: a collapsed leg, which no valid path has.
fn collapsed(scene: &Scene, ends: Endpoints, points: &[Vec3]) -> bool {
    let tol = scene.length_tolerance();
    let mut prev = ends.tx;
    for &p in points.iter().chain(std::iter::once(&ends.rx)) {
        if prev.distance(p) <= tol {
            return true;
        }
        prev = p;
    }
    false
}

/// IPC's rounds again, from the image method's points of `c`, after a first run converged
/// (`first`) to a collapsed leg in `points` ([`collapsed`]). An edge that pierces the plane
/// of the reflection next to it has a spurious fixed point there: the reflection and the
/// diffraction point both at the piercing point, each the other's neighbour (a path
/// diffracting a millimetre from it drew IPC's centroid start there). Returns the second
/// run's outcome, its rounds counted after the first's, with its points in `points` when it
/// converged without a collapsed leg; else `None`, `points` as the first run left them.
fn ipc_from_image(
    scene: &Scene,
    ends: Endpoints,
    c: DiffractedCandidate<'_>,
    (keller, options): (Option<Option<(Real, Real)>>, &IpcOptions),
    (first, points): (IpcOutcome, &mut [Vec3]),
) -> Option<IpcOutcome> {
    let IpcOutcome::Converged { iterations, .. } = first else {
        return None;
    };
    let mut again = points.to_vec();
    solve_image(scene, ends, c, keller, &mut again).ok()?;
    match solve_ipc(scene, ends, c, options, &mut again) {
        IpcOutcome::Converged {
            iterations: more,
            residual,
        } if !collapsed(scene, ends, &again) => {
            points.copy_from_slice(&again);
            Some(IpcOutcome::Converged {
                iterations: iterations + more,
                residual,
            })
        }
        _ => None,
    }
}

/// Solve and validate every candidate of `set` (in parallel when `parallel`; the output is
/// the same either way) into `out`: the valid paths appended in set order, with the
/// penetrable surfaces they cross inserted as [`FoundPath::with_crossings`] would, and every
/// outcome counted. On one thread the paths go straight into `out` (no per-chunk vectors to
/// grow and copy again); on several, consecutive chunks' results are appended in order.
pub fn trace_set(
    scene: &Scene,
    ends: Endpoints,
    set: &DiffractedSet,
    solver: &crate::Solver,
    parallel: bool,
    out: &mut TraceResult,
) {
    let work = Work {
        scene,
        ends,
        set,
        solver,
    };
    if !(parallel && set.len() >= 2 * CHUNK) {
        // Room for every candidate's path at once: the vector is not grown and copied
        // again (the pages its last paths would not reach are never touched).
        out.paths.reserve(set.len());
        solve_range(&work, 0..set.len(), out);
        return;
    }
    let chunks: Vec<std::ops::Range<usize>> = (0..set.len())
        .step_by(CHUNK)
        .map(|start| start..(start + CHUNK).min(set.len()))
        .collect();
    let parts: Vec<TraceResult> = chunks
        .par_iter()
        .map(|range| {
            let mut part = TraceResult::default();
            solve_range(&work, range.clone(), &mut part);
            part
        })
        .collect();
    out.paths.reserve(parts.iter().map(|p| p.paths.len()).sum());
    for part in parts {
        out.paths.extend(part.paths);
        out.counts.merge(&part.counts);
    }
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

/// Solve candidates `range` of the set into `out` (appended): compiled with the `fma` target
/// feature when the CPU has it (as the specular batch, `crate::batch`: the side and inside
/// tests use `mul_add`, a software call without the feature; results are bit-identical
/// either way).
fn solve_range(work: &Work<'_>, range: std::ops::Range<usize>, out: &mut TraceResult) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("fma") {
        // SAFETY: the CPU supports FMA (checked just above).
        return unsafe { solve_range_fma(work, range, out) };
    }
    solve_range_impl(work, range, out)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "fma")]
fn solve_range_fma(work: &Work<'_>, range: std::ops::Range<usize>, out: &mut TraceResult) {
    solve_range_impl(work, range, out)
}

#[inline(always)]
fn solve_range_impl(work: &Work<'_>, range: std::ops::Range<usize>, out: &mut TraceResult) {
    let mut buffer = [Vec3::ZERO; 8];
    let mut heap = Vec::new();
    let mut crossings = Vec::new();
    for i in range {
        let c = work.set.get(i);
        let points: &mut [Vec3] = if c.order() <= buffer.len() {
            &mut buffer[..c.order()]
        } else {
            heap.resize(c.order(), Vec3::ZERO);
            &mut heap[..]
        };
        let how = (work.set.keller(i), work.solver);
        let outcome =
            solve_candidate_recording(work.scene, work.ends, c, how, points, &mut crossings);
        out.counts.add(&outcome);
        // With its crossings, which validation walked ([`crate::FoundPath::with_crossings`]
        // would walk them again).
        out.paths
            .extend(found(c, &outcome, points).map(|p| p.with_found_crossings(&crossings)));
    }
}

/// The found path of a valid outcome: the specular batch's ([`crate::batch::found_path`])
/// with its diffractions.
fn found(
    c: DiffractedCandidate<'_>,
    outcome: &CandidateOutcome,
    points: &[Vec3],
) -> Option<FoundPath> {
    crate::batch::found_path(c.reflections, outcome, points).map(|path| FoundPath {
        diffractions: c
            .edges()
            .map(|(index, edge)| Diffraction { index, edge })
            .collect(),
        ..path
    })
}
