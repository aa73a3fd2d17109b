//! The study's text outputs (CSV rows and the Markdown summary) and the aggregates the plots
//! draw. Pure functions of the results: writing files is [`crate::io`]'s job.

use crate::room::Shape;
use crate::run::{AngularErrors, Comparison, Row, StudyResults, StudySolver};
use bt_geom::Real;
use std::collections::BTreeMap;
use std::fmt::Write;

/// Column names of `results.csv`.
pub const CSV_HEADER: &str = concat!(
    "seed,room,shape,edges,step,",
    crate::run::comparison_csv_columns!()
);

/// `results.csv`: a header and one line per row; floats in Rust's shortest round-trip
/// scientific notation (`1.5e-13`).
pub fn csv(results: &StudyResults) -> String {
    csv_table(CSV_HEADER, &results.rows, |out, r| {
        let _ = write!(
            out,
            "{},{},{},{},{},",
            results.config.seed,
            r.room,
            r.shape.name(),
            r.edges,
            r.step
        );
        r.comparison.write_csv(out);
    })
}

/// A CSV text: `header`, then one line per row as `line` writes it (without the newline).
pub(crate) fn csv_table<T>(
    header: &str,
    rows: &[T],
    mut line: impl FnMut(&mut String, &T),
) -> String {
    let mut out = String::with_capacity((header.len() + 1) * (rows.len() + 1));
    out.push_str(header);
    out.push('\n');
    for row in rows {
        line(&mut out, row);
        out.push('\n');
    }
    out
}

/// What an aggregate averages.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Quantity {
    /// Mean departure error of the rows with matched paths, degrees.
    ErrorTx,
    /// Mean arrival error of the rows with matched paths, degrees.
    ErrorRx,
    /// Time, seconds.
    Time,
}

impl Quantity {
    fn of(self, r: &Comparison) -> Option<Real> {
        match self {
            Quantity::ErrorTx if r.matched > 0 => Some(r.errors.mean_err_tx_deg),
            Quantity::ErrorRx if r.matched > 0 => Some(r.errors.mean_err_rx_deg),
            Quantity::Time => Some(r.time_s),
            _ => None,
        }
    }
}

/// What an aggregate groups by.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GroupBy {
    /// Time step (Figs. 6a, 7a).
    Step,
    /// Number of edges (Figs. 6b, 7b).
    Edges,
}

/// Per solver, the mean of `quantity` over the rows of each group, by group key (ascending).
pub fn mean_by(
    rows: &[Row],
    group: GroupBy,
    quantity: Quantity,
) -> BTreeMap<StudySolver, Vec<(usize, Real)>> {
    let mut sums: BTreeMap<(StudySolver, usize), (Real, usize)> = BTreeMap::new();
    for r in rows {
        let key = match group {
            GroupBy::Step => r.step,
            GroupBy::Edges => r.edges,
        };
        if let Some(v) = quantity.of(&r.comparison) {
            let e = sums.entry((r.comparison.solver, key)).or_insert((0.0, 0));
            e.0 += v;
            e.1 += 1;
        }
    }
    let mut out: BTreeMap<StudySolver, Vec<(usize, Real)>> = BTreeMap::new();
    for ((solver, key), (sum, n)) in sums {
        out.entry(solver).or_default().push((key, sum / n as Real));
    }
    out
}

/// Totals of one solver over a set of rows.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Totals {
    /// Rows.
    pub rows: usize,
    /// Paths found.
    pub paths: usize,
    /// Image-method paths missed.
    pub missed: usize,
    /// Spurious paths.
    pub spurious: usize,
    /// Mean of the rows' mean errors (rows with matches) and the largest errors, degrees.
    pub errors: AngularErrors,
    /// Total time, seconds.
    pub time_s: Real,
    /// Median time per row, seconds.
    pub median_time_s: Real,
}

