//! The paper's 3-D evaluation (Section VI, Figs. 14-20): a furnished living room in which a
//! person walks and a door opens over time steps, traced at every step by the image method
//! (geometric optics, the reference), IPC (Gauss-Seidel and Jacobi, f64), SBR (1° grid over
//! the sphere) and the accelerator's bit-exact fixed-point IPC model, with the accelerator's
//! cycle count per step from a per-step PE schedule.
//!
//! - [`run()`] here: the study, one [`Row`] per step and solver, one [`FpgaStep`] per step,
//!   and the ray directions of Fig. 18 for two steps;
//! - [`report`]: `results.csv`, `fpga.csv`, `summary.md`;
//! - [`plot`]: Figs. 17-19 on any plotters backend; [`crate::io::write_living_room`] writes
//!   them as SVG and PNG.
//!
//! Units: metres, seconds; angles in degrees where the name says `_deg`; cycles of the
//! accelerator's clock, [`bt_hls::CLOCK_HZ`]. `docs/study-living-room.md` has the measured numbers.

pub mod plot;
pub mod report;

use crate::run::{
    Comparison, Directions, PathMap, exact_directions, max_order_problem, run_solver,
};
use crate::{StudyConfig, StudyError, StudySolver};
use bt_accel as fpga;
use bt_beams::Direction;
use bt_geom::{Real, Vec3};
use bt_hls::{CLOCK_HZ, PlanOptions, ScheduleKind};
use bt_scene::dynamic::DynamicScene;
use bt_scene::{Endpoints, Scene};
use bt_schedule::GaParams;
use bt_solve::{SbrOptions, Validity, validate::validate};
use serde::Serialize;
use std::time::Instant;

/// The solvers of the living-room study, in output order.
pub const SOLVERS: [StudySolver; 5] = [
    StudySolver::Image,
    StudySolver::IpcGaussSeidel,
    StudySolver::IpcJacobi,
    StudySolver::Sbr,
    StudySolver::IpcFixedPoint,
];

/// Settings of the living-room study.
#[derive(Debug, Clone, Serialize)]
pub struct LivingRoomConfig {
    /// Where the scene came from (`builtin:living-room-dynamic`, a file name), echoed.
    pub scene: String,
    /// Highest reflection order (the paper: 3), at least 1.
    pub max_order: usize,
    /// SBR grid step over the whole sphere, degrees (the paper: 1, 64 800 rays).
    pub sbr_step_deg: Real,
    /// Fixed-point IPC convergence threshold on a round's L∞ displacement, 1/256 mm.
    pub threshold_lsb: u32,
    /// Fixed-point IPC round cap.
    pub max_rounds: u32,
    /// PE scheduler of each step.
    pub schedule: ScheduleKind,
    /// GA seed (echoed into every output).
    pub seed: u64,
    /// GA chromosomes per generation.
    pub ga_population: u32,
    /// GA generations after the initial population.
    pub ga_generations: u32,
    /// Total PE instances per step; `None`: the planes used plus 25 %.
    pub pe_budget: Option<u32>,
    /// Start each step from the points the previous step converged to ([`fpga::warm_start`]).
    pub warm_start: bool,
    /// Update order of the accelerator's rounds.
    pub round_order: bt_hls::RoundOrder,
}

impl Default for LivingRoomConfig {
    /// The paper's setting: third order, 1° SBR sphere, the `hls gen --steps` defaults
    /// (beam-tree candidates, threshold 16/256 mm, 256 rounds, the list scheduler per step,
    /// warm start, red-black rounds); with `schedule: Ga` a small GA (population 4, 2 generations, seed 1).
    fn default() -> Self {
        Self {
            scene: "builtin:living-room-dynamic".into(),
            max_order: 3,
            sbr_step_deg: 1.0,
            threshold_lsb: 16,
            max_rounds: 256,
            schedule: ScheduleKind::List,
            seed: 1,
            ga_population: 4,
            ga_generations: 2,
            pe_budget: None,
            warm_start: true,
            round_order: bt_hls::RoundOrder::RedBlack,
        }
    }
}

