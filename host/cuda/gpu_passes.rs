//! Every pass of the schedule as a launch of its PTX entry, the reductions read back in range
//! order.

use super::device_array::DeviceArray;
use super::gpu::{ByValue, CudaError, Gpu};
use crate::cpu::sum_in_order;
use crate::simulation::backend::Passes;
use coil_kernels::acceleration::AccelerationArgs;
use coil_kernels::cell_grid::Neighborhood;
use coil_kernels::continuity_molteni2009::{ContinuityArgs, DensityIntegrationArgs};
use coil_kernels::cross_viscosity::Rheology;
use coil_kernels::density::{DensityArgs, DensityKernel, Spiky};
use coil_kernels::dfsph_bender2017::{
    DensityErrorArgs, DensityRateArgs, DivergenceErrorArgs, ErrorSumArgs, FactorArgs, PressureChangeArgs, WarmStartArgs,
};
use coil_kernels::leapfrog::LeapfrogArgs;
use coil_kernels::mirrored_wall::MirroredWallArgs;
use coil_kernels::nozzle::{NozzleArgs, NozzleShiftArgs};
use coil_kernels::shifting_sun2017::{ShiftArgs, ShiftingArgs};
use coil_kernels::topology::Topology;
use coil_kernels::velocity_gradient::GradientEstimate;
use coil_kernels::view::{View, ViewMut};
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