/// Totals per solver over `rows` selected by `keep`.
pub fn totals(rows: &[Row], keep: impl Fn(&Row) -> bool) -> BTreeMap<StudySolver, Totals> {
    let mut groups: BTreeMap<StudySolver, Vec<&Comparison>> = BTreeMap::new();
    for r in rows.iter().filter(|r| keep(r)) {
        let c = &r.comparison;
        groups.entry(c.solver).or_default().push(c);
    }
    groups
        .into_iter()
        .map(|(solver, rs)| {
            let with_matches: Vec<&&Comparison> = rs.iter().filter(|r| r.matched > 0).collect();
            let mean = |f: fn(&Comparison) -> Real| {
                if with_matches.is_empty() {
                    0.0
                } else {
                    with_matches.iter().map(|r| f(r)).sum::<Real>() / with_matches.len() as Real
                }
            };
            let mut times: Vec<Real> = rs.iter().map(|r| r.time_s).collect();
            times.sort_by(Real::total_cmp);
            let t = Totals {
                rows: rs.len(),
                paths: rs.iter().map(|r| r.paths).sum(),
                missed: rs.iter().map(|r| r.missed).sum(),
                spurious: rs.iter().map(|r| r.spurious).sum(),
                errors: AngularErrors {
                    mean_err_tx_deg: mean(|r| r.errors.mean_err_tx_deg),
                    max_err_tx_deg: rs
                        .iter()
                        .map(|r| r.errors.max_err_tx_deg)
                        .fold(0.0, Real::max),
                    mean_err_rx_deg: mean(|r| r.errors.mean_err_rx_deg),
                    max_err_rx_deg: rs
                        .iter()
                        .map(|r| r.errors.max_err_rx_deg)
                        .fold(0.0, Real::max),
                },
                time_s: times.iter().sum(),
                median_time_s: times.get(times.len() / 2).copied().unwrap_or(0.0),
            };
            (solver, t)
        })
        .collect()
}

/// The entries of `solvers` in a per-solver map, in that order; the default (zeros) for a
/// solver the map lacks.
pub(crate) fn pick<T: Copy + Default, const N: usize>(
    by_solver: &BTreeMap<StudySolver, T>,
    solvers: [StudySolver; N],
) -> [T; N] {
    solvers.map(|s| by_solver.get(&s).copied().unwrap_or_default())
}

/// Headline ratios of the comparison (the paper's conclusions).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ratios {
    /// Total SBR time / total IPC (Gauss-Seidel) time.
    pub sbr_over_ipc_time: Real,
    /// Total SBR time / total IPC (Jacobi) time.
    pub sbr_over_jacobi_time: Real,
    /// Total IPC (Gauss-Seidel) time / total image-method time.
    pub ipc_over_image_time: Real,
    /// Mean SBR departure error / mean IPC (Gauss-Seidel) departure error.
    pub sbr_over_ipc_error: Real,
    /// Mean SBR departure error, degrees.
    pub sbr_error_deg: Real,
    /// Mean IPC (Gauss-Seidel) departure error, degrees.
    pub ipc_error_deg: Real,
}

/// The headline ratios over all rows.
pub fn ratios(results: &StudyResults) -> Ratios {
    let t = totals(&results.rows, |_| true);
    let [image, gs, jacobi, sbr] = pick(&t, StudySolver::ALL);
    Ratios {
        sbr_over_ipc_time: sbr.time_s / gs.time_s,
        sbr_over_jacobi_time: sbr.time_s / jacobi.time_s,
        ipc_over_image_time: gs.time_s / image.time_s,
        sbr_over_ipc_error: sbr.errors.mean_err_tx_deg / gs.errors.mean_err_tx_deg,
        sbr_error_deg: sbr.errors.mean_err_tx_deg,
        ipc_error_deg: gs.errors.mean_err_tx_deg,
    }
}

/// `summary.md`: settings, per-solver totals, the paper's conclusions as measured ratios, and
/// a breakdown by shape.
pub fn summary(results: &StudyResults) -> String {
    let mut s = String::new();
    summary_settings(&mut s, results);
    summary_per_solver(&mut s, results);
    summary_ratios(&mut s, results);
    summary_by_shape(&mut s, results);
    s
}

