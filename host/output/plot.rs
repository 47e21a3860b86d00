//! Line and scatter charts for the figures of `coil bench`, `coil validate` and `coil tradeoff`,
//! drawn by plotters: each one as SVG, as PNG (lettered in the embedded DejaVu Sans, so the
//! picture is the same on every machine), and its series as CSV to replot elsewhere.

use crate::output::write_atomically;
use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::fmt::Write as _;
use std::path::Path;

/// Distinct colours for series, in order of use.
pub const PALETTE: [[u8; 3]; 8] = [
    [31, 119, 180],
    [214, 39, 40],
    [44, 160, 44],
    [255, 127, 14],
    [148, 103, 189],
    [140, 86, 75],
    [23, 190, 207],
    [127, 127, 127],
];

/// Size of every chart (pixels).
const SIZE: (u32, u32) = (900, 640);
const FONT: &str = crate::output::font::FAMILY;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Line {
    None,
    Solid,
    Dashed,
}

/// One curve or point set.
#[derive(Debug, Clone)]
pub struct Curve {
    pub label: String,
    pub color: [u8; 3],
    /// (x, y) points; non-finite ones, and non-positive ones on a logarithmic axis, are skipped.
    pub points: Vec<[f64; 2]>,
    pub line: Line,
    /// Marker radius in pixels; 0 draws none.
    pub marker: f64,
}

impl Curve {
    /// A solid line with markers.
    pub fn new(label: impl Into<String>, color: [u8; 3], points: Vec<[f64; 2]>) -> Self {
        Self { label: label.into(), color, points, line: Line::Solid, marker: 3.0 }
    }
}

#[derive(Debug, Clone)]
pub struct Axis {
    pub label: String,
    pub log: bool,
}

impl Axis {
    pub fn linear(label: impl Into<String>) -> Self {
        Self { label: label.into(), log: false }
    }
    pub fn log(label: impl Into<String>) -> Self {
        Self { label: label.into(), log: true }
    }

    fn usable(&self, v: f64) -> bool {
        v.is_finite() && (!self.log || v > 0.0)
    }

    /// The shown interval around the usable values, 5 % wider each side (on a log axis, in
    /// decades).
    fn range(&self, values: impl Iterator<Item = f64>) -> (f64, f64) {
        let map = |v: f64| if self.log { v.log10() } else { v };
        let (lo, hi) = values
            .filter(|&v| self.usable(v))
            .map(map)
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(v), b.max(v)));
        let (lo, hi) = if lo.is_finite() { (lo, hi) } else { (0.0, 1.0) };
        let span = if hi > lo { hi - lo } else { lo.abs().max(1.0) * 0.1 };
        let (lo, hi) = (lo - 0.05 * span, hi + 0.05 * span);
        if self.log {
            (10f64.powf(lo), 10f64.powf(hi))
        } else {
            (lo, hi)
        }
    }
}

#[derive(Debug, Clone)]
pub struct Chart {
    pub title: String,
    pub x: Axis,
    pub y: Axis,
    pub series: Vec<Curve>,
}

fn rgb(c: [u8; 3]) -> RGBColor {
    RGBColor(c[0], c[1], c[2])
}

impl Chart {
    /// Writes `path` (a `.png`), the same chart as `.svg`, and its series as `.plot.csv`.
    pub fn save(&self, path: &Path) -> Result<(), String> {
        let write = |path: &Path, bytes: &[u8]| {
            write_atomically(path, bytes).map_err(|e| format!("{}: cannot be written: {e}", path.display()))
        };
        write(path, &self.to_png()?)?;
        write(&path.with_extension("svg"), self.to_svg()?.as_bytes())?;
        write(&path.with_extension("plot.csv"), self.to_csv().as_bytes())
    }

    pub fn to_svg(&self) -> Result<String, String> {
        let mut svg = String::new();
        self.draw(SVGBackend::with_string(&mut svg, SIZE).into_drawing_area())?;
        Ok(svg)
    }

    pub fn to_png(&self) -> Result<Vec<u8>, String> {
        let mut image = crate::output::image::Image::new(SIZE.0 as usize, SIZE.1 as usize);
        self.draw(BitMapBackend::with_buffer(&mut image.pixels, SIZE).into_drawing_area())?;
        Ok(image.to_png())
    }

    /// One row per point: the series' label, x and y, under a header of the axes' labels.
    pub fn to_csv(&self) -> String {
        let quote = |s: &str| format!("\"{}\"", s.replace('"', "\"\""));
        let mut csv = format!("series,{},{}\n", quote(&self.x.label), quote(&self.y.label));
        for s in &self.series {
            for p in &s.points {
                let _ = writeln!(csv, "{},{:e},{:e}", quote(&s.label), p[0], p[1]);
            }
        }
        csv
    }

    fn draw<DB: DrawingBackend>(&self, root: DrawingArea<DB, Shift>) -> Result<(), String> {
        // Both backends lay text out with the font's metrics.
        crate::output::font::register();
        let (x0, x1) = self.x.range(self.series.iter().flat_map(|s| s.points.iter().map(|p| p[0])));
        let (y0, y1) = self.y.range(self.series.iter().flat_map(|s| s.points.iter().map(|p| p[1])));
        match (self.x.log, self.y.log) {
            (false, false) => self.draw_in(root, x0..x1, y0..y1),
            (true, false) => self.draw_in(root, (x0..x1).log_scale(), y0..y1),
            (false, true) => self.draw_in(root, x0..x1, (y0..y1).log_scale()),
            (true, true) => self.draw_in(root, (x0..x1).log_scale(), (y0..y1).log_scale()),
        }
    }

