//! `coil bench`: the paper's Table I, the dam break at 1K to 1M fluid particles, timed step by
//! step on the CPU and on a CUDA GPU in f32 and f64, next to the paper's own figures.
//!
//! A figure is the median of per-step times after a warm-up. CPU steps are wall-clock times;
//! GPU steps are the intervals between CUDA events recorded on the stream between steps, with
//! nothing waiting in between, so they are what a long run achieves per step.

pub mod operation_count;
pub mod report;

use crate::bench::operation_count::{count_step_operations, StepOperations};
pub use crate::cuda::peak_rates::PeakRates;
use crate::run::Device;
use crate::scene::overrides::{apply, Override};
use crate::scene::setup::{initial_particles, InitialParticles};
use crate::scene::{Precision, Scene};
use crate::simulation::backend::Backend;
use crate::simulation::model::{Model, ModelFields};
use crate::simulation::variant::{with_precision_and_model, WithModel};
use crate::simulation::{RunState, Setup, Simulation, StepError};
use crate::statistics::Sorted;
use coil_kernels::Real;
use std::time::Instant;

/// The dam break of Table I as shipped (K = 1 s, n = 1, nu0 = 0.05, nu_inf = 0.005 m^2/s,
/// h = 2 x spacing), embedded so the benchmark is the same wherever it runs.
const DAM_BREAK: &str = include_str!("../../scenes/dam_break.toml");
const DAM_BREAK_FILE: &str = "scenes/dam_break.toml (embedded)";
/// Edge of the dam break's fluid cube (m).
const CUBE_EDGE_M: f64 = 0.4;

/// One row of Table I.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TableRow {
    pub label: &'static str,
    /// The fluid cube has this many particles along each edge.
    pub per_edge: usize,
    /// The paper's CPU time (sequential), ms per step: its seconds per 1000 steps.
    pub paper_cpu_ms: Option<f64>,
    /// The paper's GPU time (GeForce GTX 650, 384 CUDA cores), ms per step.
    pub paper_gpu_ms: f64,
}

/// Table I of the paper, sizes as cubes of fluid particles.
pub const TABLE_I: [TableRow; 7] = [
    TableRow { label: "1K", per_edge: 10, paper_cpu_ms: Some(7.20), paper_gpu_ms: 1.03 },
    TableRow { label: "4K", per_edge: 16, paper_cpu_ms: Some(35.66), paper_gpu_ms: 2.40 },
    TableRow { label: "16K", per_edge: 25, paper_cpu_ms: Some(156.42), paper_gpu_ms: 6.81 },
    TableRow { label: "64K", per_edge: 40, paper_cpu_ms: Some(682.00), paper_gpu_ms: 25.80 },
    TableRow { label: "128K", per_edge: 50, paper_cpu_ms: Some(1374.86), paper_gpu_ms: 51.35 },
    TableRow { label: "256K", per_edge: 64, paper_cpu_ms: Some(2887.20), paper_gpu_ms: 104.84 },
    TableRow { label: "1M", per_edge: 100, paper_cpu_ms: None, paper_gpu_ms: 444.93 },
];

/// The Table I row a label names (`1K`, `4k`, ...).
pub fn table_row(label: &str) -> Option<TableRow> {
    TABLE_I.iter().copied().find(|r| r.label.eq_ignore_ascii_case(label.trim()))
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BenchBackend {
    Cpu,
    Cuda,
}

impl BenchBackend {
    pub fn name(self) -> &'static str {
        match self {
            BenchBackend::Cpu => "cpu",
            BenchBackend::Cuda => "cuda",
        }
    }
}

#[derive(Debug, Clone)]
pub struct BenchOptions {
    pub sizes: Vec<TableRow>,
    pub precisions: Vec<Precision>,
    pub backends: Vec<BenchBackend>,
    /// Timed steps per measurement.
    pub steps: usize,
    /// Timed CPU steps above 64K particles, where 100 steps would take minutes.
    pub cpu_large_steps: usize,
    /// Untimed steps first, so the column has started to fall.
    pub warmup: usize,
    /// Extra GPU steps with every launch timed by CUDA events.
    pub profile_steps: usize,
}

/// One kernel's share of a GPU step.
#[derive(Debug, Clone, PartialEq)]
pub struct KernelShare {
    pub kernel: String,
    pub launches_per_step: f64,
    pub ms_per_step: f64,
}

