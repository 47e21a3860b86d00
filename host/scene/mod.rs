//! Scene files: TOML, SI units, every unit in the field name. Parsed with serde
//! (`deny_unknown_fields`), validated once at load, then turned into plain `Copy` parameter
//! structs for the kernels.

pub mod logged;
pub mod overrides;
pub mod particle_limit;
pub mod setup;
pub mod toml_field;
mod validate;

use overrides::Override;
use serde::{Deserialize, Serialize};
use std::fmt;
use std::path::Path;

/// A user mistake in a scene: which file, which field, why. The CLI prints it and exits 2.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneError {
    pub file: String,
    pub field: String,
    pub reason: String,
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}: {}", self.file, self.field, self.reason)
    }
}

impl std::error::Error for SceneError {}

#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// Short name, used for the output folder.
    pub name: String,
    #[serde(default)]
    pub description: String,
    /// Which experiment of the paper this reproduces, and for jets their Reynolds number and H/D.
    #[serde(default)]
    pub notes: String,
    pub material: Material,
    pub domain: Domain,
    pub simulation: SimulationSettings,
    #[serde(default)]
    pub output: Output,
    #[serde(default, rename = "fluid_block")]
    pub fluid_blocks: Vec<FluidBlock>,
    #[serde(default, rename = "fluid_torus")]
    pub fluid_tori: Vec<FluidTorus>,
    #[serde(default, rename = "fluid_cylinder")]
    pub fluid_cylinders: Vec<FluidCylinder>,
    #[serde(default, rename = "boundary")]
    pub boundaries: Vec<Boundary>,
    #[serde(default, rename = "inlet")]
    pub inlets: Vec<InletSettings>,
    /// Named `--set` combinations of this scene that reproduce other panels of a figure;
    /// `coil scenes` lists them with their commands.
    #[serde(default, rename = "variant")]
    pub variants: Vec<Variant>,
}

/// A named set of overrides of a scene.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Variant {
    pub name: String,
    pub description: String,
    /// `KEY=VALUE` overrides, as given to `--set`.
    pub set: Vec<String>,
}

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

fn one() -> f64 {
    1.0
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

/// The box that holds every particle (m); particles that leave it are removed and counted.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Domain {
    pub min_m: [f64; 3],
    pub max_m: [f64; 3],
    /// Axes (x, y, z) along which the domain wraps around: a particle leaving through one face
    /// re-enters through the opposite one, and neighbors are found across the seam. Each such
    /// length must be at least 3 support radii and a whole number of particle spacings.
    #[serde(default)]
    pub periodic: [bool; 3],
}

impl Domain {
    pub fn is_periodic(&self) -> bool {
        self.periodic.iter().any(|&p| p)
    }

    /// Whether `p` (m) lies in the domain box, its faces included.
    pub fn contains(&self, p: [f64; 3]) -> bool {
        (0..3).all(|a| p[a] >= self.min_m[a] && p[a] <= self.max_m[a])
    }
}

#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq, Eq, Default)]
#[serde(rename_all = "snake_case")]
pub enum Precision {
    #[default]
    F32,
    F64,
}

#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SimulationSettings {
    /// Simulated time to run (s).
    pub end_time_s: f64,
    #[serde(default)]
    pub precision: Precision,
    /// Capacity for fluid particles, the initial fluid plus all an inlet may inject (the paper's
    /// "maximum number of particles"). Defaults to the initial fluid.
    pub max_fluid_particles: Option<usize>,
    #[serde(default)]
    pub time_step: TimeStep,
    /// What wall particles show the fluid.
    #[serde(default)]
    pub walls: Walls,
    /// A, the coefficient of particle shifting (dimensionless): each step a fluid particle
    /// moving at |v| moves A h |v| dt down the gradient of its neighbors' concentration, along
    /// the surface near a free surface (Lind et al. 2012, Sun et al. 2017). 0, the paper's, turns
    /// it off; 2 is Skillen et al.'s and DualSPHysics's. Left out of the resolved scene at 0,
    /// so that checkpoints taken before the field existed keep their fingerprint.
    #[serde(default, skip_serializing_if = "is_default")]
    pub particle_shifting: f64,
    /// How pressure is found: the paper's equation of state, Eq. (6), or solved so that the
    /// flow stays divergence free and at rest density. Left out of the resolved scene at the
    /// paper's.
    #[serde(default, skip_serializing_if = "Pressure::is_weakly_compressible")]
    pub pressure: Pressure,
    /// Settings of the divergence-free pressure solves and their time step.
    #[serde(default, skip_serializing_if = "DivergenceFree::is_default")]
    pub divergence_free: DivergenceFree,
    /// Refines the scene by this factor (1/4 to 8): the particle spacing divided by it, the
    /// fluid capacity multiplied by its cube (the inlets fill it at the same time) and each
    /// nozzle's wobble divided by it (the same wobble a spacing). Applied once at load: the
    /// resolved scene holds the refined values and no factor.
    #[serde(default = "one", skip_serializing_if = "is_one")]
    pub refinement: f64,
}

