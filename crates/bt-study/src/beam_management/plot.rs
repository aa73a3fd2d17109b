//! The study's figures on any plotters backend: top-1 accuracy against the beams measured per
//! decision, and the CDF of the SNR loss; one panel per scenario.

use super::{BeamManagementResults, MethodResult, ScenarioResult};
use bt_geom::Real;
use bt_plot::{FAMILY, blank, fail, legend, mesh};
use plotters::coord::Shift;
use plotters::prelude::*;

/// Largest SNR loss drawn in the CDF, dB (larger losses sit at the right edge).
pub const LOSS_AXIS_DB: Real = 30.0;

/// One colour per method family, in the order of [`FAMILIES`].
const PALETTE: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
];

/// The families coloured by [`PALETTE`] (another family gets its last colour).
const FAMILIES: [&str; 7] = [
    "exhaustive",
    "hierarchical",
    "keep-previous",
    "twin-exact",
    "twin-stale",
    "twin-extracted",
    "geometric-los",
];

fn colour(family: &str) -> RGBColor {
    let i = FAMILIES.iter().position(|f| *f == family);
    PALETTE[i.unwrap_or(PALETTE.len() - 1)]
}

/// Lowest fraction drawn in the CDF (every method is right more often than this here).
pub const CDF_FLOOR: Real = 0.5;

/// The twins drawn: the smallest non-zero position error (else the first) at the first
/// latency of the settings.
fn drawn_variant(results: &BeamManagementResults) -> (Real, Real) {
    let c = &results.config;
    let sigma = (c.position_sigmas_m.iter().copied())
        .filter(|&s| s > 0.0)
        .reduce(Real::min)
        .unwrap_or(c.position_sigmas_m[0]);
    (sigma, c.latencies_s[0])
}

fn families(s: &ScenarioResult) -> Vec<&str> {
    let mut f: Vec<&str> = Vec::new();
    for m in &s.methods {
        if m.twin.is_some() && !f.contains(&m.family.as_str()) {
            f.push(&m.family);
        }
    }
    f
}

fn twin_series<'a>(
    s: &'a ScenarioResult,
    family: &str,
    variant: (Real, Real),
) -> Vec<&'a MethodResult> {
    s.methods
        .iter()
        .filter(|m| m.family == family && m.twin.is_some_and(|t| (t.0, t.1) == variant))
        .collect()
}

/// Top-1 accuracy (filled) and with the 1 dB margin (hollow) against beam pairs measured per
/// decision (log x): the baselines as points, each twin as a line over K.
pub fn accuracy_vs_overhead<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    results: &BeamManagementResults,
) -> Result<(), String> {
    blank(root)?;
    let variant = drawn_variant(results);
    let panels = root.split_evenly((results.scenarios.len().max(1), 1));
    for (area, s) in panels.iter().zip(&results.scenarios) {
        let max_x = (s.pairs as Real * 2.0).max(10.0);
        let title = format!(
            "{}: top-1 accuracy vs beams measured (twins at σ = {} m, latency {} ms)",
            s.name,
            variant.0,
            variant.1 * 1e3
        );
        let mut chart = ChartBuilder::on(area)
            .caption(title, (FAMILY, 20))
            .margin(12)
            .x_label_area_size(45)
            .y_label_area_size(60)
            .build_cartesian_2d((0.5..max_x).log_scale(), 0.0..1.02)
            .map_err(fail)?;
        mesh(
            &mut chart,
            ("beam pairs measured per decision", "top-1 accuracy"),
            (14, 16),
        )
        .draw()
        .map_err(fail)?;
        for m in s.methods.iter().filter(|m| m.twin.is_none()) {
            let c = colour(&m.family);
            let p = (m.metrics.beams_measured.max(0.5), m.metrics.top1);
            let q = (p.0, m.metrics.top1_1db);
            chart
                .draw_series([Circle::new(p, 7, c.filled())])
                .map_err(fail)?
                .label(m.name.clone())
                .legend(move |(x, y)| Circle::new((x + 8, y), 5, c.filled()));
            chart
                .draw_series([Circle::new(q, 7, c.stroke_width(2))])
                .map_err(fail)?;
        }
        for family in families(s) {
            let c = colour(family);
            let line = twin_series(s, family, variant);
            let pts = |f: fn(&MethodResult) -> Real| -> Vec<(Real, Real)> {
                line.iter()
                    .map(|m| (m.metrics.beams_measured.max(0.5), f(m)))
                    .collect()
            };
            chart
                .draw_series(LineSeries::new(pts(|m| m.metrics.top1), c.stroke_width(2)))
                .map_err(fail)?
                .label(format!("{family} (K = 1, 2, 4, 8 ...)"))
                .legend(move |(x, y)| PathElement::new([(x, y), (x + 16, y)], c.stroke_width(2)));
            let dots = pts(|m| m.metrics.top1)
                .into_iter()
                .map(|p| Circle::new(p, 4, c.filled()));
            chart.draw_series(dots).map_err(fail)?;
            let hollow = pts(|m| m.metrics.top1_1db)
                .into_iter()
                .map(|p| Circle::new(p, 4, c.stroke_width(1)));
            chart.draw_series(hollow).map_err(fail)?;
        }
        legend(&mut chart, SeriesLabelPosition::LowerRight, 13)?;
    }
    Ok(())
}

