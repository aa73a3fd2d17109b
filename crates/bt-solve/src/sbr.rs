//! Shooting and bouncing rays (SBR): the baseline the paper compares IPC against.
//!
//! Rays leave TX on a fixed angular pattern ([`SbrLaunch`]); each one travels to the nearest
//! surface it hits, reflects specularly off reflectors (both sides), stops at blockers, and is
//! followed up to the maximum order. After every segment the ray is tested against a
//! *capture sphere* around RX whose radius grows with the unfolded length travelled,
//! `r = c · α · L` (α the angular ray spacing in radians, L the unfolded length at the
//! closest approach to RX, c the covering factor of the launch pattern, see
//! [`SbrOptions::capture_factor`]). Rays caught through the same surface sequence are one path;
//! of them the ray passing closest to RX is kept and its actual hit points are reported.
//!
//! SBR paths are therefore *not* the exact geometric-optics paths: the departure direction is
//! a launch direction of the pattern, the points are where that ray really hit, and the last
//! segment passes near RX, not through it. Paths can be missed (no ray close enough) or
//! spurious (a capture sphere reaching across a shadow boundary). Both are what the 2-D study
//! (`bt-study`) measures against the image method. The raw SBR result is not passed through
//! [`crate::validate`]: validating it would hide exactly those artefacts.
//!
//! The hot loop (one ray) allocates nothing: each rayon chunk owns its scratch buffers and its
//! table of best rays per surface sequence, which only grows when a new sequence appears.
//! Chunks are merged in ray order, so the result does not depend on the thread count.

use crate::{FoundPath, Inline, OutcomeCounts, TraceResult};
use bt_geom::{Real, Vec3};
use bt_scene::{Endpoints, Scene, SceneError, SurfaceId, SurfaceKind};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Rays per rayon task: large enough to amortise the per-chunk tables.
const CHUNK: usize = 2048;

/// The angular pattern of the rays launched at TX.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "pattern", rename_all = "kebab-case")]
pub enum SbrLaunch {
    /// An azimuth × elevation grid with step `step_deg` degrees: `round(360 / step)` azimuths
    /// from 0° (the step is adjusted to divide 360° exactly) times `round(180 / step)`
    /// elevations at the cell centres `-90° + (j + ½) step`, so no ray is duplicated at the
    /// poles. The paper's 1° sweep is 360 × 180 = 64 800 rays.
    Grid {
        /// Angular step, degrees, in `(0, 90]`.
        step_deg: Real,
    },
    /// `rays` directions on a Fibonacci (golden-angle) sphere: near-uniform, near-hexagonal.
    Fibonacci {
        /// Number of rays, at least 1.
        rays: u32,
    },
}

/// SBR settings.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SbrOptions {
    /// Launch pattern.
    pub launch: SbrLaunch,
    /// 2-D mode: launch only in the horizontal plane through TX (elevation 0°). The grid then
    /// has `round(360 / step)` rays and the Fibonacci pattern `rays` equally spaced azimuths.
    /// Exact for 2-D rooms embedded as vertical walls with TX and RX at the same height (every
    /// path stays in that plane).
    pub planar: bool,
}

impl Default for SbrOptions {
    /// The paper's sweep: a 1° grid over the whole sphere.
    fn default() -> Self {
        Self::grid(1.0)
    }
}

/// The coarsest grid step, degrees (two elevations, four azimuths).
pub const MAX_STEP_DEG: Real = 90.0;

/// Default budget on launched rays (`--max-rays`): about 160 MB of ray state; the paper's
/// 1-degree grid launches 64,800.
pub const DEFAULT_MAX_RAYS: u64 = 10_000_000;

impl SbrOptions {
    /// A full-sphere grid with step `step_deg` degrees.
    pub fn grid(step_deg: Real) -> Self {
        Self {
            launch: SbrLaunch::Grid { step_deg },
            planar: false,
        }
    }

    /// A full-sphere Fibonacci pattern of `rays` rays.
    pub fn fibonacci(rays: u32) -> Self {
        Self {
            launch: SbrLaunch::Fibonacci { rays },
            planar: false,
        }
    }

