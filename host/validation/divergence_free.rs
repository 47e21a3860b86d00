//! The cases with pressure solved (divergence-free SPH, docs/divergence-free.md), each at the
//! CFL time step with implicit viscosity on the paper's operator with the own-density gradient
//! and the spiky density kernel. The vortex, which has no walls, is held to its exact decay. The
//! channels and the spreading are compared with the weakly compressible explicit solver on the
//! same operator, kernel and walls at Eq. (10)'s bound, with the tolerances of the implicit
//! viscosity's cases: on the paper's walls, which slip, and on mirrored ones, which do not.

use super::case::CaseResult;
use super::huppert::huppert_against_explicit;
use super::huppert::Release;
use super::poiseuille::{cross_against_explicit, startup_against_explicit};
use super::poiseuille::{Channel, CrossLaw};
use super::taylor_green::{self, Vortex};
use crate::scene::{DensityKernelKind, Pressure, VelocityGradient, ViscosityOperator, ViscositySolver, Walls};
use std::time::Instant;

const SOLVED: &str = "divergence-free pressure, implicit viscosity (paper's operator, own density) at the CFL step";

/// Morris et al.'s channel at `across` on `walls` with the spiky density kernel, with the
/// explicit solver on the paper's operator with the own-density gradient, and the same solved.
fn channels(across: usize, walls: Walls) -> (Channel, Channel) {
    let explicit = Channel {
        walls,
        density_kernel: DensityKernelKind::Spiky,
        velocity_gradient: VelocityGradient::OwnDensity,
        ..Channel::morris(across, ViscosityOperator::Stress)
    };
    (explicit, Channel { solver: ViscositySolver::Implicit, pressure: Pressure::DivergenceFree, ..explicit })
}

/// Start-up Poiseuille at `across` on `walls`: the error against Morris et al.'s series may
/// exceed the explicit solver's by at most 0.005 of the peak.
pub fn startup_poiseuille_divergence_free(across: usize, walls: Walls) -> Result<CaseResult, String> {
    let (explicit, solved) = channels(across, walls);
    let case = format!("start-up Poiseuille, {SOLVED}, {}, {across} across", walls_name(walls));
    startup_against_explicit(&explicit, &solved, case, "on the same walls at the bound")
}

/// Steady Poiseuille of the Cross fluid (K = `k_s` s, n = `n`) at `across`: the profile within
/// 0.002 of the centre speed of the explicit solver's.
pub fn cross_poiseuille_divergence_free(across: usize, k_s: f64, n: f64) -> Result<CaseResult, String> {
    let law = CrossLaw { nu_inf_m2_s: 0.25e-6, k_s, n };
    let (explicit, solved) = channels(across, Walls::Paper);
    let (explicit, solved) = (Channel { cross: Some(law), ..explicit }, Channel { cross: Some(law), ..solved });
    let fastest = |profile: &[[f64; 2]]| profile.iter().map(|p| p[1]).fold(0.0, f64::max);
    let case = format!("steady Cross Poiseuille K = {k_s} s, n = {n}, {SOLVED}, paper's walls, {across} across");
    cross_against_explicit(&explicit, &solved, fastest, case, "solved", "on the same walls at the bound")
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

/// Huppert's spreading at `across` R0 on a plate of `walls`: the fitted exponent's error within
/// 0.01 of the explicit solver's.
pub fn huppert_divergence_free(across: usize, walls: Walls) -> Result<CaseResult, String> {
    let explicit = Release {
        own_density: Some(ViscositySolver::Explicit),
        walls,
        density_kernel: DensityKernelKind::Spiky,
        ..Release::new(across, ViscosityOperator::Stress)
    };
    let solved = Release { own_density: Some(ViscositySolver::Implicit), pressure: Pressure::DivergenceFree, ..explicit };
    let case = format!("Huppert spreading, {SOLVED}, {}, {across} across R0: as the explicit", walls_name(walls));
    huppert_against_explicit(&explicit, &solved, case, "solved", " on the same plate")
}

fn walls_name(walls: Walls) -> &'static str {
    match walls {
        Walls::Paper => "paper's walls",
        Walls::Mirrored => "mirrored walls",
    }
}
