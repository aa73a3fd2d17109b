//! Running the study: every room and time step traced by every solver, matched against the
//! image method by surface sequence.

use crate::room::{self, Room, Shape};
use crate::{StudyError, embed};
use bt_geom::{Real, Vec2, Vec3};
use bt_paths::CandidateSet;
use bt_scene::{Endpoints, Scene, SurfaceId};
use bt_solve::{IpcOptions, SbrOptions, Solver, UpdateOrder, sbr, trace};
use serde::Serialize;
use std::collections::BTreeMap;
use std::fmt::Write;
use std::time::Instant;

/// Settings of a study.
#[derive(Debug, Clone, Serialize)]
pub struct StudyConfig {
    /// Number of rooms (shapes cycle L, T, U, convex).
    pub rooms: usize,
    /// Time steps per room (at least 1).
    pub steps: usize,
    /// Seed of the room generator (echoed into every output).
    pub seed: u64,
    /// Highest reflection order (the paper: 3).
    pub max_order: usize,
    /// SBR grid step, degrees (the paper: 1).
    pub sbr_step_deg: Real,
    /// Launch SBR rays over the whole sphere instead of the horizontal plane only.
    pub sbr_sphere: bool,
    /// Budget on beam-tree nodes per scene (`--max-candidates`): a room whose tree would
    /// exceed it stops the study with that error.
    #[serde(skip)]
    pub max_candidates: u64,
    /// Budget on rooms × steps (`--max-room-steps`, [`MAX_ROOM_STEPS`]), checked before any
    /// room is generated.
    #[serde(skip)]
    pub max_room_steps: u64,
}

/// Budget on a 2-D study's room-steps (rooms × steps): each holds a room's contour and four
/// result rows and takes tens of milliseconds, so the default of 100,000 (100 times the
/// paper's study) stays near 100 MB; `--rooms 1e18` is refused before anything is allocated.
pub const MAX_ROOM_STEPS: bt_geom::Budget =
    bt_geom::Budget::new("room-steps", "--max-room-steps", 100_000);

impl Default for StudyConfig {
    /// The paper's study: 100 rooms, 10 steps, third order, 1° SBR in the plane.
    fn default() -> Self {
        Self {
            rooms: 100,
            steps: 10,
            seed: 1,
            max_order: 3,
            sbr_step_deg: 1.0,
            sbr_sphere: false,
            max_candidates: bt_solve::pipeline::DEFAULT_MAX_CANDIDATES,
            max_room_steps: MAX_ROOM_STEPS.limit,
        }
    }
}

impl StudyConfig {
    /// The SBR options of this study.
    pub fn sbr_options(&self) -> SbrOptions {
        let grid = SbrOptions::grid(self.sbr_step_deg);
        if self.sbr_sphere { grid } else { grid.planar() }
    }

    /// Every problem with the settings, lowercase.
    pub fn problems(&self) -> Vec<String> {
        let mut p = Vec::new();
        if self.rooms == 0 {
            p.push("rooms must be at least 1".to_string());
        }
        if self.steps == 0 {
            p.push("steps must be at least 1".to_string());
        }
        p.extend(max_order_problem(self.max_order));
        if let Some(m) = self.sbr_options().problem() {
            p.push(m);
        }
        let room_steps = (self.rooms as u64).saturating_mul(self.steps as u64);
        if let Err(e) = MAX_ROOM_STEPS
            .with_limit(self.max_room_steps)
            .check(room_steps)
        {
            p.push(e.to_string());
        }
        p
    }
}

/// Highest reflection order either study accepts: the candidate count grows exponentially
/// with the order.
pub const MAX_STUDY_ORDER: usize = 6;

/// The problem with a study's highest reflection order, if it exceeds [`MAX_STUDY_ORDER`].
pub(crate) fn max_order_problem(max_order: usize) -> Option<String> {
    (max_order > MAX_STUDY_ORDER).then(|| {
        format!("max order {max_order} is too high for a study (at most {MAX_STUDY_ORDER})")
    })
}