    /// The same pattern restricted to the horizontal plane (2-D mode).
    pub fn planar(self) -> Self {
        Self {
            planar: true,
            ..self
        }
    }

    /// The options a user chose (CLI flags, Python keywords): `rays` on a Fibonacci sphere if
    /// given, else a grid of `step_deg` (default 1°), optionally `planar`; checked with
    /// [`SbrOptions::problem`]. Giving both a ray count and a step is refused.
    pub fn chosen(rays: Option<u32>, step_deg: Option<Real>, planar: bool) -> Result<Self, String> {
        let options = match (rays, step_deg) {
            (Some(_), Some(_)) => {
                return Err("give an sbr step or an sbr ray count, not both".into());
            }
            (Some(rays), None) => Self::fibonacci(rays),
            (None, step) => Self::grid(step.unwrap_or(1.0)),
        };
        let options = Self { planar, ..options };
        match options.problem() {
            Some(problem) => Err(problem),
            None => Ok(options),
        }
    }

    /// What is wrong with the options, if anything (a lowercase message naming the field).
    /// Invalid options launch no rays; they never panic.
    pub fn problem(&self) -> Option<String> {
        match self.launch {
            SbrLaunch::Grid { step_deg } if !(step_deg.is_finite() && step_deg > 0.0) => Some(
                format!("sbr step must be a positive number of degrees, got {step_deg}"),
            ),
            SbrLaunch::Grid { step_deg } if step_deg > MAX_STEP_DEG => Some(format!(
                "sbr step must be at most {MAX_STEP_DEG} degrees, got {step_deg}"
            )),
            SbrLaunch::Fibonacci { rays: 0 } => Some("sbr ray count must be at least 1".into()),
            _ => None,
        }
    }

    fn grid_counts(step_deg: Real) -> (usize, usize) {
        if !(step_deg.is_finite() && step_deg > 0.0 && step_deg <= MAX_STEP_DEG) {
            return (0, 0);
        }
        let azimuths = (360.0 / step_deg).round().max(1.0) as usize;
        let elevations = (180.0 / step_deg).round().max(1.0) as usize;
        (azimuths, elevations)
    }

    /// Number of rays launched (saturating; check [`SbrOptions::over_budget`] first).
    pub fn ray_count(&self) -> usize {
        match (self.launch, self.planar) {
            (SbrLaunch::Grid { step_deg }, planar) => {
                let (az, el) = Self::grid_counts(step_deg);
                if planar { az } else { az.saturating_mul(el) }
            }
            (SbrLaunch::Fibonacci { rays }, _) => rays as usize,
        }
    }

    /// Number of rays the pattern asks for, computed without overflow (a step of 1e-20 degrees
    /// asks for about 6.5e44 rays, which no integer count holds).
    pub fn ray_estimate(&self) -> f64 {
        match (self.launch, self.planar) {
            (SbrLaunch::Grid { step_deg }, planar) => {
                let az = (360.0 / step_deg).round().max(1.0);
                let el = (180.0 / step_deg).round().max(1.0);
                if planar { az } else { az * el }
            }
            (SbrLaunch::Fibonacci { rays }, _) => f64::from(rays),
        }
    }

    /// A message when the pattern launches more than `max_rays` rays (`--max-rays`), naming the
    /// estimate; `None` within the budget.
    pub fn over_budget(&self, max_rays: u64) -> Option<String> {
        let estimate = self.ray_estimate();
        (estimate.is_nan() || estimate > max_rays as f64).then(|| {
            format!(
                "sbr ray budget exceeded: {estimate:.3e} rays (budget {max_rays}); use a coarser \
                 --sbr-step-deg or fewer --sbr-rays, or raise the budget with --max-rays"
            )
        })
    }

