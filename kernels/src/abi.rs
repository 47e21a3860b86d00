//! The layout of every struct a kernel takes by value: its size, its alignment, then each of its
//! fields' offsets, in bytes, as the compiler that builds this crate lays them out for its target.
//!
//! The host (stable rustc, x86-64 or aarch64) fills these structs and the driver copies their
//! bytes to the kernels (the pinned nightly, nvptx64), which read them field by field: the two
//! compilers must agree on every offset, not only on the size. The structs are `repr(C)`, so
//! they should; the device build exports its table (`COIL_LAYOUTS_F32`, `COIL_LAYOUTS_F64` in
//! the PTX) and the host's tests compare it with this one, where no GPU is needed. Nested
//! structs have entries of their own, so an offset inside one is checked where it is declared.

use crate::acceleration::AccelerationArgs;
use crate::cell_grid::{CellGrid, HashArgs, Neighborhood};
use crate::continuity_molteni2009::{ContinuityArgs, DensityIntegrationArgs};
use crate::counting_sort::{Counters, Gathered, ReorderArgs};
use crate::cross_viscosity::{Cross, Newtonian};
use crate::density::DensityArgs;
use crate::dfsph_bender2017::{
    DensityErrorArgs, DensityRateArgs, DivergenceErrorArgs, ErrorSumArgs, FactorArgs, PressureChangeArgs, Sweep, WarmStartArgs,
};
use crate::diagnostics::{DiagnosticsArgs, StateFigures};
use crate::fluid::Fluid;
use crate::fluid_cells::{HoldsFluidArgs, NearFluidArgs};
use crate::leapfrog::LeapfrogArgs;
use crate::mirrored_wall::MirroredWallArgs;
use crate::nozzle::{NozzleArgs, NozzleShiftArgs, NozzleTube};
use crate::real::Real;
use crate::shifting_sun2017::{ShiftArgs, Shifting, ShiftingArgs};
use crate::smoothing::SmoothingKernels;
use crate::topology::{Open, Periodic};
use crate::vec3::{SymTensor, Vec3};
use crate::velocity_gradient::KernelSum;
use crate::view::{Mat3View, Mat3ViewMut, SymTensorView, SymTensorViewMut, Vec3View, Vec3ViewMut, View, ViewMut};
use crate::viscosity::hourglass_ganzenmuller2015::{HourglassControlledStress, VelocityGradientArgs};
use crate::viscosity::implicit_weiler2018::{
    CgDirectionArgs, CgStartArgs, CgStepArgs, DotArgs, ImplicitStressArgs, LaggedViscosityArgs, PredictorArgs,
    PressureAndGravity, SystemBlockArgs, SystemProductArgs, ViscousAccelerationArgs,
};
use crate::viscosity::laplacian_morris1997::{
    MorrisSystemBlockArgs, MorrisSystemProductArgs, MorrisViscosity, ShearViscosityArgs,
};
use crate::viscosity::laplacian_muller2003::VelocityLaplacian;
use crate::viscosity::stress_andrade2014::{StressArgs, StressDivergence};

/// `layouts::<R>()`: for each listed struct in order, its size, alignment and field offsets;
/// `LAYOUT_WORDS` long. On the host also `LAYOUT_NAMES`, each struct's name and fields.
macro_rules! layouts {
    ($R:ident; $($t:ty { $($f:ident),* })*) => {
        /// Words in a layout table.
        pub const LAYOUT_WORDS: usize = 0 $(+ 2 + <[&str]>::len(&[$(stringify!($f)),*]))*;

        /// Size, alignment and each field's offset (bytes) of every struct a kernel takes, at
        /// precision `R`, in the order of [`LAYOUT_NAMES`].
        pub const fn layouts<$R: Real>() -> [u32; LAYOUT_WORDS] {
            let mut out = [0u32; LAYOUT_WORDS];
            let mut k = 0;
            $(
                out[k] = core::mem::size_of::<$t>() as u32;
                out[k + 1] = core::mem::align_of::<$t>() as u32;
                k += 2;
                $(
                    out[k] = core::mem::offset_of!($t, $f) as u32;
                    k += 1;
                )*
            )*
            assert!(k == LAYOUT_WORDS);
            out
        }

        /// Each struct of [`layouts`] (as written with `R`, `O` the open neighborhood and `P`
        /// the periodic one) and its fields.
        #[cfg(not(target_arch = "nvptx64"))]
        pub const LAYOUT_NAMES: &[(&str, &[&str])] = &[$((stringify!($t), &[$(stringify!($f)),*])),*];
    };
}

type O = Neighborhood<'static, Open>;
type P = Neighborhood<'static, Periodic>;

