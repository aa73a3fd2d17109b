//! A scene as the accelerator's input: the bridge from `bt-scene` to `bt-hls`, shared by
//! `beamtrace hls gen` and the living-room study.

use bt_geom::{Real, Vec3};
use bt_hls::{EarlyStop, HlsInput, PathResult, PlaneSpec};
use bt_paths::{AllVisible, CandidateSet, enumerate};
use bt_scene::{Endpoints, Scene, SceneError, SurfaceId};
use bt_solve::{Validity, image, validate::validate};

/// Largest reflection-law error the host accepts on a fixed-point path, degrees: the angle
/// between the mirrored incoming direction and the outgoing one at any bounce. Valid paths of
/// the living room stay below 0.2° (millimetre points over legs of ≥ 0.3 m); the false
/// convergences of the fixed-point model (points stalled 0.5-2.6 m from the solution) are off
/// by degrees (`docs/study-living-room.md`).
pub const REFLECTION_TOLERANCE_DEG: Real = 0.5;

/// Largest reflection-law error over the bounces of `points` (surfaces `seq`, TX and RX),
/// degrees; infinite for a zero-length leg.
pub fn reflection_error_deg(
    scene: &Scene,
    seq: &[SurfaceId],
    tx: Vec3,
    rx: Vec3,
    points: &[Vec3],
) -> Real {
    let mut worst: Real = 0.0;
    for (i, (&p, id)) in points.iter().zip(seq).enumerate() {
        let prev = if i == 0 { tx } else { points[i - 1] };
        let next = points.get(i + 1).copied().unwrap_or(rx);
        let (Some(u), Some(v)) = ((p - prev).try_normalize(), (next - p).try_normalize()) else {
            return Real::INFINITY;
        };
        let n = scene.surface(*id).polygon.plane().normal;
        let mirrored = u - 2.0 * u.dot(n) * n;
        worst = worst.max(mirrored.angle_between(v).to_degrees());
    }
    worst
}

/// The host's check of one accelerator result (the paper's post-processor): converged, valid
/// in f64 (inside every polygon, same side, unblocked), obeying the reflection law within
/// [`REFLECTION_TOLERANCE_DEG`], and not an edge case ([`HostRejection::EdgeCase`]). `ends`
/// are the scene's terminals ([`Scene::terminals`]), local frame.
pub fn host_accepts(
    scene: &Scene,
    ends: Endpoints,
    seq: &[SurfaceId],
    result: &PathResult,
) -> Result<Vec<Vec3>, HostRejection> {
    if !result.converged {
        return Err(HostRejection::NotConverged);
    }
    let points: Vec<Vec3> = result
        .points_m
        .iter()
        .map(|p| Vec3::from_array(*p))
        .collect();
    let Endpoints { tx, rx } = ends;
    if validate(scene, seq, tx, rx, &points) != Validity::Valid {
        return Err(HostRejection::Invalid);
    }
    if reflection_error_deg(scene, seq, tx, rx, &points) > REFLECTION_TOLERANCE_DEG {
        return Err(HostRejection::ReflectionLaw);
    }
    // The fixed-point points lie within a few millimetres of the exact ones, so a ray that
    // passes a blocker's or polygon's edge by less than that is decided on the exact points of
    // the converged sequence (the image method: microseconds on the host).
    let mut exact = vec![Vec3::ZERO; seq.len()];
    if image::solve(scene, seq, tx, rx, &mut exact).is_err()
        || validate(scene, seq, tx, rx, &exact) != Validity::Valid
    {
        return Err(HostRejection::EdgeCase);
    }
    Ok(points)
}

/// Why the host rejects an accelerator result.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HostRejection {
    /// Not converged (round cap, degenerate or early-stopped).
    NotConverged,
    /// Fails the f64 validation (outside a polygon, wrong side, blocked).
    Invalid,
    /// Converged and valid, but breaks the reflection law by more than the tolerance: a false
    /// convergence of the fixed-point iteration.
    ReflectionLaw,
    /// Converged, valid and obeying the reflection law, but the exact points of the sequence
    /// are not a valid path: the fixed-point points slip past an edge (a blocker's, a
    /// polygon's) that the exact ray hits, closer than the fixed-point error.
    EdgeCase,
}

/// Reflectors whose polygon is the same in every scene of `steps` (same id, name and
/// vertices): the planes an accelerator synthesised once per room bakes into its PEs. A
/// moving reflector (the door) is solved by the host instead (`docs/hardware.md`).
pub fn static_reflectors(steps: &[Scene]) -> Vec<SurfaceId> {
    let Some(first) = steps.first() else {
        return Vec::new();
    };
    first
        .reflectors()
        .filter(|id| {
            let s = first.surface(*id);
            steps.iter().all(|scene| {
                (id.0 as usize) < scene.surfaces().len() && {
                    let t = scene.surface(*id);
                    t.name == s.name && t.polygon.vertices() == s.polygon.vertices()
                }
            })
        })
        .collect()
}

/// One step's accelerator work: the HLS input over the platform's planes and the candidates
/// left to the host because they touch a surface that is not a platform plane.
#[derive(Debug, Clone)]
pub struct StepInput {
    /// Candidates over platform planes, start points at the polygon centroids.
    pub input: HlsInput,
    /// Surface sequence of every input path (`input.paths[p]` is `sequences[p]`).
    pub sequences: Vec<Vec<SurfaceId>>,
    /// Candidates through a moving surface: solved by the host (image method).
    pub host_sequences: Vec<Vec<SurfaceId>>,
}