fn is_one(x: &f64) -> bool {
    *x == 1.0
}

/// How pressure is found.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq, Eq, Default)]
#[serde(rename_all = "snake_case")]
pub enum Pressure {
    /// The paper's: Eq. (6), p = c^2 (rho - rho0), with dt bounded by the acoustic term h / c of
    /// Eq. (10).
    #[default]
    WeaklyCompressible,
    /// Divergence-free SPH (Bender and Koschier 2017): pressure solved each step so that the
    /// velocity field is divergence free and the density stays at rho0 within a tolerance; no
    /// sound speed, dt from the flow speed (CFL).
    DivergenceFree,
}

impl Pressure {
    fn is_weakly_compressible(&self) -> bool {
        *self == Pressure::WeaklyCompressible
    }
}

/// Settings of the divergence-free pressure solves (`simulation.pressure = "divergence_free"`).
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct DivergenceFree {
    /// The density solve stops when the fluid's mean density error is below this fraction of
    /// rho0 (dimensionless).
    #[serde(default = "default_density_tolerance")]
    pub density_tolerance: f64,
    /// The divergence solve stops when the fluid's mean compression rate times dt is below this
    /// fraction of rho0 (dimensionless).
    #[serde(default = "default_divergence_tolerance")]
    pub divergence_tolerance: f64,
    /// Sweeps each solve may take at most.
    #[serde(default = "default_pressure_iterations")]
    pub max_iterations: u32,
    /// Sweeps each solve takes at least, whatever its error: with none, a solve whose mean
    /// error is within the tolerance leaves local errors standing step after step, and a
    /// resting tank boils.
    #[serde(default = "default_min_pressure_iterations")]
    pub min_iterations: u32,
    /// The share of each Jacobi update that a sweep applies (dimensionless, above 0, at most
    /// 0.75). On a particle lattice at h = 2 spacings the update overshoots the shortest
    /// pressure wave by a factor 2.65, so a full update (1) diverges and anything above
    /// 2 / 2.65 = 0.755 does; 0.5 damps that wave to a third a sweep and leaves room for the
    /// irregular neighborhoods of walls and free surfaces.
    #[serde(default = "default_relaxation")]
    pub relaxation: f64,
    /// Chebyshev acceleration of the sweeps (Wang 2015): the spectral radius assumed for a
    /// relaxed Jacobi sweep (dimensionless, 0 to below 1). From a solve's third sweep on, each
    /// update also repeats a growing share of the last one, so the long pressure waves of a
    /// deep pool, which plain sweeps shrink slowly, converge in fewer sweeps; the solution is
    /// the same. 0 sweeps plain Jacobi. Left out of the resolved scene at 0, so that checkpoints
    /// taken before the field existed keep their fingerprint.
    #[serde(default, skip_serializing_if = "is_default")]
    pub chebyshev_radius: f64,
    /// What a step does when a solve has not met its tolerance within `max_iterations`: go on
    /// and count it in the summary (the next step's solves start from what it left), or stop
    /// the run with a diagnosis.
    #[serde(default = "warn")]
    pub on_no_convergence: NoConvergence,
    /// dt = cfl_factor times the particle spacing over the fastest particle's speed
    /// (dimensionless, 0 to 1). 0.2 is SPlisHSPlasH's default step (its CFL factor 0.5 times
    /// 0.4 particle diameters); the Newtonian jet buckles alike at 0.4 in half the steps, each
    /// dearer by more solver iterations.
    #[serde(default = "default_cfl_factor")]
    pub cfl_factor: f64,
    /// The largest dt (s), which also holds while the fluid is at rest.
    #[serde(default = "default_max_time_step")]
    pub max_time_step_s: f64,
    /// What a wall particle pushes with. Left out of the resolved scene at its default, so that
    /// checkpoints taken before the field existed keep their fingerprint.
    #[serde(default, skip_serializing_if = "WallPressure::is_once")]
    pub wall_pressure: WallPressure,
}