impl LivingRoomConfig {
    /// The SBR options: a full-sphere grid.
    pub fn sbr_options(&self) -> SbrOptions {
        SbrOptions::grid(self.sbr_step_deg)
    }

    /// The scheduler options of every step.
    pub fn plan_options(&self) -> PlanOptions {
        PlanOptions {
            schedule: self.schedule,
            pe_budget: self.pe_budget,
            ga: GaParams {
                seed: self.seed,
                population: self.ga_population,
                generations: self.ga_generations,
                elite: GaParams::default().elite.min(self.ga_population),
                ..GaParams::default()
            },
            generic_pes: None,
        }
    }

    /// How every step is planned: beam-tree candidates (as `hls gen`), the threshold, round
    /// cap, scheduler and warm start of the settings.
    pub fn step_options(&self) -> fpga::StepOptions {
        fpga::StepOptions {
            trace: bt_solve::pipeline::TraceOptions::new(self.max_order),
            threshold_lsb: self.threshold_lsb,
            max_rounds: self.max_rounds,
            plan: self.plan_options(),
            warm_start: self.warm_start,
            round_order: self.round_order,
        }
    }

    /// Every problem with the settings, lowercase.
    pub fn problems(&self) -> Vec<String> {
        let mut p = Vec::new();
        if self.max_order == 0 {
            p.push("max order must be at least 1 (the accelerator traces reflections)".into());
        }
        p.extend(max_order_problem(self.max_order));
        if self.ga_population == 0 {
            p.push("ga population must be at least 1".into());
        }
        if self.max_rounds == 0 {
            p.push("max rounds must be at least 1".into());
        }
        if let Some(m) = self.sbr_options().problem() {
            p.push(m);
        }
        p
    }

    /// The 2-D study's settings that make its solver runner do this study's job.
    fn solver_config(&self) -> StudyConfig {
        StudyConfig {
            rooms: 1,
            steps: 1,
            seed: self.seed,
            max_order: self.max_order,
            sbr_step_deg: self.sbr_step_deg,
            sbr_sphere: true,
            ..StudyConfig::default()
        }
    }
}

/// One time step and solver.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Row {
    /// Time step, from 0.
    pub step: usize,
    /// The solver's paths compared with the image method's (columns `solver` ... `time_s`).
    #[serde(flatten)]
    pub comparison: Comparison,
}

/// The accelerator at one time step: its input, the fixed-point outcomes and the schedule.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FpgaStep {
    /// Time step, from 0.
    pub step: usize,
    /// Candidate paths of order ≥ 1 computed by the accelerator (beam tree, static planes).
    pub paths: usize,
    /// Candidates through a moving surface, solved by the host (image method).
    pub host_paths: usize,
    /// Paths started from the points they converged to at the previous step.
    pub warm_started: usize,
    /// Points of the accelerator's paths.
    pub points: u64,
    /// Paths converged in the fixed-point model.
    pub converged: usize,
    /// Paths that hit the round cap.
    pub not_converged: usize,
    /// Paths frozen as degenerate (overflow or zero distance sum).
    pub degenerate: usize,
    /// Paths frozen by early stopping (a point left its polygon's box).
    pub left_bounds: usize,
    /// Converged, valid paths the host rejected for breaking the reflection law
    /// ([`fpga::REFLECTION_TOLERANCE_DEG`]): false convergences of the fixed-point model.
    pub reflection_rejected: usize,
    /// Exact paths (image method, every sequence) neither the accelerator nor the host found.
    pub missed: usize,
    /// Accepted accelerator results that are no exact path.
    pub spurious: usize,
    /// PE instances the step's schedule uses.
    pub instances: u32,
    /// Duplicated PEs.
    pub duplicates: u32,
    /// The PE budget applied.
    pub pe_budget: u32,
    /// Schedule makespan, slots.
    pub makespan: u32,
    /// Makespan of the list schedule (one PE per plane), slots.
    pub list_makespan: u32,
    /// Latency factor (eq. 14, summed over paths and rounds), slots.
    pub latency_factor: u64,
    /// Busy PE cells / all cells.
    pub utilisation: Real,
    /// PE instances of the one platform every step runs on.
    pub platform_instances: u32,
    /// Mean cycles of a schedule slot (`2·(jobs + 2) + pe_latency`; idle PEs cost nothing).
    pub mean_cycles_per_slot: Real,
    /// Predicted `CYCLES` of the run on that platform (exact; co-simulation checks it).
    pub cycles: u64,
    /// Per-step latency, `cycles / CLOCK_HZ`, seconds.
    pub latency_s: Real,
    /// Host work of the step (candidates, accelerator input, schedule), seconds.
    pub host_time_s: Real,
}

