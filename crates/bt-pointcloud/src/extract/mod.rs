//! Plane extraction: sequential RANSAC (as Open3D's `segment_plane` is used in a loop),
//! split into connected patches, least-squares refit, boundary polygon, area, and the
//! reflector / blocker classification of the paper (planes of at least 0.25 m² reflect).
//!
//! Differences from a plain Open3D loop, each for a reason:
//! * Hypotheses are one point plus its PCA normal (instead of three random points), and an
//!   inlier must also have a normal within [`ExtractParams::normal_angle_deg`] of the plane.
//!   Without the normal test, a plane slicing across many perpendicular surfaces (a 3 cm
//!   band around all four walls) out-scores a real small plane late in the loop.
//! * Hypotheses are scored on a seeded random subsample of the remaining points and the
//!   number of hypotheses adapts to the best inlier ratio (standard RANSAC bound), so a
//!   10⁶-point cloud takes seconds; the winner is refined on all remaining points by
//!   alternating least-squares fit and inlier collection.
//! * Adjoining patches get exactly shared edges (see `snap`), which undoes the edge strip a
//!   perpendicular plane steals within the distance threshold.
//!
//! Determinism: one `ChaCha8Rng` seeded with [`ExtractParams::seed`] drives every random
//! choice, all parallel work is order-preserving `map`/`filter` + `collect`, and nothing
//! iterates a hash map. Same cloud and parameters ⇒ bit-identical output.

use bt_geom::{Real, Vec2, Vec3};
mod boundary;
mod layers;
mod normals;
mod snap;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::Serialize;

use crate::cloud::PointCloud;
use crate::error::PointCloudError;
use crate::linalg::fit_plane;
use crate::spatial::VoxelIndex;
use crate::tol;
use boundary::{min_area_rect, patch_boundary, signed_area};
use bt_geom::convex::hull_2d;
use snap::PatchGeom;

/// Parameters of [`extract_planes`]. Lengths in metres, angles in degrees. The defaults
/// suit an indoor scan of roughly 2 000 points/m² with ≈ 5 mm noise.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ExtractParams {
    /// Seed of the RANSAC random generator (echoed in the report).
    pub seed: u64,
    /// RANSAC inlier distance to the plane, metres (≈ 3 σ of the range noise).
    pub distance_threshold_m: Real,
    /// Neighbourhood size for normals, metres: PCA over a cube of 1.5 × this edge
    /// (≈ 3–4 point spacings or more).
    pub normal_radius_m: Real,
    /// Largest angle between a point's normal and the plane normal for an inlier, degrees.
    pub normal_angle_deg: Real,
    /// Radius of the neighbourhood a hypothesis is refitted on before scoring, metres.
    pub hypothesis_radius_m: Real,
    /// Fewest hypotheses per plane.
    pub min_iterations: usize,
    /// Most hypotheses per plane.
    pub max_iterations: usize,
    /// Probability of having drawn a point of the best plane when hypothesising stops.
    pub confidence: Real,
    /// Size of the random subsample hypotheses are scored on.
    pub score_sample: usize,
    /// Most least-squares refit / re-collect rounds for the winning hypothesis.
    pub refine_iterations: usize,
    /// Stop after this many RANSAC planes (each may split into several patches).
    pub max_planes: usize,
    /// Stop when fewer points remain, or the best plane has fewer inliers.
    pub min_plane_points: usize,
    /// Cell edge for splitting a plane's inliers into connected patches, metres. Patches
    /// separated by a gap wider than twice this are always split. Also the
    /// radius of the neighbourhood vote that separates parallel surfaces closer than the
    /// RANSAC band (a pane in front of a wall).
    pub cluster_eps_m: Real,
    /// Patches with fewer points are dropped.
    pub min_patch_points: usize,
    /// Patches whose minimum-area bounding rectangle is narrower are dropped, metres
    /// (removes slivers left along creases).
    pub min_patch_width_m: Real,
    /// Raster cell for boundary tracing, metres (≈ 2 point spacings or more).
    pub boundary_cell_m: Real,
    /// Douglas–Peucker tolerance for the traced boundary, metres.
    pub simplify_tolerance_m: Real,
    /// Largest distance over which an edge is moved onto the intersection line with an
    /// adjoining plane, metres.
    pub snap_distance_m: Real,
    /// Patches of at least this area are reflectors, others blockers, m² (paper: 0.25).
    pub min_reflector_area_m2: Real,
}

