//! The only module of the studies that touches the filesystem: writes `results.csv`,
//! `summary.md` and the figures as SVG and PNG into an output directory.

use crate::beam_management::{self, BeamManagementResults};
use crate::living_room::{self, LivingRoomResults};
use crate::run::{RoomDrawing, StudyResults};
use crate::{StudyError, plot, report};
use bt_output::{Committed, OutputDir};
use plotters::prelude::*;
use std::path::{Path, PathBuf};

/// Pixel size of Fig. 5 per drawn room and time step.
const ROOM_CELL: u32 = 300;

fn write(out: &mut OutputDir, rel: &str, text: &str) -> Result<(), StudyError> {
    Ok(out.write(rel, text.as_bytes())?)
}

/// Draw one figure with `$draw(&root, $data)` (`$data: &$ty`) as `$stem.svg` and `$stem.png`
/// of `$out` (see [`write_figure`]).
macro_rules! figure {
    ($out:expr, $stem:expr, $size:expr, $draw:path, $data:expr, $ty:ty) => {{
        struct Drawn<'a>(&'a $ty);
        impl bt_plot::Figure for Drawn<'_> {
            fn draw<DB: DrawingBackend>(
                &self,
                root: &DrawingArea<DB, plotters::coord::Shift>,
            ) -> Result<(), String> {
                $draw(root, self.0)
            }
        }
        write_figure(&mut $out, $stem, $size, &Drawn($data))?;
    }};
}

/// `figure` as `stem.svg` and `stem.png` in `out`, through `bt_plot::write_svg_png` (the one
/// home of drawing a figure on both backends).
fn write_figure(
    out: &mut OutputDir,
    stem: &str,
    size: (u32, u32),
    figure: &impl bt_plot::Figure,
) -> Result<(), StudyError> {
    let svg = out.path(&format!("{stem}.svg"))?;
    out.path(&format!("{stem}.png"))?;
    bt_plot::write_svg_png(&svg.with_extension(""), size, figure).map_err(plot_error)?;
    Ok(())
}

fn plot_error(e: bt_plot::PlotError) -> StudyError {
    StudyError::Plot {
        path: e.path,
        message: e.message,
    }
}

/// Write every output of a study into `dir` (created if missing; built in it aside and moved
/// in, see `bt_output::OutputDir`); returns the files written and the files of an earlier run
/// left alone.
pub fn write_outputs(dir: &Path, results: &StudyResults) -> Result<Committed, StudyError> {
    let mut out = OutputDir::begin(dir, &[])?;
    write(&mut out, "results.csv", &report::csv(results))?;
    write(&mut out, "summary.md", &report::summary(results))?;
    figure!(
        out,
        "fig6-angular-error",
        (1200, 900),
        plot::angular_error,
        results,
        StudyResults
    );
    figure!(
        out,
        "fig7-elapsed-time",
        (1200, 480),
        plot::elapsed_time,
        results,
        StudyResults
    );
    let drawings = &results.drawings;
    let cols = drawings
        .iter()
        .map(|d| d.steps.len())
        .max()
        .unwrap_or(1)
        .max(1) as u32;
    let size = (ROOM_CELL * cols, ROOM_CELL * drawings.len().max(1) as u32);
    figure!(
        out,
        "fig5-rooms",
        size,
        plot::rooms,
        drawings,
        [RoomDrawing]
    );
    Ok(out.commit()?)
}

/// Write every output of the living-room study into `dir` (created if missing; built aside and
/// moved in):
/// `results.csv`, `fpga.csv`, `summary.md`, `fig17-angular-error`, `fig18-ray-directions` and
/// `fig19-run-time` as SVG and PNG, refusing to replace any of `inputs` (the scene's files).
/// Returns the files written and those left alone.
pub fn write_living_room(
    dir: &Path,
    results: &LivingRoomResults,
    inputs: &[PathBuf],
) -> Result<Committed, StudyError> {
    let mut out = OutputDir::begin(dir, inputs)?;
    write(&mut out, "results.csv", &living_room::report::csv(results))?;
    write(
        &mut out,
        "fpga.csv",
        &living_room::report::fpga_csv(results),
    )?;
    write(
        &mut out,
        "summary.md",
        &living_room::report::summary(results),
    )?;
    figure!(
        out,
        "fig17-angular-error",
        (1200, 480),
        living_room::plot::angular_error,
        results,
        LivingRoomResults
    );
    let rays = &results.rays;
    let size = (1200, 420 * rays.len().max(1) as u32);
    figure!(
        out,
        "fig18-ray-directions",
        size,
        living_room::plot::ray_directions,
        rays,
        [living_room::StepRays]
    );
    figure!(
        out,
        "fig19-run-time",
        (1000, 560),
        living_room::plot::run_time,
        results,
        LivingRoomResults
    );
    Ok(out.commit()?)
}

/// Write every output of the beam-management study into `dir` (created if missing; built aside
/// and moved in): `summary.json`, `details.json`, `decisions.csv`, `trajectory.csv` and the
/// figures `accuracy-vs-overhead` and `snr-loss-cdf` as SVG and PNG, refusing to replace any
/// of `inputs` (the scenes' files). Returns the files written and those left alone.
pub fn write_beam_management(
    dir: &Path,
    results: &BeamManagementResults,
    inputs: &[PathBuf],
) -> Result<Committed, StudyError> {
    let json = |v: &dyn erased::Json| v.text();
    let mut out = OutputDir::begin(dir, inputs)?;
    write(
        &mut out,
        "summary.json",
        &json(&beam_management::report::summary(results)),
    )?;
    write(
        &mut out,
        "details.json",
        &json(&beam_management::report::details(results)),
    )?;
    write(
        &mut out,
        "decisions.csv",
        &beam_management::report::decisions_csv(results),
    )?;
    write(
        &mut out,
        "trajectory.csv",
        &beam_management::report::trajectory_csv(results),
    )?;
    let rows = results.scenarios.len().max(1) as u32;
    figure!(
        out,
        "accuracy-vs-overhead",
        (1200, 560 * rows),
        beam_management::plot::accuracy_vs_overhead,
        results,
        BeamManagementResults
    );
    figure!(
        out,
        "snr-loss-cdf",
        (1200, 560 * rows),
        beam_management::plot::snr_loss_cdf,
        results,
        BeamManagementResults
    );
    Ok(out.commit()?)
}

/// Pretty JSON with a final newline for any serialisable document.
mod erased {
    pub trait Json {
        fn text(&self) -> String;
    }
    impl<T: serde::Serialize> Json for T {
        fn text(&self) -> String {
            // Serialising plain data structs with string keys cannot fail.
            serde_json::to_string_pretty(self).unwrap_or_default() + "\n"
        }
    }
}
