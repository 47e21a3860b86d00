//! What a backend supplies to the step schedule: its particle buffers as views, a launcher for
//! every pass, and the passes that are its own (the sort, injection, the diagnostics readout).
//!
//! The order of the passes is not here: [`super::Simulation::step_with`] writes it once, for
//! every backend, over this interface.

use crate::simulation::host_particles::HostParticles;
use crate::simulation::particles::{ImplicitViews, Particles, PressureViews};
use coil_kernels::acceleration::AccelerationArgs;
use coil_kernels::cell_grid::{Neighborhood, Neighbors};
use coil_kernels::continuity_molteni2009::{ContinuityArgs, DensityIntegrationArgs};
use coil_kernels::cross_viscosity::Rheology;
use coil_kernels::density::{DensityArgs, DensityKernel};
use coil_kernels::dfsph_bender2017::{
    DensityErrorArgs, DensityRateArgs, DivergenceErrorArgs, ErrorSumArgs, FactorArgs, PressureChangeArgs, WarmStartArgs,
};
use coil_kernels::diagnostics::StateFigures;
use coil_kernels::fluid::Fluid;
use coil_kernels::leapfrog::LeapfrogArgs;
use coil_kernels::mirrored_wall::MirroredWallArgs;
use coil_kernels::nozzle::{NozzleArgs, NozzleShiftArgs};
use coil_kernels::shifting_sun2017::{ShiftArgs, ShiftingArgs};
use coil_kernels::topology::{Periodic, Topology};
use coil_kernels::velocity_gradient::GradientEstimate;
use coil_kernels::view::{Mat3ViewMut, SymTensorViewMut, Vec3View, Vec3ViewMut, View, ViewMut};
use coil_kernels::viscosity::hourglass_ganzenmuller2015::VelocityGradientArgs;
use coil_kernels::viscosity::implicit_weiler2018::{
    CgDirectionArgs, CgStartArgs, CgStepArgs, DotArgs, ImplicitStressArgs, LaggedViscosityArgs, PredictorArgs, SystemBlockArgs,
    SystemProductArgs, ViscousAccelerationArgs,
};
use coil_kernels::viscosity::laplacian_morris1997::{
    MorrisSystemBlockArgs, MorrisSystemProductArgs, ParticleViscosity, ShearViscosityArgs,
};
use coil_kernels::viscosity::stress_andrade2014::StressArgs;
use coil_kernels::viscosity::ViscousOperator;
use coil_kernels::Real;
use std::fmt::Display;

