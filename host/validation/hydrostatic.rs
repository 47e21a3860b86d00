//! A tank of fluid at rest under gravity: the pressure must be rho0 g depth and the fluid must
//! stay at rest.
//!
//! Fluid set on the lattice at rest has no pressure yet; switched on at once, gravity would
//! start an acoustic oscillation as large as the hydrostatic pressure itself, which viscosity
//! damps only over some 12 N^2 steps per e-fold for N layers. The case ramps gravity up over
//! ten periods of the tank's slowest acoustic mode instead, so the fluid compresses almost
//! quasi-statically, then holds it for five more periods before comparing.

use super::case::scene_word;
use super::case::{save_plot, CaseResult};
use super::snapshot::{snapshots, Snapshot};
use crate::output::plot::Axis;
use crate::output::plot::Chart;
use crate::output::plot::Curve;
use crate::output::plot::Line;
use crate::output::plot::PALETTE;
use crate::scene::{DensityKernelKind, Pressure, PressureGradient, Scene, Walls};
use std::f64::consts::PI;
use std::path::Path;
use std::time::Instant;

/// An open-topped cubic tank `layers` particles wide and deep, filled to the brim.
#[derive(Debug, Clone, Copy)]
pub struct Tank {
    /// Fluid depth D (m).
    pub depth_m: f64,
    /// Particles across the depth (and the width).
    pub layers: usize,
    pub gradient: PressureGradient,
    /// How pressure is found; solved, the walls are the paper's, mirroring the pressure, and
    /// the density kernel the spiky one, as a solved pressure needs.
    pub pressure: Pressure,
}

/// |g| (m/s^2).
const GRAVITY: f64 = 9.81;
/// rho0 (kg/m^3).
const REST_DENSITY: f64 = 1000.0;

impl Tank {
    pub fn new(layers: usize, gradient: PressureGradient) -> Self {
        Self { depth_m: 0.1, layers, gradient, pressure: Pressure::WeaklyCompressible }
    }

    /// The same tank with pressure solved for a divergence-free flow.
    pub fn divergence_free(self) -> Self {
        Self { pressure: Pressure::DivergenceFree, ..self }
    }

    pub fn spacing(&self) -> f64 {
        self.depth_m / self.layers as f64
    }

    /// c (m/s): ten times sqrt(g D), so the fluid compresses by g D / c^2 = 1 % at the floor.
    pub fn sound_speed(&self) -> f64 {
        10.0 * (GRAVITY * self.depth_m).sqrt()
    }

    /// The period of the slowest acoustic mode, a quarter wave over the depth (s).
    pub fn acoustic_period(&self) -> f64 {
        4.0 * self.depth_m / self.sound_speed()
    }

    /// rho0 g (Pa/m): the hydrostatic pressure per metre of depth.
    pub fn rho0_g(&self) -> f64 {
        REST_DENSITY * GRAVITY
    }

    /// Gravity rises as (1 - cos) / 2 over this time (s).
    pub fn ramp_s(&self) -> f64 {
        10.0 * self.acoustic_period()
    }

    /// The time at which the tank is compared (s).
    pub fn end_s(&self) -> f64 {
        self.ramp_s() + 5.0 * self.acoustic_period()
    }

    /// Gravity at time t (m/s^2), along -y.
    pub fn gravity(&self, t: f64) -> [f64; 3] {
        let ramp = if t < self.ramp_s() { 0.5 * (1.0 - (PI * t / self.ramp_s()).cos()) } else { 1.0 };
        [0.0, -GRAVITY * ramp, 0.0]
    }

