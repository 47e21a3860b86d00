//! A viscous thread falling freely from a nozzle: how a jet stretches before it meets the pile.
//! The shipped Newtonian jet's fluid (D = 20 mm, U0 = 1 m/s, nu = 0.1 m^2/s) leaves its nozzle
//! 0.3 m above the domain's floor with no plate below, and its axial speed along the fall is
//! compared with the steady slender-thread solution, whose extensional (Trouton) viscosity is
//! 3 nu.

use super::case::{operator_name, save_plot, scene_word, CaseResult};
use super::snapshot::snapshots;
use crate::output::plot::Axis;
use crate::output::plot::Chart;
use crate::output::plot::Curve;
use crate::output::plot::Line;
use crate::output::plot::PALETTE;
use crate::scene::{DensityEquation, DensityKernelKind, Pressure, Scene, VelocityGradient, ViscosityOperator, ViscositySolver};
use std::path::Path;
use std::time::Instant;

/// The shipped Newtonian jet.
const NEWTONIAN_JET: &str = include_str!("../../scenes/newtonian_jet.toml");

/// The nozzle's height above the floor, where the thread leaves the domain (m).
pub const FALL_M: f64 = 0.3;

/// A steady, slender, axisymmetric thread without surface tension, z downward from the nozzle:
/// U U' = g + T nu (U'' - U'^2 / U) with the Trouton ratio T (3 for a Newtonian liquid),
/// U(0) = U0, and no axial stress (U' = 0) at z = `length_m`, where it leaves the domain.
#[derive(Debug, Clone, Copy)]
pub struct SlenderThread {
    /// U0 (m/s).
    pub nozzle_speed_m_s: f64,
    /// g (m/s^2).
    pub gravity_m_s2: f64,
    /// nu (m^2/s).
    pub viscosity_m2_s: f64,
    pub length_m: f64,
    /// T: the extensional viscosity over nu (dimensionless).
    pub trouton_ratio: f64,
}

/// Integration steps along the thread: the solution is smooth on the viscous length 3 nu / U.
const STEPS: usize = 4000;

impl SlenderThread {
    /// U'' from U and U'.
    fn curvature(&self, u: f64, slope: f64) -> f64 {
        (u * slope - self.gravity_m_s2) / (self.trouton_ratio * self.viscosity_m2_s) + slope * slope / u
    }

    /// (z, U) along the thread, from z = L, where U = `end_speed` (m/s) and U' = 0, back to the
    /// nozzle, by classical Runge-Kutta: integrated upstream the equation's growing mode decays,
    /// so the shot is well conditioned. `None` where the thread breaks (U falls to 0) on the way.
    fn shoot_back(&self, end_speed: f64) -> Option<Vec<[f64; 2]>> {
        let dz = -self.length_m / STEPS as f64;
        let f = |s: [f64; 2]| [s[1], self.curvature(s[0], s[1])];
        let mut s = [end_speed, 0.0];
        let mut out = vec![[self.length_m, s[0]]];
        for k in 1..=STEPS {
            let k1 = f(s);
            let k2 = f([s[0] + 0.5 * dz * k1[0], s[1] + 0.5 * dz * k1[1]]);
            let k3 = f([s[0] + 0.5 * dz * k2[0], s[1] + 0.5 * dz * k2[1]]);
            let k4 = f([s[0] + dz * k3[0], s[1] + dz * k3[1]]);
            s = [0, 1].map(|i| s[i] + dz / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]));
            if !(s[0] > 0.0 && s[1].abs() < 1e8) {
                return None;
            }
            out.push([self.length_m + k as f64 * dz, s[0]]);
        }
        out.reverse();
        Some(out)
    }

    /// The nozzle speed (m/s) that the end speed `end_speed` (m/s) gives, 0 where the thread
    /// breaks: it grows with the end speed.
    fn nozzle_speed(&self, end_speed: f64) -> f64 {
        self.shoot_back(end_speed).map_or(0.0, |p| p[0][1])
    }

    /// The thread's speed profile: (z (m), U (m/s)) at the integration points, increasing z,
    /// found by bisecting on the end speed until U(0) = U0.
    pub fn profile(&self) -> Result<Vec<[f64; 2]>, String> {
        let u0 = self.nozzle_speed_m_s;
        let (mut low, mut high) = (0.0, u0);
        while self.nozzle_speed(high) < u0 {
            (low, high) = (high, 2.0 * high);
            if high > 1e3 * u0 {
                return Err("no end speed gives the nozzle speed".into());
            }
        }
        for _ in 0..100 {
            let middle = 0.5 * (low + high);
            if self.nozzle_speed(middle) < u0 {
                low = middle;
            } else {
                high = middle;
            }
        }
        self.shoot_back(high).ok_or_else(|| "the bisected thread breaks".into())
    }
}

