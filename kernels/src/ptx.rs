//! PTX entry points: one thread per particle (or cell, or scan chunk), each calling the same
//! function the CPU backend runs. Names carry the precision and, where there is one, the
//! physics variant and topology, so the host picks the kernel of its run once.
//!
//! Per-particle kernels read the particle count from device memory (`count`), because the
//! sort drops particles that left the domain on the device: the host launches enough threads
//! for an upper bound and never waits for the count inside a step.
//!
//! Off the device the same entries compile to plain functions of a thread index and their
//! parameters' bytes, listed by name by [`for_each_entry`]: the host's emulated device
//! (`coil::cuda::Gpu::emulated`) launches them, so the CUDA backend's host side, every launch,
//! argument and buffer of it, runs and is tested where no GPU is.

use crate::acceleration::{acceleration_pass, AccelerationArgs};
use crate::cell_grid::{hash_pass, HashArgs, Neighborhood};
use crate::continuity_molteni2009::{continuity_pass, density_integration_pass, ContinuityArgs, DensityIntegrationArgs};
use crate::counting_sort::{
    chunk_total, count_particle, reorder_pass, scan_chunk, scan_chunk_in_place, scan_chunk_offsets, scatter, sort_bucket,
    sum_chunk, Counters, ReorderArgs,
};
use crate::cross_viscosity::{Cross, Newtonian};
use crate::density::{continuity_floor_pass, density_pass, DensityArgs, Poly6, Spiky};
use crate::dfsph_bender2017::{
    density_error_pass, density_rate_pass, divergence_error_pass, error_sum_pass, factor_pass, pressure_change_pass,
    warm_start_pass, DensityErrorArgs, DensityRateArgs, DivergenceErrorArgs, ErrorSumArgs, FactorArgs, PressureChangeArgs,
    WarmStartArgs,
};
use crate::diagnostics::{diagnostics_pass, DiagnosticsArgs, StateFigures};
use crate::fluid_cells::{holds_fluid_pass, near_fluid_pass, HoldsFluidArgs, NearFluidArgs};
use crate::leapfrog::{leapfrog_pass, LeapfrogArgs};
use crate::mirrored_wall::{mirrored_wall_pass, MirroredWallArgs};
use crate::nozzle::{nozzle_pass, nozzle_shift_pass, NozzleArgs, NozzleShiftArgs};
use crate::renormalization_bonet1999::Renormalized;
use crate::shifting_sun2017::{shift_pass, shifting_pass, ShiftArgs, ShiftingArgs};
use crate::topology::{Open, Periodic};
use crate::velocity_gradient::{KernelSum, OwnDensity};
use crate::view::{View, ViewMut};
use crate::viscosity::hourglass_ganzenmuller2015::{velocity_gradient_pass, HourglassControlledStress, VelocityGradientArgs};
use crate::viscosity::implicit_weiler2018::{
    cg_direction_pass, cg_start_pass, cg_step_pass, dot_pass, implicit_stress_pass, lagged_viscosity_pass, predictor_pass,
    system_block_pass, system_product_pass, viscous_acceleration_pass, CgDirectionArgs, CgStartArgs, CgStepArgs, DotArgs,
    ImplicitStressArgs, LaggedViscosityArgs, PredictorArgs, PressureAndGravity, SystemBlockArgs, SystemProductArgs,
    ViscousAccelerationArgs,
};
use crate::viscosity::laplacian_morris1997::{
    morris_system_block_pass, morris_system_product_pass, MorrisSystemBlockArgs, MorrisSystemProductArgs, MorrisViscosity,
};
use crate::viscosity::laplacian_morris1997::{shear_viscosity_pass, ShearViscosityArgs};
use crate::viscosity::laplacian_muller2003::VelocityLaplacian;
use crate::viscosity::stress_andrade2014::StressDivergence;
use crate::viscosity::stress_andrade2014::{stress_pass, StressArgs};

#[cfg(target_arch = "nvptx64")]
#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    // SAFETY: `trap` aborts the kernel; the host sees a launch failure.
    unsafe { core::arch::nvptx::trap() }
}

/// The device's layouts of the kernels' argument structs (`crate::abi`), for the host to compare
/// with its own in the PTX.
#[cfg(target_arch = "nvptx64")]
#[no_mangle]
pub static COIL_LAYOUTS_F32: [u32; crate::abi::LAYOUT_WORDS] = crate::abi::layouts::<f32>();
#[cfg(target_arch = "nvptx64")]
#[no_mangle]
pub static COIL_LAYOUTS_F64: [u32; crate::abi::LAYOUT_WORDS] = crate::abi::layouts::<f64>();

