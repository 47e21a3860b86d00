//! The particles' arrays on the device, preallocated to the run's capacity, with the solves'
//! arrays where a run solves.

use super::device_array::{vec3_view_mut, vec3_zeros, DeviceArray, DeviceVec3};
use super::gpu::{CudaError, Gpu};
use crate::simulation::particles::{ImplicitViews, ModelFields, PressureViews};
use coil_kernels::counting_sort::scan_levels_len;
use coil_kernels::counting_sort::DEVICE_SCAN_CHUNK;
use coil_kernels::dfsph_bender2017::ERROR_RANGE;
use coil_kernels::diagnostics::StateFigures;
use coil_kernels::view::SymTensorViewMut;
use coil_kernels::viscosity::implicit_weiler2018::DOT_RANGE;
use coil_kernels::Real;

/// Scan chunks of `buckets` buckets.
pub(super) fn buckets_chunks(buckets: usize) -> usize {
    buckets.div_ceil(DEVICE_SCAN_CHUNK)
}

/// Particles per range of the diagnostics reduction.
pub(super) const DIAGNOSTICS_RANGE: usize = 256;

/// Particle and grid state on the device.
pub(super) struct DeviceState<R> {
    pub(super) position: DeviceVec3<f64>,
    pub(super) velocity: DeviceVec3<R>,
    pub(super) velocity_half: DeviceVec3<R>,
    pub(super) acceleration: DeviceVec3<R>,
    pub(super) density: DeviceArray<R>,
    /// Where density comes from the continuity equation.
    pub(super) density_rate: Option<DeviceArray<R>>,
    /// Where the scene shifts particles.
    pub(super) shift: Option<DeviceVec3<R>>,
    pub(super) id: DeviceArray<u32>,
    pub(super) stress: Option<[DeviceArray<R>; 6]>,
    pub(super) viscosity: Option<DeviceArray<R>>,
    pub(super) velocity_gradient: Option<[DeviceVec3<R>; 3]>,
    /// Targets of the reorder, swapped with the arrays they receive: one launch gathers a
    /// position axis, two arrays of `R` and the ids.
    pub(super) scratch_f64: DeviceArray<f64>,
    pub(super) scratch_real: [DeviceArray<R>; 2],
    pub(super) scratch_u32: DeviceArray<u32>,
    pub(super) cell_key: DeviceArray<u32>,
    pub(super) counters: DeviceArray<u32>,
    pub(super) cell_start: DeviceArray<u32>,
    pub(super) order: DeviceArray<u32>,
    pub(super) chunk_offsets: DeviceArray<u32>,
    /// Per cell: whether it holds fluid (where the run tracks fluid), then whether it lies near
    /// fluid (`fluid_cells`).
    pub(super) holds_fluid: Option<DeviceArray<u8>>,
    pub(super) near_fluid: DeviceArray<u8>,
    /// The live particle count (one entry).
    pub(super) count: DeviceArray<u32>,
    /// One carried array of this step's inlet layers at a time, by element type, before it is
    /// appended.
    pub(super) staged_wide: DeviceArray<f64>,
    pub(super) staged_real: DeviceArray<R>,
    pub(super) staged_index: DeviceArray<u32>,
    /// One `StateFigures` per diagnostics range.
    pub(super) figures: DeviceArray<StateFigures>,
    /// Wall particles' mirror images by id, under mirrored walls.
    pub(super) wall_mirror: Option<DeviceVec3<f64>>,
    /// The implicit viscosity solve's arrays, where viscosity is solved implicitly.
    pub(super) implicit: Option<DeviceImplicit<R>>,
    /// The pressure solves' arrays, where pressure is solved for a divergence-free flow.
    pub(super) pressure_solve: Option<DevicePressure<R>>,
}

/// The divergence-free pressure solves' arrays on the device (`particles::PressureArrays`).
pub(super) struct DevicePressure<R> {
    /// factor, stiffness, error.
    pub(super) scratch: [DeviceArray<R>; 3],
    /// The divergence and density solves' stiffness sums: state, which the sort gathers.
    pub(super) stiffness_sums: [DeviceArray<R>; 2],
    pub(super) partial_sums: DeviceArray<[f64; 2]>,
}

impl<R: Real> DevicePressure<R> {
    pub(super) fn new(gpu: &Gpu, capacity: usize) -> Result<Self, CudaError> {
        let a = || DeviceArray::zeros(gpu, capacity, "pressure solve arrays");
        Ok(Self {
            scratch: [a()?, a()?, a()?],
            stiffness_sums: [a()?, a()?],
            partial_sums: DeviceArray::zeros(gpu, capacity.div_ceil(ERROR_RANGE), "partial error sums")?,
        })
    }

