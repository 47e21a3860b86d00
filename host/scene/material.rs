//! The `[material]` table: the liquid, its viscosity and how the SPH sums read it.

use crate::scene::serde_defaults::{is_default, one};
use serde::{Deserialize, Serialize};

#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Material {
    /// rho0 (kg/m^3), Eq. (6).
    #[serde(default = "default_rest_density")]
    pub rest_density_kg_m3: f64,
    /// c (m/s), Eq. (6). The paper's sqrt(1.5) suits animation; quantitative work needs c well
    /// above the flow speed.
    #[serde(default = "default_sound_speed")]
    pub sound_speed_m_s: f64,
    /// Clamp negative pressure to zero. Eq. (6) as printed lets free-surface particles, whose
    /// density sum lacks neighbors, pull on the fluid with a tension of c^2 times their density
    /// deficit: negligible at the paper's c, violent when c is raised for accuracy.
    #[serde(default)]
    pub clamp_negative_pressure: bool,
    /// How the pressure force weighs a pair's pressures.
    #[serde(default)]
    pub pressure_gradient: PressureGradient,
    /// The kernel of the density sum, Eq. (5).
    #[serde(default)]
    pub density_kernel: DensityKernelKind,
    /// How fluid particles get their density. Left out of the resolved scene at its default,
    /// so that checkpoints taken before the field existed keep their fingerprint.
    #[serde(default, skip_serializing_if = "is_default")]
    pub density_equation: DensityEquation,
    /// delta, the weight of the density diffusion term of the continuity equation (Molteni
    /// and Colagrossi 2009's delta h c with h half the support radius); 0.1 is theirs and
    /// DualSPHysics's default. Unused by the density sum.
    #[serde(default = "default_density_diffusion", skip_serializing_if = "is_default_density_diffusion")]
    pub density_diffusion: f64,
    /// Initial particle spacing (m).
    pub particle_spacing_m: f64,
    /// Support radius h as a multiple of the spacing (2 gives about 33 neighbors).
    #[serde(default = "default_support_factor")]
    pub support_radius_factor: f64,
    /// g (m/s^2). Plates and box floors are horizontal in y, so gravity usually points along -y.
    #[serde(default = "default_gravity")]
    pub gravity_m_s2: [f64; 3],
    pub viscosity: Viscosity,
}

fn default_rest_density() -> f64 {
    1000.0
}
fn default_sound_speed() -> f64 {
    1.5f64.sqrt()
}
fn default_density_diffusion() -> f64 {
    0.1
}
fn is_default_density_diffusion(delta: &f64) -> bool {
    *delta == default_density_diffusion()
}
fn default_support_factor() -> f64 {
    2.0
}
fn default_gravity() -> [f64; 3] {
    [0.0, -9.8, 0.0]
}

/// How the pressure force, Eq. (7), weighs the pressures of a pair.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq, Eq, Default)]
#[serde(rename_all = "snake_case")]
pub enum PressureGradient {
    /// Eq. (7) as printed: Müller 2003's mean (p_i + p_j) / 2, which is half the gradient of a
    /// linear pressure field. Fluid at rest then compresses twice as much as Eq. (6) says (as
    /// if c were c / sqrt(2)), and its pressure reads twice rho0 g depth.
    #[default]
    Paper,
    /// The sum p_i + p_j: the full gradient, so hydrostatic pressure is rho0 g depth.
    Full,
}

impl PressureGradient {
    /// The weight of p_i + p_j in the pressure force.
    pub fn pair_weight(self) -> f64 {
        match self {
            PressureGradient::Paper => 0.5,
            PressureGradient::Full => 1.0,
        }
    }
}

/// The kernel of the density sum, Eq. (5).
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq, Eq, Default)]
#[serde(rename_all = "snake_case")]
pub enum DensityKernelKind {
    /// The paper's (Müller 2003's) poly6. Its gradient is not the spiky gradient of Eq. (7), so
    /// the pressure force does not follow the gradient of the density it comes from, and a
    /// lattice stiffened by a high c flutters where viscosity no longer damps the particle scale
    /// (measured by `coil tradeoff`).
    #[default]
    Poly6,
    /// The spiky kernel, whose gradient Eq. (7) takes: the pressure force then follows the
    /// gradient of the density it comes from, and high-c lattices stay still.
    Spiky,
}