/// A backend's way of running each pass over its particles, with neighbors visited through `N`
/// in topology `T`.
pub trait Passes<R: Real, T: Topology, N: Neighbors> {
    fn density<K: DensityKernel>(&mut self, args: DensityArgs<'_, R, N>);
    fn continuity<K: DensityKernel>(&mut self, args: ContinuityArgs<'_, R, N>);
    /// The walls' density, and the fluid's continuity density raised to its sum, with the
    /// spiky kernel, which the divergence-free solves require.
    fn continuity_floor(&mut self, args: DensityArgs<'_, R, N>);
    fn density_integration(&mut self, args: DensityIntegrationArgs<'_, R>);
    fn mirrored_wall(&mut self, args: MirroredWallArgs<'_, R, T>);
    fn stress<Rh: Rheology<R>, G: GradientEstimate>(&mut self, args: StressArgs<'_, R, Rh, G, N>);
    fn shear_viscosity<Rh: Rheology<R>>(&mut self, args: ShearViscosityArgs<'_, R, Rh, N>);
    fn velocity_gradient<Rh: Rheology<R>>(&mut self, args: VelocityGradientArgs<'_, R, Rh, N>);
    fn acceleration<Op: ViscousOperator<R>>(&mut self, args: AccelerationArgs<'_, R, Op, N>);
    fn nozzle(&mut self, args: NozzleArgs<'_, R>);
    fn leapfrog(&mut self, args: LeapfrogArgs<'_, R, T>);
    fn shifting(&mut self, args: ShiftingArgs<'_, R, N>);
    fn nozzle_shift(&mut self, args: NozzleShiftArgs<'_, R>);
    fn shift(&mut self, args: ShiftArgs<'_, R, T>);
    fn predictor(&mut self, args: PredictorArgs<'_, R>);
    fn lagged_viscosity<Rh: Rheology<R>>(&mut self, args: LaggedViscosityArgs<'_, R, Rh, N>);
    fn implicit_stress(&mut self, args: ImplicitStressArgs<'_, R, N>);
    fn system_block(&mut self, args: SystemBlockArgs<'_, R, N>);
    fn system_product(&mut self, args: SystemProductArgs<'_, R, N>);
    fn morris_system_block<Nu: ParticleViscosity<R>>(&mut self, args: MorrisSystemBlockArgs<'_, R, Nu, N>);
    fn morris_system_product<Nu: ParticleViscosity<R>>(&mut self, args: MorrisSystemProductArgs<'_, R, Nu, N>);
    fn cg_start(&mut self, args: CgStartArgs<'_, R>);
    fn cg_step(&mut self, args: CgStepArgs<'_, R>);
    fn cg_direction(&mut self, args: CgDirectionArgs<'_, R>);
    fn viscous_acceleration(&mut self, args: ViscousAccelerationArgs<'_, R>);
    /// The two dot products of `args` over the live particles, their ranges' parts written to
    /// `partial` and added in range order: the same on every backend and thread count. A
    /// backend that failed returns NaN and reports the fault when the schedule ends.
    fn dots(&mut self, args: DotArgs<'_, R>, partial: ViewMut<'_, [f64; 2]>) -> [f64; 2];
    fn dfsph_factor(&mut self, args: FactorArgs<'_, R, N>);
    fn divergence_error(&mut self, args: DivergenceErrorArgs<'_, R, N>);
    fn density_error(&mut self, args: DensityErrorArgs<'_, R, N>);
    fn dfsph_density_rate(&mut self, args: DensityRateArgs<'_, R, N>);
    fn pressure_change(&mut self, args: PressureChangeArgs<'_, R, N>);
    fn warm_start(&mut self, args: WarmStartArgs<'_, R>);
    /// The error of `args` summed over the live fluid particles, and their count, in range
    /// order as [`Passes::dots`].
    fn error_sums(&mut self, args: ErrorSumArgs<'_, R>, partial: ViewMut<'_, [f64; 2]>) -> [f64; 2];
}

/// A backend's particle buffers as views over its own memory, live particles only, in the
/// sorted order of the last sort.
#[derive(Clone, Copy)]
pub struct ParticleViews<'a, R, T, N> {
    pub topology: T,
    /// The sorted cell grid (the mirrored walls' neighbor loop).
    pub grid: Neighborhood<'a, T>,
    /// How the pair passes visit neighbors: the grid, or lists built from it.
    pub neighbors: N,
    pub id: View<'a, u32>,
    /// Position (m).
    pub position: Vec3ViewMut<'a, f64>,
    /// Velocity at the full step (m/s).
    pub velocity: Vec3ViewMut<'a, R>,
    /// Velocity at the half step (m/s).
    pub velocity_half: Vec3ViewMut<'a, R>,
    /// Acceleration (m/s^2).
    pub acceleration: Vec3ViewMut<'a, R>,
    /// Density (kg/m^3).
    pub density: ViewMut<'a, R>,
    /// Present where density comes from the continuity equation.
    pub density_rate: Option<ViewMut<'a, R>>,
    /// Present where the scene shifts particles.
    pub shift: Option<Vec3ViewMut<'a, R>>,
    /// Present when the model uses stress (`Model::FIELDS`).
    pub stress: Option<SymTensorViewMut<'a, R>>,
    /// Present when the model uses a viscosity per particle.
    pub viscosity: Option<ViewMut<'a, R>>,
    /// Present when the model uses the velocity gradient.
    pub velocity_gradient: Option<Mat3ViewMut<'a, R>>,
    /// Each wall particle's mirror image (m) by id, under mirrored walls.
    pub wall_mirror: Option<Vec3View<'a, f64>>,
    /// Present where viscosity is solved implicitly.
    pub implicit: Option<ImplicitViews<'a, R>>,
    /// Present where pressure is solved for a divergence-free flow.
    pub pressure_solve: Option<PressureViews<'a, R>>,
}

/// A sequence of passes over a backend's views, generic over how it visits neighbors: a
/// solver's schedule (or part of it), written once for every backend.
pub trait Schedule<R: Real> {
    fn run<T: Topology, N: Neighbors, P: Passes<R, T, N>>(self, views: ParticleViews<'_, R, T, N>, passes: &mut P);
}

/// The diagnostics reduction's result with the particle count it saw.
#[derive(Debug, Clone, Copy)]
pub struct Readout {
    pub figures: StateFigures,
    /// Live particles, boundary included.
    pub live: usize,
}

/// Where the particles of a run live and how its passes run there.
pub trait Backend<R: Real>: Send {
    /// Why a pass could not run (the CPU's never fail).
    type Fault: Display + Send;

    /// Runs `step`, which launches this backend's passes, on the thread they launch from best.
    fn on_launch_thread<T: Send>(step: impl FnOnce() -> T + Send) -> T {
        step()
    }

    /// The domain's periods, or `None` for an open domain.
    fn periodic(&self) -> Option<Periodic>;

    /// Host memory for the layers the inlets add this step, emptied, and how many particles it
    /// can take.
    fn inlet_staging(&mut self) -> (&mut Particles<R>, usize);
    /// Makes the last `added` particles staged by [`Backend::inlet_staging`] live.
    fn append_staged(&mut self, added: usize) -> Result<(), Self::Fault>;

    /// Sorts the particles by cell and reorders every field that carries state, dropping those
    /// outside the domain; returns how many it dropped where it knows now (else the next
    /// [`Backend::read_diagnostics`] tells).
    fn sort_and_reorder(&mut self) -> Result<usize, Self::Fault>;

    /// Runs `schedule` over the backend's views in topology `topology`.
    fn run<T: Topology, S: Schedule<R>>(&mut self, topology: T, schedule: S) -> Result<(), Self::Fault>;

    /// Whether the diagnostics are read after step `steps` (a device reads them every few steps,
    /// so that a step never waits for it).
    fn diagnostics_due(&self, steps: u64) -> bool;
    /// The diagnostics pass over the live particles (see `coil_kernels::diagnostics`).
    fn read_diagnostics(&mut self, fluid: Fluid<R>, runaway_speed2: f64) -> Result<Readout, Self::Fault>;

    /// Brings [`Backend::host`] up to date with the particles.
    fn download(&mut self) -> Result<(), Self::Fault>;
    /// The particles in host memory and their grid, current after [`Backend::download`].
    fn host(&self) -> &HostParticles<R>;

    /// No more particles than this are live, boundary included (exact after a readout): what
    /// a step moves.
    fn particle_bound(&self) -> usize;

    /// Bytes of particle and grid memory the backend allocated.
    fn memory_bytes(&self) -> usize;
}