/// A ray direction at both ends, degrees: azimuth from +x towards +y in (-180, 180],
/// elevation from the horizontal in [-90, 90].
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct RayAngles {
    /// Departure azimuth at TX.
    pub tx_azimuth_deg: Real,
    /// Departure elevation at TX.
    pub tx_elevation_deg: Real,
    /// Arrival azimuth at RX (the direction the path arrives from, seen at RX).
    pub rx_azimuth_deg: Real,
    /// Arrival elevation at RX.
    pub rx_elevation_deg: Real,
}

/// Fig. 18's data for one step: every path's directions by solver.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StepRays {
    /// Time step, from 0.
    pub step: usize,
    /// Geometric optics (the image method).
    pub exact: Vec<RayAngles>,
    /// The fixed-point IPC model (the accelerator).
    pub fixed_point: Vec<RayAngles>,
    /// SBR.
    pub sbr: Vec<RayAngles>,
}

/// Everything the study produced.
#[derive(Debug, Clone, Serialize)]
pub struct LivingRoomResults {
    /// The settings.
    pub config: LivingRoomConfig,
    /// Scene name.
    pub scene_name: String,
    /// Time steps.
    pub steps: usize,
    /// Reflectors (the accelerator's planes) at step 0.
    pub reflectors: usize,
    /// One row per step and solver, in that order ([`SOLVERS`]).
    pub rows: Vec<Row>,
    /// One entry per step.
    pub fpga: Vec<FpgaStep>,
    /// Ray directions at the [`drawn_steps`].
    pub rays: Vec<StepRays>,
}

/// The steps drawn in Fig. 18: the first and the fifth (the paper's time steps 1 and 5),
/// or the last when there are fewer than five.
pub fn drawn_steps(steps: usize) -> Vec<usize> {
    match steps {
        0 => Vec::new(),
        1 => vec![0],
        n => vec![0, (n - 1).min(4)],
    }
}

/// The departure's and arrival's azimuth and elevation, as every report gives them
/// ([`bt_beams::Direction::of`]).
fn angles(d: &Directions) -> RayAngles {
    let (tx, rx) = (Direction::of(d.departure), Direction::of(d.arrival));
    RayAngles {
        tx_azimuth_deg: tx.azimuth,
        tx_elevation_deg: tx.elevation,
        rx_azimuth_deg: rx.azimuth,
        rx_elevation_deg: rx.elevation,
    }
}

/// What the accelerator produced at one step.
struct FixedStep {
    paths: PathMap,
    time_s: Real,
    fpga: FpgaStep,
    planned: fpga::PlannedStep,
}

