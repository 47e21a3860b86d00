//! The CPU backend: the particles in host memory, each pass a kernel function run over all
//! particles with rayon.

pub mod neighbor_grid;
pub mod parallel;
pub mod simulation;

use crate::cpu::neighbor_grid::GridSort;
use crate::cpu::parallel::{launch, on_worker};
use crate::simulation::backend::{Backend, ParticleViews, Passes, Readout, Schedule};
use crate::simulation::host_particles::HostParticles;
use crate::simulation::particle_array::ParticleArray;
use crate::simulation::particles::{mat3_view_mut, stress_view_mut, vec3_view, vec3_view_mut, view_mut, Particles};
use crate::simulation::pass_table::pass_table;
use crate::simulation::sorted_grid::SortedGrid;
use coil_kernels::cell_grid::Neighbors;
use coil_kernels::diagnostics::{range_figures, DiagnosticsArgs, StateFigures};
use coil_kernels::fluid::Fluid;
use coil_kernels::neighbor_list::NEIGHBOR_SLOTS;
use coil_kernels::smoothing::SmoothingKernels;
use coil_kernels::topology::{Open, Periodic, Topology};
use coil_kernels::view::{Vec3View, View, ViewMut};
use coil_kernels::Real;
use rayon::prelude::*;
use std::convert::Infallible;

/// Particles per range of the diagnostics reduction.
const DIAGNOSTICS_RANGE: usize = 1024;

/// How the CPU backend's pair passes visit a particle's neighbors.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NeighborVisits {
    /// Through the grid's cells, as a device does.
    Grid,
    /// Through lists that each sort records (`coil_kernels::neighbor_list`).
    Lists,
    /// Through lists, with each pair's spiky gradient recorded beside them: for solvers that
    /// visit the neighbors many times a step.
    ListsAndGradients,
}

pub struct CpuBackend<R> {
    host: HostParticles<R>,
    sort: GridSort,
    /// The kernels of the pair passes: the lists hold the pairs within their support.
    kernels: SmoothingKernels<R>,
    /// `NEIGHBOR_SLOTS` per particle of capacity under `ListsAndGradients`, else empty.
    spiky_gradient: ParticleArray<[R; 3]>,
    /// Each wall particle's mirror image (m), x, y, z by id, under mirrored walls.
    wall_mirror: Option<[Vec<f64>; 3]>,
}

impl<R: Real> CpuBackend<R> {
    /// The backend over `host`, with pair passes over `kernels`, visiting neighbors as
    /// `visits` says.
    pub fn new(
        host: HostParticles<R>,
        wall_mirror: Option<[Vec<f64>; 3]>,
        kernels: SmoothingKernels<R>,
        visits: NeighborVisits,
    ) -> Self {
        let mut sort = GridSort::new(&host.grid, host.particles.capacity());
        if visits != NeighborVisits::Grid {
            sort.keep_neighbor_lists();
        }
        let spiky_gradient = match visits {
            NeighborVisits::ListsAndGradients => ParticleArray::zeros(host.particles.capacity() * NEIGHBOR_SLOTS),
            _ => ParticleArray::default(),
        };
        Self { host, sort, kernels, spiky_gradient, wall_mirror }
    }

    /// The particles, to set a state by hand.
    pub fn particles_mut(&mut self) -> &mut Particles<R> {
        &mut self.host.particles
    }

    /// Runs `schedule` over the particles' views in `topology`, with neighbors visited through
    /// what `neighbors` builds over the positions.
    fn run_with<'a, T: Topology, N: Neighbors + Sync, S: Schedule<R>>(
        p: &'a mut Particles<R>,
        grid: &'a SortedGrid,
        topology: T,
        wall_mirror: Option<Vec3View<'a, f64>>,
        neighbors: impl FnOnce(Vec3View<'a, f64>) -> N,
        schedule: S,
    ) {
        let n = p.len();
        let position = vec3_view_mut(&mut p.position, n);
        let views = ParticleViews {
            topology,
            grid: grid.neighborhood(position.read(), topology),
            neighbors: neighbors(position.read()),
            id: View::new(&p.id[..n]),
            position,
            velocity: vec3_view_mut(&mut p.velocity, n),
            velocity_half: vec3_view_mut(&mut p.velocity_half, n),
            acceleration: vec3_view_mut(&mut p.acceleration, n),
            density: view_mut(&mut p.density, n),
            density_rate: p.density_rate.as_mut().map(|r| view_mut(r, n)),
            shift: p.shift.as_mut().map(|s| vec3_view_mut(s, n)),
            stress: p.stress.as_mut().map(|s| stress_view_mut(s, n)),
            viscosity: p.viscosity.as_mut().map(|v| view_mut(v, n)),
            velocity_gradient: p.velocity_gradient.as_mut().map(|g| mat3_view_mut(g, n)),
            wall_mirror,
            implicit: p.implicit.as_mut().map(|a| a.views(n)),
            pressure_solve: p.pressure_solve.as_mut().map(|a| a.views(n)),
        };
        schedule.run(views, &mut CpuPasses { n });
    }
}

impl<R: Real> Backend<R> for CpuBackend<R> {
    type Fault = Infallible;

