//! Jet buckling (the paper's Fig. 5, 6): the shipped Newtonian round jet (D = 20 mm, U = 1 m/s,
//! nu = 0.1 m^2/s, Re = U D / nu = 0.2) falling from H onto the plate at y = 0. From high
//! enough the rope buckles and its axis just above the plate ([`JetAxis`]) swings sideways; from
//! a few diameters it stays straight.

use super::case::{operator_file_word, operator_label, save_plot, CaseResult};
use super::snapshot::snapshots;
use crate::output::plot::Axis;
use crate::output::plot::Chart;
use crate::output::plot::Curve;
use crate::output::plot::Line;
use crate::output::plot::PALETTE;
use crate::scene::{Scene, VelocityGradient, ViscosityOperator, ViscositySolver};
use crate::validation::jet_axis::JetAxis;
use std::path::Path;
use std::time::Instant;

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

/// Jet buckling at Re = 0.2 (the shipped Newtonian jet) with operator `op` (and its hourglass
/// control of weight `hourglass_control`), from `height_over_d` diameters: with `buckles`, the
/// axis just above the plate must swing sideways by more than D/2; otherwise it must stay
/// within 0.1 D.
pub fn jet_buckling(
    height_over_d: f64,
    op: ViscosityOperator,
    hourglass_control: f64,
    buckles: bool,
    end_time_s: f64,
    out: Option<&Path>,
) -> Result<CaseResult, String> {
    let expect = if buckles { "buckles" } else { "stays straight" };
    let tolerance = if buckles { 0.5 } else { 0.1 };
    let case = format!("jet, H/D = {height_over_d}, Re = 0.2, {}: {expect}", operator_label(op, hourglass_control));
    let started = Instant::now();
    let offsets = axis_offsets(height_over_d, op, hourglass_control, end_time_s).map_err(|e| format!("{case}: {e}"))?;
    let offset = offsets.iter().map(|p| p[1]).fold(0.0, f64::max);
    let plot = out
        .map(|dir| {
            let chart = Chart {
                title: case.clone(),
                x: Axis::linear("t (s)"),
                y: Axis::linear("axis offset / D"),
                series: vec![
                    Curve {
                        label: format!("threshold {tolerance} D"),
                        color: PALETTE[0],
                        points: vec![[0.0, tolerance], [end_time_s, tolerance]],
                        line: Line::Solid,
                        marker: 0.0,
                    },
                    Curve { label: "sph".into(), color: PALETTE[1], points: offsets, line: Line::Solid, marker: 3.0 },
                ],
            };
            let word = operator_file_word(op, hourglass_control);
            save_plot(&chart, &dir.join(format!("jet_{word}_h{height_over_d}.png")))
        })
        .transpose()?;
    Ok(CaseResult {
        case,
        measure: format!(
            "largest sideways offset / D of the axis (the centroid of the downward flux between D/2 and 3D/2 above the plate), every 0.02 s to {end_time_s} s (the plot shows it against t); c = 20 m/s"
        ),
        error: offset,
        tolerance,
        at_least: buckles,
        wall_s: started.elapsed().as_secs_f64(),
        plot,
    })
}
/// The paper's formulation of the jet (Eq. (8) as printed, summed density, clamped pressure, no
/// shifting: the scene's `paper` variant) from H/D = 12 at 1.5 times the Eq. (10) bound, its
/// viscous terms reading v_{n-1/2}, which doubles the room that leap-frog leaves a viscously
/// damped mode (`coil_kernels::leapfrog`). Reading the full step, the same run threw a particle
/// at 0.508 s; here no particle may pass the free fall from the nozzle, sqrt(U^2 + 2 g H),
/// without being thrown, to `end_time_s`.
pub fn jet_half_step_above_bound(end_time_s: f64) -> Result<CaseResult, String> {
    use crate::run::{run, Backend, RunOptions};
    use crate::scene::{DensityEquation, ViscousVelocity};
    let case =
        "jet, H/D = 12, the paper's formulation at 1.5 times the Eq. (10) bound, viscosity reading the half step: nothing thrown"
            .to_string();
    let started = Instant::now();
    let (axis, mut scene) = jet_scene(12.0, ViscosityOperator::Stress, 0.0, end_time_s)?;
    scene.name = "newtonian_jet".into();
    scene.material.viscosity.velocity_gradient = VelocityGradient::Sph;
    scene.material.density_equation = DensityEquation::Summation;
    scene.material.clamp_negative_pressure = true;
    scene.simulation.particle_shifting = 0.0;
    let time_step = &mut scene.simulation.time_step;
    time_step.safety_factor = 1.5;
    time_step.allow_above_stability_bound = true;
    time_step.viscous_velocity = ViscousVelocity::HalfStep;
    let inlet = &scene.inlets[0];
    let drop_m = inlet.position_m[1] - axis.plate_y_m;
    let g = scene.material.gravity_m_s2[1].abs();
    let free_fall = (inlet.speed_m_s * inlet.speed_m_s + 2.0 * g * drop_m).sqrt();
    let out = std::env::temp_dir().join(format!("coil-validate-jet-half-step-{}", std::process::id()));
    let options = RunOptions {
        backend: Backend::Cpu,
        out_dir: out.clone(),
        precision: None,
        quiet: true,
        preview: false,
        overrides: vec![],
        overwrite: true,
        stop: None,
    };
    let result = run(&scene, "scenes/newtonian_jet.toml", &options);
    std::fs::remove_dir_all(&out).ok();
    let summary = result.map_err(|e| format!("{case}: {e}"))?;
    Ok(CaseResult {
        case,
        measure: format!(
            "fastest particle over the whole run to {end_time_s} s against the free fall from the nozzle, {free_fall:.2} m/s"
        ),
        error: summary.max_speed_m_s / free_fall,
        tolerance: 1.0,
        at_least: false,
        wall_s: started.elapsed().as_secs_f64(),
        plot: None,
    })
}