impl Default for ExtractParams {
    fn default() -> Self {
        Self {
            seed: 0,
            distance_threshold_m: 0.015,
            normal_radius_m: 0.05,
            normal_angle_deg: 45.0,
            hypothesis_radius_m: 0.2,
            min_iterations: 64,
            max_iterations: 2000,
            confidence: 0.999,
            score_sample: 20_000,
            refine_iterations: 8,
            max_planes: 300,
            min_plane_points: 50,
            cluster_eps_m: 0.05,
            min_patch_points: 50,
            min_patch_width_m: 0.08,
            boundary_cell_m: 0.05,
            simplify_tolerance_m: 0.08,
            snap_distance_m: 0.05,
            min_reflector_area_m2: 0.25,
        }
    }
}

impl ExtractParams {
    /// Check every parameter; all problems are reported together.
    pub fn validate(&self) -> Result<(), PointCloudError> {
        let mut problems = Vec::new();
        let mut pos = |name: &str, v: Real| {
            if !(v.is_finite() && v > 0.0) {
                problems.push(format!("{name} must be finite and positive, got {v}"));
            }
        };
        pos("distance_threshold_m", self.distance_threshold_m);
        pos("normal_radius_m", self.normal_radius_m);
        pos("hypothesis_radius_m", self.hypothesis_radius_m);
        pos("cluster_eps_m", self.cluster_eps_m);
        pos("boundary_cell_m", self.boundary_cell_m);
        pos("simplify_tolerance_m", self.simplify_tolerance_m);
        pos("snap_distance_m", self.snap_distance_m);
        pos("min_reflector_area_m2", self.min_reflector_area_m2);
        if !(self.min_patch_width_m.is_finite() && self.min_patch_width_m >= 0.0) {
            problems.push(format!(
                "min_patch_width_m must be finite and non-negative, got {}",
                self.min_patch_width_m
            ));
        }
        if !(self.normal_angle_deg > 0.0 && self.normal_angle_deg <= 90.0) {
            problems.push(format!(
                "normal_angle_deg must be in (0, 90], got {}",
                self.normal_angle_deg
            ));
        }
        if !(self.confidence > 0.0 && self.confidence < 1.0) {
            problems.push(format!(
                "confidence must be in (0, 1), got {}",
                self.confidence
            ));
        }
        if self.max_iterations == 0 || self.min_iterations > self.max_iterations {
            problems.push(format!(
                "need 0 < min_iterations ≤ max_iterations, got {} and {}",
                self.min_iterations, self.max_iterations
            ));
        }
        if self.score_sample == 0 {
            problems.push("score_sample must be positive".into());
        }
        if self.min_plane_points < 3 || self.min_patch_points < 3 {
            problems.push("min_plane_points and min_patch_points must be at least 3".into());
        }
        if problems.is_empty() {
            Ok(())
        } else {
            Err(PointCloudError::InvalidParams { problems })
        }
    }
}

/// One extracted planar patch. World frame, metres.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ExtractedPlane {
    /// Unit normal. Oriented to agree with the input normals when the cloud has them,
    /// otherwise towards the centroid of the whole cloud (for a room scan: into the room).
    pub normal: Vec3,
    /// Plane offset: points `x` on the plane satisfy `normal · x = offset`, metres.
    pub offset: Real,
    /// Boundary vertices on the plane, a simple polygon, counter-clockwise seen from the
    /// side the normal points to (looking against the normal), no repeated closing vertex.
    pub polygon: Vec<Vec3>,
    /// Area of `polygon`, m².
    pub area_m2: Real,
    /// Number of cloud points assigned to this patch.
    pub inliers: usize,
    /// RMS distance of those points to the plane, metres.
    pub rms_m: Real,
    /// `area_m2 ≥ min_reflector_area_m2`: takes part in reflection; otherwise it only
    /// blocks rays.
    pub reflector: bool,
    /// Index of the RANSAC plane this patch came from (coplanar patches share it).
    pub ransac_plane: usize,
}

