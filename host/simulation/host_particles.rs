//! Particles in host memory with the grid they were sorted into: what output and checks read
//! on either backend.

use crate::simulation::particles::Particles;
use crate::simulation::sorted_grid::SortedGrid;
use coil_kernels::cell_grid::Neighborhood;
use coil_kernels::dfsph_bender2017::pressure_field;
use coil_kernels::fluid::Fluid;
use coil_kernels::topology::Periodic;
use coil_kernels::view::View;
use coil_kernels::Real;

/// Particles in host memory with their sorted grid: the CPU backend's state, and a device
/// backend's copy of its particles for output.
pub struct HostParticles<R> {
    pub particles: Particles<R>,
    pub grid: SortedGrid,
}

impl<R: Real> HostParticles<R> {
    /// The neighbor grid of the particles' current order (valid after a step), with the
    /// domain's periods (none for an open domain). For output and checks; a step's own passes
    /// take the open or periodic loop by type.
    pub fn neighborhood(&self) -> Neighborhood<'_, Periodic> {
        self.grid.neighborhood(self.particles.position_view(), self.grid.periodic)
    }

    /// Particle `i`'s pressure (Pa): Eq. (6) of its density, or, where pressure is solved,
    /// the field the solved pressures interpolate to there
    /// (`coil_kernels::dfsph_bender2017::pressure_field`), read over `neighborhood`.
    pub fn pressure(&self, i: usize, fluid: &Fluid<R>, neighborhood: &Neighborhood<'_, Periodic>) -> R {
        let p = &self.particles;
        match &p.pressure_solve {
            Some(solve) => {
                let n = p.len();
                let sums = [View::new(&solve.stiffness_sums[0][..n]), View::new(&solve.stiffness_sums[1][..n])];
                pressure_field(i, neighborhood, fluid, View::new(&p.id[..n]), View::new(&p.density[..n]), sums)
            }
            None => coil_kernels::density::pressure(p.density[i], fluid),
        }
    }
}
