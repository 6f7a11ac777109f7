//! Line plots drawn with plotters into an [`Image`]: several series with a legend, linear or
//! logarithmic axes, and fixed or automatic ranges.

mod axis;
mod clip;

use plotters::coord::Shift;
use plotters::coord::combinators::{BindKeyPoints, IntoLogRange};
use plotters::coord::ranged1d::{Ranged, ValueFormatter};
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;

use self::axis::{Axis, tick_label};
use self::clip::{Clipped, clip_series, quietest_corner};
use crate::error::{VizError, draw_error};
use crate::image::Image;
use crate::text;

/// How a series is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SeriesStyle {
    Line,
    Dashed,
    Markers,
    LineWithMarkers,
}

/// One named sequence of (x, y) points. Points that cannot be shown (NaN, infinite, ≤ 0 on a log axis)
/// are dropped and break the line there.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Legend text; an empty label keeps the series out of the legend.
    pub label: String,
    pub points: Vec<(f64, f64)>,
    pub style: SeriesStyle,
    /// `None` takes the next colour of [`PALETTE`] by the series' position in the plot.
    pub colour: Option<[u8; 3]>,
}

impl Series {
    pub fn new(label: impl Into<String>, points: Vec<(f64, f64)>, style: SeriesStyle) -> Self {
        Self { label: label.into(), points, style, colour: None }
    }

    pub fn line(label: impl Into<String>, points: Vec<(f64, f64)>) -> Self {
        Self::new(label, points, SeriesStyle::Line)
    }

    pub fn dashed(label: impl Into<String>, points: Vec<(f64, f64)>) -> Self {
        Self::new(label, points, SeriesStyle::Dashed)
    }

    pub fn markers(label: impl Into<String>, points: Vec<(f64, f64)>) -> Self {
        Self::new(label, points, SeriesStyle::Markers)
    }

    pub fn line_with_markers(label: impl Into<String>, points: Vec<(f64, f64)>) -> Self {
        Self::new(label, points, SeriesStyle::LineWithMarkers)
    }

    /// The same series in a fixed colour instead of the palette's.
    pub fn with_colour(self, colour: [u8; 3]) -> Self {
        Self { colour: Some(colour), ..self }
    }
}

/// Where the legend goes inside the plot area.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LegendPosition {
    /// The corner that hides the least data.
    Auto,
    UpperLeft,
    UpperRight,
    LowerLeft,
    LowerRight,
    Hidden,
}

/// Series colours in order: the ten "Tableau 10" hues, distinct on white and in print.
pub const PALETTE: [[u8; 3]; 10] = [
    [31, 119, 180],
    [255, 127, 14],
    [44, 160, 44],
    [214, 39, 40],
    [148, 103, 189],
    [140, 86, 75],
    [227, 119, 194],
    [127, 127, 127],
    [188, 189, 34],
    [23, 190, 207],
];

/// A 2-D line plot. Ranges left `None` are fitted to the data (x over all shown points, y over those
/// inside the x range); a given y range also clips a diverging series instead of letting it squash the
/// rest.
#[derive(Debug, Clone, PartialEq)]
pub struct LinePlot {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub series: Vec<Series>,
    pub log_x: bool,
    pub log_y: bool,
    pub x_range: Option<(f64, f64)>,
    pub y_range: Option<(f64, f64)>,
    pub legend: LegendPosition,
}

impl LinePlot {
    /// An empty plot with linear axes, automatic ranges and an automatically placed legend.
    pub fn new(title: impl Into<String>, x_label: impl Into<String>, y_label: impl Into<String>) -> Self {
        Self {
            title: title.into(),
            x_label: x_label.into(),
            y_label: y_label.into(),
            series: Vec::new(),
            log_x: false,
            log_y: false,
            x_range: None,
            y_range: None,
            legend: LegendPosition::Auto,
        }
    }

    /// Adds a series (builder style).
    pub fn with_series(mut self, series: Series) -> Self {
        self.series.push(series);
        self
    }