/// The PTX entry of a pass in precision `R`: the stem, then the physics variant and the
/// topology where they are not empty, then `R` (e.g. `stress_cross_f32`).
pub(super) fn kernel<R: Real>(stem: &'static str, variant: &'static str, topology: &'static str) -> &'static str {
    entry::<R>([stem, variant, "", topology])
}

/// The PTX entry named by `parts` (stem, physics variants, topology) that are not empty, then
/// `R` (e.g. `stress_cross_renormalized_f32`). Names are few and fixed: each is built once and
/// kept.
pub(super) fn entry<R: Real>(parts: [&'static str; 4]) -> &'static str {
    use std::collections::HashMap;
    use std::sync::{Mutex, OnceLock};
    type Names = HashMap<[&'static str; 5], &'static str>;
    static NAMES: OnceLock<Mutex<Names>> = OnceLock::new();
    let mut names = NAMES.get_or_init(Default::default).lock().unwrap_or_else(|e| e.into_inner());
    let [stem, variant, detail, topology] = parts;
    let key = [stem, variant, detail, topology, R::NAME];
    names.entry(key).or_insert_with(|| {
        Box::leak(key.iter().filter(|p| !p.is_empty()).copied().collect::<Vec<_>>().join("_").into_boxed_str())
    })
}

/// The model's passes as launches of the model's kernels.
pub(super) struct GpuPasses<'g> {
    pub(super) gpu: &'g mut Gpu,
    pub(super) count: View<'static, u32>,
    pub(super) threads: u32,
    pub(super) result: Result<(), CudaError>,
    pub(super) partial_dots: Option<PartialSums<'g>>,
    pub(super) partial_sums: Option<PartialSums<'g>>,
}

/// A reduction's partial sums on the device, and their host copy.
pub(super) type PartialSums<'g> = (&'g DeviceArray<[f64; 2]>, &'g mut [[f64; 2]]);

impl GpuPasses<'_> {
    pub(super) fn run<A: Copy>(&mut self, name: &'static str, args: A) {
        if self.result.is_ok() {
            // SAFETY: the argument struct is the entry's, built over the run's device arrays.
            self.result = unsafe { self.gpu.launch(name, self.threads, &[&ByValue(self.count), &ByValue(args)]) };
        }
    }
}

impl<R: Real, T: Topology> Passes<R, T, Neighborhood<'static, T>> for GpuPasses<'_> {
    fn density<K: DensityKernel>(&mut self, args: DensityArgs<'_, R, Neighborhood<'static, T>>) {
        self.run(kernel::<R>("density", K::NAME, T::NAME), args);
    }
    fn continuity<K: DensityKernel>(&mut self, args: ContinuityArgs<'_, R, Neighborhood<'static, T>>) {
        self.run(kernel::<R>("continuity", K::NAME, T::NAME), args);
    }
    fn continuity_floor(&mut self, args: DensityArgs<'_, R, Neighborhood<'static, T>>) {
        self.run(kernel::<R>("continuity_floor", Spiky::NAME, T::NAME), args);
    }
    fn density_integration(&mut self, args: DensityIntegrationArgs<'_, R>) {
        self.run(kernel::<R>("density_integration", "", ""), args);
    }
    fn mirrored_wall(&mut self, args: MirroredWallArgs<'_, R, T>) {
        self.run(kernel::<R>("mirrored_wall", "", T::NAME), args);
    }
    fn stress<Rh: Rheology<R>, G: GradientEstimate>(&mut self, args: StressArgs<'_, R, Rh, G, Neighborhood<'static, T>>) {
        self.run(entry::<R>(["stress", Rh::NAME, G::NAME, T::NAME]), args);
    }
    fn shear_viscosity<Rh: Rheology<R>>(&mut self, args: ShearViscosityArgs<'_, R, Rh, Neighborhood<'static, T>>) {
        self.run(kernel::<R>("shear_viscosity", Rh::NAME, T::NAME), args);
    }
    fn velocity_gradient<Rh: Rheology<R>>(&mut self, args: VelocityGradientArgs<'_, R, Rh, Neighborhood<'static, T>>) {
        self.run(kernel::<R>("velocity_gradient", Rh::NAME, T::NAME), args);
    }
    fn acceleration<Op: ViscousOperator<R>>(&mut self, args: AccelerationArgs<'_, R, Op, Neighborhood<'static, T>>) {
        self.run(kernel::<R>("acceleration", Op::NAME, T::NAME), args);
    }
    fn nozzle(&mut self, args: NozzleArgs<'_, R>) {
        self.run(kernel::<R>("nozzle", "", ""), args);
    }
    fn leapfrog(&mut self, args: LeapfrogArgs<'_, R, T>) {
        self.run(kernel::<R>("leapfrog", "", T::NAME), args);
    }
    fn shifting(&mut self, args: ShiftingArgs<'_, R, Neighborhood<'static, T>>) {
        self.run(kernel::<R>("shifting", "", T::NAME), args);
    }
    fn nozzle_shift(&mut self, args: NozzleShiftArgs<'_, R>) {
        self.run(kernel::<R>("nozzle_shift", "", ""), args);
    }
    fn shift(&mut self, args: ShiftArgs<'_, R, T>) {
        self.run(kernel::<R>("shift", "", T::NAME), args);
    }
    fn predictor(&mut self, args: PredictorArgs<'_, R>) {
        self.run(kernel::<R>("predictor", "", ""), args);
    }
    fn lagged_viscosity<Rh: Rheology<R>>(&mut self, args: LaggedViscosityArgs<'_, R, Rh, Neighborhood<'static, T>>) {
        self.run(kernel::<R>("lagged_viscosity", Rh::NAME, T::NAME), args);
    }
    fn implicit_stress(&mut self, args: ImplicitStressArgs<'_, R, Neighborhood<'static, T>>) {
        self.run(kernel::<R>("implicit_stress", "", T::NAME), args);
    }
    fn system_block(&mut self, args: SystemBlockArgs<'_, R, Neighborhood<'static, T>>) {
        self.run(kernel::<R>("system_block", "", T::NAME), args);
    }
    fn system_product(&mut self, args: SystemProductArgs<'_, R, Neighborhood<'static, T>>) {
        self.run(kernel::<R>("system_product", "", T::NAME), args);
    }
    fn morris_system_block<Nu: ParticleViscosity<R>>(
        &mut self,
        args: MorrisSystemBlockArgs<'_, R, Nu, Neighborhood<'static, T>>,
    ) {
        self.run(kernel::<R>("system_block", Nu::OPERATOR_NAME, T::NAME), args);
    }
    fn morris_system_product<Nu: ParticleViscosity<R>>(
        &mut self,
        args: MorrisSystemProductArgs<'_, R, Nu, Neighborhood<'static, T>>,
    ) {
        self.run(kernel::<R>("system_product", Nu::OPERATOR_NAME, T::NAME), args);
    }
    fn cg_start(&mut self, args: CgStartArgs<'_, R>) {
        self.run(kernel::<R>("cg_start", "", ""), args);
    }
    fn cg_step(&mut self, args: CgStepArgs<'_, R>) {
        self.run(kernel::<R>("cg_step", "", ""), args);
    }
    fn cg_direction(&mut self, args: CgDirectionArgs<'_, R>) {
        self.run(kernel::<R>("cg_direction", "", ""), args);
    }
    fn viscous_acceleration(&mut self, args: ViscousAccelerationArgs<'_, R>) {
        self.run(kernel::<R>("viscous_acceleration", "", ""), args);
    }
    /// Waits for the device: the solve's next step depends on the sums.
    fn dots(&mut self, args: DotArgs<'_, R>, partial: ViewMut<'_, [f64; 2]>) -> [f64; 2] {
        self.reduce(kernel::<R>("dots", "", ""), args, partial, Reduction::Dots)
    }
    fn dfsph_factor(&mut self, args: FactorArgs<'_, R, Neighborhood<'static, T>>) {
        self.run(kernel::<R>("dfsph_factor", "", T::NAME), args);
    }
    fn divergence_error(&mut self, args: DivergenceErrorArgs<'_, R, Neighborhood<'static, T>>) {
        self.run(kernel::<R>("divergence_error", "", T::NAME), args);
    }
    fn density_error(&mut self, args: DensityErrorArgs<'_, R, Neighborhood<'static, T>>) {
        self.run(kernel::<R>("density_error", "", T::NAME), args);
    }
    fn dfsph_density_rate(&mut self, args: DensityRateArgs<'_, R, Neighborhood<'static, T>>) {
        self.run(kernel::<R>("dfsph_density_rate", "", T::NAME), args);
    }
    fn pressure_change(&mut self, args: PressureChangeArgs<'_, R, Neighborhood<'static, T>>) {
        self.run(kernel::<R>("pressure_change", "", T::NAME), args);
    }
    fn warm_start(&mut self, args: WarmStartArgs<'_, R>) {
        self.run(kernel::<R>("warm_start", "", ""), args);
    }
    /// Waits for the device: the solve's next sweep depends on the sums.
    fn error_sums(&mut self, args: ErrorSumArgs<'_, R>, partial: ViewMut<'_, [f64; 2]>) -> [f64; 2] {
        self.reduce(kernel::<R>("error_sums", "", ""), args, partial, Reduction::ErrorSums)
    }
}

/// Which partial sums a reduction fills.
pub(super) enum Reduction {
    /// The implicit viscosity solve's dot products.
    Dots,
    /// The pressure solves' error sums.
    ErrorSums,
}

impl<'g> GpuPasses<'g> {
    /// Runs the reduction `name` over `args` into `partial` (one pair per range), then adds
    /// the ranges' parts on the host in range order; NaN where the device failed.
    pub(super) fn reduce<A: Copy>(
        &mut self,
        name: &'static str,
        args: A,
        partial: ViewMut<'_, [f64; 2]>,
        reduction: Reduction,
    ) -> [f64; 2] {
        let ranges = partial.len();
        if self.result.is_ok() {
            // SAFETY: name(count, args, out), `out` holding one pair per range.
            self.result =
                unsafe { self.gpu.launch(name, ranges as u32, &[&ByValue(self.count), &ByValue(args), &ByValue(partial)]) };
        }
        let sums = match reduction {
            Reduction::Dots => &mut self.partial_dots,
            Reduction::ErrorSums => &mut self.partial_sums,
        };
        let (device, host) = sums.as_mut().expect("a solve allocates its partial sums");
        let result = std::mem::replace(&mut self.result, Ok(()));
        let result = result.and_then(|()| device.download(self.gpu, &mut host[..ranges]));
        let total = match &result {
            Ok(()) => sum_in_order(&View::new(&host[..ranges]), ranges),
            Err(_) => [f64::NAN; 2],
        };
        self.result = result;
        total
    }
}