/// The Trouton ratio whose slender thread (otherwise `thread`) fits the `slabs` best, in the
/// least squares of their speeds: how viscous the measured thread is in extension.
pub fn fitted_trouton_ratio(thread: &SlenderThread, slabs: &[Slab]) -> Result<f64, String> {
    let misfit = |log_ratio: f64| -> Result<f64, String> {
        let profile = SlenderThread { trouton_ratio: log_ratio.exp(), ..*thread }.profile()?;
        Ok(slabs.iter().map(|s| (s.speed_m_s - speed_at(&profile, s.z_m)).powi(2)).sum())
    };
    // Golden-section search on ln T from 0.01 to 30.
    let (mut a, mut b) = (0.01f64.ln(), 30.0f64.ln());
    let golden = 0.5 * (5f64.sqrt() - 1.0);
    for _ in 0..40 {
        let (c, d) = (b - golden * (b - a), a + golden * (b - a));
        if misfit(c)? < misfit(d)? {
            b = d;
        } else {
            a = c;
        }
    }
    Ok((0.5 * (a + b)).exp())
}

/// The speed (m/s) at `z` (m) of a profile of increasing z, linearly interpolated.
pub fn speed_at(profile: &[[f64; 2]], z: f64) -> f64 {
    let k = profile.partition_point(|p| p[0] < z).clamp(1, profile.len() - 1);
    let (a, b) = (profile[k - 1], profile[k]);
    a[1] + (b[1] - a[1]) * (z - a[0]) / (b[0] - a[0])
}

/// How a thread case treats density, pressure and the particles' order.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Treatment {
    pub density_equation: DensityEquation,
    pub clamp_negative_pressure: bool,
    /// `simulation.particle_shifting`'s coefficient, 0 for none.
    pub particle_shifting: f64,
    /// The paper's operator's velocity gradient (the other operators have their own).
    pub velocity_gradient: VelocityGradient,
    /// Weakly compressible, or solved with viscosity implicit at the CFL step.
    pub pressure: Pressure,
}

impl Treatment {
    /// The treatments the validation suite compares: the paper's density sum with the pressure
    /// clamped and as printed, the continuity equation, and the continuity equation with
    /// particle shifting (A = 2).
    pub const COMPARED: [Treatment; 4] = [
        Treatment {
            density_equation: DensityEquation::Summation,
            clamp_negative_pressure: true,
            particle_shifting: 0.0,
            velocity_gradient: VelocityGradient::Sph,
            pressure: Pressure::WeaklyCompressible,
        },
        Treatment {
            density_equation: DensityEquation::Summation,
            clamp_negative_pressure: false,
            particle_shifting: 0.0,
            velocity_gradient: VelocityGradient::Sph,
            pressure: Pressure::WeaklyCompressible,
        },
        Treatment {
            density_equation: DensityEquation::Continuity,
            clamp_negative_pressure: false,
            particle_shifting: 0.0,
            velocity_gradient: VelocityGradient::Sph,
            pressure: Pressure::WeaklyCompressible,
        },
        Treatment {
            density_equation: DensityEquation::Continuity,
            clamp_negative_pressure: false,
            particle_shifting: 2.0,
            velocity_gradient: VelocityGradient::Sph,
            pressure: Pressure::WeaklyCompressible,
        },
    ];

    /// The paper's operator with the continuity equation, particle shifting (A = 2) and the
    /// renormalized velocity gradient: the formulation the shipped jets use.
    pub const RENORMALIZED: Treatment = Treatment {
        density_equation: DensityEquation::Continuity,
        clamp_negative_pressure: false,
        particle_shifting: 2.0,
        velocity_gradient: VelocityGradient::Renormalized,
        pressure: Pressure::WeaklyCompressible,
    };