    /// Draws the plot on white at `width × height` pixels. Text and lines scale with the smaller side,
    /// reading best from about 600 pixels up.
    ///
    /// Fails for an invalid picture size or a given range that is empty, not finite, or not positive on
    /// a log axis. Series without a single showable point still get their legend entry.
    pub fn render(&self, width: u32, height: u32) -> Result<Image, VizError> {
        let mut image = Image::new(width, height, [255, 255, 255])?;
        text::register_fonts();

        let x = Axis::resolve(
            "x",
            self.log_x,
            self.x_range,
            self.points().map(|p| Axis::axis_coord(self.log_x, p.0)),
        )?;
        let y = Axis::resolve(
            "y",
            self.log_y,
            self.y_range,
            self.points()
                .filter(|p| x.contains(Axis::axis_coord(self.log_x, p.0)))
                .map(|p| Axis::axis_coord(self.log_y, p.1)),
        )?;
        let clipped: Vec<Clipped> = self.series.iter().map(|s| clip_series(&s.points, &x, &y)).collect();
        let layout = Layout::new(self, &y, width, height);
        let legend = match self.legend {
            LegendPosition::Auto => {
                Some(quietest_corner(&clipped, &x, &y, layout.legend_fraction.0, layout.legend_fraction.1))
            }
            LegendPosition::Hidden => None,
            fixed => Some(fixed),
        }
        .filter(|_| self.series.iter().any(|s| !s.label.is_empty()));
        let frame = Frame { plot: self, clipped: &clipped, layout: &layout, legend };

        let root = BitMapBackend::with_buffer(image.rgb_mut(), (width, height)).into_drawing_area();
        let linear = |axis: &Axis| {
            let (lo, hi) = axis.data_range();
            RangedCoordf64::from(lo..hi)
        };
        // Explicit ticks: plotters' own log ticks stop at 2.2·10⁻¹⁶ (see `Axis::log_ticks`).
        let log = |axis: &Axis| {
            let ((lo, hi), (bold, light)) = (axis.data_range(), axis.log_ticks());
            (lo..hi).log_scale().with_key_points(bold).with_light_points(light)
        };
        match (self.log_x, self.log_y) {
            (false, false) => frame.draw(&root, linear(&x), linear(&y))?,
            (true, false) => frame.draw(&root, log(&x), linear(&y))?,
            (false, true) => frame.draw(&root, linear(&x), log(&y))?,
            (true, true) => frame.draw(&root, log(&x), log(&y))?,
        }
        root.present().map_err(draw_error)?;
        drop(root);
        Ok(image)
    }

    fn points(&self) -> impl Iterator<Item = &(f64, f64)> {
        self.series.iter().flat_map(|s| s.points.iter())
    }

    fn colour(&self, k: usize) -> RGBColor {
        let [r, g, b] = self.series[k].colour.unwrap_or(PALETTE[k % PALETTE.len()]);
        RGBColor(r, g, b)
    }
}

/// Sizes in pixels, scaled with the picture.
#[derive(Debug)]
struct Layout {
    scale: f64,
    title_size: f64,
    desc_size: f64,
    tick_size: f64,
    legend_size: f64,
    x_label_area: u32,
    y_label_area: u32,
    margin: u32,
    /// Estimated legend box size as fractions of the plot area's width and height.
    legend_fraction: (f64, f64),
}

impl Layout {
    fn new(plot: &LinePlot, y: &Axis, width: u32, height: u32) -> Self {
        let scale = (f64::from(width.min(height)) / 600.0).clamp(0.5, 4.0);
        let (title_size, desc_size, tick_size, legend_size) =
            (22.0 * scale, 18.0 * scale, 15.0 * scale, 15.0 * scale);
        // Average DejaVu Sans glyph width is about 0.6 em.
        let text_width = |chars: usize, size: f64| chars as f64 * size * 0.6;
        let widest_tick = y.approximate_tick_labels().iter().map(|t| t.chars().count()).max().unwrap_or(3);
        let tick_room = text_width(widest_tick.max(2), tick_size) + 12.0 * scale;
        let desc_room = if plot.y_label.is_empty() { 0.0 } else { desc_size * 1.3 + 6.0 * scale };
        let y_label_area = (tick_room + desc_room).round() as u32;
        let x_desc_room = if plot.x_label.is_empty() { 0.0 } else { desc_size * 1.3 };
        let x_label_area = (tick_size * 1.6 + x_desc_room + 6.0 * scale).round() as u32;
        let margin = (14.0 * scale).round() as u32;
        let title_room = if plot.title.is_empty() { 0.0 } else { title_size * 1.6 };

        let area_w = f64::from(width) - f64::from(y_label_area) - 3.0 * f64::from(margin);
        let area_h = f64::from(height) - f64::from(x_label_area) - 2.0 * f64::from(margin) - title_room;
        let labelled: Vec<&Series> = plot.series.iter().filter(|s| !s.label.is_empty()).collect();
        let widest_label = labelled.iter().map(|s| s.label.chars().count()).max().unwrap_or(0);
        let legend_w = text_width(widest_label, legend_size) + 60.0 * scale;
        let legend_h = labelled.len() as f64 * legend_size * 1.45 + 24.0 * scale;
        let legend_fraction = ((legend_w / area_w.max(1.0)).min(1.0), (legend_h / area_h.max(1.0)).min(1.0));
        Self {
            scale,
            title_size,
            desc_size,
            tick_size,
            legend_size,
            x_label_area,
            y_label_area,
            margin,
            legend_fraction,
        }
    }
}

