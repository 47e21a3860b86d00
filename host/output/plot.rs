//! Line and scatter charts as PNG, for the figures of `coil bench`, `coil validate` and
//! `coil tradeoff`: linear or logarithmic axes, ticks, a title and a legend.

use crate::output::image::{char_width, text, text_vertical, Image, INK};

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

const GRID: [u8; 3] = [225, 225, 225];
const FONT: i64 = 2;
const MARGIN_LEFT: f64 = 96.0;
const MARGIN_RIGHT: f64 = 24.0;
const MARGIN_TOP: f64 = 44.0;
const MARGIN_BOTTOM: f64 = 64.0;

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

    fn map(&self, v: f64) -> f64 {
        if self.log {
            v.log10()
        } else {
            v
        }
    }

    fn usable(&self, v: f64) -> bool {
        v.is_finite() && (!self.log || v > 0.0)
    }

    /// The shown interval, in mapped units, around the mapped data range.
    fn range(&self, values: impl Iterator<Item = f64>) -> (f64, f64) {
        let (lo, hi) = values
            .filter(|&v| self.usable(v))
            .map(|v| self.map(v))
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(v), b.max(v)));
        if !lo.is_finite() {
            return (0.0, 1.0);
        }
        let span = if hi > lo { hi - lo } else { lo.abs().max(1.0) * 0.1 };
        (lo - 0.05 * span, hi + 0.05 * span)
    }

    /// Tick values (data units) inside the mapped interval (lo, hi).
    fn ticks(&self, lo: f64, hi: f64) -> Vec<f64> {
        if self.log {
            let decades: Vec<f64> = (lo.ceil() as i32..=hi.floor() as i32).map(|k| 10f64.powi(k)).collect();
            if decades.len() >= 2 {
                return decades;
            }
            let mut ticks = Vec::new();
            for k in lo.floor() as i32..=hi.ceil() as i32 {
                for m in [1.0, 2.0, 5.0] {
                    let v = m * 10f64.powi(k);
                    if (lo..=hi).contains(&v.log10()) {
                        ticks.push(v);
                    }
                }
            }
            if ticks.len() >= 2 {
                return ticks;
            }
            // Less than a factor of 2.5 shown: evenly spaced values, placed on the log scale.
            return linear_ticks(10f64.powf(lo), 10f64.powf(hi));
        }
        linear_ticks(lo, hi)
    }
}

/// Round tick values inside (lo, hi), about six of them.
fn linear_ticks(lo: f64, hi: f64) -> Vec<f64> {
    let raw = (hi - lo) / 6.0;
    let magnitude = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0].iter().map(|m| m * magnitude).find(|&s| s >= raw).unwrap_or(10.0 * magnitude);
    let first = (lo / step).ceil() as i64;
    let last = (hi / step).floor() as i64;
    (first..=last).map(|k| k as f64 * step).collect()
}

/// A short label for a tick value.
fn tick_label(v: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    let a = v.abs();
    if (1e-3..1e5).contains(&a) {
        let s = format!("{v:.3}");
        let s = s.trim_end_matches('0').trim_end_matches('.');
        s.to_string()
    } else {
        format!("{v:.0e}")
    }
}

#[derive(Debug, Clone)]
pub struct Chart {
    pub title: String,
    pub x: Axis,
    pub y: Axis,
    pub series: Vec<Curve>,
}