    pub(super) fn bytes(&self) -> usize {
        self.scratch.iter().chain(&self.stiffness_sums).map(DeviceArray::bytes).sum::<usize>() + self.partial_sums.bytes()
    }

    pub(super) fn views(&self, n: usize) -> PressureViews<'static, R> {
        let [factor, stiffness, error] = &self.scratch;
        let [divergence_sum, density_sum] = &self.stiffness_sums;
        PressureViews {
            factor: factor.view_mut(n),
            stiffness: stiffness.view_mut(n),
            error: error.view_mut(n),
            divergence_sum: divergence_sum.view_mut(n),
            density_sum: density_sum.view_mut(n),
            partial_sums: self.partial_sums.view_mut(n.div_ceil(ERROR_RANGE)),
        }
    }
}

/// The implicit viscosity solve's arrays on the device (`particles::ImplicitArrays`).
pub(super) struct DeviceImplicit<R> {
    /// The last step's viscous change of velocity: state, which the sort gathers.
    pub(super) viscous_change: DeviceVec3<R>,
    /// predicted, solution, residual, preconditioned, direction, product.
    pub(super) vectors: [DeviceVec3<R>; 6],
    pub(super) block: [DeviceArray<R>; 6],
    pub(super) partial_dots: DeviceArray<[f64; 2]>,
}

impl<R: Real> DeviceImplicit<R> {
    pub(super) fn new(gpu: &Gpu, capacity: usize) -> Result<Self, CudaError> {
        let v = || vec3_zeros(gpu, capacity, "implicit viscosity vectors");
        let b = || DeviceArray::zeros(gpu, capacity, "implicit viscosity blocks");
        Ok(Self {
            viscous_change: v()?,
            vectors: [v()?, v()?, v()?, v()?, v()?, v()?],
            block: [b()?, b()?, b()?, b()?, b()?, b()?],
            partial_dots: DeviceArray::zeros(gpu, capacity.div_ceil(DOT_RANGE), "partial dot products")?,
        })
    }

    pub(super) fn bytes(&self) -> usize {
        self.viscous_change.iter().chain(self.vectors.iter().flatten()).map(DeviceArray::bytes).sum::<usize>()
            + self.block.iter().map(DeviceArray::bytes).sum::<usize>()
            + self.partial_dots.bytes()
    }

    pub(super) fn views(&self, n: usize) -> ImplicitViews<'static, R> {
        let [xx, yy, zz, xy, xz, yz] = &self.block;
        let v = |k: usize| vec3_view_mut(&self.vectors[k], n);
        ImplicitViews {
            viscous_change: vec3_view_mut(&self.viscous_change, n),
            predicted: v(0),
            solution: v(1),
            residual: v(2),
            preconditioned: v(3),
            direction: v(4),
            product: v(5),
            block: SymTensorViewMut {
                xx: xx.view_mut(n),
                yy: yy.view_mut(n),
                zz: zz.view_mut(n),
                xy: xy.view_mut(n),
                xz: xz.view_mut(n),
                yz: yz.view_mut(n),
            },
            partial_dots: self.partial_dots.view_mut(n.div_ceil(DOT_RANGE)),
        }
    }
}