layouts!(R;
    Open {}
    Periodic { origin, period }
    CellGrid { origin, inverse_cell_size, dims }
    View<'static, R> { ptr, len }
    ViewMut<'static, R> { ptr, len }
    Vec3View<'static, R> { x, y, z }
    Vec3ViewMut<'static, R> { x, y, z }
    SymTensorView<'static, R> { xx, yy, zz, xy, xz, yz }
    SymTensorViewMut<'static, R> { xx, yy, zz, xy, xz, yz }
    Mat3View<'static, R> { rows }
    Mat3ViewMut<'static, R> { rows }
    Counters<'static> { ptr, len }
    Gathered<'static, R> { unsorted, sorted }
    Gathered<'static, f64> { unsorted, sorted }
    Gathered<'static, u32> { unsorted, sorted }
    ReorderArgs<'static, R> { order, wide, first, second, index }
    O { grid, cell_start, position, topology, near_fluid }
    P { grid, cell_start, position, topology, near_fluid }
    Vec3<R> { x, y, z }
    SymTensor<R> { xx, yy, zz, xy, xz, yz }
    SmoothingKernels<R> {
        h, h2, poly6_coefficient, spiky_coefficient, spiky_gradient_coefficient, viscosity_laplacian_coefficient,
        morris_laplacian_coefficient
    }
    Fluid<R> {
        mass, rest_density, sound_speed2, pressure_floor, wall_density_floor, pressure_pair_weight, wall_stiffness_share, gravity, kernels,
        boundary_count
    }
    Sweep<R> { relaxation, momentum }
    Newtonian<R> { nu0 }
    Cross<R> { nu0, nu_inf, k, n }
    NozzleTube<R> { exit, axis, across, half_extent, round, length, velocity }
    Shifting<R> { coefficient, inverse_spacing_weight, surface_divergence }
    StateFigures { max_speed, max_compression, bad_particles }
    StressDivergence<'static, R> { stress }
    VelocityLaplacian<'static, R> { mu0, velocity }
    MorrisViscosity<'static, R, Newtonian<R>> { velocity, viscosity }
    MorrisViscosity<'static, R, View<'static, R>> { velocity, viscosity }
    HourglassControlledStress<'static, R> { coefficient, velocity, gradient, viscosity }
    PressureAndGravity {}

    HashArgs<'static> { grid, position, cell_key }
    HoldsFluidArgs<'static> { cell_start, id, boundary_count, holds_fluid }
    NearFluidArgs<'static, Open> { grid, topology, cell_start, holds_fluid, near_fluid }
    NearFluidArgs<'static, Periodic> { grid, topology, cell_start, holds_fluid, near_fluid }
    DensityArgs<'static, R, O> { neighborhood, fluid, id, density }
    DensityArgs<'static, R, P> { neighborhood, fluid, id, density }
    ContinuityArgs<'static, R, O> { neighborhood, fluid, diffusivity, id, velocity, density, density_rate }
    ContinuityArgs<'static, R, P> { neighborhood, fluid, diffusivity, id, velocity, density, density_rate }
    DensityIntegrationArgs<'static, R> { fluid, dt, id, density_rate, density }
    MirroredWallArgs<'static, R, Open> { neighborhood, fluid, id, mirror, velocity, density }
    MirroredWallArgs<'static, R, Periodic> { neighborhood, fluid, id, mirror, velocity, density }
    StressArgs<'static, R, Newtonian<R>, KernelSum, O> { neighborhood, gradient, fluid, rheology, velocity, density, stress }
    StressArgs<'static, R, Newtonian<R>, KernelSum, P> { neighborhood, gradient, fluid, rheology, velocity, density, stress }
    StressArgs<'static, R, Cross<R>, KernelSum, O> { neighborhood, gradient, fluid, rheology, velocity, density, stress }
    StressArgs<'static, R, Cross<R>, KernelSum, P> { neighborhood, gradient, fluid, rheology, velocity, density, stress }
    VelocityGradientArgs<'static, R, Newtonian<R>, O> { neighborhood, fluid, rheology, velocity, density, gradient, viscosity }
    VelocityGradientArgs<'static, R, Cross<R>, P> { neighborhood, fluid, rheology, velocity, density, gradient, viscosity }
    ShearViscosityArgs<'static, R, Cross<R>, O> { neighborhood, fluid, rheology, velocity, density, viscosity }
    ShearViscosityArgs<'static, R, Cross<R>, P> { neighborhood, fluid, rheology, velocity, density, viscosity }
    AccelerationArgs<'static, R, StressDivergence<'static, R>, O> { neighborhood, fluid, viscous, id, density, acceleration }
    AccelerationArgs<'static, R, StressDivergence<'static, R>, P> { neighborhood, fluid, viscous, id, density, acceleration }
    AccelerationArgs<'static, R, VelocityLaplacian<'static, R>, O> { neighborhood, fluid, viscous, id, density, acceleration }
    AccelerationArgs<'static, R, MorrisViscosity<'static, R, Newtonian<R>>, O> {
        neighborhood, fluid, viscous, id, density, acceleration
    }
    AccelerationArgs<'static, R, MorrisViscosity<'static, R, View<'static, R>>, P> {
        neighborhood, fluid, viscous, id, density, acceleration
    }
    AccelerationArgs<'static, R, HourglassControlledStress<'static, R>, O> {
        neighborhood, fluid, viscous, id, density, acceleration
    }
    AccelerationArgs<'static, R, PressureAndGravity, O> { neighborhood, fluid, viscous, id, density, acceleration }
    AccelerationArgs<'static, R, PressureAndGravity, P> { neighborhood, fluid, viscous, id, density, acceleration }
    NozzleArgs<'static, R> { fluid, tube, id, position, acceleration, velocity_half }
    NozzleShiftArgs<'static, R> { fluid, tube, id, position, shift }
    ShiftingArgs<'static, R, O> { neighborhood, fluid, shifting, dt, id, velocity, shift }
    ShiftingArgs<'static, R, P> { neighborhood, fluid, shifting, dt, id, velocity, shift }
    ShiftArgs<'static, R, Open> { topology, shift, position }
    ShiftArgs<'static, R, Periodic> { topology, shift, position }
    LeapfrogArgs<'static, R, Open> { fluid, topology, dt, kick_dt, id, acceleration, position, velocity_half, velocity }
    LeapfrogArgs<'static, R, Periodic> { fluid, topology, dt, kick_dt, id, acceleration, position, velocity_half, velocity }
    DiagnosticsArgs<'static, R> { fluid, runaway_speed2, id, velocity, density }
    PredictorArgs<'static, R> {
        fluid, kick_dt, id, velocity_half, velocity, acceleration, viscous_change, predicted, solution
    }
    LaggedViscosityArgs<'static, R, Newtonian<R>, O> { neighborhood, fluid, rheology, velocity, density, viscosity }
    LaggedViscosityArgs<'static, R, Cross<R>, P> { neighborhood, fluid, rheology, velocity, density, viscosity }
    ImplicitStressArgs<'static, R, O> { neighborhood, fluid, velocity, density, viscosity, stress }
    ImplicitStressArgs<'static, R, P> { neighborhood, fluid, velocity, density, viscosity, stress }
    SystemBlockArgs<'static, R, O> { neighborhood, fluid, kick_dt, id, density, viscosity, block }
    SystemBlockArgs<'static, R, P> { neighborhood, fluid, kick_dt, id, density, viscosity, block }
    SystemProductArgs<'static, R, O> { neighborhood, fluid, kick_dt, id, stress, velocity, product }
    SystemProductArgs<'static, R, P> { neighborhood, fluid, kick_dt, id, stress, velocity, product }
    MorrisSystemBlockArgs<'static, R, Newtonian<R>, O> { neighborhood, fluid, kick_dt, id, density, viscosity, block }
    MorrisSystemBlockArgs<'static, R, View<'static, R>, P> { neighborhood, fluid, kick_dt, id, density, viscosity, block }
    MorrisSystemProductArgs<'static, R, Newtonian<R>, O> { neighborhood, fluid, kick_dt, id, density, operator, product }
    MorrisSystemProductArgs<'static, R, View<'static, R>, P> { neighborhood, fluid, kick_dt, id, density, operator, product }
    CgStartArgs<'static, R> { fluid, id, predicted, product, block, residual, preconditioned, direction }
    CgStepArgs<'static, R> { alpha, direction, product, block, solution, residual, preconditioned }
    CgDirectionArgs<'static, R> { beta, preconditioned, direction }
    ViscousAccelerationArgs<'static, R> { fluid, kick_dt, id, predicted, solution, acceleration, viscous_change }
    DotArgs<'static, R> { a, b, c, d }
    FactorArgs<'static, R, O> { neighborhood, fluid, id, density, factor }
    FactorArgs<'static, R, P> { neighborhood, fluid, id, density, factor }
    DivergenceErrorArgs<'static, R, O> {
        neighborhood, fluid, sweep, dt, kick_dt, id, density, factor, velocity_half, stiffness_sum, stiffness, error
    }
    DivergenceErrorArgs<'static, R, P> {
        neighborhood, fluid, sweep, dt, kick_dt, id, density, factor, velocity_half, stiffness_sum, stiffness, error
    }
    DensityErrorArgs<'static, R, O> {
        neighborhood, fluid, sweep, dt, kick_dt, id, density, factor, velocity_half, acceleration, least_stiffness,
        stiffness_sum, stiffness, error
    }
    DensityErrorArgs<'static, R, P> {
        neighborhood, fluid, sweep, dt, kick_dt, id, density, factor, velocity_half, acceleration, least_stiffness,
        stiffness_sum, stiffness, error
    }
    DensityRateArgs<'static, R, O> { neighborhood, fluid, kick_dt, id, factor, velocity_half, acceleration, density_rate }
    DensityRateArgs<'static, R, P> { neighborhood, fluid, kick_dt, id, factor, velocity_half, acceleration, density_rate }
    PressureChangeArgs<'static, R, O> { neighborhood, fluid, id, density, stiffness, wall_head, scale, target, stiffness_sum }
    PressureChangeArgs<'static, R, P> { neighborhood, fluid, id, density, stiffness, wall_head, scale, target, stiffness_sum }
    WarmStartArgs<'static, R> { share, stiffness_sum, stiffness }
    ErrorSumArgs<'static, R> { fluid, id, error }
);