/// The solvers compared.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
pub enum StudySolver {
    /// The image method: the reference.
    Image,
    /// IPC, Gauss-Seidel rounds, default options for the scene.
    IpcGaussSeidel,
    /// IPC, Jacobi rounds, default options for the scene.
    IpcJacobi,
    /// Shooting and bouncing rays.
    Sbr,
    /// The accelerator: the bit-exact fixed-point IPC model of `bt-fixed` (Jacobi rounds,
    /// millimetre words), line of sight checked on the host (living-room study only).
    IpcFixedPoint,
}

impl StudySolver {
    /// The solvers of the 2-D study, in output order.
    pub const ALL: [StudySolver; 4] = [
        StudySolver::Image,
        StudySolver::IpcGaussSeidel,
        StudySolver::IpcJacobi,
        StudySolver::Sbr,
    ];

    /// Name in outputs.
    pub fn name(self) -> &'static str {
        match self {
            StudySolver::Image => "image",
            StudySolver::IpcGaussSeidel => "ipc-gauss-seidel",
            StudySolver::IpcJacobi => "ipc-jacobi",
            StudySolver::Sbr => "sbr",
            StudySolver::IpcFixedPoint => "ipc-fixed-point",
        }
    }

    /// The candidate solver of an exact host solver (image method, IPC Gauss-Seidel or Jacobi)
    /// with IPC's defaults scaled to `scene`; `None` for SBR (it traces the whole scene) and
    /// the fixed-point model (the accelerator's, per step).
    pub fn exact_solver(self, scene: &Scene) -> Option<Solver> {
        let ipc = |order| Solver::Ipc(IpcOptions::for_scene(scene, order));
        match self {
            StudySolver::Image => Some(Solver::Image),
            StudySolver::IpcGaussSeidel => Some(ipc(UpdateOrder::GaussSeidel)),
            StudySolver::IpcJacobi => Some(ipc(UpdateOrder::Jacobi)),
            StudySolver::Sbr | StudySolver::IpcFixedPoint => None,
        }
    }
}

/// One room, time step and solver.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Row {
    /// Room index.
    pub room: usize,
    /// Room shape.
    pub shape: Shape,
    /// Number of walls.
    pub edges: usize,
    /// Time step, from 0.
    pub step: usize,
    /// The solver's paths compared with the image method's (columns `solver` ... `time_s`).
    #[serde(flatten)]
    pub comparison: Comparison,
}

/// Column names of [`Comparison::write_csv`], in its order: a literal, so that each study's
/// `CSV_HEADER` can `concat!` its own columns around it.
macro_rules! comparison_csv_columns {
    () => {
        "solver,paths,matched,missed,spurious,\
mean_err_tx_deg,max_err_tx_deg,mean_err_rx_deg,max_err_rx_deg,time_s"
    };
}
pub(crate) use comparison_csv_columns;

/// One solver's paths in one scene compared with the image method's (the reference) by
/// surface sequence: the block both studies' rows share.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Comparison {
    /// Solver.
    pub solver: StudySolver,
    /// Paths the solver found.
    pub paths: usize,
    /// Of those, paths whose surface sequence the image method also found.
    pub matched: usize,
    /// Image-method paths the solver did not find.
    pub missed: usize,
    /// Solver paths the image method does not have.
    pub spurious: usize,
    /// Angular errors of the matched paths (columns `mean_err_tx_deg` ... `max_err_rx_deg`).
    #[serde(flatten)]
    pub errors: AngularErrors,
    /// Single-threaded wall-clock time from scene to paths, seconds (candidate enumeration
    /// included for the image method and IPC; for the fixed-point model: building its input
    /// and running it in software).
    pub time_s: Real,
}

