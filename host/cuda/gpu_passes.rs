//! Every pass of the schedule as a launch of its PTX entry, the reductions read back in range
//! order.

use super::device_array::DeviceArray;
use super::gpu::{ByValue, CudaError, Gpu};
use crate::cpu::sum_in_order;
use crate::simulation::backend::Passes;
use crate::simulation::pass_table::pass_table;
use coil_kernels::cell_grid::{Neighborhood, Neighbors};
use coil_kernels::topology::Topology;
use coil_kernels::view::{View, ViewMut};
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

/// The device's launcher of every row of `pass_table`: the row's PTX entry over the row's
/// arguments, neighbors visited through the device's grid.
macro_rules! gpu_passes {
    (
        passes { $($(#[$doc:meta])* $name:ident $(<$($g:ident: $bound:path),+>)? ($args:ty) => $pass:expr, [$($part:expr),+];)* }
        reductions { $($(#[$rdoc:meta])* $rname:ident ($rargs:ty) => $rpass:expr, $range:expr, $which:ident, [$($rpart:expr),+];)* }
    ) => {
        impl<R: Real, T: Topology, N: DeviceNeighbors<T>> Passes<R, T, N> for GpuPasses<'_> {
            $(fn $name $(<$($g: $bound),+>)? (&mut self, args: $args) {
                self.run(entry::<R>([$($part),+]), args);
            })*
            $(fn $rname(&mut self, args: $rargs, partial: ViewMut<'_, [f64; 2]>) -> [f64; 2] {
                self.reduce(entry::<R>([$($rpart),+]), args, partial, Reduction::$which)
            })*
        }
    };
}

pass_table!(gpu_passes);

/// How a device's passes visit neighbors: through its sorted grid, which is all its PTX
/// entries take.
pub(super) trait DeviceNeighbors<T: Topology>: Neighbors {}

impl<T: Topology> DeviceNeighbors<T> for Neighborhood<'static, T> {}

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