/// The HLS input of one step: `planes` are the platform's reflectors (PE `bt_pe_<i>` for
/// `planes[i]`), `candidates` the step's candidate sequences (empty ones skipped); a
/// candidate through a surface not in `planes` goes to the host. `threshold_lsb` in 1/256 mm,
/// `max_rounds` the round cap; early stopping ([`EarlyStop::default`]) on every plane's
/// polygon bounding box; the coordinate word sized from the planes (`platform_extent_m`).
/// A scene without both terminals fails ([`SceneError::MissingTerminal`]).
pub fn step_input(
    scene: &Scene,
    planes: &[SurfaceId],
    candidates: &CandidateSet,
    threshold_lsb: u32,
    max_rounds: u32,
) -> Result<StepInput, SceneError> {
    let ends = scene.terminals()?;
    let mut plane_of = vec![u32::MAX; scene.surfaces().len()];
    for (i, id) in planes.iter().enumerate() {
        plane_of[id.0 as usize] = i as u32;
    }
    let mut paths = Vec::new();
    let mut init_points = Vec::new();
    let mut sequences = Vec::new();
    let mut host_sequences = Vec::new();
    for (i, seq) in candidates.iter().enumerate() {
        if seq.is_empty() {
            continue;
        }
        if seq.iter().any(|id| plane_of[id.0 as usize] == u32::MAX) {
            host_sequences.push(seq.to_vec());
            continue;
        }
        paths.push(seq.iter().map(|id| plane_of[id.0 as usize]).collect());
        init_points.push(match candidates.start(i) {
            Some(starts) => starts.iter().map(|p| p.to_array()).collect(),
            None => seq
                .iter()
                .map(|id| scene.surface(*id).polygon.centroid().to_array())
                .collect(),
        });
        sequences.push(seq.to_vec());
    }
    let planes: Vec<PlaneSpec> = planes
        .iter()
        .map(|id| {
            let s = scene.surface(*id);
            let p = s.polygon.plane();
            let (min, max) = s.polygon.bounds();
            PlaneSpec {
                name: s.name.clone(),
                normal: p.normal.to_array(),
                offset_m: p.offset,
                bounds_m: Some([min.to_array(), max.to_array()]),
            }
        })
        .collect();
    let coord_bits = bt_fixed::coord_bits_for(platform_extent_m(&planes));
    let input = HlsInput {
        planes,
        paths,
        init_points,
        tx: ends.tx.to_array(),
        rx: ends.rx.to_array(),
        threshold_lsb,
        max_rounds,
        test_vectors: Vec::new(),
        early_stop: Some(EarlyStop::default()),
        coord_bits,
        // The paper's order; `plan_step` sets the order a stream runs with.
        round_order: bt_hls::RoundOrder::Jacobi,
    };
    Ok(StepInput {
        input,
        sequences,
        host_sequences,
    })
}

/// How far the platform's planes reach from the origin, metres: the largest |coordinate| of
/// their polygons' boxes and |offset|. It sizes the accelerator's coordinate word
/// ([`bt_fixed::coord_bits_for`], 4× headroom), so it depends on the static planes only and
/// every step of a stream gets the same word; terminals and start points must fit it (the
/// model refuses, naming the value, when one does not).
pub fn platform_extent_m(planes: &[PlaneSpec]) -> f64 {
    planes
        .iter()
        .flat_map(|p| {
            let corners = p.bounds_m.into_iter().flatten().flatten();
            corners.chain([p.offset_m]).map(f64::abs)
        })
        .fold(0.0, f64::max)
}

/// The HLS input of a scene: one plane per reflector (PE `bt_pe_<i>` for the `i`-th
/// reflector), every candidate path of order 1 to `max_order` (exhaustive enumeration with
/// the side test, as the paper computes *all* paths on the FPGA), starting points at the
/// polygon centroids; `threshold_lsb` in 1/256 mm, `max_rounds` the round cap; early stopping
/// ([`EarlyStop::default`]) on every plane's polygon bounding box. Also returns
/// the surface sequence of every input path (`input.paths[p]` is `sequences[p]`). A scene
/// without both terminals fails ([`SceneError::MissingTerminal`]).
pub fn hls_input(
    scene: &Scene,
    max_order: usize,
    threshold_lsb: u32,
    max_rounds: u32,
) -> Result<(HlsInput, Vec<Vec<SurfaceId>>), SceneError> {
    let reflectors: Vec<SurfaceId> = scene.reflectors().collect();
    let candidates = enumerate(scene, max_order, &AllVisible)?;
    let s = step_input(scene, &reflectors, &candidates, threshold_lsb, max_rounds)?;
    debug_assert!(s.host_sequences.is_empty());
    Ok((s.input, s.sequences))
}

/// Warm start from the previous time step (as `bt_solve::steps` warm-starts its IPC): every path of
/// `step` whose surface sequence the accelerator ran at the previous step and brought to
/// convergence starts from the points it converged to there (`previous.sequences[p]` and
/// `results[p]`, the accelerator's read-back), instead of the beam tree's window centres. The
/// PEs see the planes, TX and RX only, so with those unchanged such a path converges in one
/// round; a path that did not converge keeps its cold start. Returns the paths warm-started.
pub fn warm_start(step: &mut StepInput, previous: &StepInput, results: &[PathResult]) -> usize {
    let converged: std::collections::HashMap<&[SurfaceId], &PathResult> = previous
        .sequences
        .iter()
        .zip(results)
        .filter(|(_, r)| r.converged)
        .map(|(s, r)| (s.as_slice(), r))
        .collect();
    let mut warm = 0;
    for (seq, init) in step.sequences.iter().zip(&mut step.input.init_points) {
        if let Some(r) = converged.get(seq.as_slice()) {
            init.clone_from(&r.points_m);
            warm += 1;
        }
    }
    warm
}