impl Comparison {
    /// `found` (by `solver`, in `time_s` seconds) against `reference`: matched, missed and
    /// spurious paths, and the mean and largest departure and arrival errors over the matched
    /// ones (zeros when nothing matched).
    pub(crate) fn new(
        solver: StudySolver,
        reference: &PathMap,
        found: &PathMap,
        time_s: Real,
    ) -> Self {
        let mut tx = Vec::new();
        let mut rx = Vec::new();
        for (seq, d) in found {
            if let Some(e) = reference.get(seq) {
                tx.push(angle_deg(d.departure, e.departure));
                rx.push(angle_deg(d.arrival, e.arrival));
            }
        }
        let mean = |v: &[Real]| {
            if v.is_empty() {
                0.0
            } else {
                v.iter().sum::<Real>() / v.len() as Real
            }
        };
        let max = |v: &[Real]| v.iter().copied().fold(0.0, Real::max);
        Self {
            solver,
            paths: found.len(),
            matched: tx.len(),
            missed: reference.keys().filter(|k| !found.contains_key(*k)).count(),
            spurious: found.len() - tx.len(),
            errors: AngularErrors {
                mean_err_tx_deg: mean(&tx),
                max_err_tx_deg: max(&tx),
                mean_err_rx_deg: mean(&rx),
                max_err_rx_deg: max(&rx),
            },
            time_s,
        }
    }

    /// No paths, no errors, no time: a row a study lacks.
    pub(crate) fn empty(solver: StudySolver) -> Self {
        Self {
            solver,
            paths: 0,
            matched: 0,
            missed: 0,
            spurious: 0,
            errors: AngularErrors::default(),
            time_s: 0.0,
        }
    }

    /// The columns of `comparison_csv_columns!`, comma-separated, no line end; floats in
    /// Rust's shortest round-trip scientific notation (`1.5e-13`).
    pub fn write_csv(&self, out: &mut String) {
        let e = &self.errors;
        let _ = write!(
            out,
            "{},{},{},{},{},{:e},{:e},{:e},{:e},{:e}",
            self.solver.name(),
            self.paths,
            self.matched,
            self.missed,
            self.spurious,
            e.mean_err_tx_deg,
            e.max_err_tx_deg,
            e.mean_err_rx_deg,
            e.max_err_rx_deg,
            self.time_s
        );
    }
}

/// Angular errors of a solver's matched paths against the exact directions, degrees: the mean
/// and the largest angle between departure directions at TX and between arrival directions at
/// RX (zeros when nothing matched). Of one row, or (in [`crate::report::Totals`]) the mean of
/// the rows' means and the largest of their maxima.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct AngularErrors {
    /// Mean departure error, degrees.
    pub mean_err_tx_deg: Real,
    /// Largest departure error, degrees.
    pub max_err_tx_deg: Real,
    /// Mean arrival error, degrees.
    pub mean_err_rx_deg: Real,
    /// Largest arrival error, degrees.
    pub max_err_rx_deg: Real,
}

impl AngularErrors {
    /// The four errors as cells of a Markdown table row, `mean TX | max TX | mean RX | max RX`,
    /// three significant digits in scientific notation.
    pub(crate) fn table_cells(&self) -> String {
        format!(
            "{:.3e} | {:.3e} | {:.3e} | {:.3e}",
            self.mean_err_tx_deg, self.max_err_tx_deg, self.mean_err_rx_deg, self.max_err_rx_deg
        )
    }
}

/// A room drawn in Fig. 5: its contour, terminals and image-method paths at a few steps.
#[derive(Debug, Clone, Serialize)]
pub struct RoomDrawing {
    /// The room.
    pub room: Room,
    /// Drawn time steps.
    pub steps: Vec<usize>,
    /// Per drawn step, every exact path as a polyline TX → points → RX in the plan, metres,
    /// with its order.
    pub paths: Vec<Vec<(usize, Vec<Vec2>)>>,
}

