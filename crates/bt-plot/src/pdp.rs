//! The power-delay profile of a trace (`beamtrace channel --pdp STEM`): one stem per path at
//! its delay, up to its received power, coloured by reflection order.

use crate::{FAMILY, Figure, PlotError, blank, fail, legend, mesh, write_svg_png};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::{Path, PathBuf};

/// Pixel size of the figure.
const SIZE: (u32, u32) = (900, 500);

/// One tap of a power-delay profile: delay in nanoseconds, received power in dBm, order.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PdpTap {
    /// Delay, ns.
    pub delay_ns: f64,
    /// Received power of the path, dBm.
    pub power_dbm: f64,
    /// Reflection order (colours the stems).
    pub order: usize,
}

/// A power-delay profile: one stem per path from the floor of the axis to its power, coloured
/// by reflection order, `title` on top.
pub fn power_delay_profile<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    (title, taps): (&str, &[PdpTap]),
) -> Result<(), String> {
    blank(root)?;
    let finite = || taps.iter().filter(|t| t.power_dbm.is_finite());
    let (p_lo, p_hi) = finite().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), t| {
        (lo.min(t.power_dbm), hi.max(t.power_dbm))
    });
    let (p_lo, p_hi) = if p_lo.is_finite() {
        ((p_lo - 10.0).floor(), (p_hi + 5.0).ceil())
    } else {
        (-150.0, 0.0)
    };
    let t_hi = finite().map(|t| t.delay_ns).fold(1.0, f64::max) * 1.05;
    let mut chart = ChartBuilder::on(root)
        .caption(title, (FAMILY, 18))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(0.0..t_hi, p_lo..p_hi)
        .map_err(fail)?;
    mesh(&mut chart, ("delay (ns)", "received power (dBm)"), (12, 14))
        .draw()
        .map_err(fail)?;
    let max_order = finite().map(|t| t.order).max().unwrap_or(0);
    for order in 0..=max_order {
        let colour = Palette99::pick(order).to_rgba();
        let stems: Vec<_> = finite().filter(|t| t.order == order).collect();
        if stems.is_empty() {
            continue;
        }
        chart
            .draw_series(stems.iter().map(|t| {
                PathElement::new(
                    vec![(t.delay_ns, p_lo), (t.delay_ns, t.power_dbm)],
                    colour.stroke_width(2),
                )
            }))
            .map_err(fail)?;
        chart
            .draw_series(
                stems
                    .iter()
                    .map(|t| Circle::new((t.delay_ns, t.power_dbm), 3, colour.filled())),
            )
            .map_err(fail)?
            .label(if order == 0 {
                "line of sight".to_string()
            } else {
                format!("order {order}")
            })
            .legend(move |(x, y)| Circle::new((x + 10, y), 3, colour.filled()));
    }
    legend(&mut chart, SeriesLabelPosition::UpperRight, 12)
}

/// Write the power-delay profile of `taps` under `title` as `<stem>.svg` and `<stem>.png` (each
/// to a temporary file in the same directory, then renamed into place, see [`write_svg_png`]).
/// Returns the two files written.
pub fn write_power_delay_profile(
    stem: &Path,
    title: &str,
    taps: &[PdpTap],
) -> Result<[PathBuf; 2], PlotError> {
    struct Pdp<'a>(&'a str, &'a [PdpTap]);
    impl Figure for Pdp<'_> {
        fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), String> {
            power_delay_profile(root, (self.0, self.1))
        }
    }
    write_svg_png(stem, SIZE, &Pdp(title, taps))
}