    /// Pressure solved (divergence-free SPH) on the continuity density, with implicit viscosity
    /// on the paper's operator at the own density and particle shifting (A = 2): the
    /// divergence-free formulation that thins as the liquid does.
    pub const DIVERGENCE_FREE: Treatment = Treatment {
        density_equation: DensityEquation::Continuity,
        clamp_negative_pressure: false,
        particle_shifting: 2.0,
        velocity_gradient: VelocityGradient::OwnDensity,
        pressure: Pressure::DivergenceFree,
    };

    /// How a case names its density and pressure, and how a plot's file name does.
    fn density_names(&self) -> (&'static str, &'static str) {
        match (self.density_equation, self.clamp_negative_pressure) {
            (DensityEquation::Summation, true) => ("clamped pressure", "clamped"),
            (DensityEquation::Summation, false) => ("pressure as printed", "printed"),
            (DensityEquation::Continuity, true) => ("continuity density, clamped pressure", "continuity_clamped"),
            (DensityEquation::Continuity, false) => ("continuity density", "continuity"),
        }
    }

    /// How a case names it.
    pub fn name(&self) -> String {
        let mut name = self.density_names().0.to_string();
        if self.pressure == Pressure::DivergenceFree {
            name = format!("divergence-free pressure, implicit viscosity, {name}");
        }
        if self.particle_shifting > 0.0 {
            name += &format!(", particle shifting A = {}", self.particle_shifting);
        }
        if self.velocity_gradient == VelocityGradient::Renormalized {
            name += ", renormalized gradient";
        }
        name
    }

    /// How a plot's file name names it.
    pub fn word(&self) -> String {
        let mut word = self.density_names().1.to_string();
        if self.particle_shifting > 0.0 {
            word += "_shifted";
        }
        if self.velocity_gradient == VelocityGradient::Renormalized {
            word += "_renormalized";
        }
        if self.pressure == Pressure::DivergenceFree {
            word += "_divergence_free";
        }
        word
    }
}

/// The shipped Newtonian jet falling `FALL_M` onto nothing: no plate, the domain's floor at
/// y = 0, `across` particles across D, operator `op`, density, pressure and shifting by
/// `treatment`, run to `end_time_s`; with the thread it should follow.
pub fn thread_scene(
    across: f64,
    op: ViscosityOperator,
    treatment: Treatment,
    end_time_s: f64,
) -> Result<(Scene, SlenderThread), String> {
    let mut scene = Scene::parse(NEWTONIAN_JET, "scenes/newtonian_jet.toml").map_err(|e| e.to_string())?;
    let diameter = match scene.inlets[0].nozzle {
        crate::scene::Nozzle::Circle { radius_m } => 2.0 * radius_m,
        crate::scene::Nozzle::Rectangle { .. } => return Err("the shipped jet's nozzle is round".into()),
    };
    let material = &mut scene.material;
    material.particle_spacing_m = diameter / across;
    material.clamp_negative_pressure = treatment.clamp_negative_pressure;
    material.density_equation = treatment.density_equation;
    material.viscosity.operator = op;
    material.viscosity.velocity_gradient = treatment.velocity_gradient;
    scene.boundaries.clear();
    let inlet = &mut scene.inlets[0];
    inlet.position_m = [0.0, FALL_M, 0.0];
    inlet.wobble_m = inlet.wobble_m.min(0.25 * diameter / across);
    scene.domain.min_m[1] = 0.0;
    scene.domain.max_m[1] = FALL_M + 0.03;
    scene.simulation.end_time_s = end_time_s;
    scene.simulation.max_fluid_particles = Some(4_000_000);
    scene.simulation.particle_shifting = treatment.particle_shifting;
    if treatment.pressure == Pressure::DivergenceFree {
        scene.simulation.pressure = Pressure::DivergenceFree;
        scene.material.density_kernel = DensityKernelKind::Spiky;
        scene.material.density_diffusion = 0.0;
        scene.material.viscosity.solver = ViscositySolver::Implicit;
    }
    scene.name = format!("viscous_thread_{across}");
    let thread = SlenderThread {
        nozzle_speed_m_s: scene.inlets[0].speed_m_s,
        gravity_m_s2: -scene.material.gravity_m_s2[1],
        viscosity_m2_s: scene.material.viscosity.nu0_m2_s,
        length_m: FALL_M,
        trouton_ratio: 3.0,
    };
    Ok((scene, thread))
}