/// The accelerator at one step ([`fpga::plan_step`]: beam-tree candidates over the platform's
/// planes, warm start from the previous step, the bit-exact model, the PE schedule): the
/// results the host accepts ([`fpga::host_accepts`]), the candidates through a moving surface
/// solved by the host (image method, validated), line of sight from the host. The platform's
/// PE count is filled in once all steps are known.
fn fixed_point_step(
    scene: &Scene,
    planes: &[bt_scene::SurfaceId],
    step: usize,
    config: &LivingRoomConfig,
    previous: Option<&fpga::PlannedStep>,
) -> Result<FixedStep, StudyError> {
    let planned =
        fpga::plan_step(scene, planes, step, &config.step_options(), previous).map_err(|e| {
            StudyError::Step {
                step,
                message: e.to_string(),
            }
        })?;
    let start = Instant::now();
    let ends = scene
        .terminals()
        .map_err(|e| crate::run::scene_error(scene, e))?;
    let Endpoints { tx, rx } = ends;
    let mut paths = PathMap::new();
    if validate(scene, &[], tx, rx, &[]) == Validity::Valid {
        paths.insert(Vec::new(), exact_directions(ends, &[]));
    }
    let mut reflection_rejected = 0;
    let s = &planned.step;
    for (seq, r) in s.sequences.iter().zip(&planned.results) {
        match fpga::host_accepts(scene, ends, seq, r) {
            Ok(points) => {
                paths.insert(seq.clone(), exact_directions(ends, &points));
            }
            Err(fpga::HostRejection::ReflectionLaw) => reflection_rejected += 1,
            Err(_) => {}
        }
    }
    for seq in &s.host_sequences {
        let mut points = vec![Vec3::ZERO; seq.len()];
        if bt_solve::image::solve(scene, seq, tx, rx, &mut points).is_ok()
            && validate(scene, seq, tx, rx, &points) == Validity::Valid
        {
            paths.insert(seq.clone(), exact_directions(ends, &points));
        }
    }
    let time_s = planned.host_time_s + planned.budget_model_time_s + start.elapsed().as_secs_f64();
    let results = &planned.results;
    let converged = results.iter().filter(|r| r.converged).count();
    let degenerate = results.iter().filter(|r| r.overflow || r.zero_sum).count();
    let left_bounds = results.iter().filter(|r| r.left_bounds).count();
    let plan = &planned.plan;
    let fpga = FpgaStep {
        step,
        paths: s.input.paths.len(),
        host_paths: s.host_sequences.len(),
        warm_started: planned.warm_started,
        points: plan.points,
        converged,
        not_converged: results.len() - converged - degenerate - left_bounds,
        degenerate,
        left_bounds,
        reflection_rejected,
        missed: planned.fixed.missed,
        spurious: planned.fixed.spurious,
        instances: plan.stats.instances,
        duplicates: plan.stats.duplicates,
        pe_budget: plan.pe_budget,
        makespan: plan.stats.makespan,
        list_makespan: plan.list_makespan,
        latency_factor: plan.stats.latency_factor,
        utilisation: plan.stats.utilisation,
        platform_instances: 0,
        mean_cycles_per_slot: plan.mean_cycles_per_slot,
        cycles: plan.predicted_cycles,
        latency_s: plan.predicted_cycles as Real / CLOCK_HZ,
        host_time_s: planned.host_time_s,
    };
    Ok(FixedStep {
        paths,
        time_s,
        fpga,
        planned,
    })
}

/// The PE count of the one platform all steps run on ([`bt_hls::Platform::fitting`]). Each
/// step's cycles are predicted on the PEs its own schedule uses; a step that used fewer than
/// the platform (not so in the living room, whose steps share their PEs) would need
/// `PlannedStep::predict_on`, as `beamtrace hls gen` does.
fn fill_platform_instances(
    fpga: &mut [FpgaStep],
    work: &[bt_hls::StepWork],
) -> Result<(), StudyError> {
    let platform = bt_hls::Platform::fitting(work).map_err(|e| StudyError::Step {
        step: 0,
        message: e.to_string(),
    })?;
    let k = platform.instances.len() as u32;
    for f in fpga {
        f.platform_instances = k;
    }
    Ok(())
}

