//! The heat map of a sweep over the floor plan: one cell per grid point coloured by a
//! quantity (viridis), the scene's surfaces projected onto the xy plane as outlines
//! (reflectors black, blockers grey), the TX as a red triangle, skipped points hatched grey.

use crate::{Grid, PointStatus, Row};
use bt_geom::Real;
use bt_plot::{FAMILY, blank, fail, mesh};
use bt_scene::{Scene, SurfaceKind};
use plotters::coord::Shift;
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use plotters::style::colors::colormaps::{ColorMap, ViridisRGB};

/// What the heat map shows per grid point.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum MapQuantity {
    /// Gain of the strongest path, dB (the negated loss: free space plus reflections).
    #[default]
    StrongestGain,
    /// Number of valid paths.
    Paths,
    /// Delay of the shortest path, ns.
    ShortestDelay,
}

impl MapQuantity {
    /// Colour-bar title.
    pub fn label(self) -> &'static str {
        match self {
            MapQuantity::StrongestGain => "strongest path gain (dB)",
            MapQuantity::Paths => "number of paths",
            MapQuantity::ShortestDelay => "shortest delay (ns)",
        }
    }

    /// The value at a traced point (`None`: no path, or skipped).
    pub fn value(self, status: &PointStatus) -> Option<Real> {
        let PointStatus::Traced {
            paths,
            shortest_delay_s,
            strongest,
            ..
        } = status
        else {
            return None;
        };
        match self {
            MapQuantity::StrongestGain => strongest.as_ref().map(|s| -s.loss_db),
            MapQuantity::Paths => Some(*paths as Real),
            MapQuantity::ShortestDelay => shortest_delay_s.map(|d| d * 1e9),
        }
    }
}

/// A heat map ready to draw (implements [`bt_plot::Figure`]).
pub struct HeatMap<'a> {
    /// The scene whose outlines and TX are drawn.
    pub scene: &'a Scene,
    /// The grid the rows come from (cell size).
    pub grid: &'a Grid,
    /// The sweep's rows.
    pub rows: &'a [Row],
    /// What to colour by.
    pub quantity: MapQuantity,
}

/// Pixel width of the colour bar column.
const BAR_WIDTH: u32 = 150;
/// Cells of a traced point without any path.
const NO_PATH: RGBColor = RGBColor(30, 30, 30);
/// Cells of a skipped point.
const SKIPPED: RGBColor = RGBColor(200, 200, 200);

