//! The figures, drawn on any plotters backend (the SVG and PNG files are made by
//! [`crate::io`]): Fig. 5 (rooms, terminals and exact paths over time), Fig. 6 (angular error
//! against time step and number of edges) and Fig. 7 (elapsed time, same axes). Log y axes
//! with a floor: IPC errors are ~1e-12° and some are exactly 0.
//!
//! The font, the white canvas and the legend style are shared with every other figure
//! (`bt-plot`).

use crate::report::{GroupBy, Quantity, mean_by};
use crate::run::{RoomDrawing, StudyResults, StudySolver};
use bt_geom::Real;
use plotters::coord::Shift;
use plotters::prelude::*;

/// Errors below this are drawn at it on the log axes, degrees.
pub const ERROR_FLOOR_DEG: Real = 1e-15;
/// Times below this are drawn at it on the log axes, seconds.
pub const TIME_FLOOR_S: Real = 1e-7;

pub use bt_plot::register_font;
pub(crate) use bt_plot::{FAMILY, blank, fail, legend, mesh};

/// Colour of a solver in every figure.
pub fn colour(solver: StudySolver) -> RGBColor {
    match solver {
        StudySolver::Image => RGBColor(40, 40, 40),
        StudySolver::IpcGaussSeidel => RGBColor(31, 119, 180),
        StudySolver::IpcJacobi => RGBColor(44, 160, 44),
        StudySolver::Sbr => RGBColor(214, 39, 40),
        StudySolver::IpcFixedPoint => RGBColor(148, 103, 189),
    }
}

/// One line of a panel.
pub(crate) struct Series {
    /// Legend text.
    pub(crate) label: String,
    /// Line colour.
    pub(crate) colour: RGBColor,
    /// `(x, y)` points, x ascending.
    pub(crate) points: Vec<(usize, Real)>,
}

impl Series {
    /// A solver's series, in its colour and under its name.
    pub(crate) fn of(solver: StudySolver, points: Vec<(usize, Real)>) -> Series {
        Series {
            label: solver.name().to_string(),
            colour: colour(solver),
            points,
        }
    }
}

/// One panel: a line per series on a log y axis; `floor` clamps values (and zeros) from below.
#[allow(clippy::too_many_arguments)]
pub(crate) fn panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    title: &str,
    x_desc: &str,
    y_desc: &str,
    series: &[Series],
    floor: Real,
    legend_position: SeriesLabelPosition,
) -> Result<(), String> {
    let xs = series.iter().flat_map(|s| s.points.iter().map(|q| q.0));
    let (x_lo, x_hi) = xs.fold((usize::MAX, 0), |(lo, hi), x| (lo.min(x), hi.max(x)));
    let (x_lo, x_hi) = if x_lo > x_hi { (0, 1) } else { (x_lo, x_hi) };
    let ys = series
        .iter()
        .flat_map(|s| s.points.iter().map(|q| q.1.max(floor)));
    let (y_lo, y_hi) = ys.fold((Real::INFINITY, floor), |(lo, hi), y| {
        (lo.min(y), hi.max(y))
    });
    let y_lo = if y_lo.is_finite() { y_lo / 3.0 } else { floor };
    // Headroom above the data for the legend.
    let y_hi = (y_hi * 30.0).max(y_lo * 10.0);
    let mut chart = ChartBuilder::on(area)
        .caption(title, (FAMILY, 18))
        .margin(10)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d(
            (x_lo as Real - 0.5)..(x_hi as Real + 0.5),
            (y_lo..y_hi).log_scale(),
        )
        .map_err(fail)?;
    mesh(&mut chart, (x_desc, y_desc), (12, 14))
        .x_labels((x_hi - x_lo + 1).min(12))
        .x_label_formatter(&|x| format!("{x:.0}"))
        .y_label_formatter(&|y| format!("{y:.0e}"))
        .draw()
        .map_err(fail)?;
    for s in series {
        let c = s.colour;
        let line: Vec<(Real, Real)> = s
            .points
            .iter()
            .map(|&(x, y)| (x as Real, y.max(floor)))
            .collect();
        chart
            .draw_series(LineSeries::new(line, c.stroke_width(2)).point_size(3))
            .map_err(fail)?
            .label(s.label.as_str())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2)));
    }
    legend(&mut chart, legend_position, 12)
}

/// An angular-error panel (Figs. 6 and 17): mean error in degrees on a log axis floored at
/// [`ERROR_FLOOR_DEG`], legend at the middle right.
pub(crate) fn error_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    title: &str,
    x_desc: &str,
    series: &[Series],
) -> Result<(), String> {
    panel(
        area,
        title,
        x_desc,
        "mean angular error (deg)",
        series,
        ERROR_FLOOR_DEG,
        SeriesLabelPosition::MiddleRight,
    )
}

fn selected(
    results: &StudyResults,
    group: GroupBy,
    quantity: Quantity,
    solvers: &[StudySolver],
) -> Vec<Series> {
    let mut by = mean_by(&results.rows, group, quantity);
    solvers
        .iter()
        .filter_map(|s| by.remove(s).map(|p| Series::of(*s, p)))
        .collect()
}

