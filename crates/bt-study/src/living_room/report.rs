//! The living-room study's text outputs (`results.csv`, `fpga.csv`, `summary.md`) and the
//! aggregates behind them. Pure functions of the results: writing files is [`crate::io`]'s job.

use super::{LivingRoomResults, Row, SOLVERS};
use crate::StudySolver;
use crate::report::{csv_table, pick};
use crate::run::{AngularErrors, Comparison};
use bt_geom::Real;
use bt_hls::CLOCK_HZ;
use std::collections::BTreeMap;
use std::fmt::Write;

/// Column names of `results.csv`.
pub const CSV_HEADER: &str = concat!(
    "scene,step,",
    crate::run::comparison_csv_columns!(),
    ",fpga_cycles,fpga_latency_s"
);

/// Column names of `fpga.csv`.
pub const FPGA_CSV_HEADER: &str = "scene,step,paths,host_paths,warm_started,points,converged,not_converged,degenerate,\
left_bounds,reflection_rejected,missed,spurious,instances,duplicates,pe_budget,makespan,list_makespan,\
latency_factor,utilisation,platform_instances,mean_cycles_per_slot,cycles,latency_s,host_time_s";

/// `results.csv`: one line per step and solver; floats in Rust's shortest round-trip
/// scientific notation. `fpga_cycles` and `fpga_latency_s` (the accelerator's predicted run,
/// at 50 MHz) are filled on the `ipc-fixed-point` rows only.
pub fn csv(results: &LivingRoomResults) -> String {
    csv_table(CSV_HEADER, &results.rows, |out, r| {
        let fpga = if r.comparison.solver == StudySolver::IpcFixedPoint {
            results
                .fpga
                .iter()
                .find(|f| f.step == r.step)
                .map(|f| format!("{},{:e}", f.cycles, f.latency_s))
                .unwrap_or_else(|| ",".into())
        } else {
            ",".into()
        };
        let _ = write!(out, "{},{},", results.scene_name, r.step);
        r.comparison.write_csv(out);
        let _ = write!(out, ",{fpga}");
    })
}

/// `fpga.csv`: the accelerator of every step (candidate paths, fixed-point outcomes, the PE
/// schedule and its cycles on the one platform); `host_time_s` is the only varying column.
pub fn fpga_csv(results: &LivingRoomResults) -> String {
    csv_table(FPGA_CSV_HEADER, &results.fpga, |out, f| {
        let _ = write!(
            out,
            "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{:e},{},{:e},{},{:e},{:e}",
            results.scene_name,
            f.step,
            f.paths,
            f.host_paths,
            f.warm_started,
            f.points,
            f.converged,
            f.not_converged,
            f.degenerate,
            f.left_bounds,
            f.reflection_rejected,
            f.missed,
            f.spurious,
            f.instances,
            f.duplicates,
            f.pe_budget,
            f.makespan,
            f.list_makespan,
            f.latency_factor,
            f.utilisation,
            f.platform_instances,
            f.mean_cycles_per_slot,
            f.cycles,
            f.latency_s,
            f.host_time_s
        );
    })
}

/// Totals of one solver over all steps.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Totals {
    /// Steps.
    pub steps: usize,
    /// Paths found.
    pub paths: usize,
    /// Image-method paths missed.
    pub missed: usize,
    /// Spurious paths.
    pub spurious: usize,
    /// Angular errors over every matched path of every step (means weighted by matched
    /// paths), degrees.
    pub errors: AngularErrors,
    /// Mean time per step, seconds.
    pub mean_time_s: Real,
}

