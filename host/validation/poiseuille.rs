//! Plane Poiseuille flow between plates at y = 0 and y = L, driven by a body force F along x,
//! periodic in x and z: the start-up of a Newtonian fluid against Morris, Fox & Zhu (1997)'s
//! series solution, and the steady flow of a Cross fluid against the profile integrated from
//! its exact shear stress.

use super::case::scene_word;
use super::case::{across_gap, operator_file_word, operator_label, profile_chart, save_plot, CaseResult, MORRIS_TIMES};
use super::snapshot::snapshots;
use crate::scene::{
    DensityKernelKind, Precision, Pressure, Scene, VelocityGradient, ViscosityOperator, ViscositySolver, ViscousVelocity,
    WallPressure, Walls,
};
use std::f64::consts::PI;
use std::path::Path;
use std::time::Instant;

/// Morris et al. 1997's channel: L = 1 mm, nu = 1e-6 m^2/s, F = 2e-4 m/s^2, rho0 = 1000
/// kg/m^3, so u_max = F L^2 / (8 nu) = 2.5e-5 m/s and the flow settles over L^2 / nu = 1 s.
#[derive(Debug, Clone, Copy)]
pub struct Channel {
    /// Plate gap L (m).
    pub gap_m: f64,
    /// Body force per unit mass F (m/s^2).
    pub force_m_s2: f64,
    /// nu0 (m^2/s); with `cross` also nu_inf, K and n.
    pub nu0_m2_s: f64,
    pub cross: Option<CrossLaw>,
    /// Particles across the gap.
    pub across: usize,
    pub operator: ViscosityOperator,
    pub walls: Walls,
    pub precision: Precision,
    /// c (m/s).
    pub sound_speed_m_s: f64,
    /// Multiplies the automatic dt; above 1 the scene overrides the Eq. (10) bound.
    pub safety_factor: f64,
    /// W of Eq. (5).
    pub density_kernel: DensityKernelKind,
    /// Weight of the hourglass control of the paper's operator (0: none).
    pub hourglass_control: f64,
    /// Which velocity the viscous terms read.
    pub viscous_velocity: ViscousVelocity,
    /// The paper's operator's velocity gradient.
    pub velocity_gradient: VelocityGradient,
    /// How viscosity is integrated in time.
    pub solver: ViscositySolver,
    /// A fixed dt (s) in place of the automatic one.
    pub fixed_dt_s: Option<f64>,
    /// The implicit solve's relative residual.
    pub implicit_tolerance: f64,
    /// Eq. (6)'s pressure, or pressure solved (at the CFL time step, on the paper's walls).
    pub pressure: Pressure,
    /// What the walls push with where pressure is solved.
    pub wall_pressure: WallPressure,
}

/// The Cross model, Eq. (3), by its constants.
#[derive(Debug, Clone, Copy)]
pub struct CrossLaw {
    pub nu_inf_m2_s: f64,
    pub k_s: f64,
    pub n: f64,
}

impl CrossLaw {
    /// nu(gamma) (m^2/s), Eq. (3).
    pub fn viscosity(&self, nu0: f64, shear_rate: f64) -> f64 {
        self.nu_inf_m2_s + (nu0 - self.nu_inf_m2_s) / (1.0 + (self.k_s * shear_rate).powf(self.n))
    }
}

impl Channel {
    /// Morris et al.'s Newtonian case with `across` particles over the gap.
    pub fn morris(across: usize, operator: ViscosityOperator) -> Self {
        Self {
            gap_m: 1e-3,
            force_m_s2: 2e-4,
            nu0_m2_s: 1e-6,
            cross: None,
            across,
            operator,
            walls: Walls::Mirrored,
            precision: Precision::F64,
            // Mach 0.01 at u_max = 2.5e-5 m/s; dt stays set by the viscous term of Eq. (10).
            sound_speed_m_s: 2.5e-3,
            safety_factor: 1.0,
            density_kernel: DensityKernelKind::Poly6,
            hourglass_control: 0.0,
            viscous_velocity: ViscousVelocity::FullStep,
            velocity_gradient: VelocityGradient::Sph,
            solver: ViscositySolver::Explicit,
            fixed_dt_s: None,
            implicit_tolerance: 1e-3,
            pressure: Pressure::WeaklyCompressible,
            wall_pressure: WallPressure::Once,
        }
    }

