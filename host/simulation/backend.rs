//! What a backend supplies to the step schedule: its particle buffers as views, a launcher for
//! every pass, and the passes that are its own (the sort, injection, the diagnostics readout).
//!
//! The order of the passes is not here: [`super::Simulation::step_with`] writes it once, for
//! every backend, over this interface.

use crate::simulation::host_particles::HostParticles;
use crate::simulation::particles::{ImplicitViews, Particles, PressureViews};
use crate::simulation::pass_table::pass_table;
use coil_kernels::cell_grid::{Neighborhood, Neighbors};
use coil_kernels::diagnostics::StateFigures;
use coil_kernels::fluid::Fluid;
use coil_kernels::topology::{Periodic, Topology};
use coil_kernels::view::{Mat3ViewMut, SymTensorViewMut, Vec3View, Vec3ViewMut, View, ViewMut};
use coil_kernels::Real;
use std::fmt::Display;

/// Declares the `Passes` trait from the table's rows.
macro_rules! declare_passes {
    (
        passes { $($(#[$doc:meta])* $name:ident $(<$($g:ident: $bound:path),+>)? ($args:ty) => $pass:expr, [$($part:expr),+];)* }
        reductions { $($(#[$rdoc:meta])* $rname:ident ($rargs:ty) => $rpass:expr, $range:expr, $which:ident, [$($rpart:expr),+];)* }
    ) => {
        /// A backend's way of running each pass over its particles, with neighbors visited
        /// through `N` in topology `T`: one method per row of `pass_table`.
        pub trait Passes<R: Real, T: Topology, N: Neighbors> {
            $($(#[$doc])* fn $name $(<$($g: $bound),+>)? (&mut self, args: $args);)*
            $($(#[$rdoc])* fn $rname(&mut self, args: $rargs, partial: ViewMut<'_, [f64; 2]>) -> [f64; 2];)*
        }
    };
}

pass_table!(declare_passes);

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