/// The title and the settings of the run.
fn summary_settings(s: &mut String, results: &StudyResults) {
    let c = &results.config;
    let sbr = c.sbr_options();
    let _ = writeln!(s, "# 2-D validation study\n");
    let _ = writeln!(
        s,
        "Seed {}, {} rooms (shapes cycle L, T, U, convex), {} time steps, reflections up to order {}.\n\
         SBR: {}° grid {} ({} rays), capture radius {:.4} × unfolded length.\n\
         Every solver runs single-threaded; times are wall-clock from scene to paths (candidate \
         enumeration included for the image method and IPC).\n",
        c.seed,
        c.rooms,
        c.steps,
        c.max_order,
        c.sbr_step_deg,
        if c.sbr_sphere {
            "over the sphere"
        } else {
            "in the horizontal plane"
        },
        sbr.ray_count(),
        sbr.capture_factor(),
    );
}

/// The per-solver totals table.
fn summary_per_solver(s: &mut String, results: &StudyResults) {
    let _ = writeln!(s, "## Per solver\n");
    let _ = writeln!(
        s,
        "| solver | rows | paths | missed | spurious | mean err TX (°) | max err TX (°) | mean err RX (°) | max err RX (°) | total time (s) | median time (ms) |"
    );
    let _ = writeln!(s, "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    for (solver, t) in totals(&results.rows, |_| true) {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} | {:.3} | {:.3} |",
            solver.name(),
            t.rows,
            t.paths,
            t.missed,
            t.spurious,
            t.errors.table_cells(),
            t.time_s,
            t.median_time_s * 1e3
        );
    }
}

/// The paper's conclusions as measured ratios.
fn summary_ratios(s: &mut String, results: &StudyResults) {
    let r = ratios(results);
    let _ = writeln!(s, "\n## The paper's conclusions, measured\n");
    let _ = writeln!(s, "| quantity | measured | paper (Figs. 6-7) |");
    let _ = writeln!(s, "|---|---:|---:|");
    let _ = writeln!(
        s,
        "| SBR time / IPC (Gauss-Seidel) time | {:.3} | ≈ 200 |",
        r.sbr_over_ipc_time
    );
    let _ = writeln!(
        s,
        "| SBR time / IPC (Jacobi) time | {:.3} | — |",
        r.sbr_over_jacobi_time
    );
    let _ = writeln!(
        s,
        "| IPC (Gauss-Seidel) time / image-method time | {:.3} | — |",
        r.ipc_over_image_time
    );
    let _ = writeln!(
        s,
        "| SBR mean angular error at TX (°) | {:.3e} | ≈ 10 (3 to 30) |",
        r.sbr_error_deg
    );
    let _ = writeln!(
        s,
        "| IPC mean angular error at TX (°) | {:.3e} | ≈ 1e-4 (five orders below SBR) |",
        r.ipc_error_deg
    );
    let _ = writeln!(
        s,
        "| SBR error / IPC error | {:.3e} (10^{:.1}) | ≈ 1e5 |",
        r.sbr_over_ipc_error,
        r.sbr_over_ipc_error.log10()
    );
}

/// The per-shape table (image, IPC and SBR side by side).
fn summary_by_shape(s: &mut String, results: &StudyResults) {
    let _ = writeln!(s, "\n## By shape\n");
    let _ = writeln!(
        s,
        "| shape | rows | image paths | SBR missed | SBR spurious | SBR err TX (°) | IPC err TX (°) | image (ms) | IPC GS (ms) | IPC Jacobi (ms) | SBR (ms) |"
    );
    let _ = writeln!(s, "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    for shape in Shape::ALL {
        let t = totals(&results.rows, |r| r.shape == shape);
        let [image, gs, jacobi, sbr] = pick(&t, StudySolver::ALL);
        if image.rows == 0 {
            continue;
        }
        let ms = |t: Totals| 1e3 * t.time_s / t.rows.max(1) as Real;
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {:.3e} | {:.3e} | {:.3} | {:.3} | {:.3} | {:.3} |",
            shape.name(),
            image.rows,
            image.paths,
            sbr.missed,
            sbr.spurious,
            sbr.errors.mean_err_tx_deg,
            gs.errors.mean_err_tx_deg,
            ms(image),
            ms(gs),
            ms(jacobi),
            ms(sbr)
        );
    }
}
