//! `coil preview`: particles rendered orthographically to a PNG, coloured like the paper's
//! figures (viscosity from nu_inf to nu0) or by speed, with a colour bar.

pub use crate::output::image::Image;
use plotters::prelude::{BitMapBackend, IntoDrawingArea, RGBColor, TextStyle};
use std::path::Path;

/// Pixels right of the panels for the colour bar and its numbers.
const BAR_WIDTH: usize = 110;

/// Which way the camera looks.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum View {
    /// Along -z: x to the right, y (up) up.
    Side,
    /// Along -y: x to the right, z down the picture.
    Top,
    /// Side and top next to each other.
    Both,
}

/// Viridis, sampled at five points: dark purple (low) to yellow (high), as in the paper's
/// viscosity figures.
pub fn colormap(t: f64) -> [u8; 3] {
    const STOPS: [[f64; 3]; 5] =
        [[68.0, 1.0, 84.0], [59.0, 82.0, 139.0], [33.0, 145.0, 140.0], [94.0, 201.0, 98.0], [253.0, 231.0, 37.0]];
    let t = if t.is_finite() { t.clamp(0.0, 1.0) } else { 0.0 };
    let x = t * 4.0;
    let k = (x.floor() as usize).min(3);
    let f = x - k as f64;
    [0, 1, 2].map(|c| (STOPS[k][c] + f * (STOPS[k + 1][c] - STOPS[k][c])).round() as u8)
}

/// Renders particles at `position` (m) coloured by `value` mapped from `range.0` (dark) to
/// `range.1` (bright). Each panel is `size` pixels square; a colour bar with the range's numbers
/// sits on the right.
pub fn render(position: &[[f64; 3]], value: &[f32], range: (f64, f64), view: View, size: usize) -> Image {
    let panels: &[View] = match view {
        View::Side => &[View::Side],
        View::Top => &[View::Top],
        View::Both => &[View::Side, View::Top],
    };
    let mut img = Image::new(panels.len() * size + BAR_WIDTH, size);
    // One scale for every panel, so sizes compare between views.
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for p in position {
        for a in 0..3 {
            lo[a] = lo[a].min(p[a]);
            hi[a] = hi[a].max(p[a]);
        }
    }
    // The axes the panels show: a top view alone is not shrunk by the height of the jet.
    let shown: &[usize] = match view {
        View::Side => &[0, 1],
        View::Top => &[0, 2],
        View::Both => &[0, 1, 2],
    };
    let extent = shown.iter().map(|&a| hi[a] - lo[a]).fold(0.0, f64::max).max(1e-9);
    let margin = 0.06 * size as f64;
    let scale = (size as f64 - 2.0 * margin) / extent;
    let radius = (size as f64 / 260.0).max(1.0);
    let (vmin, vmax) = range;
    let span = if vmax > vmin { vmax - vmin } else { 1.0 };
    let mut order: Vec<usize> = (0..position.len()).collect();
    for (k, panel) in panels.iter().enumerate() {
        // (horizontal axis, vertical axis, depth axis towards the camera, vertical flipped)
        let (u, v, depth, up) = match panel {
            View::Side => (0, 1, 2, true),
            _ => (0, 2, 1, false),
        };
        // Far particles first, so near ones cover them; near ones are drawn brighter.
        order.sort_by(|&a, &b| position[a][depth].total_cmp(&position[b][depth]));
        let depth_span = (hi[depth] - lo[depth]).max(1e-9);
        let centre = [0, 1, 2].map(|a| 0.5 * (lo[a] + hi[a]));
        for &i in &order {
            let p = position[i];
            let x = k as f64 * size as f64 + 0.5 * size as f64 + (p[u] - centre[u]) * scale;
            let dy = (p[v] - centre[v]) * scale;
            let y = 0.5 * size as f64 + if up { -dy } else { dy };
            let shade = 0.65 + 0.35 * (p[depth] - lo[depth]) / depth_span;
            let c = colormap((value[i] as f64 - vmin) / span).map(|c| (c as f64 * shade) as u8);
            img.disc(x, y, radius, c);
        }
    }
    // Colour bar: bright at the top, with its top, middle and bottom values.
    let bar_left = (panels.len() * size + 12) as i64;
    let (top, bottom) = (margin as i64, size as i64 - margin as i64);
    for y in top..=bottom {
        let c = colormap((bottom - y) as f64 / (bottom - top).max(1) as f64);
        for x in bar_left..bar_left + 18 {
            img.put(x, y, c);
        }
    }
    let labels = [(top, vmax), ((top + bottom) / 2, 0.5 * (vmin + vmax)), (bottom - 12, vmin)];
    label(&mut img, labels.map(|(y, v)| ((bar_left + 24, y), format!("{v:.2e}"))));
    img
}