    fn draw_in<DB: DrawingBackend, X, Y>(&self, root: DrawingArea<DB, Shift>, x: X, y: Y) -> Result<(), String>
    where
        X: AsRangedCoord<Value = f64>,
        Y: AsRangedCoord<Value = f64>,
        X::CoordDescType: ValueFormatter<f64>,
        Y::CoordDescType: ValueFormatter<f64>,
    {
        let failed = |e: DrawingAreaErrorKind<DB::ErrorType>| format!("the chart \"{}\" cannot be drawn: {e}", self.title);
        root.fill(&WHITE).map_err(failed)?;
        let mut chart = ChartBuilder::on(&root)
            .caption(&self.title, (FONT, 24))
            .margin(16)
            .x_label_area_size(56)
            .y_label_area_size(84)
            .build_cartesian_2d(x, y)
            .map_err(failed)?;
        chart
            .configure_mesh()
            .x_desc(&self.x.label)
            .y_desc(&self.y.label)
            .label_style((FONT, 15))
            .axis_desc_style((FONT, 17))
            .light_line_style(WHITE)
            .draw()
            .map_err(failed)?;
        for s in &self.series {
            let points: Vec<(f64, f64)> =
                s.points.iter().filter(|p| self.x.usable(p[0]) && self.y.usable(p[1])).map(|p| (p[0], p[1])).collect();
            let style = rgb(s.color).stroke_width(2);
            let (line, marker) = (s.line, s.marker as i32);
            chart
                .draw_series(points.iter().filter(|_| marker > 0).map(|&p| Circle::new(p, marker, rgb(s.color).filled())))
                .map_err(failed)?;
            // The legend entry hangs on one series: the line, or an empty one for markers alone.
            let entry = match line {
                Line::None => chart.draw_series(std::iter::empty::<PathElement<(f64, f64)>>()),
                Line::Solid => chart.draw_series(LineSeries::new(points, style)),
                Line::Dashed => chart.draw_series(DashedLineSeries::new(points, 8, 6, style)),
            }
            .map_err(failed)?;
            // Relative to the legend entry's anchor; a part the series does not draw is transparent.
            let line_style = if line == Line::None { TRANSPARENT.into() } else { style };
            let marker_style = if marker > 0 { style.filled() } else { TRANSPARENT.filled() };
            entry.label(&s.label).legend(move |(x, y)| {
                EmptyElement::at((x, y))
                    + PathElement::new(vec![(0, 0), (24, 0)], line_style)
                    + Circle::new((12, 0), marker.max(1), marker_style)
            });
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperLeft)
            .label_font((FONT, 15))
            .background_style(WHITE.mix(0.9))
            .border_style(RGBColor(160, 160, 160))
            .draw()
            .map_err(failed)?;
        root.present().map_err(failed)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn chart(x: Axis, y: Axis) -> Chart {
        let points = vec![[0.5, 1.0], [1.0, 100.0], [f64::NAN, 3.0]];
        Chart { title: "T".into(), x, y, series: vec![Curve::new("a \"b\"", PALETTE[1], points)] }
    }

    #[test]
    fn a_log_axis_shows_the_positive_values_five_percent_of_the_decades_wider() {
        let (lo, hi) = Axis::log("y").range([-1.0, 1.0, 100.0].into_iter());
        assert!((lo.log10() + 0.1).abs() < 1e-12 && (hi.log10() - 2.1).abs() < 1e-12, "{lo} {hi}");
        let (lo, hi) = Axis::linear("x").range([0.0, 10.0, f64::INFINITY].into_iter());
        assert!((lo + 0.5).abs() < 1e-12 && (hi - 10.5).abs() < 1e-12);
    }

    #[test]
    fn the_csv_holds_every_point_as_plotted_with_labels_quoted() {
        let csv = chart(Axis::linear("t (s)"), Axis::log("u")).to_csv();
        let rows: Vec<&str> = csv.lines().collect();
        assert_eq!(rows[0], "series,\"t (s)\",\"u\"");
        assert_eq!(rows[1], "\"a \"\"b\"\"\",5e-1,1e0");
        assert_eq!(rows.len(), 4);
    }

    #[test]
    fn every_combination_of_axes_draws_as_svg_and_png_with_its_labels() {
        for (x, y) in [(false, false), (true, false), (false, true), (true, true)] {
            let axis = |log, name: &str| if log { Axis::log(name) } else { Axis::linear(name) };
            let c = chart(axis(x, "time"), axis(y, "speed"));
            let svg = c.to_svg().expect("draws");
            let texts: Vec<&str> = svg.lines().map(str::trim).collect();
            for label in ["T", "time", "speed", "a &quot;b&quot;"] {
                assert!(texts.contains(&label), "{label} missing from {svg}");
            }
            let png = c.to_png().expect("draws");
            assert_eq!(&png[1..4], b"PNG");
        }
    }
}