    /// Unit direction of ray `index` (`index < ray_count()`), world frame.
    pub fn direction(&self, index: usize) -> Vec3 {
        use std::f64::consts::{PI, TAU};
        match (self.launch, self.planar) {
            (SbrLaunch::Grid { step_deg }, planar) => {
                let (az, el) = Self::grid_counts(step_deg);
                if planar {
                    let phi = TAU * index as Real / az as Real;
                    return Vec3::new(phi.cos(), phi.sin(), 0.0);
                }
                let (i, j) = (index % az, index / az);
                let phi = TAU * i as Real / az as Real;
                let theta = -0.5 * PI + PI * (j as Real + 0.5) / el as Real;
                Vec3::new(
                    theta.cos() * phi.cos(),
                    theta.cos() * phi.sin(),
                    theta.sin(),
                )
            }
            (SbrLaunch::Fibonacci { rays }, true) => {
                let phi = TAU * index as Real / rays as Real;
                Vec3::new(phi.cos(), phi.sin(), 0.0)
            }
            (SbrLaunch::Fibonacci { rays }, false) => {
                // Golden-angle spiral, z at the centres of `rays` equal-area bands.
                let golden = PI * (3.0 - 5.0_f64.sqrt());
                let z = 1.0 - (2.0 * index as Real + 1.0) / rays as Real;
                let rho = (1.0 - z * z).max(0.0).sqrt();
                let phi = golden * index as Real;
                Vec3::new(rho * phi.cos(), rho * phi.sin(), z)
            }
        }
    }

    /// Angular spacing α of neighbouring rays, radians: the grid step (in-plane step in 2-D
    /// mode), or for the Fibonacci sphere the side of the equilateral triangle of a hexagonal
    /// lattice with the same ray density, `sqrt(8π / (√3 N))`.
    pub fn spacing(&self) -> Real {
        use std::f64::consts::{PI, TAU};
        match (self.launch, self.planar) {
            (SbrLaunch::Grid { step_deg }, _) => {
                let (az, _) = Self::grid_counts(step_deg);
                // The adjusted step (it divides 360° exactly).
                if az == 0 { 0.0 } else { TAU / az as Real }
            }
            (SbrLaunch::Fibonacci { rays }, true) => TAU / (rays.max(1)) as Real,
            (SbrLaunch::Fibonacci { rays }, false) => {
                (8.0 * PI / (3.0_f64.sqrt() * rays.max(1) as Real)).sqrt()
            }
        }
    }

    /// Capture radius per metre of unfolded length: `r = capture_factor() × L`.
    ///
    /// The sphere must be as large as the *covering radius* of the launch pattern (the largest
    /// angle between any direction and its nearest ray), or paths whose true departure
    /// direction falls between rays are missed:
    /// - Fibonacci sphere (near-hexagonal cells of side α): α/√3, the classic rule of Seidel
    ///   and Rappaport for triangular (geodesic) ray tubes;
    /// - azimuth × elevation grid: the cells are α × α cos(elevation) rectangles, largest at the
    ///   horizon, whose covering radius is α/√2 (α/√3 there would miss ~5 % of the paths);
    /// - 2-D mode: rays α apart on a circle, covering radius α/2.
    ///
    /// A larger sphere does not lose paths but catches more rays per path (merged, the closest
    /// kept) and more spurious ones near shadow boundaries.
    pub fn capture_factor(&self) -> Real {
        let alpha = self.spacing();
        match (self.launch, self.planar) {
            (_, true) => alpha / 2.0,
            (SbrLaunch::Grid { .. }, false) => alpha / 2.0_f64.sqrt(),
            (SbrLaunch::Fibonacci { .. }, false) => alpha / 3.0_f64.sqrt(),
        }
    }
}

/// One path found by SBR, with what only SBR knows about it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SbrPath {
    /// Reflecting surfaces, TX side first (empty: line of sight).
    pub surfaces: Vec<SurfaceId>,
    /// Where the kept ray actually hit them, TX side first, metres.
    pub points: Vec<Vec3>,
    /// Launch direction of the kept ray (unit, world frame).
    pub departure: Vec3,
    /// Direction the kept ray arrives from, seen at RX: minus its last segment's direction
    /// (unit, world frame). Mirror reflections preserve angles between rays, so its angle to
    /// the exact arrival direction equals the departure's angle to the exact departure.
    pub arrival: Vec3,
    /// Distance of the kept ray's closest approach to RX, metres.
    pub miss_distance: Real,
    /// Unfolded length of the kept ray up to that closest approach, metres.
    pub length: Real,
    /// Index of the kept ray in the launch pattern.
    pub ray: u32,
    /// How many rays were caught through this surface sequence.
    pub rays_caught: u32,
}