/// Everything needed to draw one plot once the coordinate types are chosen.
struct Frame<'p> {
    plot: &'p LinePlot,
    clipped: &'p [Clipped],
    layout: &'p Layout,
    legend: Option<LegendPosition>,
}

impl Frame<'_> {
    fn draw<X, Y>(&self, root: &DrawingArea<BitMapBackend<'_>, Shift>, x: X, y: Y) -> Result<(), VizError>
    where
        X: Ranged<ValueType = f64> + ValueFormatter<f64>,
        Y: Ranged<ValueType = f64> + ValueFormatter<f64>,
    {
        let (plot, l) = (self.plot, self.layout);
        let s = l.scale;
        let mut builder = ChartBuilder::on(root);
        builder
            .margin(l.margin)
            .margin_right(l.margin * 2)
            .x_label_area_size(l.x_label_area)
            .y_label_area_size(l.y_label_area);
        if !plot.title.is_empty() {
            builder.caption(&plot.title, text::font(l.title_size));
        }
        let mut chart = builder.build_cartesian_2d(x, y).map_err(draw_error)?;

        let x_fmt = |v: &f64| tick_label(*v, plot.log_x);
        let y_fmt = |v: &f64| tick_label(*v, plot.log_y);
        chart
            .configure_mesh()
            .x_desc(&plot.x_label)
            .y_desc(&plot.y_label)
            .axis_desc_style(text::font(l.desc_size))
            .label_style(text::font(l.tick_size))
            .x_label_formatter(&x_fmt)
            .y_label_formatter(&y_fmt)
            .x_labels(9)
            .y_labels(9)
            .bold_line_style(RGBColor(222, 222, 222).stroke_width(1))
            .light_line_style(RGBColor(243, 243, 243).stroke_width(1))
            .max_light_lines(4)
            .axis_style(RGBColor(60, 60, 60).stroke_width(1))
            .set_all_tick_mark_size((5.0 * s) as i32)
            .draw()
            .map_err(draw_error)?;

        let line_width = (2.0 * s).round().max(1.0) as u32;
        let marker_radius = (3.5 * s).round().max(2.0) as i32;
        let dash = (9.0 * s).round() as i32;
        let legend_len = (26.0 * s).round() as i32;
        for (k, (series, clipped)) in plot.series.iter().zip(self.clipped).enumerate() {
            let colour = plot.colour(k);
            let stroke = colour.stroke_width(line_width);
            let (lines, markers) = match series.style {
                SeriesStyle::Line | SeriesStyle::Dashed => (true, false),
                SeriesStyle::Markers => (false, true),
                SeriesStyle::LineWithMarkers => (true, true),
            };
            if lines {
                for line in &clipped.polylines {
                    if series.style == SeriesStyle::Dashed {
                        chart
                            .draw_series(DashedLineSeries::new(
                                line.iter().copied(),
                                dash,
                                dash * 2 / 3,
                                stroke,
                            ))
                            .map_err(draw_error)?;
                    } else {
                        chart
                            .draw_series(LineSeries::new(line.iter().copied(), stroke))
                            .map_err(draw_error)?;
                    }
                }
            }
            if markers {
                let dots = clipped.markers.iter().map(|&p| Circle::new(p, marker_radius, colour.filled()));
                chart.draw_series(dots).map_err(draw_error)?;
            }
            if series.label.is_empty() || self.legend.is_none() {
                continue;
            }
            // The legend entry hangs on an empty series, so it exists even if nothing was drawable.
            let anno =
                chart.draw_series(std::iter::empty::<Circle<(f64, f64), i32>>()).map_err(draw_error)?;
            anno.label(series.label.as_str());
            match series.style {
                SeriesStyle::Line => {
                    anno.legend(move |(px, py)| PathElement::new([(px, py), (px + legend_len, py)], stroke));
                }
                SeriesStyle::Dashed => {
                    let third = legend_len / 3;
                    anno.legend(move |(px, py)| {
                        EmptyElement::at((px, py))
                            + PathElement::new([(0, 0), (third - 1, 0)], stroke)
                            + PathElement::new([(2 * third + 1, 0), (legend_len, 0)], stroke)
                    });
                }
                SeriesStyle::Markers => {
                    anno.legend(move |(px, py)| {
                        Circle::new((px + legend_len / 2, py), marker_radius, colour.filled())
                    });
                }
                SeriesStyle::LineWithMarkers => {
                    anno.legend(move |(px, py)| {
                        EmptyElement::at((px, py))
                            + PathElement::new([(0, 0), (legend_len, 0)], stroke)
                            + Circle::new((legend_len / 2, 0), marker_radius, colour.filled())
                    });
                }
            }
        }

        if let Some(position) = self.legend {
            let position = match position {
                LegendPosition::UpperLeft => SeriesLabelPosition::UpperLeft,
                LegendPosition::LowerLeft => SeriesLabelPosition::LowerLeft,
                LegendPosition::LowerRight => SeriesLabelPosition::LowerRight,
                LegendPosition::UpperRight | LegendPosition::Auto | LegendPosition::Hidden => {
                    SeriesLabelPosition::UpperRight
                }
            };
            chart
                .configure_series_labels()
                .position(position)
                .margin((10.0 * s) as i32)
                .legend_area_size((legend_len + (8.0 * s) as i32).max(1))
                .label_font(text::font(l.legend_size))
                .background_style(WHITE.mix(0.88))
                .border_style(RGBColor(170, 170, 170))
                .draw()
                .map_err(draw_error)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn count_colour(img: &Image, colour: [u8; 3]) -> usize {
        (0..img.height())
            .flat_map(|y| (0..img.width()).map(move |x| (x, y)))
            .filter(|&(x, y)| img.pixel(x, y) == colour)
            .count()
    }

    #[test]
    fn series_with_nan_renders_and_draws_its_colour() {
        let points = (0..100)
            .map(|k| {
                let t = k as f64 * 0.1;
                (t, if k % 17 == 5 { f64::NAN } else { 2.0 + 2.0 * t.cos() })
            })
            .collect();
        let plot = LinePlot::new("x(t)", "t [s]", "x [m]").with_series(Series::line("exact", points));
        let img = plot.render(640, 480).unwrap();
        assert_eq!((img.width(), img.height()), (640, 480));
        assert!(count_colour(&img, PALETTE[0]) > 300, "series colour barely drawn");
    }

    #[test]
    fn diverging_series_is_clipped_to_the_given_y_range() {
        let blow_up = (0..200).map(|k| (k as f64 * 0.05, (k as f64 * 0.2).exp())).collect();
        let mut plot = LinePlot::new("", "t", "x").with_series(Series::line_with_markers("h = 0.5", blow_up));
        plot.series.push(Series::dashed("", vec![(0.0, 0.0), (10.0, 1.0), (f64::INFINITY, 2.0)]));
        plot.y_range = Some((-1.0, 5.0));
        plot.render(400, 300).unwrap();
        plot.y_range = Some((5.0, -1.0));
        assert!(matches!(plot.render(400, 300), Err(VizError::InvalidRange { axis: "y", .. })));
    }

    #[test]
    fn log_log_plot_skips_non_positive_points_and_labels_decades() {
        let points =
            (-1..8).map(|k| (10f64.powi(k), if k == 3 { 0.0 } else { 10f64.powi(-2 * k) })).collect();
        let mut plot =
            LinePlot::new("work–precision", "steps", "error").with_series(Series::markers("RK4", points));
        plot.log_x = true;
        plot.log_y = true;
        plot.legend = LegendPosition::LowerLeft;
        plot.render(500, 400).unwrap();
        plot.x_range = Some((0.0, 10.0));
        assert!(plot.render(500, 400).is_err(), "log axis from zero accepted");
    }

    #[test]
    fn empty_plot_and_series_without_points_render() {
        let mut plot = LinePlot::new("nothing", "", "");
        plot.render(300, 200).unwrap();
        plot.series.push(Series::line("tiny", vec![(0.0, 1.0), (1.0, 2.0)]));
        for (w, h) in [(1, 1), (20, 15), (90, 60)] {
            let img = plot.render(w, h);
            assert!(img.is_ok() || matches!(img, Err(VizError::Draw(_))), "{w}×{h}: {img:?}");
        }
        plot.series.push(Series::line("all NaN", vec![(f64::NAN, 1.0); 3]));
        plot.render(300, 200).unwrap();
    }

    #[test]
    fn auto_legend_avoids_a_rising_line() {
        let line = Series::line("y = x", (0..=50).map(|k| (k as f64, k as f64)).collect());
        let plot = LinePlot::new("", "", "").with_series(line);
        let x = Axis::resolve("x", false, None, plot.points().map(|p| p.0)).unwrap();
        let y = Axis::resolve("y", false, None, plot.points().map(|p| p.1)).unwrap();
        let clipped = [clip_series(&plot.series[0].points, &x, &y)];
        let corner = quietest_corner(&clipped, &x, &y, 0.3, 0.2);
        assert!(matches!(corner, LegendPosition::UpperLeft | LegendPosition::LowerRight), "{corner:?}");
    }
}