/// Totals per solver. The mean errors weight each step by its matched paths (a mean over
/// paths, as the paper averages the rays of a step).
pub fn totals(rows: &[Row]) -> BTreeMap<StudySolver, Totals> {
    let mut out: BTreeMap<StudySolver, (Totals, usize)> = BTreeMap::new();
    for r in rows.iter().map(|r| &r.comparison) {
        let (t, matched) = out.entry(r.solver).or_default();
        t.steps += 1;
        t.paths += r.paths;
        t.missed += r.missed;
        t.spurious += r.spurious;
        t.errors.mean_err_tx_deg += r.errors.mean_err_tx_deg * r.matched as Real;
        t.errors.mean_err_rx_deg += r.errors.mean_err_rx_deg * r.matched as Real;
        t.errors.max_err_tx_deg = t.errors.max_err_tx_deg.max(r.errors.max_err_tx_deg);
        t.errors.max_err_rx_deg = t.errors.max_err_rx_deg.max(r.errors.max_err_rx_deg);
        t.mean_time_s += r.time_s;
        *matched += r.matched;
    }
    out.into_iter()
        .map(|(s, (mut t, matched))| {
            let m = matched.max(1) as Real;
            t.errors.mean_err_tx_deg /= m;
            t.errors.mean_err_rx_deg /= m;
            t.mean_time_s /= t.steps.max(1) as Real;
            (s, t)
        })
        .collect()
}

/// Headline numbers of the comparison with the paper.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Headline {
    /// Mean angular error of the fixed-point model (the FPGA), TX and RX, degrees.
    pub fixed_err_deg: [Real; 2],
    /// Largest angular error of the fixed-point model, TX and RX, degrees.
    pub fixed_max_err_deg: [Real; 2],
    /// Mean angular error of SBR, TX and RX, degrees.
    pub sbr_err_deg: [Real; 2],
    /// Mean angular error of IPC (Gauss-Seidel, f64), TX and RX, degrees.
    pub ipc_err_deg: [Real; 2],
    /// SBR error / fixed-point error at TX (the paper: > 100).
    pub sbr_over_fixed_error: Real,
    /// Mean accelerator latency per step at 50 MHz, seconds (the paper: ≈ 1 ms).
    pub fpga_mean_latency_s: Real,
    /// Smallest and largest accelerator latency over the steps, seconds.
    pub fpga_latency_range_s: (Real, Real),
    /// Mean SBR time / mean IPC (Gauss-Seidel) time, both single-threaded CPU.
    pub sbr_over_ipc_time: Real,
    /// Mean SBR time / mean IPC (Jacobi) time.
    pub sbr_over_jacobi_time: Real,
    /// Mean SBR CPU time / mean accelerator latency.
    pub sbr_cpu_over_fpga: Real,
    /// Mean IPC (Gauss-Seidel) CPU time / mean accelerator latency.
    pub ipc_cpu_over_fpga: Real,
}

/// The headline numbers.
pub fn headline(results: &LivingRoomResults) -> Headline {
    let [gs, jacobi, sbr, fixed] = pick(
        &totals(&results.rows),
        [
            StudySolver::IpcGaussSeidel,
            StudySolver::IpcJacobi,
            StudySolver::Sbr,
            StudySolver::IpcFixedPoint,
        ],
    );
    let lat: Vec<Real> = results.fpga.iter().map(|f| f.latency_s).collect();
    let mean_lat = lat.iter().sum::<Real>() / lat.len().max(1) as Real;
    let range = lat
        .iter()
        .fold((Real::INFINITY, 0.0), |(lo, hi): (Real, Real), &x| {
            (lo.min(x), hi.max(x))
        });
    Headline {
        fixed_err_deg: [fixed.errors.mean_err_tx_deg, fixed.errors.mean_err_rx_deg],
        fixed_max_err_deg: [fixed.errors.max_err_tx_deg, fixed.errors.max_err_rx_deg],
        sbr_err_deg: [sbr.errors.mean_err_tx_deg, sbr.errors.mean_err_rx_deg],
        ipc_err_deg: [gs.errors.mean_err_tx_deg, gs.errors.mean_err_rx_deg],
        sbr_over_fixed_error: sbr.errors.mean_err_tx_deg / fixed.errors.mean_err_tx_deg,
        fpga_mean_latency_s: mean_lat,
        fpga_latency_range_s: if lat.is_empty() { (0.0, 0.0) } else { range },
        sbr_over_ipc_time: sbr.mean_time_s / gs.mean_time_s,
        sbr_over_jacobi_time: sbr.mean_time_s / jacobi.mean_time_s,
        sbr_cpu_over_fpga: sbr.mean_time_s / mean_lat,
        ipc_cpu_over_fpga: gs.mean_time_s / mean_lat,
    }
}

