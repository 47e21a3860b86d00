//! The cases with pressure solved (divergence-free SPH, docs/divergence-free.md), each at the
//! CFL time step with implicit viscosity on the paper's operator with the own-density gradient
//! and the spiky density kernel. The vortex, which has no walls, is held to its exact decay. A
//! solved pressure stands on the paper's walls only (it takes no mirrored ones), so the
//! channels and the spreading are compared with the weakly compressible explicit solver on the
//! same operator, kernel and walls at Eq. (10)'s bound, with the tolerances of the implicit
//! viscosity's cases.

use super::huppert::{self, Release, Spreading};
use super::poiseuille::{simulate, Channel, CrossLaw};
use super::taylor_green::{self, Vortex};
use super::{startup_poiseuille_in, CaseResult};
use crate::scene::{DensityKernelKind, Pressure, VelocityGradient, ViscosityOperator, ViscositySolver, Walls};
use std::time::Instant;

const SOLVED: &str = "divergence-free pressure, implicit viscosity (paper's operator, own density) at the CFL step";

/// Morris et al.'s channel at `across` on the paper's walls with the spiky density kernel, with
/// the explicit solver on the paper's operator with the own-density gradient, and the same
/// solved.
fn channels(across: usize) -> (Channel, Channel) {
    let explicit = Channel {
        walls: Walls::Paper,
        density_kernel: DensityKernelKind::Spiky,
        velocity_gradient: VelocityGradient::OwnDensity,
        ..Channel::morris(across, ViscosityOperator::Stress)
    };
    (explicit, Channel { solver: ViscositySolver::Implicit, pressure: Pressure::DivergenceFree, ..explicit })
}

/// Start-up Poiseuille at `across`: the error against Morris et al.'s series may exceed the
/// explicit solver's by at most 0.005 of the peak.
pub fn startup_poiseuille_divergence_free(across: usize) -> Result<CaseResult, String> {
    let (explicit, solved) = channels(across);
    let e = startup_poiseuille_in(&explicit, None)?;
    let s = startup_poiseuille_in(&solved, None)?;
    Ok(CaseResult {
        case: format!("start-up Poiseuille, {SOLVED}, paper's walls, {across} across"),
        measure: format!(
            "max |u - u_ref| / u_max minus the explicit solver's on the same walls at the bound: {:.4} against {:.4}; {:.1} s against {:.1} s",
            s.error, e.error, s.wall_s, e.wall_s
        ),
        error: s.error - e.error,
        tolerance: 0.005,
        at_least: false,
        wall_s: s.wall_s + e.wall_s,
        plot: None,
    })
}

/// Steady Poiseuille of the Cross fluid (K = `k_s` s, n = `n`) at `across`: the profile within
/// 0.002 of the centre speed of the explicit solver's.
pub fn cross_poiseuille_divergence_free(across: usize, k_s: f64, n: f64) -> Result<CaseResult, String> {
    let law = CrossLaw { nu_inf_m2_s: 0.25e-6, k_s, n };
    let (explicit, solved) = channels(across);
    let (explicit, solved) = (Channel { cross: Some(law), ..explicit }, Channel { cross: Some(law), ..solved });
    let end = 0.75 * explicit.gap_m * explicit.gap_m / law.nu_inf_m2_s;
    let started = Instant::now();
    let e = simulate(&explicit, &[end])?.remove(0);
    let explicit_s = started.elapsed().as_secs_f64();
    let started = Instant::now();
    let s = simulate(&solved, &[end])?.remove(0);
    let solved_s = started.elapsed().as_secs_f64();
    let centre = e.iter().map(|p| p[1]).fold(0.0, f64::max);
    let difference = e.iter().zip(&s).map(|(a, b)| (a[1] - b[1]).abs()).fold(0.0, f64::max) / centre;
    Ok(CaseResult {
        case: format!("steady Cross Poiseuille K = {k_s} s, n = {n}, {SOLVED}, paper's walls, {across} across"),
        measure: format!(
            "max |u_solved - u_explicit| / u_centre at t = {end} s, the explicit solver on the same walls at the bound; {solved_s:.1} s against {explicit_s:.1} s"
        ),
        error: difference,
        tolerance: 0.002,
        at_least: false,
        wall_s: solved_s + explicit_s,
        plot: None,
    })
}

/// The Taylor-Green vortex at `across`: the decay rate within 5 % of 8 pi^2 nu / L^2.
pub fn taylor_green_divergence_free(across: usize) -> Result<CaseResult, String> {
    let vortex = Vortex {
        velocity_gradient: VelocityGradient::OwnDensity,
        solver: ViscositySolver::Implicit,
        pressure: Pressure::DivergenceFree,
        density_kernel: DensityKernelKind::Spiky,
        ..Vortex::new(across, ViscosityOperator::Stress)
    };
    let started = Instant::now();
    let r = taylor_green::simulate(&vortex)?;
    let exact = vortex.decay_rate();
    Ok(CaseResult {
        case: format!("Taylor-Green vortex, {SOLVED}, {across} across"),
        measure: format!(
            "|rate / (8 pi^2 nu / L^2) - 1|, rate fitted to ln(amplitude) over one e-folding time (measured {:.4e} 1/s, exact {exact:.4e} 1/s); Re = 1",
            r.decay_rate
        ),
        error: (r.decay_rate / exact - 1.0).abs(),
        tolerance: 0.05,
        at_least: false,
        wall_s: started.elapsed().as_secs_f64(),
        plot: None,
    })
}

/// Huppert's spreading at `across` R0 on the paper's plate: the fitted exponent's error within
/// 0.01 of the explicit solver's.
pub fn huppert_divergence_free(across: usize) -> Result<CaseResult, String> {
    let explicit = Release {
        own_density: Some(ViscositySolver::Explicit),
        walls: Walls::Paper,
        density_kernel: DensityKernelKind::Spiky,
        ..Release::new(across, ViscosityOperator::Stress)
    };
    let solved = Release { own_density: Some(ViscositySolver::Implicit), pressure: Pressure::DivergenceFree, ..explicit };
    let started = Instant::now();
    let e = huppert::simulate(&explicit)?;
    let explicit_s = started.elapsed().as_secs_f64();
    let started = Instant::now();
    let s = huppert::simulate(&solved)?;
    let solved_s = started.elapsed().as_secs_f64();
    let error = |r: &Spreading| (r.exponent / 0.125 - 1.0).abs();
    let prefactor = |r: &Spreading| (r.prefactor / huppert::HUPPERT_PREFACTOR - 1.0).abs();
    Ok(CaseResult {
        case: format!("Huppert spreading, {SOLVED}, paper's plate, {across} across R0: as the explicit"),
        measure: format!(
            "|exponent error solved - explicit| on the same plate: {:.4} against {:.4}; prefactor errors {:.4} against {:.4}; {solved_s:.0} s against {explicit_s:.0} s",
            error(&s),
            error(&e),
            prefactor(&s),
            prefactor(&e)
        ),
        error: (error(&s) - error(&e)).abs(),
        tolerance: 0.01,
        at_least: false,
        wall_s: solved_s + explicit_s,
        plot: None,
    })
}