/// What a wall particle pushes with in the pressure solves.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq, Eq, Default)]
#[serde(rename_all = "snake_case")]
pub enum WallPressure {
    /// The stiffness of the fluid particle beside it, once (SPlisHSPlasH's walls): the layer
    /// on a floor reads about twice rho0 g depth.
    #[default]
    Once,
    /// That stiffness mirrored onto the wall plus the hydrostatic head between them (Akinci et
    /// al. 2012, Band et al. 2018): a liquid at rest reads rho0 g depth, but a channel's flow
    /// along its walls is held back (the start-up channel's error on mirrored walls: 0.10,
    /// against 0.043 once).
    Mirrored,
}

impl WallPressure {
    fn is_once(&self) -> bool {
        *self == WallPressure::Once
    }

    /// The share of a particle's stiffness that a wall pushes back with on top of its own.
    pub fn stiffness_share(self) -> f64 {
        match self {
            WallPressure::Once => 0.0,
            WallPressure::Mirrored => 1.0,
        }
    }
}

fn default_density_tolerance() -> f64 {
    5e-4
}

fn default_divergence_tolerance() -> f64 {
    1e-3
}

fn default_pressure_iterations() -> u32 {
    100
}

fn default_min_pressure_iterations() -> u32 {
    2
}

fn default_relaxation() -> f64 {
    0.5
}

fn warn() -> NoConvergence {
    NoConvergence::Warn
}

fn default_cfl_factor() -> f64 {
    0.2
}

fn default_max_time_step() -> f64 {
    1e-3
}

impl Default for DivergenceFree {
    fn default() -> Self {
        Self {
            density_tolerance: default_density_tolerance(),
            divergence_tolerance: default_divergence_tolerance(),
            max_iterations: default_pressure_iterations(),
            min_iterations: default_min_pressure_iterations(),
            relaxation: default_relaxation(),
            chebyshev_radius: 0.0,
            on_no_convergence: warn(),
            cfl_factor: default_cfl_factor(),
            max_time_step_s: default_max_time_step(),
            wall_pressure: WallPressure::Once,
        }
    }
}

impl DivergenceFree {
    fn is_default(&self) -> bool {
        *self == Self::default()
    }
}

/// The velocity and pressure that wall particles carry into the fluid's sums.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq, Eq, Default)]
#[serde(rename_all = "snake_case")]
pub enum Walls {
    /// The paper's Sec. III-B: at rest, with density from Eq. (5). The fluid slips over the
    /// first half spacing, as if the wall stood half a spacing further back, and the fluid on a
    /// floor compresses more than its weight requires.
    #[default]
    Paper,
    /// The flow mirrored through the wall surface (fixed ghost particles, Marrone et al. 2011):
    /// minus the fluid's velocity at each wall particle's mirror image, so no slip on the wall
    /// itself, and the pressure there plus the hydrostatic difference (Adami et al. 2012); where
    /// pressure is solved, the velocity only. One more pass over the particles per step and 24
    /// bytes per wall particle.
    Mirrored,
}

/// dt: automatic from Eq. (10) and the velocity CFL, or fixed.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct TimeStep {
    /// Multiplies the automatic dt (0 < factor <= 1; above 1 only with
    /// `allow_above_stability_bound`).
    #[serde(default = "one")]
    pub safety_factor: f64,
    /// A fixed dt (s) instead of the automatic one.
    pub fixed_s: Option<f64>,
    /// Accept a dt above the Eq. (10) bound, fixed or by a safety factor above 1 (how far each
    /// operator stays stable is measured, not guaranteed; the guard stops a run that blows up).
    #[serde(default)]
    pub allow_above_stability_bound: bool,
    /// Which velocity the viscous terms read. Left out of the resolved scene at its default,
    /// so that checkpoints taken before the field existed keep their fingerprint.
    #[serde(default, skip_serializing_if = "ViscousVelocity::is_full_step")]
    pub viscous_velocity: ViscousVelocity,
}

