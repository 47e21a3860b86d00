//! RGB pictures written as PNG: the particle previews draw on them pixel by pixel and disc by
//! disc, and the charts' PNGs are drawn into them by plotters.

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