/// Summary of one plane for the report.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PlaneSummary {
    /// Unit normal, world frame.
    pub normal: [Real; 3],
    /// Offset along the normal, metres.
    pub offset_m: Real,
    /// Polygon area, m².
    pub area_m2: Real,
    /// Assigned points.
    pub inliers: usize,
    /// RMS point-to-plane distance, metres.
    pub rms_m: Real,
    /// Reflector (true) or blocker (false).
    pub reflector: bool,
    /// Polygon vertex count.
    pub vertices: usize,
}

/// What the extraction did, for logs and golden files (serialisable, deterministic).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ExtractionReport {
    /// RANSAC seed used.
    pub seed: u64,
    /// Points in the input cloud.
    pub input_points: usize,
    /// Points whose neighbourhood was too sparse for a normal (never inliers).
    pub points_without_normal: usize,
    /// RANSAC planes found (before splitting into patches).
    pub ransac_planes: usize,
    /// Patches kept (length of `planes`).
    pub planes_found: usize,
    /// Kept patches that are reflectors.
    pub reflectors: usize,
    /// Kept patches that are blockers.
    pub blockers: usize,
    /// Points in kept patches.
    pub inliers: usize,
    /// Patches dropped as too small, too thin or without a valid boundary.
    pub dropped_patches: usize,
    /// Points in dropped patches.
    pub dropped_points: usize,
    /// Points never assigned to any RANSAC plane.
    pub leftover_points: usize,
    /// Inlier-weighted RMS point-to-plane distance over kept patches, metres.
    pub rms_m: Real,
    /// Total area of kept patches, m².
    pub total_area_m2: Real,
    /// Per-patch summaries, in the order of [`Extraction::planes`].
    pub planes: Vec<PlaneSummary>,
    /// Parameters used.
    pub params: ExtractParams,
}

/// Result of [`extract_planes`].
#[derive(Debug, Clone, PartialEq)]
pub struct Extraction {
    /// Kept patches, in extraction order (RANSAC plane, then patch order).
    pub planes: Vec<ExtractedPlane>,
    /// Summary.
    pub report: ExtractionReport,
}

/// Extraction stages reported to the progress callback.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stage {
    /// Estimating per-point normals.
    Normals,
    /// A RANSAC plane was found and removed.
    Ransac,
    /// Computing boundaries and shared edges.
    Boundaries,
    /// Finished.
    Done,
}

/// Progress information passed to the callback of [`extract_planes_with_progress`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Progress {
    /// Current stage.
    pub stage: Stage,
    /// Points assigned to RANSAC planes so far.
    pub points_assigned: usize,
    /// Points in the cloud.
    pub points_total: usize,
    /// RANSAC planes found so far.
    pub ransac_planes: usize,
}

/// Extract planar patches from `cloud`; see the module documentation. Deterministic for a
/// given `params.seed`. Fails only on invalid parameters.
pub fn extract_planes(
    cloud: &PointCloud,
    params: &ExtractParams,
) -> Result<Extraction, PointCloudError> {
    extract_planes_with_progress(cloud, params, &mut |_| {})
}