/// The comparison of `solver` at `step`, or an empty one.
fn find(results: &LivingRoomResults, step: usize, solver: StudySolver) -> Comparison {
    results
        .rows
        .iter()
        .find(|r| r.step == step && r.comparison.solver == solver)
        .map_or_else(|| Comparison::empty(solver), |r| r.comparison.clone())
}

/// `summary.md`: settings, per-solver totals, a per-step table and the paper's conclusions
/// as measured numbers.
pub fn summary(results: &LivingRoomResults) -> String {
    let mut s = settings(results);
    s.push_str(&per_solver(results));
    s.push_str(&per_step(results));
    s.push_str(&conclusions(results));
    s
}

/// The settings paragraph of `summary.md`.
fn settings(results: &LivingRoomResults) -> String {
    let c = &results.config;
    let sbr = c.sbr_options();
    let mut s = String::new();
    let _ = writeln!(s, "# Living-room study (paper Section VI, Figs. 17-20)\n");
    let _ = writeln!(
        s,
        "Scene `{}` ({}), {} time steps, {} reflectors, reflections up to order {}.\n\
         SBR: {}° azimuth × elevation grid over the sphere ({} rays), capture radius {:.4} × \
         unfolded length.\n\
         Fixed-point IPC: the accelerator's bit-exact model (`bt-fixed`, Jacobi rounds, \
         millimetre words, 1/256 mm inside), threshold {}/256 mm, at most {} rounds, on the \
         beam tree's candidates of order 1-{} over the static reflectors (one platform for \
         all steps; candidates through the moving door go to the host's image method), {}; \
         converged paths are checked by the host (`bt_accel::host_accepts`), which also adds \
         line of sight. Each step's accelerator dispatches its paths' rounds itself (a ready \
         queue, no model run on the host: docs/hardware.md), PE budget {}; latency = the \
         controller's cycles on the platform / {} MHz.\n\
         Every solver runs single-threaded; times are wall clock from the scene to the paths \
         (candidate enumeration included).\n",
        results.scene_name,
        c.scene,
        results.steps,
        results.reflectors,
        c.max_order,
        c.sbr_step_deg,
        sbr.ray_count(),
        sbr.capture_factor(),
        c.threshold_lsb,
        c.max_rounds,
        c.max_order,
        if c.warm_start {
            "each step starting from the points the previous step converged to"
        } else {
            "every step from the beam tree's window centres"
        },
        c.pe_budget
            .map_or_else(|| "planes used + 25 %".to_string(), |b| b.to_string()),
        CLOCK_HZ / 1e6,
    );
    s
}

/// The per-solver totals of `summary.md`.
fn per_solver(results: &LivingRoomResults) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "## Per solver, all steps\n");
    let _ = writeln!(
        s,
        "| solver | paths | missed | spurious | mean err TX (°) | max err TX (°) | mean err RX (°) | max err RX (°) | mean time per step (ms) |"
    );
    let _ = writeln!(s, "|---|---:|---:|---:|---:|---:|---:|---:|---:|");
    let t = totals(&results.rows);
    for solver in SOLVERS {
        let Some(t) = t.get(&solver) else { continue };
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {:.3} |",
            solver.name(),
            t.paths,
            t.missed,
            t.spurious,
            t.errors.table_cells(),
            t.mean_time_s * 1e3
        );
    }
    let _ = writeln!(
        s,
        "| FPGA (predicted, {} MHz) | | | | | | | | {:.3} |",
        CLOCK_HZ / 1e6,
        headline(results).fpga_mean_latency_s * 1e3
    );
    s
}