    /// The scene: mirrored walls (where pressure is solved, the paper's mirroring it),
    /// negative pressure clamped (the free surface is at p = 0), and a viscosity at which
    /// Eq. (10)'s viscous and acoustic terms are equal, to damp what the ramp leaves.
    pub fn scene(&self) -> Scene {
        let s = self.spacing();
        let (d, c) = (self.depth_m, self.sound_speed());
        let nu = 0.25 * s * c;
        let gradient = scene_word(self.gradient);
        let pressure = scene_word(self.pressure);
        let (walls, density_kernel) = match self.pressure {
            Pressure::WeaklyCompressible => (Walls::Mirrored, DensityKernelKind::Poly6),
            Pressure::DivergenceFree => (Walls::Paper, DensityKernelKind::Spiky),
        };
        let (walls, density_kernel) = (scene_word(walls), scene_word(density_kernel));
        // Solved, the walls mirror the pressure, which is what reads rho0 g depth beside them.
        let solves = match self.pressure {
            Pressure::WeaklyCompressible => "",
            Pressure::DivergenceFree => "[simulation.divergence_free]\nwall_pressure = \"mirrored\"",
        };
        let text = format!(
            r#"
name = "hydrostatic_tank"
[material]
rest_density_kg_m3 = {rho0:e}
sound_speed_m_s = {c:e}
clamp_negative_pressure = true
pressure_gradient = "{gradient}"
density_kernel = "{density_kernel}"
particle_spacing_m = {s:e}
gravity_m_s2 = [0.0, {g:e}, 0.0]
[material.viscosity]
operator = "laplacian"
nu0_m2_s = {nu:e}
[domain]
min_m = [{lo:e}, {lo:e}, {lo:e}]
max_m = [{hi:e}, {top:e}, {hi:e}]
[simulation]
end_time_s = {end:e}
precision = "f64"
walls = "{walls}"
pressure = "{pressure}"
{solves}
[[boundary]]
shape = "box"
min_m = [0.0, 0.0, 0.0]
max_m = [{d:e}, {d:e}, {d:e}]
open_top = true
[[fluid_block]]
min_m = [0.0, 0.0, 0.0]
max_m = [{d:e}, {d:e}, {d:e}]
"#,
            g = -GRAVITY,
            rho0 = REST_DENSITY,
            lo = -4.0 * s,
            hi = d + 4.0 * s,
            top = 1.5 * d,
            end = self.end_s(),
        );
        Scene::parse(&text, "hydrostatic tank (generated)").expect("the generated tank is a valid scene")
    }
}

/// What the tank measured.
#[derive(Debug, Clone)]
pub struct TankResult {
    /// The largest |mean p - rho0 g mean depth| over the layers deeper than h, over rho0 g D.
    pub pressure_error: f64,
    /// The root mean square of each particle's pressure about its layer's mean, over rho0 g D:
    /// weakly compressible SPH's pressure noise (c^2 times the density noise).
    pub pressure_scatter: f64,
    /// The least-squares slope of the layer pressures against rho0 g depth, through the origin,
    /// over the same layers: 1 for the right hydrostatics.
    pub pressure_ratio: f64,
    /// The largest fluid speed at the end, over sqrt(g D).
    pub residual_speed: f64,
    /// The free surface, half a spacing above the highest particle (m).
    pub surface_m: f64,
    /// The end state, for plots.
    pub snapshot: Snapshot,
}

/// Runs the tank and compares its pressure, layer by layer, with rho0 g depth. The layers
/// within h of the free surface are left out: their kernel sums lack the fluid above, so their
/// density and hence pressure read low (clamped to 0), whatever the pressure force does.
pub fn simulate(tank: &Tank) -> Result<TankResult, String> {
    let scene = tank.scene();
    let gravity = |t: f64| tank.gravity(t);
    let snapshot = snapshots(&scene, &[tank.end_s()], Some(&gravity))?.remove(0);
    let rho0_g = tank.rho0_g();
    let s = tank.spacing();
    let surface = snapshot.position.iter().map(|x| x[1]).fold(f64::MIN, f64::max) + 0.5 * s;
    // Per layer: particles, sum of depths, sum of pressures.
    let mut layers = vec![(0usize, 0.0, 0.0); tank.layers + 1];
    let layer_of = |y: f64| (((surface - y) / s - 0.5).round().max(0.0) as usize).min(tank.layers);
    for (x, p) in snapshot.position.iter().zip(&snapshot.pressure) {
        let l = &mut layers[layer_of(x[1])];
        *l = (l.0 + 1, l.1 + surface - x[1], l.2 + p);
    }
    let h = scene.support_radius();
    // (mean depth, mean pressure) of the layers deeper than h.
    let compared: Vec<(f64, f64)> = layers
        .iter()
        .filter(|l| l.0 > 0 && l.1 / l.0 as f64 > h)
        .map(|&(n, depth, p)| (depth / n as f64, p / n as f64))
        .collect();
    let pressure_error =
        compared.iter().map(|&(depth, p)| (p - rho0_g * depth).abs()).fold(0.0, f64::max) / (rho0_g * tank.depth_m);
    let pressure_ratio =
        compared.iter().map(|&(d, p)| d * p).sum::<f64>() / compared.iter().map(|&(d, _)| rho0_g * d * d).sum::<f64>();
    let squares: f64 = snapshot
        .position
        .iter()
        .zip(&snapshot.pressure)
        .map(|(x, p)| {
            let l = layers[layer_of(x[1])];
            (p - l.2 / l.0 as f64).powi(2)
        })
        .sum();
    let pressure_scatter = (squares / snapshot.pressure.len() as f64).sqrt() / (rho0_g * tank.depth_m);
    let residual_speed = snapshot.max_speed() / (GRAVITY * tank.depth_m).sqrt();
    Ok(TankResult { pressure_error, pressure_scatter, pressure_ratio, residual_speed, surface_m: surface, snapshot })
}

