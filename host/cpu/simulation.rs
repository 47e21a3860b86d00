//! Runs on the CPU backend: the constructors of a [`Simulation`] whose particles live in host
//! memory.

use crate::cpu::{CpuBackend, NeighborVisits};
use crate::scene::setup::InitialParticles;
use crate::scene::Scene;
use crate::simulation::model::Model;
use crate::simulation::particles::Particles;
use crate::simulation::{Setup, Simulation};
use coil_kernels::Real;

/// A run whose particles live in host memory.
pub type CpuSimulation<R, M> = Simulation<R, M, CpuBackend<R>>;

impl<R: Real, M: Model<R>> Simulation<R, M, CpuBackend<R>> {
    /// Sets up a run of `scene` with the particles `initial` on the CPU backend.
    pub fn new(scene: &Scene, initial: &InitialParticles, model: M) -> Self {
        Self::started(Setup::new(scene, initial, model), true)
    }

    /// A run on the CPU backend that visits neighbors through the grid, as a device does, not
    /// through lists: for counting the device's work, and for checking that both loops agree.
    pub fn for_device(scene: &Scene, initial: &InitialParticles, model: M) -> Self {
        Self::started(Setup::new(scene, initial, model), false)
    }

    fn started(setup: Setup<R, M>, lists: bool) -> Self {
        let mut sim = Self::on_cpu(setup, lists);
        let Ok(()) = sim.sort_and_density();
        sim
    }

    /// The run `setup` on the CPU, with neighbor lists or not; fresh runs then start with
    /// [`Self::sort_and_density`]. The lists also hold each pair's kernel gradient where a
    /// solver visits the neighbors many times a step (implicit viscosity, solved pressure).
    pub fn on_cpu(setup: Setup<R, M>, lists: bool) -> Self {
        let Setup { run, host, wall_mirror } = setup;
        let visits = match lists {
            false => NeighborVisits::Grid,
            true if M::FIELDS.implicit || run.pressure_solve.is_some() => NeighborVisits::ListsAndGradients,
            true => NeighborVisits::Lists,
        };
        let backend = CpuBackend::new(host, wall_mirror, run.fluid.kernels, visits);
        Self { run, backend }
    }

    /// The particles, to set a state by hand (checks, tests).
    pub fn particles_mut(&mut self) -> &mut Particles<R> {
        self.backend.particles_mut()
    }
}
