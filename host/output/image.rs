//! RGB pictures written as PNG, with the few drawing primitives the previews and plots need:
//! pixels, discs, lines, rectangles and a 3 x 5 pixel font.

use crate::output::write_atomically;
use std::path::Path;

/// An RGB picture.
#[derive(Debug, Clone, PartialEq)]
pub struct Image {
    pub width: usize,
    pub height: usize,
    /// Row-major RGB, 3 bytes a pixel.
    pub pixels: Vec<u8>,
}

pub const BACKGROUND: [u8; 3] = [255, 255, 255];
pub const INK: [u8; 3] = [40, 40, 40];

impl Image {
    /// A white picture.
    pub fn new(width: usize, height: usize) -> Self {
        Self { width, height, pixels: BACKGROUND.repeat(width * height) }
    }

    /// Sets one pixel; outside the picture nothing happens.
    pub fn put(&mut self, x: i64, y: i64, c: [u8; 3]) {
        if x >= 0 && y >= 0 && (x as usize) < self.width && (y as usize) < self.height {
            let k = 3 * (y as usize * self.width + x as usize);
            self.pixels[k..k + 3].copy_from_slice(&c);
        }
    }

    /// The colour of one pixel.
    pub fn get(&self, x: usize, y: usize) -> [u8; 3] {
        let k = 3 * (y * self.width + x);
        [self.pixels[k], self.pixels[k + 1], self.pixels[k + 2]]
    }

    pub fn disc(&mut self, cx: f64, cy: f64, r: f64, c: [u8; 3]) {
        let ri = r.ceil() as i64;
        let (x0, y0) = (cx.round() as i64, cy.round() as i64);
        for dy in -ri..=ri {
            for dx in -ri..=ri {
                let (fx, fy) = ((x0 + dx) as f64 - cx, (y0 + dy) as f64 - cy);
                if fx * fx + fy * fy <= r * r {
                    self.put(x0 + dx, y0 + dy, c);
                }
            }
        }
    }

    /// A line `width` pixels thick from (x0, y0) to (x1, y1); `dash` > 0 draws dashes of that
    /// many pixels with gaps as long.
    #[allow(clippy::too_many_arguments)]
    pub fn line(&mut self, x0: f64, y0: f64, x1: f64, y1: f64, width: f64, dash: f64, c: [u8; 3]) {
        let length = ((x1 - x0).powi(2) + (y1 - y0).powi(2)).sqrt();
        let samples = (2.0 * length).ceil().max(1.0) as usize;
        for k in 0..=samples {
            let t = k as f64 / samples as f64;
            if dash > 0.0 && (t * length / dash) as u64 % 2 == 1 {
                continue;
            }
            self.disc(x0 + t * (x1 - x0), y0 + t * (y1 - y0), 0.5 * width, c);
        }
    }

    /// A filled rectangle, corners included.
    pub fn rect(&mut self, x0: i64, y0: i64, x1: i64, y1: i64, c: [u8; 3]) {
        for y in y0..=y1 {
            for x in x0..=x1 {
                self.put(x, y, c);
            }
        }
    }

    /// The picture as PNG bytes.
    pub fn to_png(&self) -> Vec<u8> {
        let mut out = Vec::new();
        let mut encoder = png::Encoder::new(&mut out, self.width as u32, self.height as u32);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        let mut writer = encoder.write_header().expect("writing to memory");
        writer.write_image_data(&self.pixels).expect("writing to memory");
        drop(writer);
        out
    }

    /// Writes the PNG through a temporary name and a rename.
    pub fn save(&self, path: &Path) -> std::io::Result<()> {
        write_atomically(path, &self.to_png())
    }
}