impl SbrPath {
    /// The path as the other solvers report it (hit points; no IPC fields).
    pub fn to_found(&self) -> FoundPath {
        FoundPath {
            surfaces: Inline::from_slice(&self.surfaces),
            diffractions: Inline::new(),
            crossings: Inline::new(),
            points: Inline::from_slice(&self.points),
            iterations: None,
            residual: None,
        }
    }
}

/// Result of an SBR run.
#[derive(Debug, Clone, Default, Serialize)]
pub struct SbrResult {
    /// Paths by (order, surface ids).
    pub paths: Vec<SbrPath>,
    /// Rays launched.
    pub rays: u64,
    /// Rays caught by the capture sphere, summed over segments.
    pub receptions: u64,
}

/// Run SBR up to `max_order` reflections in parallel and return the paths as [`FoundPath`]s
/// (`counts.valid` = number of paths; SBR has no per-candidate outcomes). A scene without
/// both terminals fails ([`SceneError::MissingTerminal`]).
pub fn trace(
    scene: &Scene,
    options: &SbrOptions,
    max_order: usize,
) -> Result<TraceResult, SceneError> {
    Ok(to_trace_result(&trace_detailed(
        scene, options, max_order, true,
    )?))
}

/// The [`TraceResult`] view of an [`SbrResult`].
pub fn to_trace_result(result: &SbrResult) -> TraceResult {
    TraceResult {
        paths: result.paths.iter().map(SbrPath::to_found).collect(),
        counts: OutcomeCounts {
            valid: result.paths.len() as u64,
            ..OutcomeCounts::default()
        },
    }
}

/// Run SBR up to `max_order` reflections, with the SBR-specific details of every path.
/// `parallel` spreads rays over rayon's pool; the result is identical either way. A scene
/// without both terminals fails ([`SceneError::MissingTerminal`]).
pub fn trace_detailed(
    scene: &Scene,
    options: &SbrOptions,
    max_order: usize,
    parallel: bool,
) -> Result<SbrResult, SceneError> {
    let tracer = Tracer::new((scene, scene.terminals()?), options, max_order, None);
    let total = options.ray_count();
    let chunks = total.div_ceil(CHUNK);
    let run = |c: usize| tracer.run(c * CHUNK..((c + 1) * CHUNK).min(total));
    let parts: Vec<Table> = if parallel && chunks > 1 {
        (0..chunks).into_par_iter().map(run).collect()
    } else {
        (0..chunks).map(run).collect()
    };
    let mut merged = Table::default();
    for part in parts {
        merged.merge(part);
    }
    let mut paths = merged.paths;
    paths.sort_by(|a, b| (a.surfaces.len(), &a.surfaces).cmp(&(b.surfaces.len(), &b.surfaces)));
    Ok(SbrResult {
        paths,
        rays: total as u64,
        receptions: merged.receptions,
    })
}

/// SBR for one surface sequence: shoot the whole pattern but follow a ray only while it hits
/// the surfaces of `seq` in order; the closest ray caught after the whole sequence wins.
/// Returns it, or `None` when no ray reached RX that way. Rays leave `ends.tx` and are caught
/// around `ends.rx` (the scene's, [`Scene::terminals`]).
pub fn solve_sequence(
    scene: &Scene,
    ends: Endpoints,
    seq: &[SurfaceId],
    options: &SbrOptions,
) -> Option<SbrPath> {
    let tracer = Tracer::new((scene, ends), options, seq.len(), Some(seq));
    tracer.run(0..options.ray_count()).paths.into_iter().next()
}

struct Tracer<'a> {
    scene: &'a Scene,
    options: &'a SbrOptions,
    max_order: usize,
    target: Option<&'a [SurfaceId]>,
    tx: Vec3,
    rx: Vec3,
    capture: Real,
    tol: Real,
    reach: Real,
}

