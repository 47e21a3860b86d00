//! Jet buckling (the paper's Fig. 5, 6): the shipped Newtonian round jet (D = 20 mm, U = 1 m/s,
//! nu = 0.1 m^2/s, Re = U D / nu = 0.2) falling from H onto the plate at y = 0. From high
//! enough the rope buckles and its axis just above the plate swings sideways; from a few
//! diameters it stays straight.

use super::snapshot::{snapshots, Snapshot};
use crate::scene::{Scene, ViscosityOperator};

/// The shipped Newtonian jet.
const NEWTONIAN_JET: &str = include_str!("../../scenes/newtonian_jet.toml");

/// Seconds between the samples of the axis.
const SAMPLE_EVERY_S: f64 = 0.02;

/// Sideways offset of the jet's axis just above the plate (m): the horizontal distance from the
/// nozzle axis (x = z = 0) of the centroid of the downward mass flux through the slab between
/// D/2 and 3D/2 above the plate top `plate_y` (m), each particle there weighted by its
/// downward speed. The rope is where the fluid falls: a folding or coiling rope lays its fluid
/// on both sides of the axis, so the centroid of all the fluid in the slab stays near the axis
/// however far the rope swings, and the pile it builds there barely moves. None while nothing
/// falls there.
pub fn axis_offset(snapshot: &Snapshot, plate_y: f64, diameter: f64) -> Option<f64> {
    let slab = (plate_y + 0.5 * diameter)..(plate_y + 1.5 * diameter);
    let (mut flux, mut x, mut z) = (0.0, 0.0, 0.0);
    for (p, v) in snapshot.position.iter().zip(&snapshot.velocity).filter(|(p, _)| slab.contains(&p[1])) {
        let falling = (-v[1]).max(0.0);
        flux += falling;
        x += falling * p[0];
        z += falling * p[2];
    }
    (flux > 0.0).then(|| (x * x + z * z).sqrt() / flux)
}

/// The jet's diameter D (m) and its scene with the nozzle `height_over_d` diameters above the
/// plate, operator `op` with hourglass control of weight `hourglass_control`, run to
/// `end_time_s`.
pub fn jet_scene(
    height_over_d: f64,
    op: ViscosityOperator,
    hourglass_control: f64,
    end_time_s: f64,
) -> Result<(f64, Scene), String> {
    let mut scene = Scene::parse(NEWTONIAN_JET, "scenes/newtonian_jet.toml").map_err(|e| e.to_string())?;
    let inlet = scene.inlets.first_mut().ok_or("the jet scene has no inlet")?;
    let crate::scene::Nozzle::Circle { radius_m } = inlet.nozzle else {
        return Err("the jet scene's nozzle is not round".into());
    };
    let diameter = 2.0 * radius_m;
    let height = height_over_d * diameter;
    inlet.position_m[1] = height;
    scene.domain.max_m[1] = height + 0.03;
    scene.material.viscosity.operator = op;
    scene.material.viscosity.hourglass_control = hourglass_control;
    scene.simulation.end_time_s = end_time_s;
    scene.name = format!("jet, H/D = {height_over_d}");
    Ok((diameter, scene))
}

/// The sideways offset of the axis over `diameter` (dimensionless) against time (s), sampled
/// every 0.02 s until `end_time_s` from the first sample with fluid falling through the slab.
pub fn axis_offsets(
    height_over_d: f64,
    op: ViscosityOperator,
    hourglass_control: f64,
    end_time_s: f64,
) -> Result<Vec<[f64; 2]>, String> {
    let (diameter, scene) = jet_scene(height_over_d, op, hourglass_control, end_time_s)?;
    let samples = (end_time_s / SAMPLE_EVERY_S).round() as usize;
    let times: Vec<f64> = (1..=samples).map(|k| k as f64 * SAMPLE_EVERY_S).collect();
    let snaps = snapshots(&scene, &times, None)?;
    Ok(snaps.iter().filter_map(|s| axis_offset(s, 0.0, diameter).map(|o| [s.time_s, o / diameter])).collect())
}
