//! Coverage sweeps: trace one TX to every point of a receiver grid and summarise each point —
//! number of paths, the shortest delay, the strongest path (lowest loss) — as rows for a CSV
//! file and a heat map over the floor plan.
//!
//! Tracing goes through one [`bt_solve::Tracer`] (`trace_each`: one beam tree of the TX, kept
//! for every chunk), in chunks so a caller can show progress. A grid point on a surface or at the TX is
//! a [`PointStatus::Skipped`] row, not a failure of the sweep; a candidate budget error is.

#![warn(missing_docs)]

pub mod grid;
mod map;

pub use grid::{Axis, DEFAULT_MAX_POINTS, Grid, GridError};
pub use map::{HeatMap, MapQuantity};

use bt_beams::{PathReport, RadioOptions};
use bt_geom::{Real, Vec3};
use bt_scene::Scene;
use bt_solve::Tracer;
use bt_solve::pipeline::{TraceError, TraceOptions};

/// Why a sweep could not run.
#[derive(Debug, thiserror::Error)]
pub enum CoverageError {
    /// The grid is malformed or too large.
    #[error(transparent)]
    Grid(#[from] GridError),
    /// Tracing failed for a reason that holds for every point (the candidate budget).
    #[error(transparent)]
    Trace(#[from] TraceError),
    /// The path gains could not be computed (a material undefined at the carrier).
    #[error(transparent)]
    Report(#[from] bt_beams::ReportError),
    /// A figure could not be drawn or written.
    #[error(transparent)]
    Plot(#[from] bt_plot::PlotError),
}

/// What was found at one grid point.
#[derive(Debug, Clone, PartialEq)]
pub enum PointStatus {
    /// Traced.
    Traced {
        /// Number of valid paths.
        paths: usize,
        /// Delay of the shortest path, seconds (`None` without paths).
        shortest_delay_s: Option<Real>,
        /// The strongest path's record (`None` without paths): the lowest total loss (free
        /// space + reflections); among equal losses the better ranked one (lower order, then
        /// shorter).
        strongest: Option<Box<PathReport>>,
        /// Total received power of all paths, dBm: `trace --json`'s `received_power_dbm`
        /// (`bt_beams::received_power_dbm` with the sweep's radio options; `None`
        /// without paths).
        received_power_dbm: Option<Real>,
    },
    /// Not traced: the point lies on a surface or at the TX (the reason, from the scene's
    /// validation).
    Skipped(String),
}

/// One grid point and its result.
#[derive(Debug, Clone, PartialEq)]
pub struct Row {
    /// Receiver position, metres, world frame.
    pub rx: Vec3,
    /// The result.
    pub status: PointStatus,
}

/// Receivers traced per chunk between two progress calls (big enough to keep every core busy).
pub const CHUNK: usize = 256;

/// Trace `scene`'s TX to every one of `points` (in order; rows come back in the same order,
/// identical whatever the thread count) with `options`, and report the paths with `radio`.
/// `progress(done, total)` runs after every chunk. A scene without a TX fails as a whole
/// ([`bt_scene::SceneError::MissingTerminal`]); the scene's RX, if any, is not used.
pub fn sweep(
    scene: &Scene,
    points: &[Vec3],
    (options, radio): (&TraceOptions, &RadioOptions),
    progress: &mut dyn FnMut(usize, usize),
) -> Result<Vec<Row>, CoverageError> {
    let tx = scene.to_world(
        scene
            .terminal(bt_scene::Terminal::Tx)
            .map_err(TraceError::from)?,
    );
    let mut rows = Vec::with_capacity(points.len());
    let mut tracer = Tracer::new(scene.clone(), *options);
    // Each receiver reported into the previous one's records (their memory reused).
    let mut records = bt_beams::Records::default();
    for chunk in points.chunks(CHUNK) {
        let traced = tracer.trace_each(tx, chunk)?;
        for (rx, outcome) in chunk.iter().zip(traced) {
            let status = match outcome {
                Ok(traced) => {
                    let moved = scene.with_receiver(*rx).map_err(TraceError::from)?;
                    let reports = records.report(&moved, &traced.result.paths, radio)?;
                    summarise(reports, radio.tx_power_dbm)
                }
                Err(TraceError::Scene(e)) => PointStatus::Skipped(skip_reason(&e)),
                Err(e) => return Err(e.into()),
            };
            rows.push(Row { rx: *rx, status });
        }
        progress(rows.len(), points.len());
    }
    Ok(rows)
}

/// The problems of an invalid receiver, without the scene name.
fn skip_reason(e: &bt_scene::SceneError) -> String {
    match e {
        bt_scene::SceneError::Invalid { problems, .. } => problems
            .iter()
            .map(|p| p.message.as_str())
            .collect::<Vec<_>>()
            .join("; "),
        other => other.to_string(),
    }
}

/// A point's summary from its ranked path reports, transmitting `tx_power_dbm`.
pub fn summarise(paths: &[PathReport], tx_power_dbm: Real) -> PointStatus {
    let shortest_delay_s = paths.iter().map(|p| p.delay_s).min_by(Real::total_cmp);
    // Reports come ranked, and min_by keeps the first of equal losses: the better ranked.
    let strongest = paths
        .iter()
        .min_by(|a, b| a.loss_db.total_cmp(&b.loss_db))
        .map(|p| Box::new(p.clone()));
    PointStatus::Traced {
        paths: paths.len(),
        shortest_delay_s,
        strongest,
        received_power_dbm: bt_beams::received_power_dbm(paths, tx_power_dbm),
    }
}

/// The CSV header of [`csv`].
pub const CSV_HEADER: &str = "x_m,y_m,z_m,status,paths,shortest_delay_ns,strongest_order,strongest_loss_db,strongest_length_m,strongest_surfaces,received_power_dbm,note";

/// The rows as CSV (RFC 4180: fields with commas, quotes or line breaks are quoted; surface
/// names are data). Skipped points have empty result fields and the reason in `note`.
/// Numbers print with fixed decimals so the bytes are the same on every machine.
pub fn csv(rows: &[Row]) -> String {
    let mut out = String::with_capacity(64 * (rows.len() + 1));
    out.push_str(CSV_HEADER);
    out.push('\n');
    for row in rows {
        let p = row.rx;
        let coords = format!("{:.6},{:.6},{:.6}", p.x, p.y, p.z);
        let line = match &row.status {
            PointStatus::Traced {
                paths,
                shortest_delay_s,
                strongest,
                received_power_dbm,
            } => {
                let delay = shortest_delay_s
                    .map(|d| format!("{:.6}", d * 1e9))
                    .unwrap_or_default();
                let best = strongest
                    .as_ref()
                    .map(|s| {
                        format!(
                            "{},{:.4},{:.6},{}",
                            s.order,
                            s.loss_db,
                            s.length_m,
                            bt_output::csv::text_field(&s.route())
                        )
                    })
                    .unwrap_or_else(|| ",,,".to_string());
                let power = received_power_dbm
                    .map(|p| format!("{p:.4}"))
                    .unwrap_or_default();
                format!("{coords},ok,{paths},{delay},{best},{power},")
            }
            PointStatus::Skipped(reason) => {
                format!(
                    "{coords},skipped,,,,,,,,{}",
                    bt_output::csv::text_field(reason)
                )
            }
        };
        out.push_str(&line);
        out.push('\n');
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_far_hall_sweeps_like_the_hall_at_the_origin() {
        let desc = bt_testkit::hall_description();
        let offset = Vec3::new(-7.5e6, 1.25e6, 10.0);
        let terminals = bt_scene::Terminals::default();
        let near = Scene::from_description(&desc, "hall", terminals).unwrap();
        let far = bt_testkit::translated(&desc, offset);
        let far = Scene::from_description(&far, "hall", terminals).unwrap();
        // a grid over the hall, one point on the stage's top (skipped in both)
        let mut points: Vec<Vec3> = (0..12)
            .map(|i| Vec3::new(5.0 + 4.5 * i as Real, 3.0 + 3.0 * (i % 5) as Real, 1.5))
            .collect();
        points.push(Vec3::new(6.0, 20.0, 1.25));
        let moved: Vec<Vec3> = points.iter().map(|p| *p + offset).collect();
        let options = TraceOptions::new(2);
        let radio = RadioOptions::default();
        let a = sweep(&near, &points, (&options, &radio), &mut |_, _| {}).unwrap();
        let b = sweep(&far, &moved, (&options, &radio), &mut |_, _| {}).unwrap();
        assert!(
            matches!(a[12].status, PointStatus::Skipped(_)),
            "{:?}",
            a[12]
        );
        for (r, s) in a.iter().zip(&b) {
            assert_eq!(s.rx, r.rx + offset, "rows keep the world grid point");
            match (&r.status, &s.status) {
                (
                    PointStatus::Traced {
                        paths: n,
                        strongest: Some(x),
                        ..
                    },
                    PointStatus::Traced {
                        paths: m,
                        strongest: Some(y),
                        ..
                    },
                ) => {
                    assert_eq!((n, &x.surfaces), (m, &y.surfaces), "at {}", r.rx);
                    assert!((x.length_m - y.length_m).abs() <= 1e-9 * x.length_m);
                }
                (PointStatus::Skipped(_), PointStatus::Skipped(_)) => {}
                other => panic!("at {}: {other:?}", r.rx),
            }
        }
    }

    #[test]
    fn skipped_rows_have_empty_result_fields() {
        let rows = [Row {
            rx: Vec3::new(1.0, 2.0, 0.0),
            status: PointStatus::Skipped("lies on surface \"floor, west\"".into()),
        }];
        let text = csv(&rows);
        let line = text.lines().nth(1).unwrap();
        assert_eq!(
            line,
            "1.000000,2.000000,0.000000,skipped,,,,,,,,\"lies on surface \"\"floor, west\"\"\""
        );
        assert_eq!(
            CSV_HEADER.split(',').count(),
            "1,2,0,skipped,,,,,,,,x".split(',').count()
        );
    }
}
