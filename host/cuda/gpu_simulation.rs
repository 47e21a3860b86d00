//! The CUDA backend: every pass of a run's schedule runs on the device as the PTX kernels of
//! `kernels/`, on structure-of-arrays buffers preallocated to the run's capacity.
//!
//! The host keeps the run state (`RunState`); the backend keeps the particles on the device and
//! a copy in host memory filled only for output frames. Inside a step nothing waits for the
//! device: kernels read the particle count from device memory, and the host launches threads
//! for an upper bound (`bound`). Every `check_every` steps, and before every frame, the host
//! reads the diagnostics (largest speed, compression, runaway particles) and the count.

use super::device_array::{vec3_view, vec3_view_mut, vec3_zeros};
use super::device_carried::{append_carried, copy_carried, Transfer};
use super::device_cell_sort::DeviceCellSort;
use super::device_state::{DeviceState, DIAGNOSTICS_RANGE};
use super::gpu::{ByValue, CudaError, Gpu};
use super::gpu_passes::{kernel, GpuPasses};
use crate::simulation::backend::{Backend, ParticleViews, Readout, Schedule};
use crate::simulation::cell_sort::sort_by_cell;
use crate::simulation::host_particles::HostParticles;
use crate::simulation::model::Model;
use crate::simulation::particles::{ModelFields, Particles};
use crate::simulation::{Setup, Simulation, StepError};
use coil_kernels::cell_grid::Neighborhood;
use coil_kernels::diagnostics::{DiagnosticsArgs, StateFigures};
use coil_kernels::fluid::Fluid;
use coil_kernels::topology::{Periodic, Topology};
use coil_kernels::view::{Mat3ViewMut, View};
use coil_kernels::Real;

/// Why a step on the device stopped.
pub type GpuStepError = StepError<CudaError>;

/// A run on the device.
pub type GpuSimulation<R, M> = Simulation<R, M, CudaBackend<R>>;

impl<R: Real, M: Model<R>> Simulation<R, M, CudaBackend<R>> {
    /// The run `setup` moved onto `gpu`; fresh runs then start with `sort_and_density`.
    pub fn on_gpu(setup: Setup<R, M>, gpu: Gpu) -> Result<Self, CudaError> {
        let Setup { run, host, wall_mirror } = setup;
        // Four layers of every inlet per step is far above what dt at the Eq. (10) bound brings.
        let staged = 4 * run.inlets().iter().map(|i| i.layer_size()).sum::<usize>();
        let fields = host.particles.fields();
        let backend = CudaBackend::new(host, wall_mirror, staged, fields, gpu)?;
        Ok(Self { run, backend })
    }

    /// A fresh run of `scene` with the particles `initial` on `gpu`, sorted and with its density.
    pub fn new_on_gpu(
        scene: &crate::scene::Scene,
        initial: &crate::scene::setup::InitialParticles,
        model: M,
        gpu: Gpu,
    ) -> Result<Self, CudaError> {
        let mut sim = Self::on_gpu(Setup::new(scene, initial, model), gpu)?;
        sim.sort_and_density()?;
        Ok(sim)
    }
}

pub struct CudaBackend<R: Real> {
    gpu: Gpu,
    device: DeviceState<R>,
    /// The particles and grid in host memory, copied from the device for frames.
    mirror: HostParticles<R>,
    /// Host staging of this step's inlet layers.
    staged: Particles<R>,
    /// No more particles than this are live on the device.
    bound: usize,
    /// Steps between reads of the diagnostics.
    pub check_every: u64,
    figures: Vec<StateFigures>,
    /// The host's copy of the implicit solve's partial dot products.
    partial_dots: Vec<[f64; 2]>,
    /// The host's copy of the pressure solves' partial error sums.
    partial_sums: Vec<[f64; 2]>,
}