/// A plane hypothesis from seed point `i`: start from its PCA normal, then twice fit a plane
/// by least squares to the free points within `hypothesis_radius_m` that are inliers of the
/// current plane. Per-point normals are only good to a few degrees, which over a 2.6 m wall
/// is several centimetres; a tilted hypothesis can collect bands of two parallel surfaces
/// (a wall and a door recessed 4 cm) and the global refit then settles between them.
fn local_hypothesis(
    pts: &[Vec3],
    normals: &[Vec3],
    taken: &[bool],
    coarse: &VoxelIndex,
    i: usize,
    params: &ExtractParams,
) -> (Vec3, Real) {
    let (p, mut n) = (pts[i], normals[i]);
    let mut d = n.dot(p);
    let cos_gate = params.normal_angle_deg.to_radians().cos();
    let mut near = Vec::new();
    for _ in 0..2 {
        near.clear();
        coarse.for_each_near(pts, p, params.hypothesis_radius_m, |j| {
            let j = j as usize;
            if !taken[j]
                && (n.dot(pts[j]) - d).abs() <= params.distance_threshold_m
                && n.dot(normals[j]).abs() >= cos_gate
            {
                near.push(pts[j]);
            }
        });
        match fit_plane(near.iter().copied()) {
            Some(f) if near.len() >= 6 => {
                n = f.normal;
                d = f.offset;
            }
            _ => break,
        }
    }
    (n, d)
}

pub(super) struct RawPatch {
    pub(super) indices: Vec<u32>,
    pub(super) ransac_plane: usize,
}

/// Unit vectors `(u, v)` with `(u, v, n)` right-handed, chosen deterministically from `n`.
pub(super) fn frame(n: Vec3) -> (Vec3, Vec3) {
    let a = if n.x.abs() <= n.y.abs() && n.x.abs() <= n.z.abs() {
        Vec3::X
    } else if n.y.abs() <= n.z.abs() {
        Vec3::Y
    } else {
        Vec3::Z
    };
    let u = n.cross(a).normalize();
    (u, n.cross(u))
}

/// Like [`extract_planes`], calling `progress` after each stage and each RANSAC plane. The
/// library never prints; wire the callback to a progress bar in the binary.
///
/// Stages, one function each: normals, `ransac_patches` (planes and their connected
/// components), `separate_layers` (parallel surfaces share their points), `build_patch`
/// (refit, orient, boundary; in parallel), snapping of shared edges, `finish_planes` (area
/// and width checks) and `report`.
pub fn extract_planes_with_progress(
    cloud: &PointCloud,
    params: &ExtractParams,
    progress: &mut dyn FnMut(Progress),
) -> Result<Extraction, PointCloudError> {
    params.validate()?;
    let pts = cloud.points();
    let n = pts.len();
    let mut prog = Progress {
        stage: Stage::Normals,
        points_assigned: 0,
        points_total: n,
        ransac_planes: 0,
    };
    progress(prog);
    let normals = normals::estimate_normals(pts, params.normal_radius_m);
    let coarse = VoxelIndex::build(pts, params.hypothesis_radius_m);
    let ransac = ransac_patches(pts, &normals, &coarse, params, &mut prog, progress);
    let raw = separate_layers(pts, ransac.patches, params);
    prog.stage = Stage::Boundaries;
    progress(prog);

    // Per patch: refit, orient, frame, boundary. Order-preserving parallel map.
    let centroid = if n > 0 {
        pts.iter().fold(Vec3::ZERO, |a, p| a + *p) / n as Real
    } else {
        Vec3::ZERO
    };
    let in_normals = cloud.normals();
    let built: Vec<Option<(PatchGeom, Real, usize)>> = raw
        .par_iter()
        .map(|rp| build_patch(rp, pts, &normals, in_normals, centroid, params))
        .collect();
    let mut dropped = Dropped::default();
    let mut geoms = Vec::new();
    let mut meta = Vec::new();
    for (rp, b) in raw.iter().zip(built) {
        match b {
            Some((g, rms, plane)) => {
                geoms.push(g);
                meta.push((rp.indices.len(), rms, plane));
            }
            None => dropped.add(rp.indices.len()),
        }
    }
    let snapped = snap::snap_all(
        &geoms,
        params.snap_distance_m,
        params.boundary_cell_m,
        &snap::Cloud {
            pts,
            index: &coarse,
            band: params.distance_threshold_m,
        },
    );
    let planes = finish_planes(&geoms, snapped, meta, params, &mut dropped);
    let report = report(&planes, params, n, &ransac.counts, dropped);
    prog.stage = Stage::Done;
    progress(prog);
    Ok(Extraction { planes, report })
}