/// How fluid particles get their density.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq, Eq, Default)]
#[serde(rename_all = "snake_case")]
pub enum DensityEquation {
    /// The paper's sum, Eq. (5), over the particles' positions. A free-surface particle's sum
    /// lacks neighbors, so a thin thread reads well below rho0 at rest: Eq. (6) turns that into
    /// a tension that tears it, and the clamped pressure carries no tension at all
    /// (docs/validation.md).
    #[default]
    Summation,
    /// d rho / dt = -rho div v with Molteni and Colagrossi's density diffusion (delta-SPH):
    /// every particle starts at rho0, a free surface has no deficit, and the fluid carries the
    /// tension that stretching needs. Fixed boundary particles keep the sum.
    Continuity,
}

/// Which discretisation of the viscous term.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq, Eq, Default)]
#[serde(rename_all = "snake_case")]
pub enum ViscosityOperator {
    /// The paper's: velocity gradient, Eq. (8), stress, Eq. (2), divergence, Eq. (9).
    #[default]
    Stress,
    /// Müller et al. 2003: nu0 times the viscosity-kernel Laplacian of velocity (Newtonian).
    Laplacian,
    /// Morris, Fox & Zhu 1997: a Laplacian built on the kernel gradient, times the pair's mean
    /// viscosity; nu0, or each particle's nu(D) from Eq. (8), (2), (3) for a Cross fluid.
    Morris,
}

/// Largest `hourglass_control` a scene may ask for: the weights `coil tradeoff` measured
/// stable at the Eq. (10) bound (0.5, 1, 2); the control adds to the viscous term, which that
/// bound does not count.
pub const MAX_HOURGLASS_CONTROL: f64 = 2.0;

/// Largest `particle_shifting` coefficient a scene may ask for: five times the usual 2 (on the
/// viscous thread 5 and 10 did no better than 2). Above it a disordered particle would be
/// shifted several times farther in a step than the flow moves it.
pub const MAX_PARTICLE_SHIFTING: f64 = 10.0;

/// Kinematic viscosities (m^2/s) and the Cross model, Eq. (3).
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Viscosity {
    #[serde(default)]
    pub operator: ViscosityOperator,
    /// Zero-shear kinematic viscosity nu0 (m^2/s).
    pub nu0_m2_s: f64,
    /// Infinite-shear kinematic viscosity nu_inf (m^2/s); defaults to nu0.
    pub nu_inf_m2_s: Option<f64>,
    /// Cross consistency K (s); 0 makes the fluid Newtonian with nu0.
    #[serde(default)]
    pub cross_k_s: f64,
    /// Cross rate index n (dimensionless).
    #[serde(default = "one")]
    pub cross_n: f64,
    /// Weight of the hourglass control added to the paper's operator (dimensionless, 0 to 2):
    /// Morris's Laplacian of the part of each pair's velocity difference that the velocity
    /// gradients of Eq. (8) do not explain, which damps the odd-even mode Eq. (8) then (9)
    /// cannot see. 0 (the default) is the paper's operator alone.
    #[serde(default)]
    pub hourglass_control: f64,
    /// How the paper's operator estimates the velocity gradient. Left out of the resolved scene
    /// at its default, so that checkpoints taken before the field existed keep their
    /// fingerprint.
    #[serde(default, skip_serializing_if = "VelocityGradient::is_sph")]
    pub velocity_gradient: VelocityGradient,
    /// Whether viscosity is integrated explicitly, as the paper does (its Eq. (10) then bounds
    /// dt), or implicitly by backward Euler, which lifts that bound. Left out of the resolved
    /// scene at its default.
    #[serde(default, skip_serializing_if = "ViscositySolver::is_explicit")]
    pub solver: ViscositySolver,
    /// The implicit solve's settings (read only with `solver = "implicit"`).
    #[serde(default, skip_serializing_if = "ImplicitViscosity::is_default")]
    pub implicit: ImplicitViscosity,
}