    /// Eq. (10)'s viscous bound for this channel, 0.1 h^2 / (8 nu0) (s).
    pub fn viscous_bound_s(&self) -> f64 {
        let h = 2.0 * self.spacing();
        0.1 * h * h / (8.0 * self.nu0_m2_s)
    }

    /// Steady centre-line speed of the Newtonian flow F L^2 / (8 nu) (m/s).
    pub fn newtonian_peak(&self) -> f64 {
        self.force_m_s2 * self.gap_m * self.gap_m / (8.0 * self.nu0_m2_s)
    }

    /// The particle spacing (m).
    pub fn spacing(&self) -> f64 {
        self.gap_m / self.across as f64
    }

    /// The scene: plates of boundary particles at y = 0 and y = L, 6 spacings (3 h) of fluid
    /// along the periodic x and z, fluid at rest, F as gravity along x.
    pub fn scene(&self, end_time_s: f64) -> Scene {
        let s = self.spacing();
        let (l, w) = (self.gap_m, 6.0 * s);
        let (operator, precision, walls) = (scene_word(self.operator), scene_word(self.precision), scene_word(self.walls));
        let (density_kernel, viscous_velocity) = (scene_word(self.density_kernel), scene_word(self.viscous_velocity));
        let (velocity_gradient, solver) = (scene_word(self.velocity_gradient), scene_word(self.solver));
        let (pressure, wall_pressure) = (scene_word(self.pressure), scene_word(self.wall_pressure));
        let fixed = self.fixed_dt_s.map(|dt| format!(", fixed_s = {dt:e}")).unwrap_or_default();
        let cross = self
            .cross
            .map(|c| format!("nu_inf_m2_s = {:e}\ncross_k_s = {:e}\ncross_n = {:e}\n", c.nu_inf_m2_s, c.k_s, c.n))
            .unwrap_or_default();
        let text = format!(
            r#"
name = "poiseuille"
[material]
rest_density_kg_m3 = 1000.0
sound_speed_m_s = {c:e}
particle_spacing_m = {s:e}
support_radius_factor = 2.0
gravity_m_s2 = [{f:e}, 0.0, 0.0]
density_kernel = "{density_kernel}"
[material.viscosity]
operator = "{operator}"
nu0_m2_s = {nu0:e}
hourglass_control = {hg:e}
velocity_gradient = "{velocity_gradient}"
solver = "{solver}"
implicit = {{ tolerance = {tolerance:e} }}
{cross}
[domain]
min_m = [0.0, {ylo:e}, 0.0]
max_m = [{w:e}, {yhi:e}, {w:e}]
periodic = [true, false, true]
[simulation]
end_time_s = {end_time_s:e}
precision = "{precision}"
walls = "{walls}"
pressure = "{pressure}"
time_step = {{ safety_factor = {sf:e}, allow_above_stability_bound = {above}, viscous_velocity = "{viscous_velocity}"{fixed} }}
divergence_free = {{ wall_pressure = "{wall_pressure}" }}
[[boundary]]
shape = "box"
min_m = [0.0, 0.0, 0.0]
max_m = [{w:e}, {l:e}, {w:e}]
[[fluid_block]]
min_m = [0.0, 0.0, 0.0]
max_m = [{w:e}, {l:e}, {w:e}]
"#,
            c = self.sound_speed_m_s,
            f = self.force_m_s2,
            nu0 = self.nu0_m2_s,
            ylo = -4.0 * s,
            yhi = l + 4.0 * s,
            sf = self.safety_factor,
            above = self.safety_factor > 1.0 || self.fixed_dt_s.is_some(),
            hg = self.hourglass_control,
            tolerance = self.implicit_tolerance,
        );
        Scene::parse(&text, "poiseuille (generated)").expect("the generated channel is a valid scene")
    }
}

/// Morris et al. 1997, Eq. (20): the start-up velocity u(y, t) (m/s) of a Newtonian fluid at
/// rest at t = 0, summed until the terms fall below 1e-16 of the peak.
pub fn startup_velocity(channel: &Channel, y: f64, t: f64) -> f64 {
    let (f, l, nu) = (channel.force_m_s2, channel.gap_m, channel.nu0_m2_s);
    let mut u = f / (2.0 * nu) * y * (l - y);
    for n in 0.. {
        let k = (2 * n + 1) as f64;
        let amplitude = 4.0 * f * l * l / (nu * PI.powi(3) * k.powi(3));
        let bound = amplitude * (-(k * k) * PI * PI * nu * t / (l * l)).exp();
        u -= bound * (k * PI * y / l).sin();
        // The amplitudes alone fall as 1/k^3 and would take 1e5 terms; with the decay the
        // series at the compared times ends within a dozen.
        if bound < 1e-16 * channel.newtonian_peak() {
            break;
        }
    }
    u
}