/// Best ray per surface sequence within a range of rays.
#[derive(Default)]
struct Table {
    paths: Vec<SbrPath>,
    receptions: u64,
}

impl Table {
    /// Record a caught ray; within one table rays arrive in index order, and only a strictly
    /// closer ray replaces the kept one (so the lowest index wins ties).
    fn offer(&mut self, seq: &[SurfaceId], points: &[Vec3], catch: Catch) {
        self.receptions += 1;
        match self.paths.iter_mut().find(|p| p.surfaces == seq) {
            Some(p) => {
                p.rays_caught += 1;
                if catch.miss < p.miss_distance {
                    p.points.copy_from_slice(points);
                    p.departure = catch.departure;
                    p.arrival = catch.arrival;
                    p.miss_distance = catch.miss;
                    p.length = catch.length;
                    p.ray = catch.ray;
                }
            }
            None => self.paths.push(SbrPath {
                surfaces: seq.to_vec(),
                points: points.to_vec(),
                departure: catch.departure,
                arrival: catch.arrival,
                miss_distance: catch.miss,
                length: catch.length,
                ray: catch.ray,
                rays_caught: 1,
            }),
        }
    }

    /// Merge a table of later rays into this one (same tie rule as [`Table::offer`]).
    fn merge(&mut self, later: Table) {
        self.receptions += later.receptions;
        for q in later.paths {
            match self.paths.iter_mut().find(|p| p.surfaces == q.surfaces) {
                Some(p) => {
                    let caught = p.rays_caught + q.rays_caught;
                    if q.miss_distance < p.miss_distance {
                        *p = q;
                    }
                    p.rays_caught = caught;
                }
                None => self.paths.push(q),
            }
        }
    }
}

#[derive(Clone, Copy)]
struct Catch {
    miss: Real,
    length: Real,
    departure: Vec3,
    arrival: Vec3,
    ray: u32,
}

