//! The jet's axis just above the plate, the indicator of buckling (paper Fig. 5, 6): how far
//! the centroid of the downward flux through the slab D/2 to 3D/2 above the plate lies from the
//! nozzle's axis. `coil validate` measures its jets with it as they run; `coil axis` measures it
//! in the frames of any finished run, so that a jet run with other parameters is judged the same
//! way.

use crate::output::vtu_read::{read_run_frame, read_series};
use crate::run::folder::{series_path, LOG};
use crate::scene::{Boundary, FrameFormat, Nozzle, Scene, SceneError};
use std::path::Path;

/// Where a vertical round jet falls: its nozzle axis and the surface it lands on.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JetAxis {
    /// x and z of the nozzle's axis (m).
    pub nozzle_xz_m: [f64; 2],
    /// Height of the surface under the nozzle (m): the highest plate top or box floor below it
    /// that spans its axis.
    pub plate_y_m: f64,
    /// Nozzle diameter D (m).
    pub diameter_m: f64,
}

impl JetAxis {
    /// The axis of the scene's only inlet, which must be round, still and point straight down
    /// onto a plate or a box floor that spans its axis. Errors name `file` and the field.
    pub fn of(scene: &Scene, file: &str) -> Result<JetAxis, SceneError> {
        let bad = |field: &str, reason: String| SceneError { file: file.into(), field: field.into(), reason };
        let [inlet] = scene.inlets.as_slice() else {
            return Err(bad("inlet", format!("the axis is that of one jet; the scene has {} inlets", scene.inlets.len())));
        };
        let Nozzle::Circle { radius_m } = inlet.nozzle else {
            return Err(bad("inlet[0].nozzle", "the axis is that of a round jet; this nozzle is a rectangle".into()));
        };
        if inlet.motion.is_some() {
            return Err(bad("inlet[0].motion", "the nozzle moves; the offset is measured from a fixed axis".into()));
        }
        let [dx, dy, dz] = inlet.direction;
        let norm = (dx * dx + dy * dy + dz * dz).sqrt();
        if !(dx.abs() <= 1e-9 * norm && dz.abs() <= 1e-9 * norm && dy < 0.0) {
            return Err(bad(
                "inlet[0].direction",
                format!("the jet must point straight down, [0, -1, 0]; got {:?}", inlet.direction),
            ));
        }
        let [x, nozzle_y, z] = inlet.position_m;
        let plate_y_m = scene
            .boundaries
            .iter()
            .filter_map(|b| {
                let ([x0, z0], [x1, z1], top) = match *b {
                    Boundary::Plate { height_m, min_xz_m, max_xz_m } => {
                        (min_xz_m.unwrap_or([f64::MIN, f64::MIN]), max_xz_m.unwrap_or([f64::MAX, f64::MAX]), height_m)
                    }
                    Boundary::Box { min_m, max_m, .. } => ([min_m[0], min_m[2]], [max_m[0], max_m[2]], min_m[1]),
                };
                (x0 <= x && x <= x1 && z0 <= z && z <= z1).then_some(top)
            })
            .filter(|&y| y < nozzle_y)
            .fold(f64::NEG_INFINITY, f64::max);
        if plate_y_m == f64::NEG_INFINITY {
            return Err(bad("boundary", "the jet falls onto no plate or box floor under its nozzle".into()));
        }
        Ok(JetAxis { nozzle_xz_m: [x, z], plate_y_m, diameter_m: 2.0 * radius_m })
    }

    /// Sideways offset of the axis just above the plate (m): the horizontal distance from the
    /// nozzle axis of the centroid of the downward mass flux through the slab between D/2 and
    /// 3D/2 above the plate, each fluid particle there weighted by its downward speed (m/s).
    /// The rope is where the fluid falls: a folding or coiling rope lays its fluid on both sides
    /// of the axis, so the centroid of all the fluid in the slab stays near the axis however far
    /// the rope swings, and the pile it builds there barely moves. None while nothing falls
    /// there.
    pub fn offset(&self, particles: impl Iterator<Item = ([f64; 3], f64)>) -> Option<f64> {
        self.displacement(particles).map(|[x, z]| x.hypot(z))
    }

    /// The same centroid's x and z from the nozzle axis (m).
    pub fn displacement(&self, particles: impl Iterator<Item = ([f64; 3], f64)>) -> Option<[f64; 2]> {
        let d = self.diameter_m;
        let slab = (self.plate_y_m + 0.5 * d)..(self.plate_y_m + 1.5 * d);
        let (mut flux, mut x, mut z) = (0.0, 0.0, 0.0);
        for (p, vy) in particles.filter(|(p, _)| slab.contains(&p[1])) {
            let falling = (-vy).max(0.0);
            flux += falling;
            x += falling * (p[0] - self.nozzle_xz_m[0]);
            z += falling * (p[2] - self.nozzle_xz_m[1]);
        }
        (flux > 0.0).then(|| [x / flux, z / flux])
    }
}

/// The axis offset in one frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AxisSample {
    /// Simulated time of the frame (s).
    pub time_s: f64,
    /// [`JetAxis::displacement`] over D, x then z; None where nothing fell through the slab.
    pub displacement_over_d: Option<[f64; 2]>,
}

impl AxisSample {
    /// [`JetAxis::offset`] over D.
    pub fn offset_over_d(&self) -> Option<f64> {
        self.displacement_over_d.map(|[x, z]| x.hypot(z))
    }

    /// The direction of the offset about the vertical (rad, -pi to pi): from +z towards +x, so
    /// that it grows as the rope turns counter-clockwise seen from above (y up).
    pub fn angle_rad(&self) -> Option<f64> {
        self.displacement_over_d.map(|[x, z]| x.atan2(z))
    }
}

/// The axis of the run in output folder `dir` and its offset at each `.vtu` frame. The scene is
/// the one the run logged in `run.json`, the times those of its `.pvd` series.
pub fn offsets_in_run(dir: &Path) -> Result<(JetAxis, Vec<AxisSample>), String> {
    let log = dir.join(LOG);
    let scene = Scene::load_with(&log, &[]).map_err(|e| e.to_string())?;
    let axis = JetAxis::of(&scene, &log.display().to_string()).map_err(|e| e.to_string())?;
    if !scene.output.formats.contains(&FrameFormat::Vtu) {
        return Err(format!("{}: output.formats: the run wrote no .vtu frames, which the offset is read from", log.display()));
    }
    let frames = read_series(&series_path(dir, &scene.name))?;
    let mut offsets = Vec::with_capacity(frames.len());
    for (t, file) in frames {
        let path = dir.join(&file);
        let frame = read_run_frame(&path, &scene)?;
        let velocity = frame.vectors.get("velocity").ok_or_else(|| format!("{}: holds no velocity", path.display()))?;
        let particles = frame.position.iter().zip(velocity).map(|(&p, v)| (p, f64::from(v[1])));
        let displacement_over_d = axis.displacement(particles).map(|xz| xz.map(|c| c / axis.diameter_m));
        offsets.push(AxisSample { time_s: t, displacement_over_d });
    }
    Ok((axis, offsets))
}