/// One timed configuration.
#[derive(Debug, Clone, PartialEq)]
pub struct Measurement {
    pub size: TableRow,
    pub fluid: usize,
    pub boundary: usize,
    pub precision: Precision,
    pub backend: BenchBackend,
    pub steps: usize,
    pub median_ms: f64,
    /// 10th and 90th percentiles of the step times (ms).
    pub p10_ms: f64,
    pub p90_ms: f64,
    /// Memory the run allocated (device memory on the GPU, host memory on the CPU) over fluid
    /// particles (bytes).
    pub bytes_per_fluid_particle: f64,
    /// On the GPU: each kernel's time per step, from CUDA events.
    pub kernels: Vec<KernelShare>,
    /// On the GPU: the step's compulsory memory traffic over the measured copy bandwidth (ms).
    pub memory_floor_ms: Option<f64>,
    /// The floating-point operations of a step at this size, counted on the CPU backend.
    pub operations: Option<StepOperations>,
    /// On a GPU of known peak rates: the step's operations at those rates (ms).
    pub arithmetic_floor_ms: Option<f64>,
}

impl Measurement {
    /// Fluid particle-steps per second at the median step.
    pub fn particle_steps_per_s(&self) -> f64 {
        self.fluid as f64 / (self.median_ms * 1e-3)
    }
}

/// What `coil bench` measured, and on what.
#[derive(Debug, Clone)]
pub struct BenchReport {
    pub cpu: String,
    pub gpu: Option<String>,
    /// Device-to-device copy bandwidth (bytes/s), read + write counted.
    pub gpu_bandwidth: Option<f64>,
    /// The GPU's peak floating-point rates, where its architecture is known.
    pub gpu_peak: Option<PeakRates>,
    pub measurements: Vec<Measurement>,
}

/// The dam break with `per_edge`^3 fluid particles.
pub fn dam_break(per_edge: usize) -> Scene {
    let spacing = CUBE_EDGE_M / per_edge as f64;
    let set = Override::parse(&format!("material.particle_spacing_m={spacing}")).expect("a valid override");
    let text = apply(DAM_BREAK, DAM_BREAK_FILE, &[set]).expect("the shipped scene is valid TOML");
    Scene::parse(&text, DAM_BREAK_FILE).expect("the shipped dam break is valid at every Table I size")
}

/// The median and the 10th and 90th percentiles of `times`.
fn percentiles(times: Vec<f64>) -> (f64, f64, f64) {
    let sorted = Sorted::new(times);
    (sorted.median(), sorted.quantile(0.1), sorted.quantile(0.9))
}

fn step<R: Real, M: Model<R>, B: Backend<R>>(sim: &mut Simulation<R, M, B>) -> Result<(), String> {
    sim.step().map_err(|stop| match stop {
        StepError::Unstable(i) => format!("the dam break went unstable: {i}"),
        StepError::Backend(e) => e.to_string(),
    })
}

/// A measurement of the run `run` with `memory_bytes` of particle memory, before timing.
fn untimed<R: Real, M: Model<R>>(run: &RunState<R, M>, memory_bytes: usize, m: &Measure) -> Measurement {
    Measurement {
        size: m.size,
        fluid: run.fluid_count(),
        boundary: run.boundary_count(),
        precision: m.precision,
        backend: BenchBackend::Cpu,
        steps: m.steps,
        median_ms: 0.0,
        p10_ms: 0.0,
        p90_ms: 0.0,
        bytes_per_fluid_particle: memory_bytes as f64 / run.fluid_count() as f64,
        kernels: Vec::new(),
        memory_floor_ms: None,
        operations: None,
        arithmetic_floor_ms: None,
    }
}

/// Times one configuration; `gpu` is taken for a CUDA measurement and handed back.
struct Measure<'a> {
    scene: &'a Scene,
    initial: &'a InitialParticles,
    size: TableRow,
    precision: Precision,
    steps: usize,
    options: &'a BenchOptions,
    gpu: Option<Device>,
    /// The device's copy bandwidth (bytes/s), for the memory floor.
    #[cfg(feature = "cuda")]
    bandwidth: Option<f64>,
}

impl WithModel for Measure<'_> {
    type Output = (Result<Measurement, String>, Option<Device>);
    fn with<R: Real, M: Model<R>>(mut self, model: M) -> Self::Output {
        let setup = Setup::<R, M>::new(self.scene, self.initial, model);
        match self.gpu.take() {
            None => {
                let mut sim = Simulation::on_cpu(setup, true);
                let Ok(()) = sim.sort_and_density();
                let blank = untimed(&sim.run, sim.backend.memory_bytes(), &self);
                let timed = (|| {
                    for _ in 0..self.options.warmup {
                        step(&mut sim)?;
                    }
                    let mut times = Vec::with_capacity(self.steps);
                    for _ in 0..self.steps {
                        let started = Instant::now();
                        step(&mut sim)?;
                        times.push(started.elapsed().as_secs_f64() * 1e3);
                    }
                    Ok(times)
                })();
                let result = timed.map(|times| {
                    let (median_ms, p10_ms, p90_ms) = percentiles(times);
                    Measurement { median_ms, p10_ms, p90_ms, ..blank }
                });
                (result, None)
            }
            #[cfg(feature = "cuda")]
            Some(gpu) => gpu_measurement(setup, gpu, &self),
            #[cfg(not(feature = "cuda"))]
            Some(d) => match d {},
        }
    }
}