/// This thread's index in a 1-D launch.
#[cfg(target_arch = "nvptx64")]
#[inline(always)]
fn thread_index() -> usize {
    use core::arch::nvptx;
    // SAFETY: reading special registers has no side effects.
    unsafe { (nvptx::_block_idx_x() as usize) * (nvptx::_block_dim_x() as usize) + nvptx::_thread_idx_x() as usize }
}

/// One parameter of an emulated launch: the address and size of the value the host passes,
/// as the driver receives a kernel's parameters.
#[cfg(not(target_arch = "nvptx64"))]
#[derive(Clone, Copy, Debug)]
pub struct Param {
    value: *const u8,
    size: usize,
}

// SAFETY: a parameter is read, never written, by every thread of its launch.
#[cfg(not(target_arch = "nvptx64"))]
unsafe impl Send for Param {}
#[cfg(not(target_arch = "nvptx64"))]
unsafe impl Sync for Param {}

#[cfg(not(target_arch = "nvptx64"))]
impl Param {
    /// The `size` bytes at `value`, as a driver receives a parameter: the entry checks the size
    /// against its parameter's type.
    ///
    /// # Safety
    /// The bytes must outlive every launch that reads the parameter.
    pub unsafe fn from_raw(value: *const u8, size: usize) -> Self {
        Self { value, size }
    }

    /// The value as the entry's parameter type, whose size it must have.
    ///
    /// # Safety
    /// The value must be a `T`, as a PTX entry trusts its parameters to be.
    unsafe fn read<T: Copy>(self, entry: &str) -> T {
        assert!(
            self.size == core::mem::size_of::<T>(),
            "{entry}: a parameter of {} bytes where the entry takes {}",
            self.size,
            core::mem::size_of::<T>()
        );
        core::ptr::read_unaligned(self.value.cast())
    }
}

/// An entry as the host runs it: one thread of a launch, given its index and the parameters.
#[cfg(not(target_arch = "nvptx64"))]
pub type Emulated = unsafe fn(usize, &[Param]);

/// A PTX entry `$name` whose thread `$i` runs `$body`: on the device an `extern "ptx-kernel"`
/// function, on the host an [`Emulated`] one that reads its parameters from their bytes.
macro_rules! entry {
    ($name:ident($i:ident; $($p:ident: $t:ty),+) $body:block) => {
        #[cfg(target_arch = "nvptx64")]
        #[no_mangle]
        // An open run's arguments hold its topology as an empty struct, which C has no word
        // for; the driver copies parameters as bytes, and tests check each entry's parameter
        // sizes against the host's structs, so the empty field costs nothing and is safe.
        #[allow(improper_ctypes_definitions)]
        pub unsafe extern "ptx-kernel" fn $name($($p: $t),+) {
            let $i = thread_index();
            $body
        }

        /// The entry's thread `i` on the host.
        ///
        /// # Safety
        /// `params` must be the entry's parameters, and every view in them must cover live
        /// memory of the length it claims, as on the device.
        #[cfg(not(target_arch = "nvptx64"))]
        pub unsafe fn $name($i: usize, params: &[Param]) {
            let expected = [$(stringify!($p)),+].len();
            assert!(params.len() == expected, "{}: {} parameters where the entry takes {expected}", stringify!($name), params.len());
            let mut params = params.iter();
            $(let $p: $t = params.next().expect("counted").read(stringify!($name));)+
            $body
        }
    };
}

macro_rules! per_index_kernel {
    ($name:ident, $args:ty, $pass:expr) => {
        entry!($name(i; count: View<'static, u32>, args: $args) {
            if i < count.at(0) as usize {
                $pass(i, &args);
            }
        });
    };
}