/// Point counts of the RANSAC stage for the report.
struct RansacCounts {
    /// RANSAC planes accepted.
    planes: usize,
    /// Points without an estimated normal (never candidates).
    without_normal: usize,
    /// Points with a normal no plane took, plus those without a normal.
    leftover: usize,
}

/// The connected patches found by RANSAC, in discovery order, with the counts.
struct Ransac {
    patches: Vec<RawPatch>,
    counts: RansacCounts,
}

/// Patches and points dropped on the way (too small, no boundary, degenerate after snapping).
#[derive(Default)]
struct Dropped {
    patches: usize,
    points: usize,
}

impl Dropped {
    fn add(&mut self, points: usize) {
        self.patches += 1;
        self.points += points;
    }
}

/// The inlier test of RANSAC: a point is an inlier of the plane `nrm · x = d` when it lies
/// within the band `distance_threshold_m` and its normal within the angle gate.
#[derive(Clone, Copy)]
struct InlierTest<'a> {
    pts: &'a [Vec3],
    normals: &'a [Vec3],
    band: Real,
    cos_gate: Real,
}

impl<'a> InlierTest<'a> {
    fn new(pts: &'a [Vec3], normals: &'a [Vec3], params: &ExtractParams) -> Self {
        Self {
            pts,
            normals,
            band: params.distance_threshold_m,
            cos_gate: params.normal_angle_deg.to_radians().cos(),
        }
    }

    #[inline]
    fn holds(&self, i: u32, nrm: Vec3, d: Real) -> bool {
        let i = i as usize;
        (nrm.dot(self.pts[i]) - d).abs() <= self.band
            && nrm.dot(self.normals[i]).abs() >= self.cos_gate
    }
}

/// The RANSAC stage: best plane hypothesis on the remaining points, refit, split into
/// connected components (tilted components go back to the pool), until `max_planes` or too
/// few points remain. Reports progress after every plane.
fn ransac_patches(
    pts: &[Vec3],
    normals: &[Vec3],
    coarse: &VoxelIndex,
    params: &ExtractParams,
    prog: &mut Progress,
    progress: &mut dyn FnMut(Progress),
) -> Ransac {
    let n = pts.len();
    let mut remaining: Vec<u32> = (0..n as u32)
        .filter(|&i| normals[i as usize] != Vec3::ZERO)
        .collect();
    let points_without_normal = n - remaining.len();
    let mut rng = ChaCha8Rng::seed_from_u64(params.seed);
    let mut raw: Vec<RawPatch> = Vec::new();
    let mut taken = vec![false; n];
    let mut ransac_planes = 0;
    while ransac_planes < params.max_planes && remaining.len() >= params.min_plane_points {
        let Some((nrm, d)) =
            best_hypothesis(pts, normals, coarse, &taken, &remaining, params, &mut rng)
        else {
            break;
        };
        let Some((nrm, inliers)) = refined_inliers(pts, normals, &remaining, params, nrm, d) else {
            break;
        };
        // A component whose own least-squares plane is tilted against the RANSAC plane is a
        // band where the infinite plane cuts through another surface (e.g. a 15° sofa back
        // extended into a picture on the wall): its points go back to the pool. If nothing
        // survives, everything is removed anyway so the loop makes progress.
        let comps = split_connected(pts, &inliers, nrm, params.cluster_eps_m);
        let belongs: Vec<bool> = comps
            .par_iter()
            .map(|c| {
                fit_plane(c.iter().map(|&i| pts[i as usize]))
                    .is_none_or(|f| f.normal.dot(nrm).abs() >= tol::COMPONENT_COS)
            })
            .collect();
        let keep_all = !belongs.iter().any(|&b| b);
        for (c, &b) in comps.iter().zip(&belongs) {
            if b || keep_all {
                for &i in c {
                    taken[i as usize] = true;
                }
            }
        }
        remaining.retain(|&i| !taken[i as usize]);
        for (indices, b) in comps.into_iter().zip(belongs) {
            if b || keep_all {
                raw.push(RawPatch {
                    indices,
                    ransac_plane: ransac_planes,
                });
            }
        }
        ransac_planes += 1;
        *prog = Progress {
            stage: Stage::Ransac,
            points_assigned: n - remaining.len() - points_without_normal,
            points_total: n,
            ransac_planes,
        };
        progress(*prog);
    }
    Ransac {
        patches: raw,
        counts: RansacCounts {
            planes: ransac_planes,
            without_normal: points_without_normal,
            leftover: remaining.len() + points_without_normal,
        },
    }
}