/// The jet of Fig. 5 with implicit viscosity (the paper's operator with the own-density
/// gradient): from H/D = 12 it must still buckle (largest offset above D/2); from H/D = 3 its
/// largest offset must be within 0.03 D of the explicit solver's on the same operator.
pub fn jet_implicit(height_over_d: f64, end_time_s: f64) -> Result<CaseResult, String> {
    use crate::scene::ViscositySolver;
    let buckles = height_over_d >= 10.0;
    let largest = |o: &[[f64; 2]]| o.iter().map(|p| p[1]).fold(0.0, f64::max);
    let started = Instant::now();
    let implicit = largest(&own_density_axis_offsets(height_over_d, ViscositySolver::Implicit, end_time_s)?);
    let implicit_s = started.elapsed().as_secs_f64();
    let base = format!("jet, H/D = {height_over_d}, Re = 0.2, paper's operator (own density), implicit viscosity");
    if buckles {
        return Ok(CaseResult {
            case: format!("{base}: buckles"),
            measure: format!("largest sideways offset / D of the axis, every 0.02 s to {end_time_s} s ({implicit_s:.0} s)"),
            error: implicit,
            tolerance: 0.5,
            at_least: true,
            wall_s: implicit_s,
            plot: None,
        });
    }
    let started = Instant::now();
    let explicit = largest(&own_density_axis_offsets(height_over_d, ViscositySolver::Explicit, end_time_s)?);
    let explicit_s = started.elapsed().as_secs_f64();
    Ok(CaseResult {
        case: format!("{base}: as the explicit solver"),
        measure: format!(
            "|largest offset implicit - explicit| / D, every 0.02 s to {end_time_s} s: {implicit:.3} against {explicit:.3} ({implicit_s:.0} s against {explicit_s:.0} s)"
        ),
        error: (implicit - explicit).abs(),
        tolerance: 0.03,
        at_least: false,
        wall_s: implicit_s + explicit_s,
        plot: None,
    })
}
