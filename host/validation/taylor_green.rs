//! The Taylor-Green vortex: u = U sin(kx) cos(ky), v = -U cos(kx) sin(ky), k = 2 pi / L, in a
//! domain periodic along x, y and z. Its velocity decays as exp(-2 nu k^2 t) = exp(-8 pi^2 nu t
//! / L^2) exactly (Taylor & Green 1937), whatever the Reynolds number.

use super::case::scene_word;
use super::case::{operator_file_word, operator_label, save_plot, CaseResult};
use super::snapshot::{snapshots_from, Snapshot};
use crate::output::plot::Axis;
use crate::output::plot::Chart;
use crate::output::plot::Curve;
use crate::output::plot::Line;
use crate::output::plot::PALETTE;
use crate::scene::setup::initial_particles;
use crate::scene::{DensityKernelKind, Pressure, Scene, VelocityGradient, ViscosityOperator, ViscositySolver};
use std::f64::consts::PI;
use std::path::Path;
use std::time::Instant;

/// The vortex at `across` particles over the period L, Re = U L / nu = 1.
#[derive(Debug, Clone, Copy)]
pub struct Vortex {
    /// Period L (m).
    pub period_m: f64,
    /// Peak speed U (m/s).
    pub speed_m_s: f64,
    /// nu (m^2/s).
    pub nu_m2_s: f64,
    pub across: usize,
    pub operator: ViscosityOperator,
    /// Weight of the hourglass control of the paper's operator (0: none).
    pub hourglass_control: f64,
    /// The paper's operator's velocity gradient.
    pub velocity_gradient: VelocityGradient,
    /// How viscosity is integrated in time.
    pub solver: ViscositySolver,
    /// Eq. (6)'s pressure at c = 10 U, or pressure solved at the CFL time step, at most
    /// [`Self::largest_solved_step`].
    pub pressure: Pressure,
    /// W of Eq. (5).
    pub density_kernel: DensityKernelKind,
}

impl Vortex {
    pub fn new(across: usize, operator: ViscosityOperator) -> Self {
        Self {
            period_m: 1e-3,
            speed_m_s: 1e-3,
            nu_m2_s: 1e-6,
            across,
            operator,
            hourglass_control: 0.0,
            velocity_gradient: VelocityGradient::Sph,
            solver: ViscositySolver::Explicit,
            pressure: Pressure::WeaklyCompressible,
            density_kernel: DensityKernelKind::Poly6,
        }
    }

    /// The exact decay rate of the velocity amplitude, 8 pi^2 nu / L^2 (1/s).
    pub fn decay_rate(&self) -> f64 {
        8.0 * PI * PI * self.nu_m2_s / (self.period_m * self.period_m)
    }

    /// c (m/s): ten times U, Mach 0.1.
    pub fn sound_speed(&self) -> f64 {
        10.0 * self.speed_m_s
    }

    /// The largest dt under solved pressure (s): 1/50 of an e-folding time. The CFL step,
    /// 0.2 s / U, is 80 % of one at 20 across; at the default cap of 1e-3 s backward Euler
    /// lagged the decay by 9 %.
    pub fn largest_solved_step(&self) -> f64 {
        0.02 / self.decay_rate()
    }

    fn wavenumber(&self) -> f64 {
        2.0 * PI / self.period_m
    }

    /// The scene: L by L in x and y, 6 spacings (3 h) deep in z, periodic along all three, no
    /// gravity, no walls; the velocity field is set on the particles.
    pub fn scene(&self) -> Scene {
        let s = self.period_m / self.across as f64;
        let (l, w) = (self.period_m, 6.0 * s);
        let operator = scene_word(self.operator);
        let (velocity_gradient, solver, pressure) =
            (scene_word(self.velocity_gradient), scene_word(self.solver), scene_word(self.pressure));
        let density_kernel = scene_word(self.density_kernel);
        let text = format!(
            r#"
name = "taylor_green"
[material]
rest_density_kg_m3 = 1000.0
sound_speed_m_s = {c:e}
particle_spacing_m = {s:e}
gravity_m_s2 = [0.0, 0.0, 0.0]
density_kernel = "{density_kernel}"
[material.viscosity]
operator = "{operator}"
nu0_m2_s = {nu:e}
hourglass_control = {hg:e}
velocity_gradient = "{velocity_gradient}"
solver = "{solver}"
[domain]
min_m = [0.0, 0.0, 0.0]
max_m = [{l:e}, {l:e}, {w:e}]
periodic = [true, true, true]
[simulation]
end_time_s = 1.0
precision = "f64"
pressure = "{pressure}"
divergence_free = {{ max_time_step_s = {largest:e} }}
[[fluid_block]]
min_m = [0.0, 0.0, 0.0]
max_m = [{l:e}, {l:e}, {w:e}]
"#,
            c = self.sound_speed(),
            nu = self.nu_m2_s,
            hg = self.hourglass_control,
            largest = self.largest_solved_step(),
        );
        Scene::parse(&text, "taylor-green (generated)").expect("the generated vortex is a valid scene")
    }