impl<R: Real> CudaBackend<R> {
    /// Copies the particles `host` (and the walls' mirror images, under mirrored walls) onto
    /// `gpu`, with room for `staged` inlet particles a step and the arrays of `fields`.
    fn new(
        host: HostParticles<R>,
        wall_mirror: Option<[Vec<f64>; 3]>,
        staged: usize,
        fields: ModelFields,
        gpu: Gpu,
    ) -> Result<Self, CudaError> {
        let capacity = host.particles.capacity();
        let buckets = host.grid.grid.cell_count() as usize + 1;
        let tracks_fluid = host.grid.tracks_fluid().is_some();
        let mut device = DeviceState::new(&gpu, capacity, buckets, staged, fields, tracks_fluid)?;
        if let Some(mirror) = &wall_mirror {
            let mut on_device = vec3_zeros(&gpu, mirror[0].len(), "wall mirror images")?;
            for a in 0..3 {
                on_device[a].upload(&gpu, &mirror[a])?;
            }
            device.wall_mirror = Some(on_device);
        }
        let mut backend = Self {
            bound: host.particles.len(),
            staged: Particles::with_capacity(staged, fields),
            figures: vec![StateFigures::default(); device.figures.len()],
            partial_dots: vec![[0.0; 2]; device.implicit.as_ref().map_or(0, |i| i.partial_dots.len())],
            partial_sums: vec![[0.0; 2]; device.pressure_solve.as_ref().map_or(0, |p| p.partial_sums.len())],
            mirror: host,
            gpu,
            device,
            check_every: 10,
        };
        backend.upload()?;
        Ok(backend)
    }

    /// The device, for timing (`Gpu::mark`, `Gpu::start_profile`).
    pub fn gpu(&mut self) -> &mut Gpu {
        &mut self.gpu
    }

    /// Ends the run and hands its device back, its memory freed.
    pub fn into_gpu(self) -> Gpu {
        self.gpu
    }

    /// Copies the host's particles and grid to the device.
    fn upload(&mut self) -> Result<(), CudaError> {
        let n = self.mirror.particles.len();
        let (gpu, d) = (&self.gpu, &mut self.device);
        copy_carried(gpu, d, &mut self.mirror.particles, n, Transfer::Upload)?;
        d.cell_start.upload(gpu, self.mirror.grid.cell_start())?;
        d.near_fluid.upload(gpu, self.mirror.grid.near_fluid())?;
        d.count.upload(gpu, &[n as u32])?;
        gpu.synchronize()
    }

    fn count(&self) -> ByValue<View<'static, u32>> {
        ByValue(self.device.count.view(1))
    }

    fn neighborhood<T: Topology>(&self, topology: T) -> Neighborhood<'static, T> {
        Neighborhood {
            grid: self.mirror.grid.grid,
            cell_start: self.device.cell_start.view(self.device.cell_start.len()),
            position: vec3_view(&self.device.position, self.bound),
            topology,
            near_fluid: self.device.near_fluid.view(self.device.near_fluid.len()),
        }
    }
}

impl<R: Real> Backend<R> for CudaBackend<R> {
    type Fault = CudaError;

    fn periodic(&self) -> Option<Periodic> {
        self.mirror.grid.is_periodic().then_some(self.mirror.grid.periodic)
    }

    fn inlet_staging(&mut self) -> (&mut Particles<R>, usize) {
        self.staged.set_len(0);
        let room = self.staged.capacity();
        (&mut self.staged, room)
    }

    /// Uploads the staged layers and appends them behind the live particles.
    fn append_staged(&mut self, added: usize) -> Result<(), CudaError> {
        if added == 0 {
            return Ok(());
        }
        let (gpu, d) = (&mut self.gpu, &mut self.device);
        append_carried(gpu, d, &mut self.staged, added)?;
        // SAFETY: grow_count(count, added) on the one-entry count.
        unsafe {
            gpu.launch("grow_count", 1, &[&ByValue(d.count.view_mut(1)), &ByValue(added as u32)])?;
        }
        self.bound += added;
        Ok(())
    }

    /// The device's count is read back with the diagnostics: the particles the sort drops are
    /// counted then.
    fn sort_and_reorder(&mut self) -> Result<usize, CudaError> {
        let (gpu, d, grid, bound) = (&mut self.gpu, &mut self.device, &self.mirror.grid, self.bound);
        sort_by_cell(&mut DeviceCellSort { gpu, d, grid, bound })?;
        Ok(0)
    }