/// A pass's entries for an open and for a periodic domain: `$args<'static, .., T>` run by
/// `$pass::<.., T>`, the topology last in both.
macro_rules! per_topology_kernels {
    ($open:ident, $periodic:ident, $args:ident<$($a:ty),+>, $pass:ident<$($p:ty),+>) => {
        per_index_kernel!($open, $args<'static, $($a),+, Open>, $pass::<$($p),+, Open>);
        per_index_kernel!($periodic, $args<'static, $($a),+, Periodic>, $pass::<$($p),+, Periodic>);
    };
}

/// A neighbor pass's entries for an open and for a periodic domain, visiting neighbors through
/// the grid (`Neighborhood<'static, T>` last in both).
macro_rules! per_neighborhood_kernels {
    ($open:ident, $periodic:ident, $args:ident<$($a:ty),+>, $pass:ident<$($p:ty),+>) => {
        per_index_kernel!(
            $open,
            $args<'static, $($a),+, Neighborhood<'static, Open>>,
            $pass::<$($p),+, Neighborhood<'static, Open>>
        );
        per_index_kernel!(
            $periodic,
            $args<'static, $($a),+, Neighborhood<'static, Periodic>>,
            $pass::<$($p),+, Neighborhood<'static, Periodic>>
        );
    };
}

/// One thread per range of `DOT_RANGE` particles; ranges past the live count write zeros.
macro_rules! dots_kernel {
    ($name:ident, $t:ty) => {
        entry!($name(r; count: View<'static, u32>, args: DotArgs<'static, $t>, out: ViewMut<'static, [f64; 2]>) {
            if r < out.len() {
                dot_pass(r, count.at(0) as usize, &args, out);
            }
        });
    };
}

/// One thread per range of `ERROR_RANGE` particles; ranges past the live count write zeros.
macro_rules! error_sums_kernel {
    ($name:ident, $t:ty) => {
        entry!($name(r; count: View<'static, u32>, args: ErrorSumArgs<'static, $t>, out: ViewMut<'static, [f64; 2]>) {
            if r < out.len() {
                error_sum_pass(r, count.at(0) as usize, &args, out);
            }
        });
    };
}

/// Copies `added` staged inlet particles' values behind the `count` live ones.
macro_rules! append_kernel {
    ($name:ident, $t:ty) => {
        entry!($name(j; count: View<'static, u32>, added: u32, staged: View<'static, $t>, field: ViewMut<'static, $t>) {
            if j < added as usize {
                field.write(count.at(0) as usize + j, staged.at(j));
            }
        });
    };
}

macro_rules! diagnostics_kernel {
    ($name:ident, $t:ty) => {
        entry!($name(r;
            count: View<'static, u32>,
            range_len: u32,
            args: DiagnosticsArgs<'static, $t>,
            out: ViewMut<'static, StateFigures>
        ) {
            let n = count.at(0) as usize;
            if r * (range_len as usize) < n {
                diagnostics_pass(r, range_len as usize, n, &args, out);
            }
        });
    };
}

/// Declares every entry of its input (invocations of the entry macros above), and
/// [`for_each_entry`] over their names: one list of the entries for the device and the host's
/// emulated device alike.
macro_rules! entries {
    ($($kind:ident!($($input:tt)*);)*) => {
        $($kind!($($input)*);)*

        /// Calls `f` with every entry's PTX name and host build, for the host's emulated device.
        #[cfg(not(target_arch = "nvptx64"))]
        pub fn for_each_entry(mut f: impl FnMut(&'static str, Emulated)) {
            $(entry_names!(f, $kind, $($input)*);)*
        }
    };
}

/// Hands `$f` the entries one invocation of an entry macro declares: a pass's two (open and
/// periodic) where the macro makes both, else the one its input names first.
#[cfg(not(target_arch = "nvptx64"))]
macro_rules! entry_names {
    ($f:ident, per_topology_kernels, $open:ident, $periodic:ident, $($rest:tt)*) => {
        $f(stringify!($open), $open as Emulated);
        $f(stringify!($periodic), $periodic as Emulated);
    };
    ($f:ident, per_neighborhood_kernels, $open:ident, $periodic:ident, $($rest:tt)*) => {
        $f(stringify!($open), $open as Emulated);
        $f(stringify!($periodic), $periodic as Emulated);
    };
    ($f:ident, $kind:ident, $name:ident $($rest:tt)*) => {
        $f(stringify!($name), $name as Emulated);
    };
}

entries! {
    per_index_kernel!(hash, HashArgs<'static>, hash_pass);
    per_neighborhood_kernels!(density_f32, density_periodic_f32, DensityArgs<f32>, density_pass<f32, Poly6>);
    per_neighborhood_kernels!(density_f64, density_periodic_f64, DensityArgs<f64>, density_pass<f64, Poly6>);
    per_neighborhood_kernels!(density_spiky_f32, density_spiky_periodic_f32, DensityArgs<f32>, density_pass<f32, Spiky>);
    per_neighborhood_kernels!(density_spiky_f64, density_spiky_periodic_f64, DensityArgs<f64>, density_pass<f64, Spiky>);
    per_neighborhood_kernels!(
        continuity_floor_spiky_f32,
        continuity_floor_spiky_periodic_f32,
        DensityArgs<f32>,
        continuity_floor_pass<f32, Spiky>
    );
    per_neighborhood_kernels!(
        continuity_floor_spiky_f64,
        continuity_floor_spiky_periodic_f64,
        DensityArgs<f64>,
        continuity_floor_pass<f64, Spiky>
    );
    per_neighborhood_kernels!(continuity_f32, continuity_periodic_f32, ContinuityArgs<f32>, continuity_pass<f32, Poly6>);
    per_neighborhood_kernels!(continuity_f64, continuity_periodic_f64, ContinuityArgs<f64>, continuity_pass<f64, Poly6>);
    per_neighborhood_kernels!(
        continuity_spiky_f32,
        continuity_spiky_periodic_f32,
        ContinuityArgs<f32>,
        continuity_pass<f32, Spiky>
    );
    per_neighborhood_kernels!(
        continuity_spiky_f64,
        continuity_spiky_periodic_f64,
        ContinuityArgs<f64>,
        continuity_pass<f64, Spiky>
    );
    per_topology_kernels!(mirrored_wall_f32, mirrored_wall_periodic_f32, MirroredWallArgs<f32>, mirrored_wall_pass<f32>);
    per_topology_kernels!(mirrored_wall_f64, mirrored_wall_periodic_f64, MirroredWallArgs<f64>, mirrored_wall_pass<f64>);
    per_neighborhood_kernels!(
        stress_newtonian_f32,
        stress_newtonian_periodic_f32,
        StressArgs<f32, Newtonian<f32>, KernelSum>,
        stress_pass<f32, Newtonian<f32>, KernelSum>
    );
    per_neighborhood_kernels!(
        stress_newtonian_f64,
        stress_newtonian_periodic_f64,
        StressArgs<f64, Newtonian<f64>, KernelSum>,
        stress_pass<f64, Newtonian<f64>, KernelSum>
    );
    per_neighborhood_kernels!(
        stress_cross_f32,
        stress_cross_periodic_f32,
        StressArgs<f32, Cross<f32>, KernelSum>,
        stress_pass<f32, Cross<f32>, KernelSum>
    );
    per_neighborhood_kernels!(
        stress_cross_f64,
        stress_cross_periodic_f64,
        StressArgs<f64, Cross<f64>, KernelSum>,
        stress_pass<f64, Cross<f64>, KernelSum>
    );
    per_neighborhood_kernels!(
        stress_newtonian_renormalized_f32,
        stress_newtonian_renormalized_periodic_f32,
        StressArgs<f32, Newtonian<f32>, Renormalized>,
        stress_pass<f32, Newtonian<f32>, Renormalized>
    );
    per_neighborhood_kernels!(
        stress_newtonian_renormalized_f64,
        stress_newtonian_renormalized_periodic_f64,
        StressArgs<f64, Newtonian<f64>, Renormalized>,
        stress_pass<f64, Newtonian<f64>, Renormalized>
    );
    per_neighborhood_kernels!(
        stress_cross_renormalized_f32,
        stress_cross_renormalized_periodic_f32,
        StressArgs<f32, Cross<f32>, Renormalized>,
        stress_pass<f32, Cross<f32>, Renormalized>
    );
    per_neighborhood_kernels!(
        stress_cross_renormalized_f64,
        stress_cross_renormalized_periodic_f64,
        StressArgs<f64, Cross<f64>, Renormalized>,
        stress_pass<f64, Cross<f64>, Renormalized>
    );
    per_neighborhood_kernels!(
        stress_newtonian_own_density_f32,
        stress_newtonian_own_density_periodic_f32,
        StressArgs<f32, Newtonian<f32>, OwnDensity>,
        stress_pass<f32, Newtonian<f32>, OwnDensity>
    );
    per_neighborhood_kernels!(
        stress_newtonian_own_density_f64,
        stress_newtonian_own_density_periodic_f64,
        StressArgs<f64, Newtonian<f64>, OwnDensity>,
        stress_pass<f64, Newtonian<f64>, OwnDensity>
    );
    per_neighborhood_kernels!(
        stress_cross_own_density_f32,
        stress_cross_own_density_periodic_f32,
        StressArgs<f32, Cross<f32>, OwnDensity>,
        stress_pass<f32, Cross<f32>, OwnDensity>
    );
    per_neighborhood_kernels!(
        stress_cross_own_density_f64,
        stress_cross_own_density_periodic_f64,
        StressArgs<f64, Cross<f64>, OwnDensity>,
        stress_pass<f64, Cross<f64>, OwnDensity>
    );
    per_neighborhood_kernels!(
        acceleration_stress_f32,
        acceleration_stress_periodic_f32,
        AccelerationArgs<f32, StressDivergence<'static, f32>>,
        acceleration_pass<f32, StressDivergence<'static, f32>>
    );
    per_neighborhood_kernels!(
        acceleration_stress_f64,
        acceleration_stress_periodic_f64,
        AccelerationArgs<f64, StressDivergence<'static, f64>>,
        acceleration_pass<f64, StressDivergence<'static, f64>>
    );
    per_neighborhood_kernels!(
        acceleration_laplacian_f32,
        acceleration_laplacian_periodic_f32,
        AccelerationArgs<f32, VelocityLaplacian<'static, f32>>,
        acceleration_pass<f32, VelocityLaplacian<'static, f32>>
    );
    per_neighborhood_kernels!(
        acceleration_laplacian_f64,
        acceleration_laplacian_periodic_f64,
        AccelerationArgs<f64, VelocityLaplacian<'static, f64>>,
        acceleration_pass<f64, VelocityLaplacian<'static, f64>>
    );
    per_neighborhood_kernels!(
        shear_viscosity_cross_f32,
        shear_viscosity_cross_periodic_f32,
        ShearViscosityArgs<f32, Cross<f32>>,
        shear_viscosity_pass<f32, Cross<f32>>
    );
    per_neighborhood_kernels!(
        shear_viscosity_cross_f64,
        shear_viscosity_cross_periodic_f64,
        ShearViscosityArgs<f64, Cross<f64>>,
        shear_viscosity_pass<f64, Cross<f64>>
    );
    per_neighborhood_kernels!(
        acceleration_morris_f32,
        acceleration_morris_periodic_f32,
        AccelerationArgs<f32, MorrisViscosity<'static, f32, Newtonian<f32>>>,
        acceleration_pass<f32, MorrisViscosity<'static, f32, Newtonian<f32>>>
    );
    per_neighborhood_kernels!(
        acceleration_morris_f64,
        acceleration_morris_periodic_f64,
        AccelerationArgs<f64, MorrisViscosity<'static, f64, Newtonian<f64>>>,
        acceleration_pass<f64, MorrisViscosity<'static, f64, Newtonian<f64>>>
    );
    per_neighborhood_kernels!(
        acceleration_morris_shear_f32,
        acceleration_morris_shear_periodic_f32,
        AccelerationArgs<f32, MorrisViscosity<'static, f32, View<'static, f32>>>,
        acceleration_pass<f32, MorrisViscosity<'static, f32, View<'static, f32>>>
    );
    per_neighborhood_kernels!(
        acceleration_morris_shear_f64,
        acceleration_morris_shear_periodic_f64,
        AccelerationArgs<f64, MorrisViscosity<'static, f64, View<'static, f64>>>,
        acceleration_pass<f64, MorrisViscosity<'static, f64, View<'static, f64>>>
    );
    per_neighborhood_kernels!(
        velocity_gradient_newtonian_f32,
        velocity_gradient_newtonian_periodic_f32,
        VelocityGradientArgs<f32, Newtonian<f32>>,
        velocity_gradient_pass<f32, Newtonian<f32>>
    );
    per_neighborhood_kernels!(
        velocity_gradient_newtonian_f64,
        velocity_gradient_newtonian_periodic_f64,
        VelocityGradientArgs<f64, Newtonian<f64>>,
        velocity_gradient_pass<f64, Newtonian<f64>>
    );
    per_neighborhood_kernels!(
        velocity_gradient_cross_f32,
        velocity_gradient_cross_periodic_f32,
        VelocityGradientArgs<f32, Cross<f32>>,
        velocity_gradient_pass<f32, Cross<f32>>
    );
    per_neighborhood_kernels!(
        velocity_gradient_cross_f64,
        velocity_gradient_cross_periodic_f64,
        VelocityGradientArgs<f64, Cross<f64>>,
        velocity_gradient_pass<f64, Cross<f64>>
    );
    per_neighborhood_kernels!(
        acceleration_hourglass_f32,
        acceleration_hourglass_periodic_f32,
        AccelerationArgs<f32, HourglassControlledStress<'static, f32>>,
        acceleration_pass<f32, HourglassControlledStress<'static, f32>>
    );
    per_neighborhood_kernels!(
        acceleration_hourglass_f64,
        acceleration_hourglass_periodic_f64,
        AccelerationArgs<f64, HourglassControlledStress<'static, f64>>,
        acceleration_pass<f64, HourglassControlledStress<'static, f64>>
    );
    per_index_kernel!(nozzle_f32, NozzleArgs<'static, f32>, nozzle_pass::<f32>);
    per_index_kernel!(nozzle_f64, NozzleArgs<'static, f64>, nozzle_pass::<f64>);
    per_index_kernel!(nozzle_shift_f32, NozzleShiftArgs<'static, f32>, nozzle_shift_pass::<f32>);
    per_index_kernel!(nozzle_shift_f64, NozzleShiftArgs<'static, f64>, nozzle_shift_pass::<f64>);
    per_index_kernel!(density_integration_f32, DensityIntegrationArgs<'static, f32>, density_integration_pass::<f32>);
    per_index_kernel!(density_integration_f64, DensityIntegrationArgs<'static, f64>, density_integration_pass::<f64>);
    per_neighborhood_kernels!(
        acceleration_pressure_f32,
        acceleration_pressure_periodic_f32,
        AccelerationArgs<f32, PressureAndGravity>,
        acceleration_pass<f32, PressureAndGravity>
    );
    per_neighborhood_kernels!(
        acceleration_pressure_f64,
        acceleration_pressure_periodic_f64,
        AccelerationArgs<f64, PressureAndGravity>,
        acceleration_pass<f64, PressureAndGravity>
    );
    per_index_kernel!(predictor_f32, PredictorArgs<'static, f32>, predictor_pass::<f32>);
    per_index_kernel!(predictor_f64, PredictorArgs<'static, f64>, predictor_pass::<f64>);
    per_neighborhood_kernels!(
        lagged_viscosity_newtonian_f32,
        lagged_viscosity_newtonian_periodic_f32,
        LaggedViscosityArgs<f32, Newtonian<f32>>,
        lagged_viscosity_pass<f32, Newtonian<f32>>
    );
    per_neighborhood_kernels!(
        lagged_viscosity_newtonian_f64,
        lagged_viscosity_newtonian_periodic_f64,
        LaggedViscosityArgs<f64, Newtonian<f64>>,
        lagged_viscosity_pass<f64, Newtonian<f64>>
    );
    per_neighborhood_kernels!(
        lagged_viscosity_cross_f32,
        lagged_viscosity_cross_periodic_f32,
        LaggedViscosityArgs<f32, Cross<f32>>,
        lagged_viscosity_pass<f32, Cross<f32>>
    );
    per_neighborhood_kernels!(
        lagged_viscosity_cross_f64,
        lagged_viscosity_cross_periodic_f64,
        LaggedViscosityArgs<f64, Cross<f64>>,
        lagged_viscosity_pass<f64, Cross<f64>>
    );
    per_neighborhood_kernels!(implicit_stress_f32, implicit_stress_periodic_f32, ImplicitStressArgs<f32>, implicit_stress_pass<f32>);
    per_neighborhood_kernels!(implicit_stress_f64, implicit_stress_periodic_f64, ImplicitStressArgs<f64>, implicit_stress_pass<f64>);
    per_neighborhood_kernels!(system_block_f32, system_block_periodic_f32, SystemBlockArgs<f32>, system_block_pass<f32>);
    per_neighborhood_kernels!(system_block_f64, system_block_periodic_f64, SystemBlockArgs<f64>, system_block_pass<f64>);
    per_neighborhood_kernels!(system_product_f32, system_product_periodic_f32, SystemProductArgs<f32>, system_product_pass<f32>);
    per_neighborhood_kernels!(system_product_f64, system_product_periodic_f64, SystemProductArgs<f64>, system_product_pass<f64>);
    per_neighborhood_kernels!(
        system_block_morris_f32,
        system_block_morris_periodic_f32,
        MorrisSystemBlockArgs<f32, Newtonian<f32>>,
        morris_system_block_pass<f32, Newtonian<f32>>
    );
    per_neighborhood_kernels!(
        system_block_morris_f64,
        system_block_morris_periodic_f64,
        MorrisSystemBlockArgs<f64, Newtonian<f64>>,
        morris_system_block_pass<f64, Newtonian<f64>>
    );
    per_neighborhood_kernels!(
        system_block_morris_shear_f32,
        system_block_morris_shear_periodic_f32,
        MorrisSystemBlockArgs<f32, View<'static, f32>>,
        morris_system_block_pass<f32, View<'static, f32>>
    );
    per_neighborhood_kernels!(
        system_block_morris_shear_f64,
        system_block_morris_shear_periodic_f64,
        MorrisSystemBlockArgs<f64, View<'static, f64>>,
        morris_system_block_pass<f64, View<'static, f64>>
    );
    per_neighborhood_kernels!(
        system_product_morris_f32,
        system_product_morris_periodic_f32,
        MorrisSystemProductArgs<f32, Newtonian<f32>>,
        morris_system_product_pass<f32, Newtonian<f32>>
    );
    per_neighborhood_kernels!(
        system_product_morris_f64,
        system_product_morris_periodic_f64,
        MorrisSystemProductArgs<f64, Newtonian<f64>>,
        morris_system_product_pass<f64, Newtonian<f64>>
    );
    per_neighborhood_kernels!(
        system_product_morris_shear_f32,
        system_product_morris_shear_periodic_f32,
        MorrisSystemProductArgs<f32, View<'static, f32>>,
        morris_system_product_pass<f32, View<'static, f32>>
    );
    per_neighborhood_kernels!(
        system_product_morris_shear_f64,
        system_product_morris_shear_periodic_f64,
        MorrisSystemProductArgs<f64, View<'static, f64>>,
        morris_system_product_pass<f64, View<'static, f64>>
    );
    per_index_kernel!(cg_start_f32, CgStartArgs<'static, f32>, cg_start_pass::<f32>);
    per_index_kernel!(cg_start_f64, CgStartArgs<'static, f64>, cg_start_pass::<f64>);
    per_index_kernel!(cg_step_f32, CgStepArgs<'static, f32>, cg_step_pass::<f32>);
    per_index_kernel!(cg_step_f64, CgStepArgs<'static, f64>, cg_step_pass::<f64>);
    per_index_kernel!(cg_direction_f32, CgDirectionArgs<'static, f32>, cg_direction_pass::<f32>);
    per_index_kernel!(cg_direction_f64, CgDirectionArgs<'static, f64>, cg_direction_pass::<f64>);
    per_index_kernel!(viscous_acceleration_f32, ViscousAccelerationArgs<'static, f32>, viscous_acceleration_pass::<f32>);
    per_index_kernel!(viscous_acceleration_f64, ViscousAccelerationArgs<'static, f64>, viscous_acceleration_pass::<f64>);
    dots_kernel!(dots_f32, f32);
    dots_kernel!(dots_f64, f64);
    per_neighborhood_kernels!(dfsph_factor_f32, dfsph_factor_periodic_f32, FactorArgs<f32>, factor_pass<f32>);
    per_neighborhood_kernels!(dfsph_factor_f64, dfsph_factor_periodic_f64, FactorArgs<f64>, factor_pass<f64>);
    per_neighborhood_kernels!(
        divergence_error_f32,
        divergence_error_periodic_f32,
        DivergenceErrorArgs<f32>,
        divergence_error_pass<f32>
    );
    per_neighborhood_kernels!(
        divergence_error_f64,
        divergence_error_periodic_f64,
        DivergenceErrorArgs<f64>,
        divergence_error_pass<f64>
    );
    per_neighborhood_kernels!(density_error_f32, density_error_periodic_f32, DensityErrorArgs<f32>, density_error_pass<f32>);
    per_neighborhood_kernels!(density_error_f64, density_error_periodic_f64, DensityErrorArgs<f64>, density_error_pass<f64>);
    per_neighborhood_kernels!(dfsph_density_rate_f32, dfsph_density_rate_periodic_f32, DensityRateArgs<f32>, density_rate_pass<f32>);
    per_neighborhood_kernels!(dfsph_density_rate_f64, dfsph_density_rate_periodic_f64, DensityRateArgs<f64>, density_rate_pass<f64>);
    per_neighborhood_kernels!(pressure_change_f32, pressure_change_periodic_f32, PressureChangeArgs<f32>, pressure_change_pass<f32>);
    per_neighborhood_kernels!(pressure_change_f64, pressure_change_periodic_f64, PressureChangeArgs<f64>, pressure_change_pass<f64>);
    per_index_kernel!(warm_start_f32, WarmStartArgs<'static, f32>, warm_start_pass::<f32>);
    per_index_kernel!(warm_start_f64, WarmStartArgs<'static, f64>, warm_start_pass::<f64>);
    error_sums_kernel!(error_sums_f32, f32);
    error_sums_kernel!(error_sums_f64, f64);
    per_topology_kernels!(leapfrog_f32, leapfrog_periodic_f32, LeapfrogArgs<f32>, leapfrog_pass<f32>);
    per_topology_kernels!(leapfrog_f64, leapfrog_periodic_f64, LeapfrogArgs<f64>, leapfrog_pass<f64>);
    per_neighborhood_kernels!(shifting_f32, shifting_periodic_f32, ShiftingArgs<f32>, shifting_pass<f32>);
    per_neighborhood_kernels!(shifting_f64, shifting_periodic_f64, ShiftingArgs<f64>, shifting_pass<f64>);
    per_topology_kernels!(shift_f32, shift_periodic_f32, ShiftArgs<f32>, shift_pass<f32>);
    per_topology_kernels!(shift_f64, shift_periodic_f64, ShiftArgs<f64>, shift_pass<f64>);
    entry!(count_particles(i; count: View<'static, u32>, cell_key: View<'static, u32>, counts: Counters<'static>) {
        if i < count.at(0) as usize {
            count_particle(i, cell_key, counts);
        }
    });
    entry!(scan_chunk_totals(c; chunks: u32, chunk_len: u32, counts: Counters<'static>, totals: ViewMut<'static, u32>) {
        if c < chunks as usize {
            totals.write(c, chunk_total(c, chunk_len as usize, counts));
        }
    });
    entry!(scan_offsets(t; totals: ViewMut<'static, u32>) {
        if t == 0 {
            scan_chunk_offsets(totals);
        }
    });
    entry!(scan_sum_chunks(c; chunks: u32, values: View<'static, u32>, sums: ViewMut<'static, u32>) {
        if c < chunks as usize {
            sums.write(c, sum_chunk(c, values));
        }
    });
    entry!(scan_chunks_in_place(c; chunks: u32, offsets: View<'static, u32>, values: ViewMut<'static, u32>) {
        if c < chunks as usize {
            scan_chunk_in_place(c, offsets.at(c), values);
        }
    });
    entry!(scan_chunks(c;
        chunks: u32,
        chunk_len: u32,
        chunk_offsets: View<'static, u32>,
        counts: Counters<'static>,
        bucket_start: ViewMut<'static, u32>
    ) {
        if c < chunks as usize {
            scan_chunk(c, chunk_len as usize, chunk_offsets.at(c), counts, bucket_start);
        }
    });
    entry!(scatter_particles(i; count: View<'static, u32>, cell_key: View<'static, u32>, cursor: Counters<'static>, order: ViewMut<'static, u32>) {
        if i < count.at(0) as usize {
            scatter(i, cell_key, cursor, order);
        }
    });
    entry!(sort_buckets(c; buckets: u32, bucket_start: View<'static, u32>, order: ViewMut<'static, u32>) {
        if c < buckets as usize {
            sort_bucket(c, bucket_start, order);
        }
    });
    entry!(holds_fluid(c; cells: u32, args: HoldsFluidArgs<'static>) {
        if c < cells as usize {
            holds_fluid_pass(c, &args);
        }
    });
    entry!(near_fluid(c; cells: u32, args: NearFluidArgs<'static, Open>) {
        if c < cells as usize {
            near_fluid_pass(c, &args);
        }
    });
    entry!(near_fluid_periodic(c; cells: u32, args: NearFluidArgs<'static, Periodic>) {
        if c < cells as usize {
            near_fluid_pass(c, &args);
        }
    });
    per_index_kernel!(reorder_f32, ReorderArgs<'static, f32>, reorder_pass);
    per_index_kernel!(reorder_f64, ReorderArgs<'static, f64>, reorder_pass);
    // After the sort: the live count is the start of the bucket of particles outside the domain.
    entry!(set_count(t; count: ViewMut<'static, u32>, bucket_start: View<'static, u32>, cells: u32) {
        if t == 0 {
            count.write(0, bucket_start.at(cells as usize));
        }
    });
    // After new inlet particles were appended behind the live ones.
    entry!(grow_count(t; count: ViewMut<'static, u32>, added: u32) {
        if t == 0 {
            count.write(0, count.at(0) + added);
        }
    });
    append_kernel!(append_u32, u32);
    append_kernel!(append_f32, f32);
    append_kernel!(append_f64, f64);
    diagnostics_kernel!(diagnostics_f32, f32);
    diagnostics_kernel!(diagnostics_f64, f64);
}

/// The host build of the entry named `name`, for the host's emulated device.
#[cfg(not(target_arch = "nvptx64"))]
pub fn find_entry(name: &str) -> Option<Emulated> {
    let mut found = None;
    for_each_entry(|n, entry| {
        if n == name {
            found = Some(entry);
        }
    });
    found
}