/// Scores local plane hypotheses (64 per batch, seeded from random remaining points) on a
/// random subsample of the remaining points until the adaptive RANSAC count for the requested
/// confidence is reached; returns the best plane `(normal, offset)`.
fn best_hypothesis(
    pts: &[Vec3],
    normals: &[Vec3],
    coarse: &VoxelIndex,
    taken: &[bool],
    remaining: &[u32],
    params: &ExtractParams,
    rng: &mut ChaCha8Rng,
) -> Option<(Vec3, Real)> {
    let log_fail = (1.0 - params.confidence).ln();
    let inlier = InlierTest::new(pts, normals, params);
    // Score hypotheses on a random subsample of the remaining points.
    let sample: Vec<u32> = if remaining.len() <= params.score_sample {
        remaining.to_vec()
    } else {
        (0..params.score_sample)
            .map(|_| remaining[rng.random_range(0..remaining.len())])
            .collect()
    };
    let mut best: Option<(usize, Vec3, Real)> = None;
    let mut tried = 0;
    let mut needed = params.min_iterations;
    while tried < needed.min(params.max_iterations) {
        let seeds: Vec<usize> = (0..64)
            .map(|_| remaining[rng.random_range(0..remaining.len())] as usize)
            .collect();
        let batch: Vec<(Vec3, Real)> = seeds
            .par_iter()
            .map(|&i| local_hypothesis(pts, normals, taken, coarse, i, params))
            .collect();
        let counts: Vec<usize> = batch
            .par_iter()
            .map(|&(nrm, d)| sample.iter().filter(|&&i| inlier.holds(i, nrm, d)).count())
            .collect();
        for (&(nrm, d), &c) in batch.iter().zip(&counts) {
            if best.is_none_or(|(bc, _, _)| c > bc) {
                best = Some((c, nrm, d));
            }
        }
        tried += batch.len();
        let w = best.map_or(0.0, |b| b.0 as Real / sample.len() as Real);
        needed = if w >= 1.0 {
            0
        } else if w <= 0.0 {
            params.max_iterations
        } else {
            (log_fail / (1.0 - w).ln()).ceil() as usize
        }
        .max(params.min_iterations);
    }
    best.map(|(_, nrm, d)| (nrm, d))
}

/// The inliers of plane `(nrm, d)` among `remaining`, refit by least squares while the set
/// grows; `None` when fewer than `min_plane_points` remain. Returns the final normal too.
fn refined_inliers(
    pts: &[Vec3],
    normals: &[Vec3],
    remaining: &[u32],
    params: &ExtractParams,
    mut nrm: Vec3,
    d: Real,
) -> Option<(Vec3, Vec<u32>)> {
    let inlier = InlierTest::new(pts, normals, params);
    let collect = |nrm: Vec3, d: Real| -> Vec<u32> {
        remaining
            .par_iter()
            .copied()
            .filter(|&i| inlier.holds(i, nrm, d))
            .collect()
    };
    let mut inliers = collect(nrm, d);
    for _ in 0..params.refine_iterations {
        let Some(fit) = fit_plane(inliers.iter().map(|&i| pts[i as usize])) else {
            break;
        };
        let next = collect(fit.normal, fit.offset);
        if next.len() < inliers.len() || next == inliers {
            break;
        }
        (nrm, inliers) = (fit.normal, next);
    }
    (inliers.len() >= params.min_plane_points).then_some((nrm, inliers))
}

