//! A typed array in device memory, and the kernel views over it.
//!
//! Stored as bytes so that any plain-data element type (the run's `Real`, `u32`, the
//! diagnostics' figures) needs no CUDA trait of its own.

use super::gpu::{Buffer, CudaError, Gpu};
use coil_kernels::counting_sort::Counters;
use coil_kernels::view::{Vec3View, Vec3ViewMut, View, ViewMut};
use std::marker::PhantomData;

pub struct DeviceArray<T> {
    bytes: Buffer,
    len: usize,
    address: u64,
    _t: PhantomData<T>,
}

fn as_bytes<T: Copy>(s: &[T]) -> &[u8] {
    // SAFETY: T is plain data (numbers), so its bytes are initialised.
    unsafe { std::slice::from_raw_parts(s.as_ptr().cast(), std::mem::size_of_val(s)) }
}

fn as_bytes_mut<T: Copy>(s: &mut [T]) -> &mut [u8] {
    // SAFETY: as above; every byte pattern the device wrote is a valid number.
    unsafe { std::slice::from_raw_parts_mut(s.as_mut_ptr().cast(), std::mem::size_of_val(s)) }
}

impl<T: Copy> DeviceArray<T> {
    /// `len` zeroed elements; `what` names the array in an out-of-memory error.
    pub fn zeros(gpu: &Gpu, len: usize, what: &str) -> Result<Self, CudaError> {
        let bytes = gpu.zeros(len * std::mem::size_of::<T>(), what)?;
        let address = gpu.address(&bytes);
        Ok(Self { bytes, len, address, _t: PhantomData })
    }

    pub fn len(&self) -> usize {
        self.len
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    pub fn bytes(&self) -> usize {
        self.len * std::mem::size_of::<T>()
    }

    /// Copies `host` into the first `host.len()` elements.
    pub fn upload(&mut self, gpu: &Gpu, host: &[T]) -> Result<(), CudaError> {
        assert!(host.len() <= self.len, "upload beyond the array");
        gpu.upload(as_bytes(host), &mut self.bytes)
    }

    /// Copies the first `host.len()` elements into `host`.
    pub fn download(&self, gpu: &Gpu, host: &mut [T]) -> Result<(), CudaError> {
        assert!(host.len() <= self.len, "download beyond the array");
        gpu.download(&self.bytes, as_bytes_mut(host))
    }

    pub fn clear(&mut self, gpu: &Gpu) -> Result<(), CudaError> {
        gpu.clear(&mut self.bytes)
    }

    /// Poisons the array on the emulated device ([`Gpu::poison`]).
    pub fn poison(&mut self, gpu: &Gpu) {
        gpu.poison(&mut self.bytes)
    }

    /// A kernel view of the first `len` elements. Only the device dereferences it.
    pub fn view(&self, len: usize) -> View<'static, T> {
        assert!(len <= self.len);
        // SAFETY: the device memory lives as long as `self`; the run keeps every array for its
        // whole length and only kernels read through the view.
        unsafe { View::from_raw(self.address as *const T, len) }
    }

    pub fn view_mut(&self, len: usize) -> ViewMut<'static, T> {
        assert!(len <= self.len);
        // SAFETY: as for `view`.
        unsafe { ViewMut::from_raw(self.address as *mut T, len) }
    }

    /// A kernel view of the `len` elements from `start`.
    pub fn view_range(&self, start: usize, len: usize) -> View<'static, T> {
        assert!(start + len <= self.len);
        // SAFETY: as for `view`.
        unsafe { View::from_raw(self.element_address(start) as *const T, len) }
    }

    pub fn view_mut_range(&self, start: usize, len: usize) -> ViewMut<'static, T> {
        assert!(start + len <= self.len);
        // SAFETY: as for `view`.
        unsafe { ViewMut::from_raw(self.element_address(start) as *mut T, len) }
    }

    /// The device address of element `k`: arithmetic on the number, since the host never
    /// dereferences it.
    fn element_address(&self, k: usize) -> u64 {
        self.address + (k * std::mem::size_of::<T>()) as u64
    }
}

impl DeviceArray<u32> {
    /// The array as atomic counters.
    pub fn counters(&self) -> Counters<'static> {
        // SAFETY: as for `view`; AtomicU32 has u32's layout.
        unsafe { Counters::from_raw(self.address as *const _, self.len) }
    }
}

/// Three device arrays for the components of a vector.
pub type DeviceVec3<T> = [DeviceArray<T>; 3];

pub fn vec3_zeros<T: Copy>(gpu: &Gpu, len: usize, what: &str) -> Result<DeviceVec3<T>, CudaError> {
    Ok([DeviceArray::zeros(gpu, len, what)?, DeviceArray::zeros(gpu, len, what)?, DeviceArray::zeros(gpu, len, what)?])
}

pub fn vec3_view<T: Copy>(a: &DeviceVec3<T>, len: usize) -> Vec3View<'static, T> {
    Vec3View { x: a[0].view(len), y: a[1].view(len), z: a[2].view(len) }
}

pub fn vec3_view_mut<T: Copy>(a: &DeviceVec3<T>, len: usize) -> Vec3ViewMut<'static, T> {
    Vec3ViewMut { x: a[0].view_mut(len), y: a[1].view_mut(len), z: a[2].view_mut(len) }
}