/// The hydrostatic tank, `layers` particles deep, with the full pressure gradient: the pressure
/// against rho0 g depth, and the residual speed once settled.
pub fn hydrostatic_tank(layers: usize, pressure: Pressure, out: Option<&Path>) -> Result<Vec<CaseResult>, String> {
    let weakly_compressible = Tank::new(layers, PressureGradient::Full);
    let (tank, solved, file) = match pressure {
        Pressure::WeaklyCompressible => (weakly_compressible, "", ""),
        Pressure::DivergenceFree => {
            (weakly_compressible.divergence_free(), ", divergence-free pressure mirrored onto the walls", "_divergence_free")
        }
    };
    let started = Instant::now();
    let r = simulate(&tank)?;
    let wall_s = started.elapsed().as_secs_f64();
    let case = format!("hydrostatic tank, {layers} layers deep{solved}");
    let plot = out
        .map(|dir| {
            let d = tank.depth_m;
            let surface = r.surface_m;
            let rho0_g = tank.rho0_g();
            let points =
                r.snapshot.position.iter().zip(&r.snapshot.pressure).map(|(x, p)| [(surface - x[1]) / d, p / (rho0_g * d)]);
            let chart = Chart {
                title: case.clone(),
                x: Axis::linear("depth / D"),
                y: Axis::linear("p / (rho0 g D)"),
                series: vec![
                    Curve {
                        label: "rho0 g depth".into(),
                        color: PALETTE[0],
                        points: vec![[0.0, 0.0], [1.0, 1.0]],
                        line: Line::Solid,
                        marker: 0.0,
                    },
                    Curve { label: "sph".into(), color: PALETTE[1], points: points.collect(), line: Line::None, marker: 2.0 },
                ],
            };
            save_plot(&chart, &dir.join(format!("hydrostatic_{layers}{file}.png")))
        })
        .transpose()?;
    // Solved, the fluid does not compress and the tolerance is the 2 % a solved pressure is
    // asked to read within.
    let (c, tolerance) = match pressure {
        Pressure::WeaklyCompressible => (format!("c = {:.2} m/s (g D / c^2 = 0.01)", tank.sound_speed()), 0.05),
        Pressure::DivergenceFree => ("the pressure read as the solved pressures' SPH interpolant".to_string(), 0.02),
    };
    Ok(vec![
        CaseResult {
            case: format!("{case}: pressure"),
            measure: format!(
                "max over layers deeper than h of |mean p - rho0 g depth| / (rho0 g D) after gravity is ramped up (particle scatter about the layer mean: {:.3} rms); {c}",
                r.pressure_scatter
            ),
            error: r.pressure_error,
            tolerance,
            at_least: false,
            wall_s,
            plot,
        },
        CaseResult {
            case: format!("{case}: at rest"),
            measure: format!("max |v| / sqrt(g D) at the end; {c}"),
            error: r.residual_speed,
            tolerance: 0.01,
            at_least: false,
            wall_s,
            plot: None,
        },
    ])
}
