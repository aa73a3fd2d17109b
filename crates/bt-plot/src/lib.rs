//! The chart setup every beamtrace figure shares: the shipped font, a white canvas, the legend
//! style, and writing one figure as SVG and PNG (atomically: temp file + rename); and the
//! figures that belong to no study: the power-delay profile of a trace ([`pdp`]).
//!
//! Text needs a font and the machines that draw figures may have none: DejaVu Sans (Bitstream
//! Vera licence, `assets/DejaVuSans-LICENSE.txt`) is compiled in and registered as
//! `sans-serif` by [`register_font`].

#![warn(missing_docs)]

pub mod pdp;

pub use pdp::{PdpTap, power_delay_profile, write_power_delay_profile};

use plotters::chart::MeshStyle;
use plotters::coord::ranged1d::{Ranged, ValueFormatter};
use plotters::coord::{CoordTranslate, Shift};
use plotters::prelude::*;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

const FONT: &[u8] = include_bytes!("../assets/DejaVuSans.ttf");
/// The font family of every label (the shipped DejaVu Sans).
pub const FAMILY: &str = "sans-serif";

/// Register the shipped font as `sans-serif` (idempotent). Must run before drawing text.
pub fn register_font() -> Result<(), String> {
    static DONE: OnceLock<Result<(), String>> = OnceLock::new();
    DONE.get_or_init(|| {
        plotters::style::register_font(FAMILY, FontStyle::Normal, FONT)
            .map_err(|_| "the shipped font DejaVuSans.ttf is not a valid font".to_string())
    })
    .clone()
}

/// A plotters error as the message the figure writers report.
pub fn fail<E: std::fmt::Display>(e: E) -> String {
    e.to_string()
}

/// Start a figure: register the font and fill the whole area white.
pub fn blank<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>) -> Result<(), String> {
    register_font()?;
    root.fill(&WHITE).map_err(fail)
}

/// Draw the legend of a chart: `font_size` text in a translucent white box with a black
/// border at `position`.
pub fn legend<'a, DB: DrawingBackend + 'a, CT: CoordTranslate>(
    chart: &mut ChartContext<'a, DB, CT>,
    position: SeriesLabelPosition,
    font_size: u32,
) -> Result<(), String> {
    chart
        .configure_series_labels()
        .position(position)
        .label_font((FAMILY, font_size))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
        .map_err(fail)
}

/// Start the mesh of a 2-D chart with axis titles `x_desc` and `y_desc` in the shipped font:
/// tick labels at `sizes.0` points and axis titles at `sizes.1` points. The caller adds what
/// its chart needs (label counts, formatters, `disable_mesh`) and draws it.
pub fn mesh<'a, 'b, DB, X, Y, XT, YT>(
    chart: &'b mut ChartContext<'a, DB, Cartesian2d<X, Y>>,
    (x_desc, y_desc): (&str, &str),
    sizes: (u32, u32),
) -> MeshStyle<'a, 'b, X, Y, DB>
where
    DB: DrawingBackend,
    X: Ranged<ValueType = XT> + ValueFormatter<XT>,
    Y: Ranged<ValueType = YT> + ValueFormatter<YT>,
{
    let mut mesh = chart.configure_mesh();
    mesh.x_desc(x_desc)
        .y_desc(y_desc)
        .label_style((FAMILY, sizes.0))
        .axis_desc_style((FAMILY, sizes.1));
    mesh
}

/// A figure that can draw itself on any plotters backend.
pub trait Figure {
    /// Draw on `root` (the caller presents it).
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), String>;
}

/// Why a figure could not be written.
#[derive(Debug, thiserror::Error)]
#[error("{path}: {message}")]
pub struct PlotError {
    /// The figure file.
    pub path: String,
    /// What went wrong (drawing or writing).
    pub message: String,
}

/// Write `figure` as `{stem}.svg` and `{stem}.png` of `size` pixels; each file is drawn into a
/// temporary file beside it and renamed into place. Returns the two paths.
pub fn write_svg_png(
    stem: &Path,
    size: (u32, u32),
    figure: &impl Figure,
) -> Result<[PathBuf; 2], PlotError> {
    let svg = with_extension(stem, "svg");
    let png = with_extension(stem, "png");
    atomically(&svg, |tmp| {
        let root = SVGBackend::new(tmp, size).into_drawing_area();
        figure.draw(&root)?;
        root.present().map_err(fail)
    })?;
    atomically(&png, |tmp| {
        let root = BitMapBackend::new(tmp, size).into_drawing_area();
        figure.draw(&root)?;
        root.present().map_err(fail)
    })?;
    Ok([svg, png])
}

fn with_extension(stem: &Path, ext: &str) -> PathBuf {
    let mut name = stem.as_os_str().to_owned();
    name.push(".");
    name.push(ext);
    PathBuf::from(name)
}

/// Why an atomic figure write failed: the drawing, or the file operations of `bt-output`.
enum Failure {
    Draw(String),
    Output(bt_output::OutputError),
}

impl From<bt_output::OutputError> for Failure {
    fn from(e: bt_output::OutputError) -> Self {
        Failure::Output(e)
    }
}

/// Draw into a temporary file beside `path` that keeps its extension (the backends pick the
/// format by extension) and rename it over `path` (`bt_output::write_atomic_via`); the
/// temporary file is removed on failure.
fn atomically(
    path: &Path,
    draw: impl FnOnce(&Path) -> Result<(), String>,
) -> Result<(), PlotError> {
    let error = |message: String| PlotError {
        path: path.display().to_string(),
        message,
    };
    if path.file_name().is_none() || path.extension().is_none() {
        return Err(error("not a file name".into()));
    }
    bt_output::write_atomic_via(path, |tmp| draw(tmp).map_err(Failure::Draw)).map_err(|e| match e {
        Failure::Draw(message) => error(message),
        Failure::Output(bt_output::OutputError::Io { source, .. }) => error(source.to_string()),
        Failure::Output(other) => error(other.to_string()),
    })
}
