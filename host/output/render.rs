//! Shaded pictures of a frame's free surface (`surface`), the way the paper shows its jets: an
//! orthographic camera per view, fixed across a run's frames, a z-buffer, Gouraud-shaded
//! triangles coloured by the fluid's viscosity or speed, the plate drawn as a grey slab, the
//! simulated time, a scale bar and a colour bar naming its quantity and unit.

use crate::output::image::Image;
use crate::output::preview::colormap;
use crate::output::surface::SurfaceMesh;
use plotters::prelude::{BitMapBackend, IntoDrawingArea, RGBColor, TextStyle};

/// Where a camera looks from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Camera {
    /// Along -z: x to the right, y up.
    Front,
    /// Along -x: -z to the right, y up.
    Side,
    /// Along -y: x to the right, z down the picture.
    Top,
    /// From 35 degrees round from the front towards +x and 25 degrees above the plate.
    Oblique,
}

impl Camera {
    pub const ALL: [Camera; 4] = [Camera::Front, Camera::Side, Camera::Top, Camera::Oblique];

    pub fn name(self) -> &'static str {
        match self {
            Camera::Front => "front (along -z)",
            Camera::Side => "side (along -x)",
            Camera::Top => "top",
            Camera::Oblique => "oblique",
        }
    }

    /// The screen's right, up and towards-the-viewer directions, orthonormal.
    fn basis(self) -> [[f64; 3]; 3] {
        match self {
            Camera::Front => [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            Camera::Side => [[0.0, 0.0, -1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]],
            Camera::Top => [[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]],
            Camera::Oblique => {
                let (azimuth, elevation) = (35f64.to_radians(), 25f64.to_radians());
                let back = [elevation.cos() * azimuth.sin(), elevation.sin(), elevation.cos() * azimuth.cos()];
                let right = [azimuth.cos(), 0.0, -azimuth.sin()];
                [right, cross(back, right), back]
            }
        }
    }
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// What a run's pictures share: the box the cameras frame (m), the plate, and the colours.
#[derive(Debug, Clone, PartialEq)]
pub struct Stage {
    pub min_m: [f64; 3],
    pub max_m: [f64; 3],
    /// The plate's top (m) and thickness drawn (m), if there is one, spanning the box in x and z.
    pub plate: Option<(f64, f64)>,
    /// The colour bar's quantity and unit, e.g. "viscosity nu (m^2/s)", and its range.
    pub quantity: String,
    pub range: (f64, f64),
    /// Pixels per panel side.
    pub size: usize,
}

/// Pixels right of the panels for the colour bar.
const BAR_WIDTH: usize = 150;
/// Pixels above the panels for the time and the views' names.
const TITLE_HEIGHT: usize = 28;
/// The light: from above, in front and to the right (unit vector towards it).
const LIGHT: [f64; 3] = [0.3, 0.8, 0.52];

struct Projection {
    basis: [[f64; 3]; 3],
    /// Pixels per metre, and the screen point of the box's centre.
    scale: f64,
    centre: [f64; 3],
    origin: (f64, f64),
}

impl Projection {
    /// Screen x, y (pixels, y down) and depth towards the viewer (m).
    fn project(&self, p: [f64; 3]) -> [f64; 3] {
        let r = [p[0] - self.centre[0], p[1] - self.centre[1], p[2] - self.centre[2]];
        let [right, up, back] = self.basis;
        [self.origin.0 + dot(r, right) * self.scale, self.origin.1 - dot(r, up) * self.scale, dot(r, back)]
    }
}

impl Stage {
    /// One scale for every view, so that sizes compare between them and between frames: the
    /// widest projection of the box over all views fills a panel less a margin.
    fn scale(&self, cameras: &[Camera]) -> f64 {
        let corners = self.corners();
        let widest = cameras
            .iter()
            .map(|c| {
                let [right, up, _] = c.basis();
                let span = |axis: [f64; 3]| {
                    let d: Vec<f64> = corners.iter().map(|&p| dot(p, axis)).collect();
                    d.iter().cloned().fold(f64::MIN, f64::max) - d.iter().cloned().fold(f64::MAX, f64::min)
                };
                span(right).max(span(up))
            })
            .fold(0.0, f64::max)
            .max(1e-9);
        0.9 * self.size as f64 / widest
    }

    fn corners(&self) -> [[f64; 3]; 8] {
        let (a, b) = (self.min_m, self.max_m);
        std::array::from_fn(|k| {
            [if k & 1 == 0 { a[0] } else { b[0] }, if k & 2 == 0 { a[1] } else { b[1] }, if k & 4 == 0 { a[2] } else { b[2] }]
        })
    }

    /// The plate as a grey slab, 12 triangles.
    fn plate_triangles(&self) -> Vec<[[f64; 3]; 3]> {
        let Some((top, thickness)) = self.plate else { return Vec::new() };
        let (a, b) = ([self.min_m[0], top - thickness, self.min_m[2]], [self.max_m[0], top, self.max_m[2]]);
        let c = |k: usize| {
            [if k & 1 == 0 { a[0] } else { b[0] }, if k & 2 == 0 { a[1] } else { b[1] }, if k & 4 == 0 { a[2] } else { b[2] }]
        };
        let faces = [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]];
        faces.iter().flat_map(|f| [[c(f[0]), c(f[1]), c(f[2])], [c(f[0]), c(f[2]), c(f[3])]]).collect()
    }

    /// Draws `mesh` (the fluid's surface, its vertex field `value`) at simulated time `time_s`
    /// from each camera, side by side, with the annotations.
    pub fn render(&self, mesh: &SurfaceMesh, value: &[f32], time_s: f64, cameras: &[Camera]) -> Image {
        let size = self.size;
        let mut img = Image::new(cameras.len() * size + BAR_WIDTH, size + TITLE_HEIGHT);
        let scale = self.scale(cameras);
        let centre = [0, 1, 2].map(|a| 0.5 * (self.min_m[a] + self.max_m[a]));
        let (lo, hi) = self.range;
        let span = if hi > lo { hi - lo } else { 1.0 };
        let plate = self.plate_triangles();
        let mut texts = vec![((8, 6), format!("t = {time_s:.3} s"))];
        for (k, &camera) in cameras.iter().enumerate() {
            let origin = ((k as f64 + 0.5) * size as f64, TITLE_HEIGHT as f64 + 0.5 * size as f64);
            let view = Projection { basis: camera.basis(), scale, centre, origin };
            let mut depth = vec![f64::NEG_INFINITY; size * size];
            let x0 = (k * size) as i64;
            let mut fill = |img: &mut Image, tri: [[f64; 3]; 3], colours: [[f64; 3]; 3]| {
                let s = tri.map(|p| view.project(p));
                raster(img, &mut depth, x0, size, s, colours);
            };
            for tri in &plate {
                let n = normalised(cross(sub(tri[1], tri[0]), sub(tri[2], tri[0])));
                let grey = 150.0 + 80.0 * dot(n, LIGHT).abs();
                fill(&mut img, *tri, [[grey; 3]; 3]);
            }
            for t in &mesh.triangles {
                let k3 = t.map(|k| k as usize);
                let tri = k3.map(|k| mesh.vertices[k].map(f64::from));
                let colours = k3.map(|k| {
                    let n = mesh.normals[k].map(f64::from);
                    // Two-sided, so a face seen from inside a thin sheet is not black.
                    let light = 0.35 + 0.65 * dot(n, LIGHT).abs();
                    colormap((f64::from(value[k]) - lo) / span).map(|c| f64::from(c) * light)
                });
                fill(&mut img, tri, colours);
            }
            texts.push(((x0 + 8, TITLE_HEIGHT as i64 + 4), camera.name().to_string()));
            if k == 0 {
                texts.push(scale_bar(&mut img, scale, size));
            }
        }
        texts.extend(colour_bar(&mut img, cameras.len() * size, size, &self.quantity, self.range));
        label(&mut img, &texts);
        img
    }
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn normalised(a: [f64; 3]) -> [f64; 3] {
    let n = dot(a, a).sqrt();
    if n > 0.0 {
        a.map(|c| c / n)
    } else {
        a
    }
}

/// Fills screen triangle `s` (pixels, depth) into the panel of `size` pixels at column `x0`,
/// nearer than what `depth` holds, with the colours of its corners blended across it.
fn raster(img: &mut Image, depth: &mut [f64], x0: i64, size: usize, s: [[f64; 3]; 3], colours: [[f64; 3]; 3]) {
    let area = (s[1][0] - s[0][0]) * (s[2][1] - s[0][1]) - (s[2][0] - s[0][0]) * (s[1][1] - s[0][1]);
    if area.abs() < 1e-12 {
        return;
    }
    let top = TITLE_HEIGHT as f64;
    let min_x = s.iter().map(|p| p[0]).fold(f64::MAX, f64::min).floor().max(x0 as f64) as i64;
    let max_x = s.iter().map(|p| p[0]).fold(f64::MIN, f64::max).ceil().min((x0 + size as i64 - 1) as f64) as i64;
    let min_y = s.iter().map(|p| p[1]).fold(f64::MAX, f64::min).floor().max(top) as i64;
    let max_y = s.iter().map(|p| p[1]).fold(f64::MIN, f64::max).ceil().min(top + size as f64 - 1.0) as i64;
    for y in min_y..=max_y {
        for x in min_x..=max_x {
            let (px, py) = (x as f64 + 0.5, y as f64 + 0.5);
            let w0 = ((s[1][0] - px) * (s[2][1] - py) - (s[2][0] - px) * (s[1][1] - py)) / area;
            let w1 = ((s[2][0] - px) * (s[0][1] - py) - (s[0][0] - px) * (s[2][1] - py)) / area;
            let w2 = 1.0 - w0 - w1;
            if w0 < 0.0 || w1 < 0.0 || w2 < 0.0 {
                continue;
            }
            let z = w0 * s[0][2] + w1 * s[1][2] + w2 * s[2][2];
            let cell = (y - top as i64) as usize * size + (x - x0) as usize;
            if z > depth[cell] {
                depth[cell] = z;
                let c = [0, 1, 2].map(|i| (w0 * colours[0][i] + w1 * colours[1][i] + w2 * colours[2][i]).clamp(0.0, 255.0) as u8);
                img.put(x, y, c);
            }
        }
    }
}

/// A bar of a round length (1, 2 or 5 times a power of ten metres) about a fifth of the panel,
/// at its bottom left; returns its label.
fn scale_bar(img: &mut Image, scale: f64, size: usize) -> ((i64, i64), String) {
    let target = 0.2 * size as f64 / scale;
    let power = 10f64.powf(target.log10().floor());
    let length = [5.0, 2.0, 1.0].into_iter().map(|m| m * power).find(|&l| l <= target).unwrap_or(power);
    let pixels = (length * scale).round() as i64;
    let (x, y) = (12, (TITLE_HEIGHT + size) as i64 - 14);
    for dx in 0..pixels {
        for dy in 0..3 {
            img.put(x + dx, y + dy, [30, 30, 30]);
        }
    }
    let text = if length >= 1.0 { format!("{length} m") } else { format!("{} mm", (length * 1e3).round()) };
    ((x, y - 20), text)
}

/// The colour bar at column `x`, bright at the top, with its quantity and three values.
fn colour_bar(img: &mut Image, x: usize, size: usize, quantity: &str, (lo, hi): (f64, f64)) -> Vec<((i64, i64), String)> {
    let left = x as i64 + 14;
    let (top, bottom) = ((TITLE_HEIGHT + 40) as i64, (TITLE_HEIGHT + size) as i64 - 30);
    for y in top..=bottom {
        let c = colormap((bottom - y) as f64 / (bottom - top).max(1) as f64);
        for dx in 0..18 {
            img.put(left + dx, y, c);
        }
    }
    let values = [(top, hi), ((top + bottom) / 2, 0.5 * (lo + hi)), (bottom - 12, lo)];
    let mut texts: Vec<_> = values.iter().map(|&(y, v)| ((left + 24, y), format!("{v:.3}"))).collect();
    texts.push(((left - 4, TITLE_HEIGHT as i64 + 8), quantity.to_string()));
    texts
}

/// Writes each text with its top left corner at its pixel.
fn label(img: &mut Image, texts: &[((i64, i64), String)]) {
    crate::output::font::register();
    let size = (img.width as u32, img.height as u32);
    let area = BitMapBackend::with_buffer(&mut img.pixels, size).into_drawing_area();
    let style = TextStyle::from((crate::output::font::FAMILY, 15)).color(&RGBColor(40, 40, 40));
    for ((x, y), text) in texts {
        // Text that does not fit is cut at the picture's edge by the backend; nothing else can fail.
        let _ = area.draw_text(text, &style, (*x as i32, *y as i32));
    }
}