/// The per-step table of `summary.md`: accuracy, CPU times, the accelerator's latency per
/// step and the host's time.
fn per_step(results: &LivingRoomResults) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "\n## Per step\n");
    let _ = writeln!(
        s,
        "Errors are means over the step's matched paths, TX / RX, degrees; SBR and fixed-point \
         missed / spurious paths against the image method; times in ms; FPGA ms = the step's \
         latency at {} MHz; host ms = the host's work for the step (candidates, input, \
         schedule).\n",
        CLOCK_HZ / 1e6
    );
    let _ = writeln!(
        s,
        "| step | exact paths | candidates | host paths | warm | IPC GS err | fixed-point err | SBR err | SBR miss/spur | fixed miss/spur | image | IPC GS | IPC Jacobi | SBR | makespan | FPGA cycles | FPGA ms | host ms |"
    );
    let _ = writeln!(
        s,
        "|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
    );
    for f in &results.fpga {
        let get = |solver| find(results, f.step, solver);
        let (image, gs, jacobi, sbr, fixed) = (
            get(StudySolver::Image),
            get(StudySolver::IpcGaussSeidel),
            get(StudySolver::IpcJacobi),
            get(StudySolver::Sbr),
            get(StudySolver::IpcFixedPoint),
        );
        let err = |r: &Comparison| {
            format!(
                "{:.1e} / {:.1e}",
                r.errors.mean_err_tx_deg, r.errors.mean_err_rx_deg
            )
        };
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} / {} | {} / {} | {:.2} | {:.2} | {:.2} | {:.2} | {} | {} | {:.3} | {:.2} |",
            f.step,
            image.paths,
            f.paths,
            f.host_paths,
            f.warm_started,
            err(&gs),
            err(&fixed),
            err(&sbr),
            sbr.missed,
            sbr.spurious,
            fixed.missed,
            fixed.spurious,
            image.time_s * 1e3,
            gs.time_s * 1e3,
            jacobi.time_s * 1e3,
            sbr.time_s * 1e3,
            f.makespan,
            f.cycles,
            f.latency_s * 1e3,
            f.host_time_s * 1e3
        );
    }
    s
}

/// The paper's conclusions, measured: the last table of `summary.md`.
fn conclusions(results: &LivingRoomResults) -> String {
    let h = headline(results);
    let mut s = String::new();
    let _ = writeln!(s, "\n## The paper's conclusions, measured\n");
    let _ = writeln!(s, "| quantity | measured | paper |");
    let _ = writeln!(s, "|---|---:|---:|");
    let lines = [
        format!(
            "| FPGA IPC (fixed-point model) mean angular error, TX / RX (°) | {:.3e} / {:.3e} | < 0.1 (Fig. 17) |",
            h.fixed_err_deg[0], h.fixed_err_deg[1]
        ),
        format!(
            "| FPGA IPC largest angular error, TX / RX (°) | {:.3e} / {:.3e} | within the 10° tolerance (Fig. 18) |",
            h.fixed_max_err_deg[0], h.fixed_max_err_deg[1]
        ),
        format!(
            "| SBR mean angular error, TX / RX (°) | {:.3e} / {:.3e} | clusters around the GO rays (Fig. 18) |",
            h.sbr_err_deg[0], h.sbr_err_deg[1]
        ),
        format!(
            "| SBR error / FPGA IPC error (TX) | {:.3e} | > 100 (Fig. 17) |",
            h.sbr_over_fixed_error
        ),
        format!(
            "| IPC f64 (Gauss-Seidel) mean angular error, TX / RX (°) | {:.3e} / {:.3e} | — |",
            h.ipc_err_deg[0], h.ipc_err_deg[1]
        ),
        format!(
            "| FPGA IPC time per step (cycles / 50 MHz), mean (min-max) | {:.3} ms ({:.3}-{:.3}) | ≈ 1 ms (Fig. 19) |",
            h.fpga_mean_latency_s * 1e3,
            h.fpga_latency_range_s.0 * 1e3,
            h.fpga_latency_range_s.1 * 1e3
        ),
        format!(
            "| SBR time / IPC (Gauss-Seidel) time, one CPU core | {:.3} | > 1 (Fig. 19: IPC faster on the same platform) |",
            h.sbr_over_ipc_time
        ),
        format!(
            "| SBR time / IPC (Jacobi) time, one CPU core | {:.3} | — |",
            h.sbr_over_jacobi_time
        ),
        format!(
            "| SBR (one CPU core) / FPGA IPC time | {:.3e} | ≈ 9e4 (≈ 500 × the FPGA SBR's 200 ms, vs 1 ms; Figs. 19-20) |",
            h.sbr_cpu_over_fpga
        ),
        format!(
            "| IPC Gauss-Seidel (one CPU core) / FPGA IPC time | {:.3e} | — |",
            h.ipc_cpu_over_fpga
        ),
    ];
    for line in lines {
        let _ = writeln!(s, "{line}");
    }
    s
}