    fn run<T: Topology, S: Schedule<R>>(&mut self, topology: T, schedule: S) -> Result<(), CudaError> {
        let n = self.bound;
        let d = &self.device;
        let views = ParticleViews {
            topology,
            grid: self.neighborhood(topology),
            neighbors: self.neighborhood(topology),
            id: d.id.view(n),
            position: vec3_view_mut(&d.position, n),
            velocity: vec3_view_mut(&d.velocity, n),
            velocity_half: vec3_view_mut(&d.velocity_half, n),
            acceleration: vec3_view_mut(&d.acceleration, n),
            density: d.density.view_mut(n),
            density_rate: d.density_rate.as_ref().map(|r| r.view_mut(n)),
            shift: d.shift.as_ref().map(|s| vec3_view_mut(s, n)),
            stress: d.stress_view(n),
            viscosity: d.viscosity.as_ref().map(|v| v.view_mut(n)),
            velocity_gradient: d
                .velocity_gradient
                .as_ref()
                .map(|g| Mat3ViewMut { rows: [vec3_view_mut(&g[0], n), vec3_view_mut(&g[1], n), vec3_view_mut(&g[2], n)] }),
            wall_mirror: d.wall_mirror.as_ref().map(|m| vec3_view(m, m[0].len())),
            implicit: d.implicit.as_ref().map(|i| i.views(n)),
            pressure_solve: d.pressure_solve.as_ref().map(|p| p.views(n)),
        };
        let partial_dots = d.implicit.as_ref().map(|i| (&i.partial_dots, &mut self.partial_dots[..]));
        let partial_sums = d.pressure_solve.as_ref().map(|p| (&p.partial_sums, &mut self.partial_sums[..]));
        let mut passes = GpuPasses {
            gpu: &mut self.gpu,
            count: d.count.view(1),
            threads: n as u32,
            result: Ok(()),
            partial_dots,
            partial_sums,
        };
        schedule.run(views, &mut passes);
        passes.result
    }

    fn diagnostics_due(&self, steps: u64) -> bool {
        steps.is_multiple_of(self.check_every)
    }

    fn read_diagnostics(&mut self, fluid: Fluid<R>, runaway_speed2: f64) -> Result<Readout, CudaError> {
        let n = self.bound;
        let d = &self.device;
        let args = DiagnosticsArgs {
            fluid,
            runaway_speed2,
            id: d.id.view(n),
            velocity: vec3_view(&d.velocity, n),
            density: d.density.view(n),
        };
        let ranges = n.div_ceil(DIAGNOSTICS_RANGE);
        let out = ByValue(self.device.figures.view_mut(ranges));
        let count = self.count();
        // SAFETY: diagnostics_<R>(count, range_len, args, out), `out` holding one figure per range.
        unsafe {
            self.gpu.launch(
                kernel::<R>("diagnostics", "", ""),
                ranges as u32,
                &[&count, &ByValue(DIAGNOSTICS_RANGE as u32), &ByValue(args), &out],
            )?;
        }
        let mut live = [0u32];
        self.device.count.download(&self.gpu, &mut live)?;
        let live = live[0] as usize;
        let figures = &mut self.figures[..live.div_ceil(DIAGNOSTICS_RANGE)];
        self.device.figures.download(&self.gpu, figures)?;
        self.bound = live;
        Ok(Readout { figures: figures.iter().fold(StateFigures::default(), |a, &b| a.combine(b)), live })
    }

    /// Copies the particles in sorted order and the grid to the host (for frames).
    fn download(&mut self) -> Result<(), CudaError> {
        let n = self.bound;
        let (gpu, d) = (&self.gpu, &mut self.device);
        let p = &mut self.mirror.particles;
        p.set_len(n);
        copy_carried(gpu, d, p, n, Transfer::Download)?;
        for a in 0..3 {
            d.acceleration[a].download(gpu, &mut p.acceleration[a][..n])?;
        }
        d.cell_start.download(gpu, self.mirror.grid.cell_start_mut())?;
        d.near_fluid.download(gpu, self.mirror.grid.near_fluid_mut())?;
        Ok(())
    }

    fn host(&self) -> &HostParticles<R> {
        &self.mirror
    }

    fn particle_bound(&self) -> usize {
        self.bound
    }

    /// Bytes of device memory.
    fn memory_bytes(&self) -> usize {
        self.device.bytes()
    }
}