/// Run the study over every step of `scene`. `progress(done, total)` is called after every
/// step. Steps and solvers run one after the other, every solver single-threaded, so the times
/// compare fairly (only the scheduler, which is not timed as a solver, uses every core). All
/// results but the times are deterministic.
pub fn run(
    scene: &DynamicScene,
    config: &LivingRoomConfig,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<LivingRoomResults, StudyError> {
    StudyError::check_settings(config.problems())?;
    let solver_config = config.solver_config();
    let steps = scene.len();
    let drawn = drawn_steps(steps);
    let mut rows = Vec::with_capacity(steps * SOLVERS.len());
    let mut fpga = Vec::with_capacity(steps);
    let mut rays = Vec::new();
    // The platform's planes: the reflectors that no step moves (a PE for each that a step
    // meets, `bt_hls::Platform::fitting`).
    let planes = fpga::static_reflectors(scene.scenes());
    let mut work = Vec::with_capacity(steps);
    let mut previous = None;
    for (step, s) in scene.scenes().iter().enumerate() {
        let (reference, time_s) = run_solver(s, StudySolver::Image, &solver_config)?;
        let row = |solver, found: &PathMap, time_s| Row {
            step,
            comparison: Comparison::new(solver, &reference, found, time_s),
        };
        rows.push(row(StudySolver::Image, &reference, time_s));
        let mut sbr_paths = PathMap::new();
        for solver in [
            StudySolver::IpcGaussSeidel,
            StudySolver::IpcJacobi,
            StudySolver::Sbr,
        ] {
            let (found, time_s) = run_solver(s, solver, &solver_config)?;
            rows.push(row(solver, &found, time_s));
            if solver == StudySolver::Sbr {
                sbr_paths = found;
            }
        }
        let fixed = fixed_point_step(s, &planes, step, config, previous.as_ref())?;
        rows.push(row(StudySolver::IpcFixedPoint, &fixed.paths, fixed.time_s));
        fpga.push(fixed.fpga);
        work.push(fixed.planned.work());
        previous = Some(fixed.planned);
        if drawn.contains(&step) {
            rays.push(StepRays {
                step,
                exact: reference.values().map(angles).collect(),
                fixed_point: fixed.paths.values().map(angles).collect(),
                sbr: sbr_paths.values().map(angles).collect(),
            });
        }
        progress(step + 1, steps);
    }
    fill_platform_instances(&mut fpga, &work)?;
    let step0 = scene.step(0);
    Ok(LivingRoomResults {
        config: config.clone(),
        scene_name: step0.name().to_string(),
        steps,
        reflectors: step0.reflectors().count(),
        rows,
        fpga,
        rays,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use bt_import::builtin_dynamic_scene;
    use bt_scene::Terminals;

    #[test]
    fn drawn_steps_are_the_papers_first_and_fifth() {
        assert_eq!(drawn_steps(10), vec![0, 4]);
        assert_eq!(drawn_steps(2), vec![0, 1]);
        assert_eq!(drawn_steps(1), vec![0]);
    }

    #[test]
    fn azimuth_and_elevation_follow_the_conventions() {
        let d = Directions {
            departure: Vec3::new(0.0, 1.0, 0.0),
            arrival: Vec3::new(-1.0, 0.0, 1.0).normalize(),
        };
        let a = angles(&d);
        assert!((a.tx_azimuth_deg - 90.0).abs() < 1e-12);
        assert!(a.tx_elevation_deg.abs() < 1e-12);
        assert!((a.rx_azimuth_deg - 180.0).abs() < 1e-12);
        assert!((a.rx_elevation_deg - 45.0).abs() < 1e-12);
    }

    #[test]
    fn first_order_study_of_the_living_room_matches_the_reference() {
        let scene = builtin_dynamic_scene("living-room-dynamic", Terminals::default())
            .expect("built in")
            .expect("valid");
        let config = LivingRoomConfig {
            max_order: 1,
            sbr_step_deg: 5.0,
            schedule: ScheduleKind::List,
            ..LivingRoomConfig::default()
        };
        let results = run(&scene, &config, &mut |_, _| {}).expect("study runs");
        assert_eq!(results.rows.len(), scene.len() * SOLVERS.len());
        assert_eq!(results.fpga.len(), scene.len());
        for r in results.rows.iter().map(|r| &r.comparison) {
            let limit = match r.solver {
                StudySolver::Image => 0.0,
                StudySolver::IpcGaussSeidel | StudySolver::IpcJacobi => 1e-6,
                StudySolver::IpcFixedPoint => 0.1,
                StudySolver::Sbr => 90.0,
            };
            assert!(r.errors.max_err_tx_deg <= limit, "{r:?}");
            assert!(r.errors.max_err_rx_deg <= limit, "{r:?}");
        }
        for f in &results.fpga {
            assert!(f.cycles > f.points && f.makespan > 0, "{f:?}");
        }
    }
}