impl HeatMap<'_> {
    /// Range of the plotted values (a unit range around a single value).
    fn range(&self) -> (Real, Real) {
        let values = self
            .rows
            .iter()
            .filter_map(|r| self.quantity.value(&r.status));
        let (lo, hi) = values.fold((Real::INFINITY, Real::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
        if !lo.is_finite() {
            (0.0, 1.0)
        } else if hi - lo < 1e-9 {
            (lo - 0.5, hi + 0.5)
        } else {
            (lo, hi)
        }
    }

    /// The plotted xy window: the grid and the scene's surfaces, with a small margin.
    fn window(&self) -> ((Real, Real), (Real, Real)) {
        let (hx, hy) = (self.grid.x.step / 2.0, self.grid.y.step / 2.0);
        let (mut x0, mut x1) = (self.grid.x.start - hx, self.grid.x.stop + hx);
        let (mut y0, mut y1) = (self.grid.y.start - hy, self.grid.y.stop + hy);
        for s in self.scene.surfaces() {
            let (lo, hi) = s.polygon.bounds();
            (x0, x1, y0, y1) = (x0.min(lo.x), x1.max(hi.x), y0.min(lo.y), y1.max(hi.y));
        }
        let m = 0.03 * (x1 - x0).max(y1 - y0);
        ((x0 - m, x1 + m), (y0 - m, y1 + m))
    }

    fn draw_map<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        range: (Real, Real),
    ) -> Result<(), String> {
        let ((x0, x1), (y0, y1)) = self.window();
        let title = format!(
            "{}: {} at z = {} m",
            self.scene.name(),
            self.quantity.label(),
            self.grid.z
        );
        let mut chart = ChartBuilder::on(area)
            .caption(title, (FAMILY, 18))
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(50)
            .build_cartesian_2d(x0..x1, y0..y1)
            .map_err(fail)?;
        mesh(&mut chart, ("x (m)", "y (m)"), (12, 14))
            .disable_mesh()
            .draw()
            .map_err(fail)?;
        let (hx, hy) = (self.grid.x.step / 2.0, self.grid.y.step / 2.0);
        let (lo, hi) = range;
        chart
            .draw_series(self.rows.iter().map(|r| {
                let colour = match (&r.status, self.quantity.value(&r.status)) {
                    (PointStatus::Skipped(_), _) => SKIPPED,
                    (_, Some(v)) => ViridisRGB.get_color_normalized(v as f32, lo as f32, hi as f32),
                    (_, None) => NO_PATH,
                };
                let (x, y) = (r.rx.x, r.rx.y);
                Rectangle::new([(x - hx, y - hy), (x + hx, y + hy)], colour.filled())
            }))
            .map_err(fail)?;
        // Skipped points also get a cross, so they read as "not traced" in grey scale too.
        chart
            .draw_series(
                self.rows
                    .iter()
                    .filter(|r| matches!(r.status, PointStatus::Skipped(_)))
                    .map(|r| Cross::new((r.rx.x, r.rx.y), 3, BLACK.stroke_width(1))),
            )
            .map_err(fail)?;
        for s in self.scene.surfaces() {
            let colour = match s.kind {
                SurfaceKind::Reflector => BLACK.mix(0.8),
                SurfaceKind::Blocker => RGBColor(120, 120, 120).mix(0.9),
            };
            let mut outline: Vec<(Real, Real)> = s
                .polygon
                .vertices()
                .iter()
                .map(|v| {
                    let v = self.scene.to_world(*v);
                    (v.x, v.y)
                })
                .collect();
            outline.push(outline[0]);
            chart
                .draw_series(std::iter::once(PathElement::new(
                    outline,
                    colour.stroke_width(1),
                )))
                .map_err(fail)?;
        }
        // `sweep` refuses a scene without a TX; a map of one draws no marker, not a made-up one.
        if let Some(tx) = self.scene.tx_world() {
            chart
                .draw_series(std::iter::once(TriangleMarker::new(
                    (tx.x, tx.y),
                    8,
                    RED.filled(),
                )))
                .map_err(fail)?
                .label("TX")
                .legend(|(x, y)| TriangleMarker::new((x + 5, y), 6, RED.filled()));
        }
        self.draw_legend(&mut chart)
    }

    /// The legend of what the colour bar does not say: skipped points and points without a
    /// path, each only when the map has one, and the TX.
    fn draw_legend<'c, DB: DrawingBackend + 'c>(
        &self,
        chart: &mut ChartContext<'c, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
    ) -> Result<(), String> {
        let skipped = |r: &&Row| matches!(r.status, PointStatus::Skipped(_));
        let no_path = |r: &&Row| !skipped(r) && self.quantity.value(&r.status).is_none();
        let entries = [
            (
                self.rows.iter().any(|r| skipped(&r)),
                SKIPPED,
                "skipped: on a surface or at the TX",
            ),
            (
                self.rows.iter().any(|r| no_path(&r)),
                NO_PATH,
                "traced, no path",
            ),
        ];
        for (present, colour, text) in entries {
            if present {
                chart
                    .draw_series(std::iter::empty::<Rectangle<(Real, Real)>>())
                    .map_err(fail)?
                    .label(text)
                    .legend(move |(x, y)| {
                        Rectangle::new([(x, y - 5), (x + 10, y + 5)], colour.filled())
                    });
            }
        }
        chart
            .configure_series_labels()
            .label_font((FAMILY, 12))
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .position(SeriesLabelPosition::LowerRight)
            .draw()
            .map_err(fail)
    }

    fn draw_bar<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        (lo, hi): (Real, Real),
    ) -> Result<(), String> {
        let mut chart = ChartBuilder::on(area)
            .margin_top(40)
            .margin_bottom(50)
            .margin_right(10)
            .y_label_area_size(60)
            .build_cartesian_2d(0.0..1.0, lo..hi)
            .map_err(fail)?;
        chart
            .configure_mesh()
            .disable_mesh()
            .disable_x_axis()
            .y_desc(self.quantity.label())
            .label_style((FAMILY, 12))
            .axis_desc_style((FAMILY, 13))
            .draw()
            .map_err(fail)?;
        let n = 100;
        let step = (hi - lo) / n as Real;
        chart
            .draw_series((0..n).map(|k| {
                let v0 = lo + k as Real * step;
                let c =
                    ViridisRGB.get_color_normalized((v0 + step / 2.0) as f32, lo as f32, hi as f32);
                Rectangle::new([(0.0, v0), (1.0, v0 + step)], c.filled())
            }))
            .map_err(fail)?;
        Ok(())
    }
}

impl bt_plot::Figure for HeatMap<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), String> {
        blank(root)?;
        let (w, _) = root.dim_in_pixel();
        let (map, bar) = root.split_horizontally(w.saturating_sub(BAR_WIDTH));
        let range = self.range();
        self.draw_map(&map, range)?;
        self.draw_bar(&bar, range)
    }
}

/// Pixel size of a heat map: 800 px across the longer side of the window plus the bar.
pub fn size(map: &HeatMap<'_>) -> (u32, u32) {
    let ((x0, x1), (y0, y1)) = map.window();
    let (w, h) = (x1 - x0, y1 - y0);
    let scale = 800.0 / w.max(h);
    ((w * scale) as u32 + BAR_WIDTH + 60, (h * scale) as u32 + 90)
}

impl HeatMap<'_> {
    /// Write the map as `{stem}.svg` and `{stem}.png`.
    pub fn write(
        &self,
        stem: &std::path::Path,
    ) -> Result<[std::path::PathBuf; 2], crate::CoverageError> {
        Ok(bt_plot::write_svg_png(stem, size(self), self)?)
    }
}