/// Parallel surfaces closer than the RANSAC band share their points out competitively;
/// patches that changed are split into connected parts again.
fn separate_layers(pts: &[Vec3], mut raw: Vec<RawPatch>, params: &ExtractParams) -> Vec<RawPatch> {
    let changed = layers::separate_parallel(
        pts,
        &mut raw,
        params.distance_threshold_m,
        params.cluster_eps_m,
        params.min_patch_points,
    );
    if changed.is_empty() {
        return raw;
    }
    let mut next = Vec::with_capacity(raw.len());
    for (k, rp) in raw.into_iter().enumerate() {
        if changed.binary_search(&k).is_err() {
            next.push(rp);
            continue;
        }
        let Some(fit) = fit_plane(rp.indices.iter().map(|&i| pts[i as usize])) else {
            next.push(rp);
            continue;
        };
        for indices in split_connected(pts, &rp.indices, fit.normal, params.cluster_eps_m) {
            next.push(RawPatch {
                indices,
                ransac_plane: rp.ransac_plane,
            });
        }
    }
    next
}

/// One patch's geometry: least-squares refit on the points whose normals agree, orientation
/// (towards the input normals, else away from the cloud's centroid), in-plane frame and
/// boundary polygon; with the refit's RMS distance (m) and the RANSAC plane index. `None` for
/// patches too small or without a boundary.
fn build_patch(
    rp: &RawPatch,
    pts: &[Vec3],
    normals: &[Vec3],
    in_normals: Option<&[Vec3]>,
    centroid: Vec3,
    params: &ExtractParams,
) -> Option<(PatchGeom, Real, usize)> {
    if rp.indices.len() < params.min_patch_points {
        return None;
    }
    let mut fit = fit_plane(rp.indices.iter().map(|&i| pts[i as usize]))?;
    for _ in 0..2 {
        let core = rp
            .indices
            .iter()
            .filter(|&&i| normals[i as usize].dot(fit.normal).abs() >= tol::REFIT_GATE_COS);
        match fit_plane(core.map(|&i| pts[i as usize])) {
            Some(f) => fit = f,
            None => break,
        }
    }
    let rms = (rp
        .indices
        .iter()
        .map(|&i| (fit.normal.dot(pts[i as usize]) - fit.offset).powi(2))
        .sum::<Real>()
        / rp.indices.len() as Real)
        .sqrt();
    let mut normal = fit.normal;
    let flip = match in_normals {
        Some(ns) => {
            rp.indices
                .iter()
                .map(|&i| normal.dot(ns[i as usize]))
                .sum::<Real>()
                < 0.0
        }
        None => normal.dot(centroid - fit.centroid) < 0.0,
    };
    if flip {
        normal = -normal;
    }
    let (u, v) = frame(normal);
    let origin = fit.centroid;
    let p2: Vec<Vec2> = rp
        .indices
        .iter()
        .map(|&i| {
            let r = pts[i as usize] - origin;
            Vec2::new(r.dot(u), r.dot(v))
        })
        .collect();
    let poly = patch_boundary(&p2, params.boundary_cell_m, params.simplify_tolerance_m)?;
    let mut g = PatchGeom {
        normal,
        offset: normal.dot(origin),
        origin,
        u,
        v,
        poly,
        lo: Vec3::ZERO,
        hi: Vec3::ZERO,
        density: 0.0,
    };
    g.density = rp.indices.len() as Real / signed_area(&g.poly).max(Real::MIN_POSITIVE);
    g.update_bounds();
    Some((g, rms, rp.ransac_plane))
}

/// The extracted planes from the snapped polygons: patches whose polygon lost its area or is
/// narrower than `min_patch_width_m` are dropped; reflectors by area.
fn finish_planes(
    geoms: &[PatchGeom],
    snapped: Vec<Vec<Vec2>>,
    meta: Vec<(usize, Real, usize)>,
    params: &ExtractParams,
    dropped: &mut Dropped,
) -> Vec<ExtractedPlane> {
    let mut planes = Vec::new();
    for ((g, poly), (count, rms, plane)) in geoms.iter().zip(snapped).zip(meta) {
        let area = signed_area(&poly);
        let (_, width, _) = min_area_rect(&hull_2d(&poly));
        if !(area > 0.0 && area.is_finite()) || width < params.min_patch_width_m {
            dropped.add(count);
            continue;
        }
        planes.push(ExtractedPlane {
            normal: g.normal,
            offset: g.offset,
            polygon: poly.iter().map(|p| g.lift(*p)).collect(),
            area_m2: area,
            inliers: count,
            rms_m: rms,
            reflector: area >= params.min_reflector_area_m2,
            ransac_plane: plane,
        });
    }
    planes
}