impl<'a> Tracer<'a> {
    fn new(
        (scene, ends): (&'a Scene, Endpoints),
        options: &'a SbrOptions,
        max_order: usize,
        target: Option<&'a [SurfaceId]>,
    ) -> Self {
        Self {
            scene,
            options,
            max_order,
            target,
            tx: ends.tx,
            rx: ends.rx,
            capture: options.capture_factor(),
            tol: scene.length_tolerance(),
            // Every hit lies in the scene's bounding box, which contains the ray's origin.
            reach: 2.0 * scene.extent() + 1.0,
        }
    }

    fn run(&self, rays: std::ops::Range<usize>) -> Table {
        let mut table = Table::default();
        let mut seq: Vec<SurfaceId> = Vec::with_capacity(self.max_order);
        let mut points: Vec<Vec3> = Vec::with_capacity(self.max_order);
        for ray in rays {
            self.shoot(ray, &mut seq, &mut points, &mut table);
        }
        table
    }

    /// Follow one ray; `seq` and `points` are scratch buffers.
    fn shoot(
        &self,
        ray: usize,
        seq: &mut Vec<SurfaceId>,
        points: &mut Vec<Vec3>,
        table: &mut Table,
    ) {
        seq.clear();
        points.clear();
        let departure = self.options.direction(ray);
        let (mut origin, mut dir) = (self.tx, departure);
        let mut travelled = 0.0;
        let mut on: Option<SurfaceId> = None;
        for order in 0..=self.max_order {
            let hit = self.closest_hit(origin, dir, on);
            let end = hit.map_or(self.reach, |(t, _)| t);
            let wanted = self.target.is_none_or(|t| t.len() == order);
            if wanted {
                // Closest approach to RX within this segment (RX behind the origin or beyond
                // the hit does not count).
                let along = (self.rx - origin).dot(dir);
                if along > 0.0 && along < end {
                    let miss = (origin + along * dir).distance(self.rx);
                    let length = travelled + along;
                    if miss <= self.capture * length {
                        let catch = Catch {
                            miss,
                            length,
                            departure,
                            arrival: -dir,
                            ray: ray as u32,
                        };
                        table.offer(seq, points, catch);
                    }
                }
            }
            let Some((t, id)) = hit else { break };
            if order == self.max_order {
                break;
            }
            let surface = self.scene.surface(id);
            if surface.kind == SurfaceKind::Blocker {
                break;
            }
            if self.target.is_some_and(|t| t.get(order) != Some(&id)) {
                break;
            }
            let p = origin + t * dir;
            let n = surface.polygon.plane().normal;
            dir = (dir - 2.0 * dir.dot(n) * n).normalize();
            seq.push(id);
            points.push(p);
            travelled += t;
            origin = p;
            on = Some(id);
        }
    }

    /// Nearest surface hit by the ray `origin + t dir`, `t` in `(tol, reach)`, other than the
    /// surface the ray leaves from; `(t, id)` with `t` in metres (`dir` is a unit vector).
    fn closest_hit(
        &self,
        origin: Vec3,
        dir: Vec3,
        leaving: Option<SurfaceId>,
    ) -> Option<(Real, SurfaceId)> {
        let far = origin + self.reach * dir;
        let mut best_t = self.reach;
        let mut best = None;
        // Boxes grown by twice the tolerance: `contains` accepts hits that far outside.
        self.scene.bvh().any_hit(origin, far, 2.0 * self.tol, |i| {
            let id = SurfaceId(i);
            if Some(id) == leaving {
                return false;
            }
            let polygon = &self.scene.surface(id).polygon;
            let plane = polygon.plane();
            let approach = plane.normal.dot(dir);
            // A ray parallel to a plane grazes it: no reflection, no occlusion.
            if approach.abs() <= Real::EPSILON {
                return false;
            }
            let t = -plane.signed_distance(origin) / approach;
            if t > self.tol && t < best_t && polygon.contains(origin + t * dir, self.tol) {
                best_t = t;
                best = Some(id);
            }
            false
        });
        best.map(|id| (best_t, id))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Solver, image};
    use bt_paths::{AllVisible, enumerate};
    use std::collections::BTreeSet;

    fn box_room() -> Scene {
        bt_testkit::box_room([4.0, 3.0, 2.5], [1.1, 0.9, 1.2], [3.2, 2.1, 1.6])
    }

    fn angle_deg(a: Vec3, b: Vec3) -> Real {
        a.cross(b).length().atan2(a.dot(b)).to_degrees()
    }

    fn image_paths(scene: &Scene, max_order: usize) -> Vec<FoundPath> {
        let candidates = enumerate(scene, max_order, &AllVisible).unwrap();
        crate::trace(scene, &candidates, &Solver::Image, false)
            .unwrap()
            .paths
    }

    /// Mean departure-angle error of SBR against the image method over matched paths, and the
    /// sequences only one of them found.
    fn compare(scene: &Scene, options: &SbrOptions, max_order: usize) -> (Real, usize, usize) {
        let exact = image_paths(scene, max_order);
        let sbr = trace_detailed(scene, options, max_order, true).unwrap();
        let exact_seqs: BTreeSet<_> = exact.iter().map(|p| p.surfaces.to_vec()).collect();
        let sbr_seqs: BTreeSet<_> = sbr.paths.iter().map(|p| p.surfaces.clone()).collect();
        let mut sum = 0.0;
        let mut matched = 0;
        for p in &sbr.paths {
            if let Some(e) = exact.iter().find(|e| e.surfaces[..] == p.surfaces[..]) {
                let first = e.points.first().copied().unwrap_or(scene.rx().unwrap());
                sum += angle_deg(p.departure, first - scene.tx().unwrap());
                let last = e.points.last().copied().unwrap_or(scene.tx().unwrap());
                let rx_err = angle_deg(p.arrival, last - scene.rx().unwrap());
                assert!(
                    (rx_err - angle_deg(p.departure, first - scene.tx().unwrap())).abs() < 1e-6
                );
                matched += 1;
            }
        }
        (
            sum / matched.max(1) as Real,
            exact_seqs.difference(&sbr_seqs).count(),
            sbr_seqs.difference(&exact_seqs).count(),
        )
    }

    #[test]
    fn fine_sweep_finds_the_image_method_sequences_in_a_box() {
        let scene = box_room();
        let (err, missed, spurious) = compare(&scene, &SbrOptions::grid(0.25), 2);
        assert_eq!((missed, spurious), (0, 0));
        assert!(err < 0.25, "mean error {err}°");
        // LOS, six first-order paths, and of the 30 second-order sequences the 6 between
        // parallel faces plus one order of each of the 12 perpendicular pairs.
        assert_eq!(image_paths(&scene, 2).len(), 1 + 6 + 6 + 12);
    }

    #[test]
    fn error_shrinks_with_the_step() {
        let scene = box_room();
        let (coarse, _, _) = compare(&scene, &SbrOptions::grid(2.0), 2);
        let (fine, _, _) = compare(&scene, &SbrOptions::grid(0.5), 2);
        assert!(fine < coarse / 2.0, "0.5°: {fine}°, 2°: {coarse}°");
        assert!(coarse < 2.0 && coarse > 0.0);
    }

    #[test]
    fn fibonacci_sphere_finds_first_order_paths() {
        let scene = box_room();
        let (err, missed, _) = compare(&scene, &SbrOptions::fibonacci(200_000), 1);
        assert_eq!(missed, 0);
        assert!(err < 0.5, "mean error {err}°");
    }

    #[test]
    fn serial_and_parallel_agree() {
        let scene = box_room();
        let options = SbrOptions::grid(2.0);
        let a = trace_detailed(&scene, &options, 3, false).unwrap();
        let b = trace_detailed(&scene, &options, 3, true).unwrap();
        assert_eq!(a.paths, b.paths);
        assert_eq!(a.receptions, b.receptions);
        assert_eq!(a.rays, 180 * 90);
    }

    #[test]
    fn planar_mode_launches_in_the_plane() {
        let options = SbrOptions::grid(1.0).planar();
        assert_eq!(options.ray_count(), 360);
        assert!((0..360).all(|i| options.direction(i).z == 0.0));
        assert!((options.capture_factor() - 0.5_f64.to_radians()).abs() < 1e-15);
        let grid = SbrOptions::grid(1.0);
        assert_eq!(grid.ray_count(), 64_800);
        let d = grid.direction(64_799);
        assert!((d.length() - 1.0).abs() < 1e-12 && d.z > 0.9999);
    }

    #[test]
    fn invalid_options_launch_nothing() {
        for bad in [
            SbrOptions::grid(0.0),
            SbrOptions::grid(Real::NAN),
            SbrOptions::grid(120.0),
            SbrOptions::fibonacci(0),
        ] {
            assert!(bad.problem().is_some());
            assert_eq!(bad.ray_count(), 0);
            assert!(trace(&box_room(), &bad, 2).unwrap().paths.is_empty());
        }
    }

    #[test]
    fn per_sequence_sbr_matches_the_image_method_approximately() {
        let scene = box_room();
        let floor = scene.find("room.bottom").unwrap();
        let west = scene.find("room.west").unwrap();
        // Of the two orders of a perpendicular pair exactly one is a real path.
        let exact_paths = image_paths(&scene, 2);
        let seq = [[floor, west], [west, floor]]
            .into_iter()
            .find(|s| exact_paths.iter().any(|p| p.surfaces[..] == s[..]))
            .unwrap();
        let other = [seq[1], seq[0]];
        assert!(
            solve_sequence(
                &scene,
                scene.terminals().unwrap(),
                &other,
                &SbrOptions::grid(0.5)
            )
            .is_none()
        );
        let found = solve_sequence(
            &scene,
            scene.terminals().unwrap(),
            &seq,
            &SbrOptions::grid(0.5),
        )
        .expect("reached");
        let mut exact = [Vec3::ZERO; 2];
        image::solve(
            &scene,
            &seq,
            scene.tx().unwrap(),
            scene.rx().unwrap(),
            &mut exact,
        )
        .unwrap();
        assert!(found.points[0].distance(exact[0]) < 0.1);
        assert!(angle_deg(found.departure, exact[0] - scene.tx().unwrap()) < 0.5);
    }
}