impl<R: Real> DeviceState<R> {
    pub(super) fn new(
        gpu: &Gpu,
        capacity: usize,
        buckets: usize,
        staged: usize,
        fields: ModelFields,
        tracks_fluid: bool,
    ) -> Result<Self, CudaError> {
        let stress = if fields.stress {
            Some([
                DeviceArray::zeros(gpu, capacity, "stress")?,
                DeviceArray::zeros(gpu, capacity, "stress")?,
                DeviceArray::zeros(gpu, capacity, "stress")?,
                DeviceArray::zeros(gpu, capacity, "stress")?,
                DeviceArray::zeros(gpu, capacity, "stress")?,
                DeviceArray::zeros(gpu, capacity, "stress")?,
            ])
        } else {
            None
        };
        Ok(Self {
            position: vec3_zeros(gpu, capacity, "positions")?,
            velocity: vec3_zeros(gpu, capacity, "velocities")?,
            velocity_half: vec3_zeros(gpu, capacity, "half-step velocities")?,
            acceleration: vec3_zeros(gpu, capacity, "accelerations")?,
            density: DeviceArray::zeros(gpu, capacity, "densities")?,
            density_rate: if fields.density_rate { Some(DeviceArray::zeros(gpu, capacity, "density rates")?) } else { None },
            shift: if fields.shift { Some(vec3_zeros(gpu, capacity, "shifts")?) } else { None },
            id: DeviceArray::zeros(gpu, capacity, "ids")?,
            stress,
            viscosity: if fields.viscosity { Some(DeviceArray::zeros(gpu, capacity, "viscosities")?) } else { None },
            velocity_gradient: if fields.velocity_gradient {
                Some([
                    vec3_zeros(gpu, capacity, "velocity gradients")?,
                    vec3_zeros(gpu, capacity, "velocity gradients")?,
                    vec3_zeros(gpu, capacity, "velocity gradients")?,
                ])
            } else {
                None
            },
            scratch_f64: DeviceArray::zeros(gpu, capacity, "sort scratch")?,
            scratch_real: [
                DeviceArray::zeros(gpu, capacity, "sort scratch")?,
                DeviceArray::zeros(gpu, capacity, "sort scratch")?,
            ],
            scratch_u32: DeviceArray::zeros(gpu, capacity, "sort scratch")?,
            cell_key: DeviceArray::zeros(gpu, capacity, "cell keys")?,
            counters: DeviceArray::zeros(gpu, buckets, "cell counters")?,
            cell_start: DeviceArray::zeros(gpu, buckets + 1, "cell starts")?,
            order: DeviceArray::zeros(gpu, capacity, "sort order")?,
            chunk_offsets: DeviceArray::zeros(gpu, scan_levels_len(buckets_chunks(buckets)), "scan chunks")?,
            holds_fluid: if tracks_fluid { Some(DeviceArray::zeros(gpu, buckets - 1, "cells holding fluid")?) } else { None },
            near_fluid: DeviceArray::zeros(gpu, buckets - 1, "cells near fluid")?,
            count: DeviceArray::zeros(gpu, 1, "particle count")?,
            staged_wide: DeviceArray::zeros(gpu, staged, "inlet layers")?,
            staged_real: DeviceArray::zeros(gpu, staged, "inlet layers")?,
            staged_index: DeviceArray::zeros(gpu, staged, "inlet layers")?,
            figures: DeviceArray::zeros(gpu, capacity.div_ceil(DIAGNOSTICS_RANGE), "diagnostics")?,
            wall_mirror: None,
            implicit: if fields.implicit { Some(DeviceImplicit::new(gpu, capacity)?) } else { None },
            pressure_solve: if fields.pressure_solve { Some(DevicePressure::new(gpu, capacity)?) } else { None },
        })
    }

    pub(super) fn bytes(&self) -> usize {
        let v3 = |a: &DeviceVec3<f64>| a.iter().map(DeviceArray::bytes).sum::<usize>();
        let r3 = |a: &DeviceVec3<R>| a.iter().map(DeviceArray::bytes).sum::<usize>();
        v3(&self.position)
            + r3(&self.velocity)
            + r3(&self.velocity_half)
            + r3(&self.acceleration)
            + self.density.bytes()
            + self.density_rate.as_ref().map_or(0, DeviceArray::bytes)
            + self.shift.as_ref().map_or(0, r3)
            + self.id.bytes()
            + self.stress.as_ref().map_or(0, |s| s.iter().map(DeviceArray::bytes).sum())
            + self.viscosity.as_ref().map_or(0, DeviceArray::bytes)
            + self.velocity_gradient.as_ref().map_or(0, |g| g.iter().map(r3).sum())
            + self.scratch_f64.bytes()
            + self.scratch_real.iter().map(DeviceArray::bytes).sum::<usize>()
            + self.scratch_u32.bytes()
            + self.cell_key.bytes()
            + self.counters.bytes()
            + self.cell_start.bytes()
            + self.order.bytes()
            + self.chunk_offsets.bytes()
            + self.holds_fluid.as_ref().map_or(0, DeviceArray::bytes)
            + self.near_fluid.bytes()
            + self.count.bytes()
            + self.staged_wide.bytes()
            + self.staged_real.bytes()
            + self.staged_index.bytes()
            + self.figures.bytes()
            + self.wall_mirror.as_ref().map_or(0, v3)
            + self.implicit.as_ref().map_or(0, DeviceImplicit::bytes)
            + self.pressure_solve.as_ref().map_or(0, DevicePressure::bytes)
    }

    pub(super) fn stress_view(&self, n: usize) -> Option<SymTensorViewMut<'static, R>> {
        self.stress.as_ref().map(|[xx, yy, zz, xy, xz, yz]| SymTensorViewMut {
            xx: xx.view_mut(n),
            yy: yy.view_mut(n),
            zz: zz.view_mut(n),
            xy: xy.view_mut(n),
            xz: xz.view_mut(n),
            yz: yz.view_mut(n),
        })
    }
}