/// The thread's measured state in one slab along the fall, averaged over frames.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Slab {
    /// The slab's middle, below the nozzle (m).
    pub z_m: f64,
    /// Mean downward speed of the particles in it (m/s).
    pub speed_m_s: f64,
    /// Mean density over rho0.
    pub density_ratio: f64,
    /// Particles counted, over all frames.
    pub particles: usize,
}

/// Runs `scene` and averages the downward speed of its fluid in `slabs` slabs between
/// `margin_m` below the nozzle and `margin_m` above the floor, over the frames every 0.02 s from
/// `steady_s` to the end.
pub fn measure(scene: &Scene, slabs: usize, margin_m: f64, steady_s: f64) -> Result<Vec<Slab>, String> {
    let end = scene.simulation.end_time_s;
    let frames = ((end - steady_s) / 0.02).round() as usize;
    let times: Vec<f64> = (0..=frames).map(|k| steady_s + k as f64 * 0.02).filter(|&t| t <= end + 1e-12).collect();
    let snaps = snapshots(scene, &times, None)?;
    let nozzle_y = scene.inlets[0].position_m[1];
    let width = (FALL_M - 2.0 * margin_m) / slabs as f64;
    let rho0 = scene.material.rest_density_kg_m3;
    let mut sums = vec![(0.0, 0.0, 0usize); slabs];
    for snap in &snaps {
        for (k, p) in snap.position.iter().enumerate() {
            let z = nozzle_y - p[1] - margin_m;
            if z < 0.0 || z >= slabs as f64 * width {
                continue;
            }
            let slab = &mut sums[(z / width) as usize];
            slab.0 -= snap.velocity[k][1];
            slab.1 += snap.density[k] / rho0;
            slab.2 += 1;
        }
    }
    Ok(sums
        .iter()
        .enumerate()
        .map(|(k, &(speed, density, n))| Slab {
            z_m: margin_m + (k as f64 + 0.5) * width,
            speed_m_s: speed / n.max(1) as f64,
            density_ratio: density / n.max(1) as f64,
            particles: n,
        })
        .collect())
}

