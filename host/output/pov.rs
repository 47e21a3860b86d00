//! POV-Ray scenes of a frame as the paper renders its figures (Sec. III): the fluid as one blob
//! whose components are the particles, each of radius h, coloured by the particle's value, over
//! the plate, seen by a camera fixed across a run's frames.

use crate::output::preview::colormap;
use std::fmt::Write as _;

/// What a run's scenes share: the box the camera frames (m), the plate's top and thickness (m),
/// the components' radius h (m) and the colour range.
#[derive(Debug, Clone, PartialEq)]
pub struct PovStage {
    pub min_m: [f64; 3],
    pub max_m: [f64; 3],
    pub plate: Option<(f64, f64)>,
    pub radius_m: f64,
    pub range: (f64, f64),
}

/// The blob's threshold over each component's strength 1 (the paper gives none): the field
/// (1 - (d/h)^2)^2 of a lone particle reaches it 0.54 h from its centre, about a spacing.
const THRESHOLD: f64 = 0.5;

impl PovStage {
    /// The scene of particles at `position` (m) with `value` (the colour's quantity) at
    /// simulated time `time_s`, as POV-Ray 3.7 source.
    pub fn scene(&self, position: &[[f64; 3]], value: &[f32], time_s: f64) -> String {
        let mut s = String::new();
        let centre = [0, 1, 2].map(|a| 0.5 * (self.min_m[a] + self.max_m[a]));
        let extent = (0..3).map(|a| self.max_m[a] - self.min_m[a]).fold(0.0, f64::max).max(1e-9);
        // From 35 degrees round from the front towards +x and 25 above, far enough that a
        // 30-degree view (22 degrees high at 4:3) takes in the box.
        let (azimuth, elevation) = (35f64.to_radians(), 25f64.to_radians());
        let distance = 3.2 * extent;
        let eye = [
            centre[0] + distance * elevation.cos() * azimuth.sin(),
            centre[1] + distance * elevation.sin(),
            centre[2] + distance * elevation.cos() * azimuth.cos(),
        ];
        let v = |p: [f64; 3]| format!("<{:.6}, {:.6}, {:.6}>", p[0], p[1], p[2]);
        let _ = writeln!(
            s,
            "// coil: t = {time_s:.6} s, {} particles, blob components of radius h = {} m",
            position.len(),
            self.radius_m
        );
        let _ = writeln!(s, "#version 3.7;");
        let _ = writeln!(s, "global_settings {{ assumed_gamma 1.0 }}");
        let _ = writeln!(s, "background {{ color rgb <1, 1, 1> }}");
        // POV-Ray's frame is left-handed: z is mirrored so the picture is coil's right-handed one.
        let _ = writeln!(
            s,
            "camera {{ right x*image_width/image_height location {} look_at {} angle 30 }}",
            v(mirror(eye)),
            v(mirror(centre))
        );
        let light = [centre[0] + 2.0 * extent, centre[1] + 4.0 * extent, centre[2] + 3.0 * extent];
        let _ = writeln!(s, "light_source {{ {} color rgb <1, 1, 1> }}", v(mirror(light)));
        let _ = writeln!(s, "light_source {{ {} color rgb <0.4, 0.4, 0.4> shadowless }}", v(mirror(eye)));
        if let Some((top, thickness)) = self.plate {
            let a = [self.min_m[0], top - thickness, self.min_m[2]];
            let b = [self.max_m[0], top, self.max_m[2]];
            let _ = writeln!(s, "box {{ {} {} pigment {{ color rgb <0.8, 0.8, 0.8> }} }}", v(mirror(a)), v(mirror(b)));
        }
        if position.is_empty() {
            return s;
        }
        let (lo, hi) = self.range;
        let span = if hi > lo { hi - lo } else { 1.0 };
        let _ = writeln!(s, "blob {{\n  threshold {THRESHOLD}");
        for (p, &value) in position.iter().zip(value) {
            let [r, g, b] = colormap((f64::from(value) - lo) / span).map(|c| f64::from(c) / 255.0);
            let _ = writeln!(
                s,
                "  sphere {{ {}, {:.6}, 1 texture {{ pigment {{ color rgb <{r:.3}, {g:.3}, {b:.3}> }} finish {{ phong 0.5 }} }} }}",
                v(mirror(*p)),
                self.radius_m
            );
        }
        let _ = writeln!(s, "}}");
        s
    }
}

fn mirror(p: [f64; 3]) -> [f64; 3] {
    [p[0], p[1], -p[2]]
}
