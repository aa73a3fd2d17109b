//! The living-room figures on any plotters backend: Fig. 17 (angular error per time step),
//! Fig. 18 (ray directions at TX and RX for two steps) and Fig. 19 (run time per step,
//! including the accelerator's predicted latency).

use super::{LivingRoomResults, RayAngles, StepRays};
use crate::StudySolver;
use crate::plot::{
    FAMILY, Series, TIME_FLOOR_S, blank, colour, error_panel, fail, legend, mesh, panel,
};
use crate::run::Comparison;
use bt_geom::Real;
use plotters::coord::Shift;
use plotters::prelude::*;

/// Colour of the accelerator's latency series in Fig. 19.
const FPGA_COLOUR: RGBColor = RGBColor(255, 127, 14);

fn per_step(
    results: &LivingRoomResults,
    solver: StudySolver,
    value: impl Fn(&Comparison) -> Real,
) -> Series {
    let points = results
        .rows
        .iter()
        .filter(|r| r.comparison.solver == solver)
        .map(|r| (r.step, value(&r.comparison)))
        .collect();
    Series::of(solver, points)
}

/// Fig. 17: mean angular error per time step at TX (left) and RX (right), for IPC
/// (Gauss-Seidel, Jacobi), the fixed-point model of the accelerator and SBR. Log y; errors
/// below [`ERROR_FLOOR_DEG`](crate::plot::ERROR_FLOOR_DEG) are drawn at it.
pub fn angular_error<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    results: &LivingRoomResults,
) -> Result<(), String> {
    blank(root)?;
    let solvers = [
        StudySolver::IpcGaussSeidel,
        StudySolver::IpcJacobi,
        StudySolver::IpcFixedPoint,
        StudySolver::Sbr,
    ];
    let panels = root.split_evenly((1, 2));
    type Side = fn(&Comparison) -> Real;
    let sides: [(&str, Side); 2] = [
        ("(a) TX side", |r| r.errors.mean_err_tx_deg),
        ("(b) RX side", |r| r.errors.mean_err_rx_deg),
    ];
    for (area, (title, value)) in panels.iter().zip(sides) {
        let series: Vec<Series> = solvers
            .iter()
            .map(|s| per_step(results, *s, value))
            .collect();
        error_panel(area, title, "time step", &series)?;
    }
    Ok(())
}

/// Fig. 19: run time per time step: every solver single-threaded on the CPU and the
/// accelerator's predicted latency per step (cycles on the one platform / 50 MHz). Log y.
pub fn run_time<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    results: &LivingRoomResults,
) -> Result<(), String> {
    blank(root)?;
    let mut series: Vec<Series> = [
        StudySolver::Image,
        StudySolver::IpcGaussSeidel,
        StudySolver::IpcJacobi,
        StudySolver::Sbr,
    ]
    .iter()
    .map(|s| {
        let mut line = per_step(results, *s, |r| r.time_s);
        line.label = format!("{} (CPU, 1 core)", line.label);
        line
    })
    .collect();
    series.push(Series {
        label: format!("ipc on the FPGA (cycles / {} MHz)", bt_hls::CLOCK_HZ / 1e6),
        colour: FPGA_COLOUR,
        points: results.fpga.iter().map(|f| (f.step, f.latency_s)).collect(),
    });
    panel(
        root,
        "run time per time step",
        "time step",
        "time (s)",
        &series,
        TIME_FLOOR_S,
        SeriesLabelPosition::UpperRight,
    )
}

/// Fig. 18: azimuth vs elevation of every path at TX and RX for the drawn steps (one row per
/// step): geometric optics (black crosses), the accelerator's fixed-point IPC (blue
/// triangles), SBR (red circles).
pub fn ray_directions<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    rays: &[StepRays],
) -> Result<(), String> {
    blank(root)?;
    let cells = root.split_evenly((rays.len().max(1), 2));
    let exact_colour = RGBColor(20, 20, 20);
    let fixed_colour = colour(StudySolver::IpcGaussSeidel);
    let sbr_colour = colour(StudySolver::Sbr);
    for (r, step) in rays.iter().enumerate() {
        for (c, side) in ["TX", "RX"].into_iter().enumerate() {
            let area = &cells[2 * r + c];
            let pick = |a: &RayAngles| {
                if c == 0 {
                    (a.tx_azimuth_deg, a.tx_elevation_deg)
                } else {
                    (a.rx_azimuth_deg, a.rx_elevation_deg)
                }
            };
            let mut chart = ChartBuilder::on(area)
                .caption(
                    format!("time step {}, {side} side", step.step),
                    (FAMILY, 16),
                )
                .margin(10)
                .x_label_area_size(36)
                .y_label_area_size(50)
                .build_cartesian_2d(-180.0..180.0, -90.0..90.0)
                .map_err(fail)?;
            mesh(&mut chart, ("azimuth (deg)", "elevation (deg)"), (11, 13))
                .x_labels(9)
                .y_labels(7)
                .x_label_formatter(&|x| format!("{x:.0}"))
                .y_label_formatter(&|y| format!("{y:.0}"))
                .draw()
                .map_err(fail)?;
            chart
                .draw_series(
                    step.sbr
                        .iter()
                        .map(|a| Circle::new(pick(a), 6, sbr_colour.stroke_width(1))),
                )
                .map_err(fail)?
                .label(format!("SBR ({} paths)", step.sbr.len()))
                .legend(move |(x, y)| Circle::new((x + 10, y), 5, sbr_colour.stroke_width(1)));
            chart
                .draw_series(
                    step.fixed_point
                        .iter()
                        .map(|a| TriangleMarker::new(pick(a), 5, fixed_colour.filled())),
                )
                .map_err(fail)?
                .label(format!(
                    "IPC, FPGA fixed point ({})",
                    step.fixed_point.len()
                ))
                .legend(move |(x, y)| TriangleMarker::new((x + 10, y), 5, fixed_colour.filled()));
            chart
                .draw_series(
                    step.exact
                        .iter()
                        .map(|a| Cross::new(pick(a), 5, exact_colour.stroke_width(2))),
                )
                .map_err(fail)?
                .label(format!("geometric optics ({})", step.exact.len()))
                .legend(move |(x, y)| Cross::new((x + 10, y), 5, exact_colour.stroke_width(2)));
            legend(&mut chart, SeriesLabelPosition::LowerLeft, 11)?;
        }
    }
    Ok(())
}
