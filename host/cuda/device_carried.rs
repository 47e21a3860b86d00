//! The carried state (`simulation::carried_state`) on the device: copied to and from the host,
//! gathered into sorted order, and appended from the host's inlet layers, each array as the
//! one list of the carried state gives it.

use super::device_array::DeviceArray;
use super::device_state::DeviceState;
use super::gpu::{ByValue, CudaError, Gpu};
use super::gpu_passes::kernel;
use crate::simulation::carried_state::{Carried, VisitCarried, VisitCarriedPair};
use crate::simulation::particle_array::ParticleArray;
use crate::simulation::particles::Particles;
use coil_kernels::counting_sort::{Gathered, ReorderArgs};
use coil_kernels::view::View;
use coil_kernels::Real;
use std::marker::PhantomData;

/// Which way a copy between the device and the host goes.
#[derive(Clone, Copy)]
pub(super) enum Transfer {
    /// The host's first `n` particles to the device.
    Upload,
    /// The device's first `n` particles to the host.
    Download,
}

/// Copies the first `n` particles' carried arrays between `device` and `host`.
pub(super) fn copy_carried<R: Real>(
    gpu: &Gpu,
    device: &mut DeviceState<R>,
    host: &mut Particles<R>,
    n: usize,
    way: Transfer,
) -> Result<(), CudaError> {
    let mut copy = CopyArrays::<R> { gpu, n, way, result: Ok(()), real: PhantomData };
    crate::visit_carried!(mut &mut copy; device, host);
    copy.result
}

struct CopyArrays<'g, R> {
    gpu: &'g Gpu,
    n: usize,
    way: Transfer,
    result: Result<(), CudaError>,
    real: PhantomData<R>,
}

impl<R> CopyArrays<'_, R> {
    fn copy<T: Copy>(&mut self, device: &mut [DeviceArray<T>], host: &mut [ParticleArray<T>]) {
        for (d, h) in device.iter_mut().zip(host) {
            if self.result.is_ok() {
                let h = &mut h[..self.n];
                self.result = match self.way {
                    Transfer::Upload => d.upload(self.gpu, h),
                    Transfer::Download => d.download(self.gpu, h),
                };
            }
        }
    }
}

impl<'a, R: Real>
    VisitCarriedPair<
        &'a mut [DeviceArray<f64>],
        &'a mut [DeviceArray<R>],
        &'a mut [DeviceArray<u32>],
        &'a mut [ParticleArray<f64>],
        &'a mut [ParticleArray<R>],
        &'a mut [ParticleArray<u32>],
    > for CopyArrays<'_, R>
{
    fn wide(&mut self, _: Carried, a: &'a mut [DeviceArray<f64>], b: &'a mut [ParticleArray<f64>]) {
        self.copy(a, b);
    }
    fn real(&mut self, _: Carried, a: &'a mut [DeviceArray<R>], b: &'a mut [ParticleArray<R>]) {
        self.copy(a, b);
    }
    fn index(&mut self, _: Carried, a: &'a mut [DeviceArray<u32>], b: &'a mut [ParticleArray<u32>]) {
        self.copy(a, b);
    }
}

/// Appends the first `added` particles of `staged` behind the device's live ones: every carried
/// array that is state, through the staging array of its type, one array at a time.
pub(super) fn append_carried<R: Real>(
    gpu: &mut Gpu,
    d: &mut DeviceState<R>,
    staged: &mut Particles<R>,
    added: usize,
) -> Result<(), CudaError> {
    let mut append = Append {
        gpu,
        count: d.count.view(1),
        added,
        density_rate: d.density_rate.is_some(),
        wide: &mut d.staged_wide,
        real: &mut d.staged_real,
        index: &mut d.staged_index,
        result: Ok(()),
    };
    crate::visit_carried!(mut &mut append; d, staged);
    append.result
}

struct Append<'g, R> {
    gpu: &'g mut Gpu,
    count: View<'static, u32>,
    added: usize,
    density_rate: bool,
    wide: &'g mut DeviceArray<f64>,
    real: &'g mut DeviceArray<R>,
    index: &'g mut DeviceArray<u32>,
    result: Result<(), CudaError>,
}

/// Uploads each of `host`'s first `added` entries into `staging` and appends them to the
/// matching `device` array with the entry `name`.
fn append<T: Copy + 'static>(
    gpu: &mut Gpu,
    name: &'static str,
    count: View<'static, u32>,
    added: usize,
    staging: &mut DeviceArray<T>,
    device: &[DeviceArray<T>],
    host: &[ParticleArray<T>],
) -> Result<(), CudaError> {
    for (target, source) in device.iter().zip(host) {
        staging.upload(gpu, &source[..added])?;
        let capacity = target.len();
        let (count, added_count) = (ByValue(count), ByValue(added as u32));
        // SAFETY: append_<T>(count, added, staged, field) over an array of the run's capacity,
        // which the run's budget keeps the appended particles within; the next upload into
        // `staging` is ordered after this launch on the device's stream.
        unsafe {
            gpu.launch(
                name,
                added as u32,
                &[&count, &added_count, &ByValue(staging.view(added)), &ByValue(target.view_mut(capacity))],
            )?;
        }
    }
    Ok(())
}