/// The empirical CDF of the SNR loss (dB, losses above [`LOSS_AXIS_DB`] at the edge, fractions
/// from [`CDF_FLOOR`]) of the baselines and of each twin at K = 1 (thin) and the largest K
/// (thick), one colour per family.
pub fn snr_loss_cdf<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    results: &BeamManagementResults,
) -> Result<(), String> {
    blank(root)?;
    let variant = drawn_variant(results);
    let k_max = results.config.top_k.iter().copied().max().unwrap_or(1);
    let panels = root.split_evenly((results.scenarios.len().max(1), 1));
    for (area, s) in panels.iter().zip(&results.scenarios) {
        let title = format!(
            "{}: CDF of the SNR loss (twins at σ = {} m, latency {} ms)",
            s.name,
            variant.0,
            variant.1 * 1e3
        );
        let mut chart = ChartBuilder::on(area)
            .caption(title, (FAMILY, 20))
            .margin(12)
            .x_label_area_size(45)
            .y_label_area_size(60)
            .build_cartesian_2d(0.0..LOSS_AXIS_DB, CDF_FLOOR..1.01)
            .map_err(fail)?;
        mesh(
            &mut chart,
            (
                "SNR loss against the best pair (dB)",
                "fraction of decisions",
            ),
            (14, 16),
        )
        .draw()
        .map_err(fail)?;
        let mut drawn: Vec<&MethodResult> = s.methods.iter().filter(|m| m.twin.is_none()).collect();
        for family in families(s) {
            drawn.extend(
                twin_series(s, family, variant)
                    .into_iter()
                    .filter(|m| m.twin.is_some_and(|t| t.2 == 1 || t.2 == k_max)),
            );
        }
        for m in drawn {
            let c = colour(&m.family);
            let mut loss: Vec<Real> = m
                .outcomes
                .iter()
                .filter_map(|o| o.1)
                .map(|o| o.snr_loss_db.min(LOSS_AXIS_DB))
                .collect();
            loss.sort_by(Real::total_cmp);
            let n = loss.len().max(1) as Real;
            let steps = loss
                .iter()
                .enumerate()
                .flat_map(|(i, &x)| [(x, i as Real / n), (x, (i + 1) as Real / n)]);
            let line: Vec<(Real, Real)> = steps.chain([(LOSS_AXIS_DB, 1.0)]).collect();
            let dashed = m.twin.is_some_and(|t| t.2 == 1);
            let style = c.stroke_width(if dashed { 1 } else { 2 });
            chart
                .draw_series(LineSeries::new(line, style))
                .map_err(fail)?
                .label(m.name.clone())
                .legend(move |(x, y)| PathElement::new([(x, y), (x + 16, y)], style));
        }
        legend(&mut chart, SeriesLabelPosition::LowerRight, 13)?;
    }
    Ok(())
}
