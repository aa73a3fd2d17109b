//! The only module of the studies that touches the filesystem: writes `results.csv`,
//! `summary.md` and the figures as SVG and PNG into an output directory.

use crate::living_room::{self, LivingRoomResults};
use crate::run::StudyResults;
use crate::{StudyError, plot, report};
use plotters::prelude::*;
use std::path::{Path, PathBuf};

/// Pixel size of Fig. 5 per drawn room and time step.
const ROOM_CELL: u32 = 300;

fn write(path: &Path, text: &str) -> Result<PathBuf, StudyError> {
    std::fs::write(path, text).map_err(|source| StudyError::Io {
        path: path.display().to_string(),
        source,
    })?;
    Ok(path.to_path_buf())
}

/// Draw one figure with `$draw(&root, $data)` to `$dir/$stem.svg` and `$dir/$stem.png`.
macro_rules! figure {
    ($out:expr, $dir:expr, $stem:expr, $size:expr, $draw:path, $data:expr) => {{
        for ext in ["svg", "png"] {
            let path = $dir.join(format!("{}.{ext}", $stem));
            let plot_error = |message: String| StudyError::Plot {
                path: path.display().to_string(),
                message,
            };
            if ext == "svg" {
                let root = SVGBackend::new(&path, $size).into_drawing_area();
                $draw(&root, $data).map_err(plot_error)?;
                root.present().map_err(|e| plot_error(e.to_string()))?;
            } else {
                let root = BitMapBackend::new(&path, $size).into_drawing_area();
                $draw(&root, $data).map_err(plot_error)?;
                root.present().map_err(|e| plot_error(e.to_string()))?;
            }
            $out.push(path);
        }
    }};
}

/// Write the power-delay profile of `taps` as `<stem>.svg` and `<stem>.png` (each to a temporary
/// file in the same directory, then renamed into place). Returns the files written.
pub fn write_power_delay_profile(
    stem: &Path,
    title: &str,
    taps: &[plot::PdpTap],
) -> Result<Vec<PathBuf>, StudyError> {
    let mut out = Vec::new();
    for ext in ["svg", "png"] {
        let path = stem.with_extension(ext);
        let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("pdp");
        let temp = path.with_file_name(format!(".{name}.{}.tmp.{ext}", std::process::id()));
        let plot_error = |message: String| StudyError::Plot {
            path: path.display().to_string(),
            message,
        };
        let drawn = if ext == "svg" {
            let root = SVGBackend::new(&temp, (900, 500)).into_drawing_area();
            plot::power_delay_profile(&root, (title, taps))
                .and_then(|()| root.present().map_err(|e| e.to_string()))
        } else {
            let root = BitMapBackend::new(&temp, (900, 500)).into_drawing_area();
            plot::power_delay_profile(&root, (title, taps))
                .and_then(|()| root.present().map_err(|e| e.to_string()))
        };
        if let Err(message) = drawn {
            let _ = std::fs::remove_file(&temp);
            return Err(plot_error(message));
        }
        std::fs::rename(&temp, &path).map_err(|source| StudyError::Io {
            path: path.display().to_string(),
            source,
        })?;
        out.push(path);
    }
    Ok(out)
}

/// Write every output of a study into `dir` (created if missing); returns the files written.
pub fn write_outputs(dir: &Path, results: &StudyResults) -> Result<Vec<PathBuf>, StudyError> {
    std::fs::create_dir_all(dir).map_err(|source| StudyError::Io {
        path: dir.display().to_string(),
        source,
    })?;
    let mut out = vec![
        write(&dir.join("results.csv"), &report::csv(results))?,
        write(&dir.join("summary.md"), &report::summary(results))?,
    ];
    figure!(
        out,
        dir,
        "fig6-angular-error",
        (1200, 900),
        plot::angular_error,
        results
    );
    figure!(
        out,
        dir,
        "fig7-elapsed-time",
        (1200, 480),
        plot::elapsed_time,
        results
    );
    let drawings = &results.drawings;
    let cols = drawings
        .iter()
        .map(|d| d.steps.len())
        .max()
        .unwrap_or(1)
        .max(1) as u32;
    let size = (ROOM_CELL * cols, ROOM_CELL * drawings.len().max(1) as u32);
    figure!(out, dir, "fig5-rooms", size, plot::rooms, drawings);
    Ok(out)
}

/// Write every output of the living-room study into `dir` (created if missing):
/// `results.csv`, `fpga.csv`, `summary.md`, `fig17-angular-error`, `fig18-ray-directions` and
/// `fig19-run-time` as SVG and PNG. Returns the files written.
pub fn write_living_room(
    dir: &Path,
    results: &LivingRoomResults,
) -> Result<Vec<PathBuf>, StudyError> {
    std::fs::create_dir_all(dir).map_err(|source| StudyError::Io {
        path: dir.display().to_string(),
        source,
    })?;
    let mut out = vec![
        write(&dir.join("results.csv"), &living_room::report::csv(results))?,
        write(
            &dir.join("fpga.csv"),
            &living_room::report::fpga_csv(results),
        )?,
        write(
            &dir.join("summary.md"),
            &living_room::report::summary(results),
        )?,
    ];
    figure!(
        out,
        dir,
        "fig17-angular-error",
        (1200, 480),
        living_room::plot::angular_error,
        results
    );
    let rays = &results.rays;
    let size = (1200, 420 * rays.len().max(1) as u32);
    figure!(
        out,
        dir,
        "fig18-ray-directions",
        size,
        living_room::plot::ray_directions,
        rays
    );
    figure!(
        out,
        dir,
        "fig19-run-time",
        (1000, 560),
        living_room::plot::run_time,
        results
    );
    Ok(out)
}