/// 3 x 5 pixel glyphs, one row per 3 bits; lower case is drawn as upper case.
fn glyph(c: char) -> [u8; 5] {
    match c.to_ascii_uppercase() {
        '0' => [7, 5, 5, 5, 7],
        '1' => [2, 6, 2, 2, 7],
        '2' => [7, 1, 7, 4, 7],
        '3' => [7, 1, 7, 1, 7],
        '4' => [5, 5, 7, 1, 1],
        '5' => [7, 4, 7, 1, 7],
        '6' => [7, 4, 7, 5, 7],
        '7' => [7, 1, 1, 1, 1],
        '8' => [7, 5, 7, 5, 7],
        '9' => [7, 5, 7, 1, 7],
        'A' => [2, 5, 7, 5, 5],
        'B' => [6, 5, 6, 5, 6],
        'C' => [3, 4, 4, 4, 3],
        'D' => [6, 5, 5, 5, 6],
        'E' => [7, 4, 6, 4, 7],
        'F' => [7, 4, 6, 4, 4],
        'G' => [3, 4, 5, 5, 3],
        'H' => [5, 5, 7, 5, 5],
        'I' => [7, 2, 2, 2, 7],
        'J' => [1, 1, 1, 5, 2],
        'K' => [5, 5, 6, 5, 5],
        'L' => [4, 4, 4, 4, 7],
        'M' => [5, 7, 7, 5, 5],
        'N' => [6, 5, 5, 5, 5],
        'O' => [2, 5, 5, 5, 2],
        'P' => [6, 5, 6, 4, 4],
        'Q' => [2, 5, 5, 6, 3],
        'R' => [6, 5, 6, 5, 5],
        'S' => [3, 4, 2, 1, 6],
        'T' => [7, 2, 2, 2, 2],
        'U' => [5, 5, 5, 5, 7],
        'V' => [5, 5, 5, 5, 2],
        'W' => [5, 5, 7, 7, 5],
        'X' => [5, 5, 2, 5, 5],
        'Y' => [5, 5, 2, 2, 2],
        'Z' => [7, 1, 2, 4, 7],
        '.' => [0, 0, 0, 0, 2],
        ',' => [0, 0, 0, 2, 4],
        ':' => [0, 2, 0, 2, 0],
        '-' => [0, 0, 7, 0, 0],
        '+' => [0, 2, 7, 2, 0],
        '=' => [0, 7, 0, 7, 0],
        '/' => [1, 1, 2, 4, 4],
        '(' => [1, 2, 2, 2, 1],
        ')' => [4, 2, 2, 2, 4],
        '%' => [5, 1, 2, 4, 5],
        '^' => [2, 5, 0, 0, 0],
        '_' => [0, 0, 0, 0, 7],
        '*' => [0, 5, 2, 5, 0],
        '<' => [1, 2, 4, 2, 1],
        '>' => [4, 2, 1, 2, 4],
        _ => [0; 5],
    }
}

/// Pixels one character of `text` advances at `scale`.
pub fn char_width(scale: i64) -> i64 {
    4 * scale
}

/// Writes `s` with its top-left corner at (x, y), each font pixel `scale` pixels square.
pub fn text(img: &mut Image, x: i64, y: i64, s: &str, scale: i64) {
    for (k, ch) in s.chars().enumerate() {
        let g = glyph(ch);
        let left = x + k as i64 * char_width(scale);
        for (row, bits) in g.iter().enumerate() {
            for col in 0..3 {
                if bits & (4 >> col) != 0 {
                    img.rect(
                        left + col * scale,
                        y + row as i64 * scale,
                        left + col * scale + scale - 1,
                        y + row as i64 * scale + scale - 1,
                        INK,
                    );
                }
            }
        }
    }
}

/// `s` written from bottom to top, its first character at the bottom, for a vertical axis label
/// whose left edge is `x` and whose middle is `y_middle`.
pub fn text_vertical(img: &mut Image, x: i64, y_middle: i64, s: &str, scale: i64) {
    let n = s.chars().count() as i64;
    let bottom = y_middle + n * char_width(scale) / 2;
    for (k, ch) in s.chars().enumerate() {
        let g = glyph(ch);
        let base = bottom - k as i64 * char_width(scale);
        for (row, bits) in g.iter().enumerate() {
            for col in 0..3 {
                if bits & (4 >> col) != 0 {
                    // Turned a quarter anticlockwise: font column -> up, font row -> right.
                    let (px, py) = (x + row as i64 * scale, base - (col + 1) * scale);
                    img.rect(px, py, px + scale - 1, py + scale - 1, INK);
                }
            }
        }
    }
}