/// How viscosity is integrated in time.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq, Eq, Default)]
#[serde(rename_all = "snake_case")]
pub enum ViscositySolver {
    /// Explicitly, with the rest of Algorithm 1; Eq. (10)'s viscous term bounds dt.
    #[default]
    Explicit,
    /// By backward Euler, solved with conjugate gradients (Weiler et al. 2018) on the paper's
    /// operator with the own-density velocity gradient or on Morris's; dt is bounded by sound
    /// and flow speed only.
    Implicit,
}

impl ViscositySolver {
    fn is_explicit(&self) -> bool {
        *self == ViscositySolver::Explicit
    }
}

/// Settings of the implicit viscosity solve.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ImplicitViscosity {
    /// The solve stops when the residual's norm falls below this fraction of its first norm,
    /// the velocity change an explicit step would make (dimensionless, 0 to 1).
    #[serde(default = "default_implicit_tolerance")]
    pub tolerance: f64,
    /// Conjugate-gradient iterations a step may take at most.
    #[serde(default = "default_implicit_iterations")]
    pub max_iterations: u32,
    /// What a step does when the solve has not met its tolerance within `max_iterations`:
    /// stop the run with a diagnosis (frames kept), or go on and count it in the summary.
    #[serde(default)]
    pub on_no_convergence: NoConvergence,
    /// How many times a step may read a shear-thinning fluid's viscosity again from the
    /// solution and solve again (Picard iterations), while the solution misses the tolerance
    /// at its own viscosity; 0 (the default) reads it once, from the solve's first guess.
    /// Ignored for a Newtonian fluid.
    #[serde(default)]
    pub picard_iterations: u32,
}

/// What a step does with a solve that did not converge.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq, Eq, Default)]
#[serde(rename_all = "snake_case")]
pub enum NoConvergence {
    #[default]
    Stop,
    Warn,
}

fn default_implicit_tolerance() -> f64 {
    1e-3
}

fn default_implicit_iterations() -> u32 {
    100
}

impl Default for ImplicitViscosity {
    fn default() -> Self {
        Self {
            tolerance: default_implicit_tolerance(),
            max_iterations: default_implicit_iterations(),
            on_no_convergence: NoConvergence::Stop,
            picard_iterations: 0,
        }
    }
}

impl ImplicitViscosity {
    fn is_default(&self) -> bool {
        *self == Self::default()
    }
}

/// The velocity gradient the paper's operator reads (Eq. (8), then (2) and (9)).
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq, Eq, Default)]
#[serde(rename_all = "snake_case")]
pub enum VelocityGradient {
    /// Eq. (8) as printed: exact for a linear field only where the support is full, so about
    /// half of the gradient on a free surface.
    #[default]
    Sph,
    /// Eq. (8) times the inverse of its moment matrix (Bonet and Lok 1999): exact for a linear
    /// field wherever the neighbors span three dimensions, so a thin thread carries the
    /// viscous stress it should.
    Renormalized,
    /// Eq. (8) with the neighbors' volumes at the particle's own density, m_j / rho_i: Eq. (9)
    /// is then its exact adjoint, so the operator never adds kinetic energy and its matrix is
    /// symmetric, which an implicit viscosity solve needs.
    OwnDensity,
}

impl VelocityGradient {
    fn is_sph(&self) -> bool {
        *self == VelocityGradient::Sph
    }
}

impl Viscosity {
    pub fn nu_inf(&self) -> f64 {
        self.nu_inf_m2_s.unwrap_or(self.nu0_m2_s)
    }
    /// The viscosity of Eq. (10)'s viscous term (m^2/s) for a law whose largest is `largest`:
    /// none where viscosity is solved implicitly, which that term no longer bounds.
    pub fn bounding_viscosity(&self, largest: f64) -> f64 {
        match self.solver {
            ViscositySolver::Explicit => largest,
            ViscositySolver::Implicit => 0.0,
        }
    }
    /// K = 0 (or nu_inf = nu0) is a Newtonian fluid: the Cross model is never evaluated.
    pub fn is_newtonian(&self) -> bool {
        self.cross_k_s == 0.0 || self.nu_inf() == self.nu0_m2_s
    }
}