impl Default for TimeStep {
    fn default() -> Self {
        Self {
            safety_factor: 1.0,
            fixed_s: None,
            allow_above_stability_bound: false,
            viscous_velocity: ViscousVelocity::default(),
        }
    }
}

/// The velocity the viscous terms of step n read, where leap-frog keeps v_{n-1/2} and the
/// full step v_n = v_{n-1/2} + a_{n-1} dt / 2 (see `coil_kernels::leapfrog`).
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq, Eq, Default)]
#[serde(rename_all = "snake_case")]
pub enum ViscousVelocity {
    /// v_n: second order in time; on a mode that viscosity damps at the rate lambda, stable
    /// for lambda dt < 1.
    #[default]
    FullStep,
    /// v_{n-1/2}: the viscous force lags dt / 2 (first order in time) and is stable for
    /// lambda dt < 2, which keeps two particles closing in a thinned jet stable at the
    /// Eq. (10) bound (docs/tradeoff.md).
    HalfStep,
}

impl ViscousVelocity {
    fn is_full_step(&self) -> bool {
        *self == ViscousVelocity::FullStep
    }
}

#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Output {
    /// Write a frame every this many simulated seconds.
    pub every_s: Option<f64>,
    /// Or every this many steps.
    pub every_steps: Option<u64>,
    /// File formats of each frame: `vtu` (with the `.pvd` series, for ParaView), `ply` (binary),
    /// `xyz` (positions as f32 triples, which splashsurf meshes directly).
    #[serde(default = "default_formats")]
    pub formats: Vec<FrameFormat>,
    /// How `.vtu` frames hold their arrays: `raw` (appended binary, for ParaView; the default)
    /// or `base64` (inline, which meshio and splashsurf also read).
    #[serde(default, skip_serializing_if = "is_default")]
    pub vtu_encoding: VtuEncoding,
}

fn is_default<T: Default + PartialEq>(value: &T) -> bool {
    *value == T::default()
}

/// How a `.vtu` frame holds its arrays.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum VtuEncoding {
    /// Appended raw binary: the smallest and fastest to write; ParaView reads it, meshio and
    /// vtkio (splashsurf) do not.
    #[default]
    Raw,
    /// Each array inline in base64 (`format="binary"`, header and data in one stream, as VTK
    /// writes them): a third larger, and read by ParaView, meshio and vtkio alike.
    Base64,
}

/// A file format of output frames.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum FrameFormat {
    Vtu,
    Ply,
    Xyz,
    /// The free surface's mesh (`output::surface`), `frame_NNNNNN.surface.ply`.
    Surface,
}

fn default_formats() -> Vec<FrameFormat> {
    vec![FrameFormat::Vtu]
}

impl Default for Output {
    fn default() -> Self {
        Self { every_s: Some(0.01), every_steps: None, formats: default_formats(), vtu_encoding: VtuEncoding::Raw }
    }
}

/// A block of fluid on the particle lattice, at rest unless given a velocity.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct FluidBlock {
    pub min_m: [f64; 3],
    pub max_m: [f64; 3],
    #[serde(default)]
    pub velocity_m_s: [f64; 3],
}

/// A ring of fluid with a vertical axis (the spreading torus of Fig. 3 and 4), on the particle
/// lattice: the points within `minor_radius_m` of the circle of `major_radius_m` around `centre_m`
/// in the horizontal plane.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct FluidTorus {
    pub centre_m: [f64; 3],
    pub major_radius_m: f64,
    pub minor_radius_m: f64,
    #[serde(default)]
    pub velocity_m_s: [f64; 3],
}

/// An upright cylinder of fluid (Huppert's fixed-volume release): the lattice points within
/// `radius_m` of the vertical axis through `base_centre_m`, from its height up to
/// `height_m` above it.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct FluidCylinder {
    pub base_centre_m: [f64; 3],
    pub radius_m: f64,
    pub height_m: f64,
    #[serde(default)]
    pub velocity_m_s: [f64; 3],
}