/// The viscous thread at `across` particles across D with operator `op`, density by
/// `density_equation`, negative pressure clamped or not, against the slender-thread solution: the largest relative error of the
/// downward speed over 12 slabs of the fall, averaged over the frames from 0.5 to 0.7 s.
pub fn viscous_thread(
    across: f64,
    op: ViscosityOperator,
    treatment: Treatment,
    out: Option<&Path>,
) -> Result<CaseResult, String> {
    let case = format!("viscous thread, {} across D, {}, {}", across, operator_name(op), treatment.name());
    let started = Instant::now();
    let (scene, thread) = thread_scene(across, op, treatment, 0.7)?;
    let reference = thread.profile()?;
    let slabs = measure(&scene, 12, 0.0125, 0.5).map_err(|e| format!("{case}: {e}"))?;
    let error = slabs
        .iter()
        .map(|s| {
            let u = speed_at(&reference, s.z_m);
            (s.speed_m_s - u).abs() / u
        })
        .fold(0.0, f64::max);
    let plot = out
        .map(|dir| {
            let chart = Chart {
                title: case.clone(),
                x: Axis::linear("distance below the nozzle z (m)"),
                y: Axis::linear("downward speed (m/s)"),
                series: vec![
                    Curve {
                        label: "slender thread, Trouton viscosity 3 nu".into(),
                        color: PALETTE[0],
                        points: reference.iter().step_by(40).copied().collect(),
                        line: Line::Solid,
                        marker: 0.0,
                    },
                    Curve {
                        label: "free fall".into(),
                        color: PALETTE[2],
                        points: reference
                            .iter()
                            .step_by(40)
                            .map(|p| [p[0], (thread.nozzle_speed_m_s.powi(2) + 2.0 * thread.gravity_m_s2 * p[0]).sqrt()])
                            .collect(),
                        line: Line::Solid,
                        marker: 0.0,
                    },
                    Curve {
                        label: "sph".into(),
                        color: PALETTE[1],
                        points: slabs.iter().map(|s| [s.z_m, s.speed_m_s]).collect(),
                        line: Line::None,
                        marker: 3.0,
                    },
                ],
            };
            save_plot(&chart, &dir.join(format!("thread_{}_{}_{across}.png", scene_word(op), treatment.word())))
        })
        .transpose()?;
    let densities: Vec<String> = slabs.iter().map(|s| format!("{:.3}", s.density_ratio)).collect();
    let trouton = fitted_trouton_ratio(&thread, &slabs)?;
    let lowest = slabs.last().ok_or("no slab")?;
    Ok(CaseResult {
        case,
        measure: format!(
            "largest |U / U_thread - 1| over 12 slabs from 12.5 mm below the nozzle to 12.5 mm above the floor, frames every 0.02 s from 0.5 to 0.7 s (lowest slab: {:.3} m/s, the thread {:.3}, free fall {:.3}); fitted Trouton ratio {trouton:.2} (3 for the liquid); density / rho0 by slab {}; {}",
            lowest.speed_m_s,
            speed_at(&reference, lowest.z_m),
            (thread.nozzle_speed_m_s.powi(2) + 2.0 * thread.gravity_m_s2 * lowest.z_m).sqrt(),
            densities.join(", "),
            match treatment.pressure {
                Pressure::WeaklyCompressible => "c = 20 m/s",
                Pressure::DivergenceFree => "at the CFL step",
            }
        ),
        error,
        tolerance: 0.05,
        at_least: false,
        wall_s: started.elapsed().as_secs_f64(),
        plot,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Without viscosity's pull the thread falls freely: U^2 = U0^2 + 2 g z. With it, it is
    /// held back, and the profile ends stress-free.
    #[test]
    fn the_slender_thread_is_held_back_by_its_extensional_viscosity() {
        let thread =
            SlenderThread { nozzle_speed_m_s: 1.0, gravity_m_s2: 9.8, viscosity_m2_s: 0.1, length_m: 0.3, trouton_ratio: 3.0 };
        let profile = thread.profile().expect("a profile");
        let end = profile.last().expect("points")[1];
        let free_fall = (1.0f64 + 2.0 * 9.8 * 0.3).sqrt();
        // 1.813 m/s at the floor (the case was designed around about 1.8), against 2.55 in free
        // fall.
        assert!((end - 1.813).abs() < 2e-3, "{end}");
        assert!(end < 0.75 * free_fall);
        assert!((profile[0][1] - 1.0).abs() < 1e-9, "U(0) = {}", profile[0][1]);
        let slope = (profile[STEPS][1] - profile[STEPS - 1][1]) / (profile[STEPS][0] - profile[STEPS - 1][0]);
        assert!(slope.abs() < 1e-2, "U'(L) = {slope}");
        // The profile satisfies the equation, by central differences at interior points.
        for k in (100..STEPS - 100).step_by(97) {
            let dz = profile[k + 1][0] - profile[k][0];
            let (u, up) = (profile[k][1], (profile[k + 1][1] - profile[k - 1][1]) / (2.0 * dz));
            let upp = (profile[k + 1][1] - 2.0 * u + profile[k - 1][1]) / (dz * dz);
            let residual = u * up - 9.8 - 3.0 * 0.1 * (upp - up * up / u);
            assert!(residual.abs() < 1e-4 * 9.8, "z = {}: residual {residual}", profile[k][0]);
        }
        // Twice the viscosity holds the thread back further; a hundredth of it nearly not: the
        // thread falls freely but for a stress-free end a few viscous lengths 3 nu / U long.
        let thick = SlenderThread { viscosity_m2_s: 0.2, ..thread };
        let slower = thick.profile().expect("a profile").last().expect("points")[1];
        assert!(slower < end - 0.1, "{slower} against {end}");
        let thin = SlenderThread { viscosity_m2_s: 1e-3, ..thread };
        let profile = thin.profile().expect("a profile");
        let middle = speed_at(&profile, 0.15);
        let falling = (1.0f64 + 2.0 * 9.8 * 0.15).sqrt();
        assert!((middle - falling).abs() < 0.01 * falling, "{middle} against free fall {falling}");
    }

    #[test]
    fn speeds_interpolate_between_profile_points() {
        let profile = [[0.0, 1.0], [0.1, 2.0], [0.2, 4.0]];
        assert_eq!(speed_at(&profile, 0.05), 1.5);
        assert_eq!(speed_at(&profile, 0.15), 3.0);
        assert_eq!(speed_at(&profile, 0.0), 1.0);
    }
}