#[cfg(feature = "cuda")]
fn gpu_measurement<R: Real, M: Model<R>>(
    setup: Setup<R, M>,
    gpu: crate::cuda::Gpu,
    measure: &Measure,
) -> (Result<Measurement, String>, Option<Device>) {
    use crate::cuda::GpuSimulation;
    let (options, bandwidth) = (measure.options, measure.bandwidth);
    let particles = setup.host.particles.len();
    let cells = setup.host.grid.grid.cell_count() as f64;
    let mut state = match GpuSimulation::on_gpu(setup, gpu) {
        Ok(s) => s,
        Err(e) => return (Err(e.to_string()), None),
    };
    if let Err(e) = state.sort_and_density() {
        return (Err(e.to_string()), Some(state.backend.into_gpu()));
    }
    let bytes = state.backend.memory_bytes() as f64;
    let blank = untimed(&state.run, 0, measure);
    let timed = (|| -> Result<Measurement, String> {
        for _ in 0..options.warmup {
            step(&mut state)?;
        }
        let err = |e: crate::cuda::CudaError| e.to_string();
        let mut marks = Vec::with_capacity(blank.steps + 1);
        marks.push(state.backend.gpu().mark().map_err(err)?);
        for _ in 0..blank.steps {
            step(&mut state)?;
            marks.push(state.backend.gpu().mark().map_err(err)?);
        }
        let mut times = Vec::with_capacity(blank.steps);
        for w in marks.windows(2) {
            times.push(state.backend.gpu().elapsed_ms(&w[0], &w[1]).map_err(err)?);
        }
        state.backend.gpu().start_profile();
        for _ in 0..options.profile_steps {
            step(&mut state)?;
        }
        let per_step = 1.0 / options.profile_steps.max(1) as f64;
        let kernels = state
            .backend
            .gpu()
            .finish_profile()
            .map_err(err)?
            .into_iter()
            .map(|k| KernelShare {
                kernel: k.kernel.to_string(),
                launches_per_step: k.launches as f64 * per_step,
                ms_per_step: k.total_ms * per_step,
            })
            .collect();
        let bytes_moved = compulsory_bytes(std::mem::size_of::<R>(), M::FIELDS, particles as f64, cells);
        let (median_ms, p10_ms, p90_ms) = percentiles(times);
        Ok(Measurement {
            backend: BenchBackend::Cuda,
            median_ms,
            p10_ms,
            p90_ms,
            bytes_per_fluid_particle: bytes / blank.fluid as f64,
            kernels,
            memory_floor_ms: bandwidth.map(|b| bytes_moved / b * 1e3),
            ..blank
        })
    })();
    (timed, Some(state.backend.into_gpu()))
}

/// Bytes a step must move between the GPU and its memory, however well the kernels use the
/// caches: every per-particle array each pass reads or writes, once. `real` is the size of the
/// physics precision; positions are always f64. Neighbours' reads hit the caches after the sort
/// and are not counted, which makes this a floor.
pub fn compulsory_bytes(real: usize, fields: ModelFields, particles: f64, cells: f64) -> f64 {
    let (p, r) = (24.0, real as f64);
    let hash = p + 4.0;
    let histogram_and_scatter = 4.0 + 4.0 + 4.0;
    // Gathers position, velocity, half-step velocity and id through the order array.
    let reorder = 2.0 * (p + 6.0 * r + 4.0) + 4.0;
    let density = p + r;
    // Positions, velocity and density read; stress, velocity gradient or viscosity written in
    // one pass, then read.
    let gradient = if fields.velocity_gradient { 9.0 * r } else { 0.0 };
    let written = if fields.stress { 6.0 * r } else { 0.0 } + gradient + if fields.viscosity { r } else { 0.0 };
    let gradient_pass = if written > 0.0 { p + 4.0 * r + written } else { 0.0 };
    let acceleration = p + 4.0 * r + written + 3.0 * r;
    let leapfrog = 2.0 * (p + 6.0 * r);
    // Counters cleared, counted and scanned; cell starts written and read.
    let grid = 4.0 * 4.0;
    // The cells near fluid: ids read; a byte a cell for holding fluid written and read, and
    // one for lying near it written.
    let (fluid_cells_per_particle, fluid_cells_per_cell) = (4.0, 3.0);
    particles
        * (hash + histogram_and_scatter + reorder + fluid_cells_per_particle + density + gradient_pass + acceleration + leapfrog)
        + cells * (grid + fluid_cells_per_cell)
}