/// Everything a study produced.
#[derive(Debug, Clone, Serialize)]
pub struct StudyResults {
    /// The settings.
    pub config: StudyConfig,
    /// One row per room, step and solver, in that order.
    pub rows: Vec<Row>,
    /// The rooms drawn in Fig. 5 (the first room of each shape).
    pub drawings: Vec<RoomDrawing>,
}

/// A path reduced to what the comparison needs: unit departure and arrival directions.
pub(crate) struct Directions {
    /// Unit direction the path leaves TX in.
    pub(crate) departure: Vec3,
    /// Unit direction, seen from RX, the path arrives from.
    pub(crate) arrival: Vec3,
}

/// Departure and arrival directions of a path through `points` between the scene's TX and RX
/// (`ends`, local frame).
pub(crate) fn exact_directions(ends: Endpoints, points: &[Vec3]) -> Directions {
    let Endpoints { tx, rx } = ends;
    let first = points.first().copied().unwrap_or(rx);
    let last = points.last().copied().unwrap_or(tx);
    Directions {
        departure: (first - tx).normalize(),
        arrival: (last - rx).normalize(),
    }
}

/// Angle between two vectors, degrees; `atan2(|a × b|, a · b)` keeps tiny angles accurate
/// (`acos` of a dot product cannot resolve angles below ~1e-8 rad).
pub fn angle_deg(a: Vec3, b: Vec3) -> Real {
    a.cross(b).length().atan2(a.dot(b)).to_degrees()
}

pub(crate) type PathMap = BTreeMap<Vec<SurfaceId>, Directions>;

/// Trace one scene with one solver (image, IPC or SBR), timed; paths keyed by surface
/// sequence. The fixed-point model is not a host solver (it runs per step in the living-room
/// study, with its own quantisation): asking for it here is an error, not a silent fallback.
pub(crate) fn run_solver(
    scene: &Scene,
    solver: StudySolver,
    config: &StudyConfig,
) -> Result<(PathMap, Real), StudyError> {
    let ends = scene.terminals().map_err(|e| scene_error(scene, e))?;
    let start = Instant::now();
    let s = match solver {
        StudySolver::Image | StudySolver::IpcGaussSeidel | StudySolver::IpcJacobi => {
            solver.exact_solver(scene).expect("an exact host solver")
        }
        StudySolver::Sbr => {
            let result = sbr::trace_detailed(scene, &config.sbr_options(), config.max_order, false)
                .map_err(|e| scene_error(scene, e))?;
            let elapsed = start.elapsed().as_secs_f64();
            let map = result
                .paths
                .into_iter()
                .map(|p| {
                    let d = Directions {
                        departure: p.departure,
                        arrival: p.arrival,
                    };
                    (p.surfaces, d)
                })
                .collect();
            return Ok((map, elapsed));
        }
        StudySolver::IpcFixedPoint => {
            return Err(StudyError::Config(
                "the fixed-point solver runs only in the living-room study".into(),
            ));
        }
    };
    let candidates = study_candidates(scene, config)?;
    let result = trace(scene, &candidates, &s, false).map_err(|e| scene_error(scene, e))?;
    let elapsed = start.elapsed().as_secs_f64();
    let map = result
        .paths
        .into_iter()
        .map(|p| {
            let d = exact_directions(ends, &p.points);
            (p.surfaces.to_vec(), d)
        })
        .collect();
    Ok((map, elapsed))
}

/// The time steps drawn in Fig. 5: all when there are at most four, else four spread evenly.
pub fn drawn_steps(steps: usize) -> Vec<usize> {
    if steps <= 4 {
        (0..steps).collect()
    } else {
        (0..4).map(|k| k * (steps - 1) / 3).collect()
    }
}

