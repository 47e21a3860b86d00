//! Jet buckling (the paper's Fig. 5, 6): the shipped Newtonian round jet (D = 20 mm, U = 1 m/s,
//! nu = 0.1 m^2/s, Re = U D / nu = 0.2) falling from H onto the plate at y = 0. From high
//! enough the rope buckles and its axis just above the plate ([`JetAxis`]) swings sideways; from
//! a few diameters it stays straight.

use super::snapshot::snapshots;
use crate::scene::{Scene, VelocityGradient, ViscosityOperator, ViscositySolver};
use crate::validation::jet_axis::JetAxis;

/// The shipped Newtonian jet.
const NEWTONIAN_JET: &str = include_str!("../../scenes/newtonian_jet.toml");

/// Seconds between the samples of the axis.
const SAMPLE_EVERY_S: f64 = 0.02;

/// The shipped jet's axis and its scene with the nozzle `height_over_d` diameters above the
/// plate, operator `op` with hourglass control of weight `hourglass_control`, run to
/// `end_time_s`.
pub fn jet_scene(
    height_over_d: f64,
    op: ViscosityOperator,
    hourglass_control: f64,
    end_time_s: f64,
) -> Result<(JetAxis, Scene), String> {
    let file = "scenes/newtonian_jet.toml";
    let mut scene = Scene::parse(NEWTONIAN_JET, file).map_err(|e| e.to_string())?;
    let axis = JetAxis::of(&scene, file).map_err(|e| e.to_string())?;
    let height = axis.plate_y_m + height_over_d * axis.diameter_m;
    scene.inlets[0].position_m[1] = height;
    scene.domain.max_m[1] = height + 0.03;
    scene.material.viscosity.operator = op;
    scene.material.viscosity.hourglass_control = hourglass_control;
    if op != ViscosityOperator::Stress || hourglass_control > 0.0 {
        // Only the paper's operator without hourglass control takes the renormalized gradient.
        scene.material.viscosity.velocity_gradient = VelocityGradient::Sph;
    }
    scene.simulation.end_time_s = end_time_s;
    scene.name = format!("jet, H/D = {height_over_d}");
    Ok((axis, scene))
}

/// The sideways offset of the axis over D (dimensionless) against time (s), sampled every
/// 0.02 s until `end_time_s` from the first sample with fluid falling through the slab.
pub fn axis_offsets(
    height_over_d: f64,
    op: ViscosityOperator,
    hourglass_control: f64,
    end_time_s: f64,
) -> Result<Vec<[f64; 2]>, String> {
    let (axis, scene) = jet_scene(height_over_d, op, hourglass_control, end_time_s)?;
    offsets_of(&axis, &scene, end_time_s)
}

/// [`axis_offsets`] of the paper's operator with the own-density gradient (the operator the
/// implicit solve takes), integrated explicitly or implicitly.
pub fn own_density_axis_offsets(height_over_d: f64, solver: ViscositySolver, end_time_s: f64) -> Result<Vec<[f64; 2]>, String> {
    let (axis, mut scene) = jet_scene(height_over_d, ViscosityOperator::Stress, 0.0, end_time_s)?;
    scene.material.viscosity.velocity_gradient = VelocityGradient::OwnDensity;
    scene.material.viscosity.solver = solver;
    offsets_of(&axis, &scene, end_time_s)
}

fn offsets_of(axis: &JetAxis, scene: &Scene, end_time_s: f64) -> Result<Vec<[f64; 2]>, String> {
    let samples = (end_time_s / SAMPLE_EVERY_S).round() as usize;
    let times: Vec<f64> = (1..=samples).map(|k| k as f64 * SAMPLE_EVERY_S).collect();
    let snaps = snapshots(scene, &times, None)?;
    Ok(snaps
        .iter()
        .filter_map(|s| {
            let particles = s.position.iter().zip(&s.velocity).map(|(&p, v)| (p, v[1]));
            axis.offset(particles).map(|o| [s.time_s, o / axis.diameter_m])
        })
        .collect())
}