/// The CPU's model name and the worker threads, for the report.
fn describe_cpu() -> String {
    let model = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines().find(|l| l.starts_with("model name")).and_then(|l| l.split(':').nth(1)).map(|m| m.trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".into());
    format!("{model}, {} threads", rayon::current_num_threads())
}

/// Runs every configuration of `options`, smallest first. A GPU is opened once when asked for;
/// without one a `cuda` measurement is an error that names why.
pub fn bench(options: &BenchOptions, progress: impl FnMut(&Measurement)) -> Result<BenchReport, String> {
    bench_on(open_gpu(options)?, options, progress)
}

/// [`bench()`] on a device already opened (the emulated one, in tests), which the `cuda`
/// measurements need.
pub fn bench_on(
    mut gpu: Option<Device>,
    options: &BenchOptions,
    mut progress: impl FnMut(&Measurement),
) -> Result<BenchReport, String> {
    if gpu.is_none() && options.backends.contains(&BenchBackend::Cuda) {
        return Err("--backend cuda: no device was opened".into());
    }
    let (gpu_name, gpu_bandwidth, gpu_peak) = gpu_facts(&gpu)?;
    let mut measurements = Vec::new();
    for &size in &options.sizes {
        let scene = dam_break(size.per_edge);
        let initial = initial_particles(&scene, DAM_BREAK_FILE).map_err(|e| e.to_string())?;
        let operations = count_step_operations(&scene, &initial).map_err(|e| format!("{}: {e}", size.label))?;
        for &precision in &options.precisions {
            for &backend in &options.backends {
                let steps = match backend {
                    BenchBackend::Cpu if size.per_edge > 40 => options.cpu_large_steps,
                    _ => options.steps,
                };
                let device = if backend == BenchBackend::Cuda { gpu.take() } else { None };
                let work = Measure {
                    scene: &scene,
                    initial: &initial,
                    size,
                    precision,
                    steps,
                    options,
                    gpu: device,
                    #[cfg(feature = "cuda")]
                    bandwidth: gpu_bandwidth,
                };
                let (result, returned) = with_precision_and_model(precision, &scene, work);
                if returned.is_some() {
                    gpu = returned;
                }
                let mut m =
                    result.map_err(|e| format!("{} {} {}: {e}", size.label, precision_name(precision), backend.name()))?;
                m.operations = Some(operations);
                if backend == BenchBackend::Cuda {
                    m.arithmetic_floor_ms = gpu_peak.map(|p| operations.floor_s(p.of_precision(precision), p.f64) * 1e3);
                }
                progress(&m);
                measurements.push(m);
            }
        }
    }
    Ok(BenchReport { cpu: describe_cpu(), gpu: gpu_name, gpu_bandwidth, gpu_peak, measurements })
}

pub fn precision_name(p: Precision) -> &'static str {
    match p {
        Precision::F32 => "f32",
        Precision::F64 => "f64",
    }
}

/// The device `options` measure on, when they ask for one.
fn open_gpu(options: &BenchOptions) -> Result<Option<Device>, String> {
    if !options.backends.contains(&BenchBackend::Cuda) {
        return Ok(None);
    }
    crate::run::open_cuda().map(Some).map_err(|e| format!("--backend cuda: {e}"))
}

/// Whether `--backend auto` finds a CUDA device, and if not, why.
pub fn cuda_available() -> Result<(), String> {
    crate::run::open_cuda().map(drop)
}

/// What the report says of the device, taken once for every configuration: its name, its
/// copy bandwidth (bytes/s, measured, for the memory floor) and its peak rates (for the
/// arithmetic floor).
type GpuFacts = (Option<String>, Option<f64>, Option<PeakRates>);

#[cfg(feature = "cuda")]
fn gpu_facts(gpu: &Option<Device>) -> Result<GpuFacts, String> {
    let Some(g) = gpu else { return Ok((None, None, None)) };
    Ok((Some(g.describe()), Some(g.copy_bandwidth().map_err(|e| e.to_string())?), g.peak_rates()))
}

#[cfg(not(feature = "cuda"))]
fn gpu_facts(gpu: &Option<Device>) -> Result<GpuFacts, String> {
    Ok(gpu.as_ref().map_or((None, None, None), |d| match *d {}))
}