/// Writes each text with its top left corner at its pixel.
fn label<const N: usize>(img: &mut Image, texts: [((i64, i64), String); N]) {
    crate::output::font::register();
    let size = (img.width as u32, img.height as u32);
    let area = BitMapBackend::with_buffer(&mut img.pixels, size).into_drawing_area();
    let style = TextStyle::from((crate::output::font::FAMILY, 15)).color(&RGBColor(40, 40, 40));
    for ((x, y), text) in texts {
        // Text that does not fit is cut at the picture's edge by the backend; nothing else can fail.
        let _ = area.draw_text(&text, &style, (x as i32, y as i32));
    }
}

/// What the colours show.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Coloring {
    /// Kinematic viscosity nu (m^2/s).
    Viscosity,
    /// |v| (m/s).
    Speed,
}

/// The frame a path names: the file itself, or the last `frame_*.vtu` of a folder.
pub fn frame_path(path: &Path) -> Result<std::path::PathBuf, String> {
    if !path.is_dir() {
        return Ok(path.to_path_buf());
    }
    let entries = std::fs::read_dir(path).map_err(|e| format!("{}: cannot be read: {e}", path.display()))?;
    entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.file_name().and_then(|n| n.to_str()).is_some_and(|n| n.starts_with("frame_") && n.ends_with(".vtu")))
        .max()
        .ok_or_else(|| format!("{}: holds no frame_*.vtu", path.display()))
}

/// |v| (m/s) of each velocity.
pub fn speeds(velocity: &[[f32; 3]]) -> Vec<f32> {
    velocity.iter().map(|v| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()).collect()
}

/// The colour range of `value` by itself: its smallest to largest viscosity, or 0 to the top
/// speed; (0, 1) when there is nothing to show.
pub fn own_range(coloring: Coloring, value: &[f32]) -> (f64, f64) {
    let max = value.iter().copied().fold(f32::NEG_INFINITY, f32::max) as f64;
    let min = match coloring {
        Coloring::Viscosity => value.iter().copied().fold(f32::INFINITY, f32::min) as f64,
        Coloring::Speed => 0.0,
    };
    if min.is_finite() && max.is_finite() {
        (min, max)
    } else {
        (0.0, 1.0)
    }
}

/// Renders a frame file. `range` defaults to the frame's own smallest and largest value (for
/// viscosity, nu_inf and nu0 wherever the flow reaches both), or 0 to the largest speed.
pub fn render_frame(
    frame: &crate::output::vtu_read::FrameData,
    view: View,
    coloring: Coloring,
    range: Option<(f64, f64)>,
    size: usize,
) -> Result<Image, String> {
    let value: Vec<f32> = match coloring {
        Coloring::Viscosity => frame.scalars.get("viscosity").cloned().ok_or("the frame has no viscosity array")?,
        Coloring::Speed => speeds(frame.vectors.get("velocity").ok_or("the frame has no velocity array")?),
    };
    let range = range.unwrap_or_else(|| own_range(coloring, &value));
    Ok(render(&frame.position, &value, range, view, size))
}
