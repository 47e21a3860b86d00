//! The `[simulation]` table: precision, capacity, pressure and its solve, walls and time step.

use crate::scene::material::NoConvergence;
use crate::scene::serde_defaults::{is_default, is_one, one};
use serde::{Deserialize, Serialize};

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