/// Run the study. `progress(done, total)` is called after every room and time step.
/// Rooms and steps run one after the other and every solver single-threaded, so the times
/// compare fairly; all results but the times are deterministic for a seed.
pub fn run(
    config: &StudyConfig,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<StudyResults, StudyError> {
    StudyError::check_settings(config.problems())?;
    let total = config.rooms * config.steps;
    let mut rows = Vec::with_capacity(total * StudySolver::ALL.len());
    let mut drawings = Vec::new();
    for index in 0..config.rooms {
        let room = room::generate(config.seed, index, config.steps)?;
        let draw = index < Shape::ALL.len();
        let mut drawing = RoomDrawing {
            room: room.clone(),
            steps: drawn_steps(config.steps),
            paths: Vec::new(),
        };
        for (step, contour) in room.contours.iter().enumerate() {
            let name = format!("room-{index}-step-{step}");
            let scene = embed::scene(&name, contour, room.tx, room.rx)?;
            let mut reference = PathMap::new();
            for solver in StudySolver::ALL {
                let (found, time_s) = run_solver(&scene, solver, config)?;
                if solver == StudySolver::Image {
                    reference = found;
                    rows.push(row(&room, step, solver, &reference, &reference, time_s));
                } else {
                    rows.push(row(&room, step, solver, &reference, &found, time_s));
                }
            }
            if draw && drawing.steps.contains(&step) {
                drawing.paths.push(exact_polylines(&scene, config)?);
            }
            progress(index * config.steps + step + 1, total);
        }
        if draw {
            drawings.push(drawing);
        }
    }
    Ok(StudyResults {
        config: config.clone(),
        rows,
        drawings,
    })
}

fn row(
    room: &Room,
    step: usize,
    solver: StudySolver,
    reference: &PathMap,
    found: &PathMap,
    time_s: Real,
) -> Row {
    Row {
        room: room.index,
        shape: room.shape,
        edges: room.edges,
        step,
        comparison: Comparison::new(solver, reference, found, time_s),
    }
}

/// The study's candidates: the beam tree (the generator every consumer uses), within the
/// study's node budget.
fn study_candidates(scene: &Scene, config: &StudyConfig) -> Result<CandidateSet, StudyError> {
    let options = bt_solve::pipeline::TraceOptions {
        parallel: false,
        max_candidates: config.max_candidates,
        ..bt_solve::pipeline::TraceOptions::new(config.max_order)
    };
    bt_solve::pipeline::candidates(scene, &options).map_err(|e| scene_error(scene, e))
}

/// A study scene's error (a generator bug: every study scene has its terminals).
pub(crate) fn scene_error(scene: &Scene, e: impl std::fmt::Display) -> StudyError {
    StudyError::Scene {
        name: scene.name().to_string(),
        message: e.to_string(),
    }
}

fn exact_polylines(
    scene: &Scene,
    config: &StudyConfig,
) -> Result<Vec<(usize, Vec<Vec2>)>, StudyError> {
    let candidates = study_candidates(scene, config)?;
    let ends = scene.terminals().map_err(|e| scene_error(scene, e))?;
    Ok(trace(scene, &candidates, &Solver::Image, false)
        .map_err(|e| scene_error(scene, e))?
        .paths
        .iter()
        .map(|p| {
            let mut line = vec![ends.tx.truncate()];
            line.extend(p.points.iter().map(|q| q.truncate()));
            line.push(ends.rx.truncate());
            (p.surfaces.len(), line)
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_fixed_point_solver_is_refused_not_replaced_by_the_image_method() {
        let square = [(1.0, 1.0), (9.0, 1.0), (9.0, 9.0), (1.0, 9.0)].map(|(x, y)| Vec2::new(x, y));
        let scene = embed::scene("square", &square, Vec2::new(3.0, 3.0), Vec2::new(7.0, 6.0))
            .expect("valid square room");
        let config = StudyConfig::default();
        let Err(err) = run_solver(&scene, StudySolver::IpcFixedPoint, &config) else {
            panic!("the fixed-point solver must be refused");
        };
        assert!(err.to_string().contains("fixed-point"), "{err}");
        let Ok((image, _)) = run_solver(&scene, StudySolver::Image, &config) else {
            panic!("the image method must run");
        };
        assert!(!image.is_empty());
    }
}