/// Walls of fixed virtual particles (paper Sec. III-B), in layers that cover the support.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields, tag = "shape", rename_all = "snake_case")]
pub enum Boundary {
    /// Walls around the interior `min_m`..`max_m`; `open_top` leaves out the lid (max y).
    Box {
        min_m: [f64; 3],
        max_m: [f64; 3],
        #[serde(default)]
        open_top: bool,
    },
    /// A horizontal plate whose top surface is at `height_m` (y), spanning x and z between
    /// `min_xz_m` and `max_xz_m` (default: the whole domain, a plane).
    Plate { height_m: f64, min_xz_m: Option<[f64; 2]>, max_xz_m: Option<[f64; 2]> },
}

#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields, tag = "shape", rename_all = "snake_case")]
pub enum Nozzle {
    Circle {
        radius_m: f64,
    },
    /// `width_m` along the first in-plane axis, `depth_m` along the second (see `inlet`).
    Rectangle {
        width_m: f64,
        depth_m: f64,
    },
}

/// A jet inlet (paper Sec. III-C): layers of particles are injected each time the previous
/// layer has moved one layer spacing away, until the particle budget is reached.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct InletSettings {
    pub nozzle: Nozzle,
    /// Nozzle centre at t = 0 (m).
    pub position_m: [f64; 3],
    /// Direction of the jet (normalised at load).
    pub direction: [f64; 3],
    /// Jet speed (m/s).
    pub speed_m_s: f64,
    /// Injection starts at this time (s).
    #[serde(default)]
    pub start_s: f64,
    /// Injection stops at this time (s).
    pub stop_s: Option<f64>,
    /// How the nozzle moves (stitching patterns, Fig. 9).
    pub motion: Option<NozzleMotion>,
    /// Largest sideways offset of a layer from the nozzle axis (m), drawn per layer from a
    /// fixed pseudo-random sequence: the nozzle's wobble. A jet that is symmetric to round-off
    /// buckles only after many seconds; a real jet always carries such noise.
    #[serde(default)]
    pub wobble_m: f64,
}

#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields, untagged)]
pub enum NozzleMotion {
    /// Constant velocity (m/s).
    Velocity { velocity_m_s: [f64; 3] },
    /// Piecewise-linear path through `[t_s, x_m, y_m, z_m]` waypoints, held at the ends.
    Waypoints { waypoints: Vec<[f64; 4]> },
}

/// A number as an error message prints it: plainly when that is short, else in scientific
/// notation to four digits (`1e308`, not 309 digits).
pub fn short(v: f64) -> String {
    let plain = v.to_string();
    if plain.len() <= 9 {
        return plain;
    }
    let rounded: f64 = format!("{v:.3e}").parse().unwrap_or(v);
    format!("{rounded:e}")
}

/// The TOML text of a scene file; a `run.json` gives its `scene`, written back as TOML.
fn scene_text(path: &Path) -> Result<String, SceneError> {
    if path.extension().is_some_and(|x| x == "json") {
        return logged::logged_scene_text(path);
    }
    crate::regular_file::read_text(path, MAX_SCENE_BYTES).map_err(|e| SceneError {
        file: path.display().to_string(),
        field: "(file)".into(),
        reason: format!("cannot be read: {e}"),
    })
}

/// The largest scene file read (bytes): the shipped scenes are about 2 KiB.
pub const MAX_SCENE_BYTES: u64 = 1 << 20;

/// For serde's "unknown field `x`, expected one of `a`, `b`" (or "expected `a` or `b`"): the
/// valid name that adds a unit to `x` (`cross_k` for `cross_k_s`: the unit is what users leave
/// out), else the nearest valid name, when it is a plausible typo.
fn suggestion(message: &str) -> String {
    let Some(rest) = message.strip_prefix("unknown field `") else { return String::new() };
    let Some((unknown, expected)) = rest.split_once('`') else { return String::new() };
    let names = || expected.split('`').skip(1).step_by(2);
    let with_unit = names().find(|name| name.strip_prefix(unknown).is_some_and(|unit| unit.starts_with('_')));
    let nearest = || {
        names()
            .map(|name| (edit_distance(unknown, name), name))
            .min()
            .filter(|&(d, name)| d <= 1 + name.len().max(unknown.len()) / 3)
            .map(|(_, name)| name)
    };
    with_unit.or_else(nearest).map(|name| format!("; did you mean `{name}`?")).unwrap_or_default()
}