    /// A worker of rayon's pool, so that each pass forks from it instead of handing its job to
    /// the pool from outside.
    fn on_launch_thread<T: Send>(step: impl FnOnce() -> T + Send) -> T {
        on_worker(step)
    }

    fn periodic(&self) -> Option<Periodic> {
        self.host.grid.is_periodic().then_some(self.host.grid.periodic)
    }

    fn inlet_staging(&mut self) -> (&mut Particles<R>, usize) {
        (&mut self.host.particles, usize::MAX)
    }

    fn append_staged(&mut self, _added: usize) -> Result<(), Infallible> {
        Ok(())
    }

    /// Also rebuilds the neighbor lists, where the backend keeps them.
    fn sort_and_reorder(&mut self) -> Result<usize, Infallible> {
        let HostParticles { particles, grid } = &mut self.host;
        let sort = &mut self.sort;
        let removed = sort.sort(grid, particles);
        if sort.keeps_neighbor_lists() {
            let position = vec3_view(&particles.position, particles.len());
            let (kernels, gradient) = (self.kernels, &mut self.spiky_gradient[..]);
            if grid.is_periodic() {
                sort.record_neighbors(grid, position, kernels, gradient, grid.periodic);
            } else {
                sort.record_neighbors(grid, position, kernels, gradient, Open);
            }
        }
        Ok(removed)
    }

    fn run<T: Topology, S: Schedule<R>>(&mut self, topology: T, schedule: S) -> Result<(), Infallible> {
        let HostParticles { particles, grid } = &mut self.host;
        let grid = &*grid;
        let mirror = self.wall_mirror.as_ref().map(|m| Vec3View::new(&m[0], &m[1], &m[2]));
        if self.sort.keeps_neighbor_lists() {
            let (sort, kernels, gradient) = (&self.sort, self.kernels, &self.spiky_gradient[..]);
            let lists = |position| sort.listed_neighborhood(grid, position, topology, kernels, gradient);
            Self::run_with(particles, grid, topology, mirror, lists, schedule);
        } else {
            let cells = |position| grid.neighborhood(position, topology);
            Self::run_with(particles, grid, topology, mirror, cells, schedule);
        }
        Ok(())
    }

    fn diagnostics_due(&self, _steps: u64) -> bool {
        true
    }

    fn read_diagnostics(&mut self, fluid: Fluid<R>, runaway_speed2: f64) -> Result<Readout, Infallible> {
        let p = &self.host.particles;
        let n = p.len();
        let args =
            DiagnosticsArgs { fluid, runaway_speed2, id: p.id_view(), velocity: p.velocity_view(), density: p.density_view() };
        let figures = (0..n.div_ceil(DIAGNOSTICS_RANGE))
            .into_par_iter()
            .map(|r| range_figures(r, DIAGNOSTICS_RANGE, n, &args))
            .reduce(StateFigures::default, StateFigures::combine);
        Ok(Readout { figures, live: n })
    }

    fn download(&mut self) -> Result<(), Infallible> {
        Ok(())
    }

    fn host(&self) -> &HostParticles<R> {
        &self.host
    }

    fn particle_bound(&self) -> usize {
        self.host.particles.len()
    }

    fn memory_bytes(&self) -> usize {
        let mirror = self.wall_mirror.as_ref().map_or(0, |m| 3 * m[0].len() * std::mem::size_of::<f64>());
        let p = &self.host.particles;
        let gradients = self.spiky_gradient.len() * std::mem::size_of::<[R; 3]>();
        p.capacity() * p.bytes_per_particle() + self.host.grid.bytes() + self.sort.bytes() + mirror + gradients
    }
}

/// The CPU's passes: each kernel function over `n` particles with rayon; a model's schedule
/// can run on arrays a test or check built by hand.
pub struct CpuPasses {
    pub n: usize,
}

/// The CPU's launcher of every row of `pass_table`.
macro_rules! cpu_passes {
    (
        passes { $($(#[$doc:meta])* $name:ident $(<$($g:ident: $bound:path),+>)? ($args:ty) => $pass:expr, [$($part:expr),+];)* }
        reductions { $($(#[$rdoc:meta])* $rname:ident ($rargs:ty) => $rpass:expr, $range:expr, $which:ident, [$($rpart:expr),+];)* }
    ) => {
        impl<R: Real, T: Topology, N: Neighbors + Sync> Passes<R, T, N> for CpuPasses {
            $(fn $name $(<$($g: $bound),+>)? (&mut self, args: $args) {
                launch(self.n, |i| $pass(i, &args));
            })*
            $(fn $rname(&mut self, args: $rargs, partial: ViewMut<'_, [f64; 2]>) -> [f64; 2] {
                let n = self.n;
                let ranges = n.div_ceil($range);
                (0..ranges).into_par_iter().for_each(|r| $rpass(r, n, &args, partial));
                sum_in_order(&partial.read(), ranges)
            })*
        }
    };
}

pass_table!(cpu_passes);

/// The first `ranges` partial dot products added in range order.
pub fn sum_in_order(partial: &View<'_, [f64; 2]>, ranges: usize) -> [f64; 2] {
    (0..ranges).fold([0.0; 2], |[a, b], r| {
        let [x, y] = partial.at(r);
        [a + x, b + y]
    })
}