/// The extraction report: counts, inlier-weighted RMS and one summary per plane.
fn report(
    planes: &[ExtractedPlane],
    params: &ExtractParams,
    input_points: usize,
    ransac: &RansacCounts,
    dropped: Dropped,
) -> ExtractionReport {
    let inliers: usize = planes.iter().map(|p| p.inliers).sum();
    let rms_m = if inliers > 0 {
        (planes
            .iter()
            .map(|p| p.rms_m * p.rms_m * p.inliers as Real)
            .sum::<Real>()
            / inliers as Real)
            .sqrt()
    } else {
        0.0
    };
    ExtractionReport {
        seed: params.seed,
        input_points,
        points_without_normal: ransac.without_normal,
        ransac_planes: ransac.planes,
        planes_found: planes.len(),
        reflectors: planes.iter().filter(|p| p.reflector).count(),
        blockers: planes.iter().filter(|p| !p.reflector).count(),
        inliers,
        dropped_patches: dropped.patches,
        dropped_points: dropped.points,
        leftover_points: ransac.leftover,
        rms_m,
        total_area_m2: planes.iter().map(|p| p.area_m2).sum(),
        planes: planes
            .iter()
            .map(|p| PlaneSummary {
                normal: p.normal.to_array(),
                offset_m: p.offset,
                area_m2: p.area_m2,
                inliers: p.inliers,
                rms_m: p.rms_m,
                reflector: p.reflector,
                vertices: p.polygon.len(),
            })
            .collect(),
        params: params.clone(),
    }
}

/// Split a plane's inliers into connected patches: points are binned into square cells of
/// `eps` metres in the plane's 2-D frame and cells touching by side or corner are joined.
/// Patches come out in ascending order of their smallest cell, point indices ascending.
fn split_connected(pts: &[Vec3], inliers: &[u32], normal: Vec3, eps: Real) -> Vec<Vec<u32>> {
    use std::collections::HashMap;
    let (u, v) = frame(normal);
    let mut keyed: Vec<((i64, i64), u32)> = inliers
        .iter()
        .map(|&i| {
            let p = pts[i as usize];
            (
                (
                    (p.dot(u) / eps).floor() as i64,
                    (p.dot(v) / eps).floor() as i64,
                ),
                i,
            )
        })
        .collect();
    keyed.sort_unstable();
    // Cells as runs of the sorted list.
    let mut cells: Vec<((i64, i64), usize, usize)> = Vec::new();
    let mut s = 0;
    for k in 1..=keyed.len() {
        if k == keyed.len() || keyed[k].0 != keyed[s].0 {
            cells.push((keyed[s].0, s, k));
            s = k;
        }
    }
    let lookup: HashMap<(i64, i64), usize> =
        cells.iter().enumerate().map(|(c, x)| (x.0, c)).collect();
    let mut comp = vec![usize::MAX; cells.len()];
    let mut out = Vec::new();
    let mut stack = Vec::new();
    for c0 in 0..cells.len() {
        if comp[c0] != usize::MAX {
            continue;
        }
        let id = out.len();
        comp[c0] = id;
        stack.push(c0);
        let mut members = Vec::new();
        while let Some(c) = stack.pop() {
            members.extend(keyed[cells[c].1..cells[c].2].iter().map(|x| x.1));
            let (ci, cj) = cells[c].0;
            for di in -1..=1 {
                for dj in -1..=1 {
                    if let Some(&nc) = lookup.get(&(ci.saturating_add(di), cj.saturating_add(dj)))
                        && comp[nc] == usize::MAX
                    {
                        comp[nc] = id;
                        stack.push(nc);
                    }
                }
            }
        }
        members.sort_unstable();
        out.push(members);
    }
    out
}