impl Chart {
    pub fn render(&self, width: usize, height: usize) -> Image {
        let mut img = Image::new(width, height);
        let (x0, x1) = self.x.range(self.series.iter().flat_map(|s| s.points.iter().map(|p| p[0])));
        let (y0, y1) = self.y.range(self.series.iter().flat_map(|s| s.points.iter().map(|p| p[1])));
        let (left, right) = (MARGIN_LEFT, width as f64 - MARGIN_RIGHT);
        let (top, bottom) = (MARGIN_TOP, height as f64 - MARGIN_BOTTOM);
        let px = |v: f64| left + (self.x.map(v) - x0) / (x1 - x0) * (right - left);
        let py = |v: f64| bottom - (self.y.map(v) - y0) / (y1 - y0) * (bottom - top);

        for t in self.x.ticks(x0, x1) {
            let x = px(t);
            img.line(x, top, x, bottom, 1.0, 0.0, GRID);
            let label = tick_label(t);
            let w = label.len() as i64 * char_width(FONT);
            text(&mut img, x as i64 - w / 2, bottom as i64 + 8, &label, FONT);
        }
        for t in self.y.ticks(y0, y1) {
            let y = py(t);
            img.line(left, y, right, y, 1.0, 0.0, GRID);
            let label = tick_label(t);
            let w = label.len() as i64 * char_width(FONT);
            text(&mut img, left as i64 - 6 - w, y as i64 - 5, &label, FONT);
        }
        img.line(left, bottom, right, bottom, 1.5, 0.0, INK);
        img.line(left, top, left, bottom, 1.5, 0.0, INK);

        for s in &self.series {
            let points: Vec<(f64, f64)> =
                s.points.iter().filter(|p| self.x.usable(p[0]) && self.y.usable(p[1])).map(|p| (px(p[0]), py(p[1]))).collect();
            if s.line != Line::None {
                let dash = if s.line == Line::Dashed { 6.0 } else { 0.0 };
                for w in points.windows(2) {
                    img.line(w[0].0, w[0].1, w[1].0, w[1].1, 2.0, dash, s.color);
                }
            }
            if s.marker > 0.0 {
                for &(x, y) in &points {
                    img.disc(x, y, s.marker, s.color);
                }
            }
        }

        let title_w = self.title.len() as i64 * char_width(FONT);
        text(&mut img, (width as i64 - title_w) / 2, 14, &self.title, FONT);
        let xw = self.x.label.len() as i64 * char_width(FONT);
        text(&mut img, ((left + right) / 2.0) as i64 - xw / 2, height as i64 - 24, &self.x.label, FONT);
        text_vertical(&mut img, 8, ((top + bottom) / 2.0) as i64, &self.y.label, FONT);

        // Legend, top left inside the axes.
        let row = 16.0;
        let widest = self.series.iter().map(|s| s.label.len()).max().unwrap_or(0) as i64 * char_width(FONT);
        let (lx, ly) = (left + 10.0, top + 8.0);
        if !self.series.is_empty() {
            img.rect(
                lx as i64 - 4,
                ly as i64 - 4,
                lx as i64 + 40 + widest,
                (ly + row * self.series.len() as f64) as i64,
                [250, 250, 250],
            );
        }
        for (k, s) in self.series.iter().enumerate() {
            let y = ly + row * k as f64 + 5.0;
            if s.line != Line::None {
                img.line(lx, y, lx + 28.0, y, 2.0, if s.line == Line::Dashed { 6.0 } else { 0.0 }, s.color);
            }
            if s.marker > 0.0 {
                img.disc(lx + 14.0, y, s.marker, s.color);
            }
            text(&mut img, lx as i64 + 36, y as i64 - 5, &s.label, FONT);
        }
        img
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn linear_ticks_are_round_and_inside() {
        let ticks = Axis::linear("x").ticks(-0.03, 1.07);
        assert_eq!(ticks.len(), 6);
        assert!((ticks[1] - 0.2).abs() < 1e-12 && ticks[0] == 0.0);
    }

    #[test]
    fn log_ticks_are_decades_or_their_1_2_5_steps() {
        assert_eq!(Axis::log("x").ticks(-0.2, 3.3), vec![1.0, 10.0, 100.0, 1000.0]);
        assert_eq!(Axis::log("x").ticks(0.1, 0.9), vec![2.0, 5.0]);
        // 5.4 to 7.2: no 1-2-5 value inside, so evenly spaced ones.
        let narrow = Axis::log("x").ticks(5.4f64.log10(), 7.2f64.log10());
        assert!(narrow.len() >= 3 && narrow.iter().all(|&t| (5.4..=7.2).contains(&t)), "{narrow:?}");
    }

    #[test]
    fn a_point_is_drawn_where_its_axes_put_it() {
        let chart = Chart {
            title: "T".into(),
            x: Axis::linear("x"),
            y: Axis::log("y"),
            series: vec![Curve {
                label: "s".into(),
                color: PALETTE[1],
                points: vec![[0.0, 1.0], [1.0, 100.0]],
                line: Line::None,
                marker: 3.0,
            }],
        };
        let img = chart.render(400, 300);
        // The data span maps to the axes' inner 1/1.1 (5 % padding each side).
        let (left, right, top, bottom) = (MARGIN_LEFT, 400.0 - MARGIN_RIGHT, MARGIN_TOP, 300.0 - MARGIN_BOTTOM);
        let x = left + (0.05 / 1.1) * (right - left);
        let y = bottom - (0.05 / 1.1) * (bottom - top);
        assert_eq!(img.get(x.round() as usize, y.round() as usize), PALETTE[1]);
        let x = right - (0.05 / 1.1) * (right - left);
        let y = top + (0.05 / 1.1) * (bottom - top);
        assert_eq!(img.get(x.round() as usize, y.round() as usize), PALETTE[1]);
    }
}