/// The steady profile of a Cross fluid: the shear stress at distance d from the mid-plane is
/// rho F d exactly, so nu(g) g = F d gives the local shear rate g (unique while nu(g) g
/// increases, which n <= 1 ensures), and u is its integral from the wall. Returns u at `ys`
/// (m/s), by the midpoint rule on 4000 intervals per half gap.
pub fn cross_steady_velocity(channel: &Channel, law: &CrossLaw, ys: &[f64]) -> Vec<f64> {
    let (f, l, nu0) = (channel.force_m_s2, channel.gap_m, channel.nu0_m2_s);
    let shear_rate = |d: f64| {
        let target = f * d;
        // nu(g) g lies between nu_inf g and nu0 g, which brackets g.
        let (mut lo, mut hi) = (target / nu0, target / law.nu_inf_m2_s);
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if law.viscosity(nu0, mid) * mid < target {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        0.5 * (lo + hi)
    };
    let intervals = 4000;
    let dy = 0.5 * l / intervals as f64;
    // u at the ends of each interval from the lower wall to the mid-plane.
    let mut u = vec![0.0; intervals + 1];
    for k in 0..intervals {
        let y_mid = (k as f64 + 0.5) * dy;
        u[k + 1] = u[k] + shear_rate(0.5 * l - y_mid) * dy;
    }
    ys.iter()
        .map(|&y| {
            let from_wall = y.min(l - y).clamp(0.0, 0.5 * l);
            let x = from_wall / dy;
            let k = (x.floor() as usize).min(intervals - 1);
            u[k] + (x - k as f64) * (u[k + 1] - u[k])
        })
        .collect()
}

/// Fluid particles' (y (m), u_x (m/s)) at each requested time.
pub type Profiles = Vec<Vec<[f64; 2]>>;

/// Runs the channel and samples the fluid's (y, u_x) at each of `times` (s, increasing).
/// Errors name the instability.
pub fn simulate(channel: &Channel, times: &[f64]) -> Result<Profiles, String> {
    let end = *times.last().expect("at least one time");
    let snapshots = snapshots(&channel.scene(end), times, None)?;
    Ok(snapshots.iter().map(|s| s.position.iter().zip(&s.velocity).map(|(x, v)| [x[1], v[0]]).collect()).collect())
}

/// Largest |u - reference(y)| over the particles of `profile`, over `scale` (m/s).
pub fn relative_max_error(profile: &[[f64; 2]], reference: impl Fn(f64) -> f64, scale: f64) -> f64 {
    profile.iter().map(|&[y, u]| (u - reference(y)).abs()).fold(0.0, f64::max) / scale
}

/// The start-up Poiseuille flow against Morris et al.'s series, at `across` particles over the
/// gap: L-infinity error over all sampled times, relative to the steady peak.
pub fn startup_poiseuille(across: usize, op: ViscosityOperator, out: Option<&Path>) -> Result<CaseResult, String> {
    startup_poiseuille_in(&Channel::morris(across, op), out)
}
/// [`startup_poiseuille`] in a given channel (its resolution, operator, walls, precision, c and
/// dt safety factor), for the trade-off sweeps.
pub fn startup_poiseuille_in(channel: &Channel, out: Option<&Path>) -> Result<CaseResult, String> {
    let (channel, across, op) = (*channel, channel.across, channel.operator);
    let started = Instant::now();
    let times = MORRIS_TIMES.map(|t| t * channel.gap_m * channel.gap_m / channel.nu0_m2_s);
    let profiles = simulate(&channel, &times)?;
    let peak = channel.newtonian_peak();
    let mut error: f64 = 0.0;
    let mut samples = Vec::new();
    for (&t, profile) in times.iter().zip(&profiles) {
        error = error.max(relative_max_error(profile, |y| startup_velocity(&channel, y, t), peak));
        let reference = across_gap(channel.gap_m, 100).into_iter().map(|y| [y, startup_velocity(&channel, y, t)]).collect();
        samples.push((format!("t={t:.4}s"), profile.clone(), reference));
    }
    let hg = channel.hourglass_control;
    let case = format!("start-up Poiseuille, {}, {across} across", operator_label(op, hg));
    let plot = out
        .map(|dir| {
            let name = format!("poiseuille_{}_{across}.png", operator_file_word(op, hg));
            save_plot(&profile_chart(case.clone(), channel.gap_m, peak, &samples), &dir.join(name))
        })
        .transpose()?;
    Ok(CaseResult {
        case,
        measure: format!(
            "max |u - u_ref| / u_max at nu t / L^2 = {MORRIS_TIMES:?}; c = {} m/s (Mach {:.3})",
            channel.sound_speed_m_s,
            channel.newtonian_peak() / channel.sound_speed_m_s
        ),
        error,
        tolerance: 0.03,
        at_least: false,
        wall_s: started.elapsed().as_secs_f64(),
        plot,
    })
}
/// The steady Poiseuille flow of a Cross fluid (K in s, n) with operator `op`, against the
/// profile integrated from its exact shear stress: L-infinity error over the centre velocity.
pub fn cross_poiseuille(
    across: usize,
    op: ViscosityOperator,
    k_s: f64,
    n: f64,
    out: Option<&Path>,
) -> Result<CaseResult, String> {
    let law = CrossLaw { nu_inf_m2_s: 0.25e-6, k_s, n };
    cross_poiseuille_in(&Channel { cross: Some(law), ..Channel::morris(across, op) }, out)
}
/// [`cross_poiseuille`] in a given channel, whose `cross` must be set.
pub fn cross_poiseuille_in(channel: &Channel, out: Option<&Path>) -> Result<CaseResult, String> {
    let law = channel.cross.expect("a Cross channel");
    let (channel, across, k_s, n, op) = (*channel, channel.across, law.k_s, law.n, channel.operator);
    let started = Instant::now();
    // The slowest mode decays at the rate of nu_inf: 0.75 L^2 / nu_inf leaves e^-30 of it.
    let end = 0.75 * channel.gap_m * channel.gap_m / law.nu_inf_m2_s;
    let profile = simulate(&channel, &[end])?.remove(0);
    let ys: Vec<f64> = profile.iter().map(|p| p[0]).collect();
    let reference = cross_steady_velocity(&channel, &law, &ys);
    let centre = cross_steady_velocity(&channel, &law, &[0.5 * channel.gap_m])[0];
    let error = profile.iter().zip(&reference).map(|(p, r)| (p[1] - r).abs()).fold(0.0, f64::max) / centre;
    let hg = channel.hourglass_control;
    let case = format!("steady Cross Poiseuille K = {k_s} s, n = {n}, {}, {across} across", operator_label(op, hg));
    let plot = out
        .map(|dir| {
            let path = dir.join(format!("cross_poiseuille_{}_k{k_s}_n{n}_{across}.png", operator_file_word(op, hg)));
            let curve_y = across_gap(channel.gap_m, 100);
            let curve = curve_y.iter().zip(cross_steady_velocity(&channel, &law, &curve_y)).map(|(&y, u)| [y, u]).collect();
            save_plot(&profile_chart(case.clone(), channel.gap_m, centre, &[("steady".into(), profile.clone(), curve)]), &path)
        })
        .transpose()?;
    Ok(CaseResult {
        case,
        measure: format!(
            "max |u - u_ref| / u_centre at t = {end} s (steady); nu0 = 1e-6, nu_inf = 2.5e-7 m^2/s; c = {} m/s",
            channel.sound_speed_m_s
        ),
        error,
        tolerance: 0.03,
        at_least: false,
        wall_s: started.elapsed().as_secs_f64(),
        plot,
    })
}
/// The channel of `operator` at `across` that the implicit solver can take: the paper's with
/// the own-density gradient, or Morris's.
fn implicit_ready(across: usize, operator: ViscosityOperator) -> Channel {
    use crate::scene::VelocityGradient;
    let velocity_gradient =
        if operator == ViscosityOperator::Stress { VelocityGradient::OwnDensity } else { VelocityGradient::Sph };
    Channel { velocity_gradient, ..Channel::morris(across, operator) }
}
/// `operator`'s name in the implicit cases.
fn implicit_operator_name(operator: ViscosityOperator) -> &'static str {
    if operator == ViscosityOperator::Stress {
        "paper's operator (own density)"
    } else {
        "Morris's operator"
    }
}
/// Start-up Poiseuille at `across` with implicit viscosity at `multiple` times Eq. (10)'s
/// viscous bound, against the explicit solver on the same operator (the paper's with the
/// own-density gradient, or Morris's) at the bound: the error against Morris et al.'s series may
/// exceed the explicit solver's by at most 0.005 of the peak (what the larger dt may add).
pub fn startup_poiseuille_implicit(across: usize, operator: ViscosityOperator, multiple: f64) -> Result<CaseResult, String> {
    use crate::scene::ViscositySolver;
    let explicit = implicit_ready(across, operator);
    let implicit =
        Channel { solver: ViscositySolver::Implicit, fixed_dt_s: Some(multiple * explicit.viscous_bound_s()), ..explicit };
    let case =
        format!("start-up Poiseuille, {}, implicit at {multiple} x the bound, {across} across", implicit_operator_name(operator));
    startup_against_explicit(&explicit, &implicit, case, "at the bound")
}
/// Start-up Poiseuille in `other` against `explicit`, described by `reference`: the error
/// against Morris et al.'s series may exceed the explicit solver's by at most 0.005 of the peak.
pub(super) fn startup_against_explicit(
    explicit: &Channel,
    other: &Channel,
    case: String,
    reference: &str,
) -> Result<CaseResult, String> {
    let e = startup_poiseuille_in(explicit, None)?;
    let o = startup_poiseuille_in(other, None)?;
    Ok(CaseResult {
        case,
        measure: format!(
            "max |u - u_ref| / u_max minus the explicit solver's {reference}: {:.4} against {:.4}; {:.1} s against {:.1} s",
            o.error, e.error, o.wall_s, e.wall_s
        ),
        error: o.error - e.error,
        tolerance: 0.005,
        at_least: false,
        wall_s: o.wall_s + e.wall_s,
        plot: None,
    })
}
/// Steady Poiseuille of the Cross fluid (K = `k_s` s, n = `n`) with implicit viscosity at
/// `multiple` times the viscous bound: the steady profile within 0.002 of the centre speed of
/// the explicit solver's on the same operator.
pub fn cross_poiseuille_implicit(
    across: usize,
    operator: ViscosityOperator,
    k_s: f64,
    n: f64,
    multiple: f64,
) -> Result<CaseResult, String> {
    use crate::scene::ViscositySolver;
    let law = CrossLaw { nu_inf_m2_s: 0.25e-6, k_s, n };
    let explicit = Channel { cross: Some(law), ..implicit_ready(across, operator) };
    let implicit =
        Channel { solver: ViscositySolver::Implicit, fixed_dt_s: Some(multiple * explicit.viscous_bound_s()), ..explicit };
    let centre = cross_steady_velocity(&explicit, &law, &[0.5 * explicit.gap_m])[0];
    let case = format!(
        "steady Cross Poiseuille K = {k_s} s, n = {n}, {}, implicit at {multiple} x the bound, {across} across",
        implicit_operator_name(operator)
    );
    cross_against_explicit(&explicit, &implicit, |_| centre, case, "implicit", "at the bound on the same operator")
}
/// The steady Cross channel `other` against `explicit`, described by `reference`, run to
/// 0.75 L^2 / nu_inf: the largest difference of the profiles within 0.002 of the centre speed
/// that `centre` reads from the explicit profile. `name` names `other`'s speed.
pub(super) fn cross_against_explicit(
    explicit: &Channel,
    other: &Channel,
    centre: impl Fn(&[[f64; 2]]) -> f64,
    case: String,
    name: &str,
    reference: &str,
) -> Result<CaseResult, String> {
    let law = explicit.cross.expect("a Cross channel");
    let end = 0.75 * explicit.gap_m * explicit.gap_m / law.nu_inf_m2_s;
    let started = Instant::now();
    let e = simulate(explicit, &[end])?.remove(0);
    let explicit_s = started.elapsed().as_secs_f64();
    let started = Instant::now();
    let o = simulate(other, &[end])?.remove(0);
    let other_s = started.elapsed().as_secs_f64();
    let difference = e.iter().zip(&o).map(|(a, b)| (a[1] - b[1]).abs()).fold(0.0, f64::max) / centre(&e);
    Ok(CaseResult {
        case,
        measure: format!(
            "max |u_{name} - u_explicit| / u_centre at t = {end} s, the explicit solver {reference}; {other_s:.1} s against {explicit_s:.1} s"
        ),
        error: difference,
        tolerance: 0.002,
        at_least: false,
        wall_s: other_s + explicit_s,
        plot: None,
    })
}