/// Levenshtein distance between two names.
fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut diagonal = row[0];
        row[0] = i + 1;
        for (j, &cb) in b.iter().enumerate() {
            let next = (diagonal + usize::from(ca != cb)).min(row[j] + 1).min(row[j + 1] + 1);
            diagonal = row[j + 1];
            row[j + 1] = next;
        }
    }
    row[b.len()]
}

impl Scene {
    /// Reads and validates a scene file: TOML, or the `run.json` of an earlier run, whose
    /// resolved scene reproduces that run.
    pub fn load(path: &Path) -> Result<Scene, SceneError> {
        Self::load_with(path, &[])
    }

    /// Reads a scene file, applies `--set` overrides in order, and validates the result as one.
    pub fn load_with(path: &Path, overrides: &[Override]) -> Result<Scene, SceneError> {
        Self::with_overrides(&scene_text(path)?, &path.display().to_string(), overrides)
    }

    /// The scene `logged` in the run log `path`, with `--set` overrides applied in order and
    /// validated as one.
    pub fn from_log(logged: &Scene, path: &Path, overrides: &[Override]) -> Result<Scene, SceneError> {
        Self::with_overrides(&logged::scene_as_toml(logged, path)?, &path.display().to_string(), overrides)
    }

    fn with_overrides(text: &str, file: &str, overrides: &[Override]) -> Result<Scene, SceneError> {
        if overrides.is_empty() {
            return Self::parse(text, file);
        }
        Self::parse(&overrides::apply(text, file, overrides)?, &format!("{file} with --set")).map_err(|mut e| {
            // Line numbers would point into the rewritten text, not the user's file.
            if let Some(at) = e.reason.find(" (at line ") {
                e.reason.truncate(at);
            }
            e
        })
    }

    /// Parses and validates scene text; `file` names it in errors.
    pub fn parse(text: &str, file: &str) -> Result<Scene, SceneError> {
        let scene: Scene = toml::from_str(text).map_err(|e| {
            let mut field =
                e.span().and_then(|s| crate::scene::toml_field::field_at(text, s.start)).unwrap_or_else(|| "(syntax)".into());
            // serde points a missing field at the table that lacks it: name the field itself.
            let missing = e.message().strip_prefix("missing field `").and_then(|rest| rest.strip_suffix('`'));
            if let Some(name) = missing {
                field = if field == "(syntax)" || field.is_empty() { name.to_string() } else { format!("{field}.{name}") };
            }
            SceneError {
                file: file.into(),
                field,
                reason: e.message().to_string()
                    + &suggestion(e.message())
                    + &e.span().map(|s| format!(" (at line {})", 1 + text[..s.start].matches('\n').count())).unwrap_or_default(),
            }
        })?;
        let given: toml::Table = toml::from_str(text).map_err(|e| SceneError {
            file: file.into(),
            field: "(syntax)".into(),
            reason: e.message().to_string(),
        })?;
        let mut scene = scene;
        scene.refine(file)?;
        scene.validate(&given, file)?;
        Ok(scene)
    }

    /// Applies `simulation.refinement` and sets it back to 1.
    fn refine(&mut self, file: &str) -> Result<(), SceneError> {
        let r = self.simulation.refinement;
        if r == 1.0 {
            return Ok(());
        }
        if !(0.25..=8.0).contains(&r) {
            return Err(SceneError {
                file: file.into(),
                field: "simulation.refinement".into(),
                reason: format!("must be from 0.25 to 8 (the spacing's divisor), got {r}"),
            });
        }
        self.material.particle_spacing_m /= r;
        if let Some(capacity) = &mut self.simulation.max_fluid_particles {
            *capacity = (*capacity as f64 * r * r * r).ceil() as usize;
        }
        for inlet in &mut self.inlets {
            inlet.wobble_m /= r;
        }
        self.simulation.refinement = 1.0;
        Ok(())
    }

    /// Support radius h (m).
    pub fn support_radius(&self) -> f64 {
        self.material.particle_spacing_m * self.material.support_radius_factor
    }
}