    /// The amplitude of the vortex mode in `snapshot` (m/s): the least-squares projection of
    /// the particles' velocities onto the mode shape at their positions.
    pub fn amplitude(&self, snapshot: &Snapshot) -> f64 {
        let k = self.wavenumber();
        let (mut dot, mut norm) = (0.0, 0.0);
        for (x, v) in snapshot.position.iter().zip(&snapshot.velocity) {
            let (sx, cx, sy, cy) = ((k * x[0]).sin(), (k * x[0]).cos(), (k * x[1]).sin(), (k * x[1]).cos());
            let mode = [sx * cy, -cx * sy];
            dot += v[0] * mode[0] + v[1] * mode[1];
            norm += mode[0] * mode[0] + mode[1] * mode[1];
        }
        dot / norm
    }
}

/// What the vortex measured.
#[derive(Debug, Clone)]
pub struct VortexResult {
    /// The least-squares decay rate of ln(amplitude) over the sampled times (1/s).
    pub decay_rate: f64,
    /// (t (s), amplitude / U) at each sampled time, t = 0 included.
    pub amplitudes: Vec<[f64; 2]>,
}

/// Runs the vortex over one e-folding time of the exact decay, sampled at eight times.
pub fn simulate(vortex: &Vortex) -> Result<VortexResult, String> {
    let scene = vortex.scene();
    let mut initial = initial_particles(&scene, &scene.name).map_err(|e| e.to_string())?;
    let (k, u) = (vortex.wavenumber(), vortex.speed_m_s);
    for (x, v) in initial.fluid.iter().zip(initial.fluid_velocity.iter_mut()) {
        *v = [u * (k * x[0]).sin() * (k * x[1]).cos(), -u * (k * x[0]).cos() * (k * x[1]).sin(), 0.0];
    }
    let e_fold = 1.0 / vortex.decay_rate();
    let times: Vec<f64> = (1..=8).map(|i| i as f64 / 8.0 * e_fold).collect();
    let snaps = snapshots_from(&scene, &initial, &times, None)?;
    let mut amplitudes = vec![[0.0, 1.0]];
    amplitudes.extend(snaps.iter().map(|s| [s.time_s, vortex.amplitude(s) / u]));
    // Fit ln A = a - rate t by least squares.
    let n = amplitudes.len() as f64;
    let (st, sl) = amplitudes.iter().fold((0.0, 0.0), |(st, sl), p| (st + p[0], sl + p[1].ln()));
    let (mt, ml) = (st / n, sl / n);
    let (cov, var) =
        amplitudes.iter().fold((0.0, 0.0), |(c, v), p| (c + (p[0] - mt) * (p[1].ln() - ml), v + (p[0] - mt).powi(2)));
    Ok(VortexResult { decay_rate: -cov / var, amplitudes })
}

/// The Taylor-Green vortex at `across` particles over the period, with operator `op` (and its
/// hourglass control of weight `hourglass_control`): the measured decay rate of its amplitude
/// against 8 pi^2 nu / L^2.
pub fn taylor_green(
    across: usize,
    op: ViscosityOperator,
    hourglass_control: f64,
    out: Option<&Path>,
) -> Result<CaseResult, String> {
    let vortex = Vortex { hourglass_control, ..Vortex::new(across, op) };
    let started = Instant::now();
    let r = simulate(&vortex)?;
    let exact = vortex.decay_rate();
    let case = format!("Taylor-Green vortex, {}, {across} across", operator_label(op, hourglass_control));
    let plot = out
        .map(|dir| {
            let t_max = r.amplitudes.last().map_or(1.0, |p| p[0]);
            let reference = (0..=50).map(|k| k as f64 / 50.0 * t_max).map(|t| [t * exact, (-exact * t).exp()]).collect();
            let simulated = r.amplitudes.iter().map(|p| [p[0] * exact, p[1]]).collect();
            let chart = Chart {
                title: case.clone(),
                x: Axis::linear("8 pi^2 nu t / L^2"),
                y: Axis::log("amplitude / U"),
                series: vec![
                    Curve {
                        label: "exp(-8 pi^2 nu t / L^2)".into(),
                        color: PALETTE[0],
                        points: reference,
                        line: Line::Solid,
                        marker: 0.0,
                    },
                    Curve { label: "sph".into(), color: PALETTE[1], points: simulated, line: Line::None, marker: 3.0 },
                ],
            };
            let name = format!("taylor_green_{}_{across}.png", operator_file_word(op, hourglass_control));
            save_plot(&chart, &dir.join(name))
        })
        .transpose()?;
    Ok(CaseResult {
        case,
        measure: format!(
            "|rate / (8 pi^2 nu / L^2) - 1|, rate fitted to ln(amplitude) over one e-folding time (measured {:.4e} 1/s, exact {exact:.4e} 1/s); Re = 1, c = {} m/s (Mach 0.1)",
            r.decay_rate,
            vortex.sound_speed()
        ),
        error: (r.decay_rate / exact - 1.0).abs(),
        tolerance: 0.05,
        at_least: false,
        wall_s: started.elapsed().as_secs_f64(),
        plot,
    })
}