/// Fig. 6: mean angular error at TX and RX against the time step (top) and the number of
/// edges (bottom), for IPC and SBR (the image method is the zero reference).
pub fn angular_error<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    results: &StudyResults,
) -> Result<(), String> {
    blank(root)?;
    let solvers = [
        StudySolver::IpcGaussSeidel,
        StudySolver::IpcJacobi,
        StudySolver::Sbr,
    ];
    let panels = root.split_evenly((2, 2));
    let specs = [
        (
            GroupBy::Step,
            Quantity::ErrorTx,
            "(a1) TX side vs dynamics",
            "time step",
        ),
        (
            GroupBy::Step,
            Quantity::ErrorRx,
            "(a2) RX side vs dynamics",
            "time step",
        ),
        (
            GroupBy::Edges,
            Quantity::ErrorTx,
            "(b1) TX side vs complexity",
            "number of edges",
        ),
        (
            GroupBy::Edges,
            Quantity::ErrorRx,
            "(b2) RX side vs complexity",
            "number of edges",
        ),
    ];
    for (area, (group, quantity, title, x_desc)) in panels.iter().zip(specs) {
        let series = selected(results, group, quantity, &solvers);
        error_panel(area, title, x_desc, &series)?;
    }
    Ok(())
}

/// Fig. 7: mean single-threaded elapsed time per room and step, against the time step and the
/// number of edges, for every solver.
pub fn elapsed_time<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    results: &StudyResults,
) -> Result<(), String> {
    blank(root)?;
    let panels = root.split_evenly((1, 2));
    let specs = [
        (GroupBy::Step, "(a) elapsed time vs dynamics", "time step"),
        (
            GroupBy::Edges,
            "(b) elapsed time vs complexity",
            "number of edges",
        ),
    ];
    for (area, (group, title, x_desc)) in panels.iter().zip(specs) {
        let series = selected(results, group, Quantity::Time, &StudySolver::ALL);
        panel(
            area,
            title,
            x_desc,
            "mean elapsed time (s)",
            &series,
            TIME_FLOOR_S,
            SeriesLabelPosition::UpperLeft,
        )?;
    }
    Ok(())
}

/// Colour of a path of the given reflection order in Fig. 5.
fn order_colour(order: usize) -> RGBAColor {
    match order {
        0 => RGBColor(0, 0, 0).mix(0.9),
        1 => RGBColor(31, 119, 180).mix(0.8),
        2 => RGBColor(44, 160, 44).mix(0.5),
        _ => RGBColor(255, 127, 14).mix(0.3),
    }
}

/// Fig. 5: one row per drawn room, one column per drawn time step: walls (the step-0 contour
/// in grey underneath), the moving vertex, TX (red triangle), RX (blue dot) and every exact
/// path coloured by order (black LOS, blue 1st, green 2nd, orange 3rd).
pub fn rooms<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    drawings: &[RoomDrawing],
) -> Result<(), String> {
    blank(root)?;
    let cols = drawings
        .iter()
        .map(|d| d.steps.len())
        .max()
        .unwrap_or(1)
        .max(1);
    let cells = root.split_evenly((drawings.len().max(1), cols));
    for (r, drawing) in drawings.iter().enumerate() {
        let room = &drawing.room;
        for (c, (&step, paths)) in drawing.steps.iter().zip(&drawing.paths).enumerate() {
            let area = &cells[r * cols + c];
            let title = format!(
                "room {} ({}, {} edges), step {step}",
                room.index,
                room.shape.name(),
                room.edges
            );
            let mut chart = ChartBuilder::on(area)
                .caption(title, (FAMILY, 14))
                .margin(6)
                .x_label_area_size(20)
                .y_label_area_size(24)
                .build_cartesian_2d(0.0..crate::room::SQUARE, 0.0..crate::room::SQUARE)
                .map_err(fail)?;
            chart
                .configure_mesh()
                .disable_mesh()
                .x_labels(3)
                .y_labels(3)
                .label_style((FAMILY, 10))
                .draw()
                .map_err(fail)?;
            let closed = |contour: &[bt_geom::Vec2]| {
                let mut line: Vec<(Real, Real)> = contour.iter().map(|p| (p.x, p.y)).collect();
                line.push(line[0]);
                line
            };
            if step > 0 {
                chart
                    .draw_series(std::iter::once(PathElement::new(
                        closed(&room.contours[0]),
                        RGBColor(180, 180, 180).stroke_width(1),
                    )))
                    .map_err(fail)?;
            }
            let mut ordered: Vec<&(usize, Vec<bt_geom::Vec2>)> = paths.iter().collect();
            ordered.sort_by_key(|(order, _)| std::cmp::Reverse(*order));
            chart
                .draw_series(ordered.into_iter().map(|(order, line)| {
                    PathElement::new(
                        line.iter().map(|p| (p.x, p.y)).collect::<Vec<_>>(),
                        order_colour(*order).stroke_width(1),
                    )
                }))
                .map_err(fail)?;
            let contour = &room.contours[step];
            chart
                .draw_series(std::iter::once(PathElement::new(
                    closed(contour),
                    BLACK.stroke_width(2),
                )))
                .map_err(fail)?;
            let m = contour[room.moving_vertex];
            chart
                .draw_series([
                    Circle::new((m.x, m.y), 4, MAGENTA.stroke_width(2)),
                    Circle::new((room.rx.x, room.rx.y), 4, BLUE.filled()),
                ])
                .map_err(fail)?;
            chart
                .draw_series(std::iter::once(TriangleMarker::new(
                    (room.tx.x, room.tx.y),
                    6,
                    RED.filled(),
                )))
                .map_err(fail)?;
        }
    }
    Ok(())
}