impl<'a, R: Real>
    VisitCarriedPair<
        &'a mut [DeviceArray<f64>],
        &'a mut [DeviceArray<R>],
        &'a mut [DeviceArray<u32>],
        &'a mut [ParticleArray<f64>],
        &'a mut [ParticleArray<R>],
        &'a mut [ParticleArray<u32>],
    > for Append<'_, R>
{
    fn wide(&mut self, array: Carried, a: &'a mut [DeviceArray<f64>], b: &'a mut [ParticleArray<f64>]) {
        if self.result.is_ok() && array.is_state(self.density_rate) {
            self.result = append(self.gpu, "append_f64", self.count, self.added, self.wide, a, b);
        }
    }
    fn real(&mut self, array: Carried, a: &'a mut [DeviceArray<R>], b: &'a mut [ParticleArray<R>]) {
        if self.result.is_ok() && array.is_state(self.density_rate) {
            let name = kernel::<R>("append", "", "");
            self.result = append(self.gpu, name, self.count, self.added, self.real, a, b);
        }
    }
    fn index(&mut self, array: Carried, a: &'a mut [DeviceArray<u32>], b: &'a mut [ParticleArray<u32>]) {
        if self.result.is_ok() && array.is_state(self.density_rate) {
            self.result = append(self.gpu, "append_u32", self.count, self.added, self.index, a, b);
        }
    }
}

/// Gathers every carried array that is state into the order `order` of the sort just done,
/// `n` threads reading the live count from the device. Each launch gathers one array of each
/// kind (a position axis, two of `R`, the ids) into the scratch arrays, which then swap places
/// with the arrays they received.
pub(super) fn reorder_carried<R: Real>(
    gpu: &mut Gpu,
    d: &mut DeviceState<R>,
    order: View<'static, u32>,
    n: usize,
) -> Result<(), CudaError> {
    let count = ByValue(d.count.view(1));
    let capacity = d.id.len();
    let mut carried = Collect { density_rate: d.density_rate.is_some(), wide: Vec::new(), real: Vec::new(), index: Vec::new() };
    crate::visit_carried!(mut &mut carried; d);
    let Collect { wide, real, index, .. } = carried;
    let launches = wide.len().max(real.len().div_ceil(2)).max(index.len());
    let mut wide = wide.into_iter();
    let mut real = real.into_iter();
    let mut index = index.into_iter();
    let name = kernel::<R>("reorder", "", "");
    for _ in 0..launches {
        let (w, first, second, i) = (wide.next(), real.next(), real.next(), index.next());
        let [scratch_first, scratch_second] = &mut d.scratch_real;
        let args = ReorderArgs {
            order,
            wide: gathered(&w, &d.scratch_f64, capacity, n),
            first: gathered(&first, scratch_first, capacity, n),
            second: gathered(&second, scratch_second, capacity, n),
            index: gathered(&i, &d.scratch_u32, capacity, n),
        };
        // SAFETY: reorder_<R>(count, args), every array gathered of the capacity's length into
        // a scratch array of its type, `count` the live count.
        unsafe { gpu.launch(name, n as u32, &[&count, &ByValue(args)])? };
        swap_in(gpu, w, &mut d.scratch_f64);
        swap_in(gpu, first, scratch_first);
        swap_in(gpu, second, scratch_second);
        swap_in(gpu, i, &mut d.scratch_u32);
    }
    Ok(())
}

/// `field`'s `capacity` entries gathered into `scratch`'s first `n`, or nothing.
fn gathered<T: Copy>(
    field: &Option<&mut DeviceArray<T>>,
    scratch: &DeviceArray<T>,
    capacity: usize,
    n: usize,
) -> Gathered<'static, T> {
    field.as_ref().map_or(Gathered::none(), |f| Gathered::new(f.view(capacity), scratch.view_mut(n)))
}

/// Puts the gathered `scratch` in `field`'s place, the old array becoming the scratch, its
/// contents poisoned so that a read of it shows.
fn swap_in<T: Copy>(gpu: &Gpu, field: Option<&mut DeviceArray<T>>, scratch: &mut DeviceArray<T>) {
    if let Some(field) = field {
        std::mem::swap(field, scratch);
        scratch.poison(gpu);
    }
}

/// The carried arrays that are state, by element type.
struct Collect<'a, R> {
    density_rate: bool,
    wide: Vec<&'a mut DeviceArray<f64>>,
    real: Vec<&'a mut DeviceArray<R>>,
    index: Vec<&'a mut DeviceArray<u32>>,
}

impl<'a, R: Real> VisitCarried<&'a mut [DeviceArray<f64>], &'a mut [DeviceArray<R>], &'a mut [DeviceArray<u32>]>
    for Collect<'a, R>
{
    fn wide(&mut self, array: Carried, components: &'a mut [DeviceArray<f64>]) {
        if array.is_state(self.density_rate) {
            self.wide.extend(components);
        }
    }
    fn real(&mut self, array: Carried, components: &'a mut [DeviceArray<R>]) {
        if array.is_state(self.density_rate) {
            self.real.extend(components);
        }
    }
    fn index(&mut self, array: Carried, components: &'a mut [DeviceArray<u32>]) {
        if array.is_state(self.density_rate) {
            self.index.extend(components);
        }
    }
}
