//! Views of particle arrays that are the same on the host and on the device.
//!
//! A kernel receives `#[repr(C)]` pointer-and-length pairs by value, so the very same argument
//! struct is built from Rust slices by the CPU backend and from device pointers by the CUDA
//! backend. Each kernel invocation writes only the entries its index owns (or claims through an
//! atomic counter), which is what makes the shared mutable view sound.

use crate::vec3::SymTensor;
use core::marker::PhantomData;

/// Panics off the device where `i` is past a view of `len` elements.
#[inline(always)]
fn check_index(i: usize, len: usize) {
    #[cfg(not(target_arch = "nvptx64"))]
    if i >= len {
        out_of_bounds(i, len);
    }
    #[cfg(target_arch = "nvptx64")]
    let _ = (i, len);
}

/// The panic of [`check_index`], kept out of line so that the check costs the reading loop one
/// compare and a branch never taken.
#[cfg(not(target_arch = "nvptx64"))]
#[cold]
#[inline(never)]
fn out_of_bounds(i: usize, len: usize) -> ! {
    panic!("index {i} past a view of {len} elements")
}

/// A read-only view of `len` elements.
#[repr(C)]
#[derive(Debug)]
pub struct View<'a, T> {
    pub(crate) ptr: *const T,
    pub(crate) len: usize,
    _life: PhantomData<&'a [T]>,
}

impl<T> Clone for View<'_, T> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<T> Copy for View<'_, T> {}
// SAFETY: a view is a shared borrow of `[T]`.
unsafe impl<T: Sync> Send for View<'_, T> {}
unsafe impl<T: Sync> Sync for View<'_, T> {}

impl<'a, T: Copy> View<'a, T> {
    #[inline(always)]
    pub fn new(s: &'a [T]) -> Self {
        Self { ptr: s.as_ptr(), len: s.len(), _life: PhantomData }
    }

    /// A view of device memory.
    ///
    /// # Safety
    /// `ptr` must point to `len` initialised elements that outlive the view.
    #[inline(always)]
    pub unsafe fn from_raw(ptr: *const T, len: usize) -> Self {
        Self { ptr, len, _life: PhantomData }
    }

    #[inline(always)]
    pub fn len(&self) -> usize {
        self.len
    }

    #[inline(always)]
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Entry `i`. Off the device an index past the view panics; on the device it is not
    /// checked (a trap there would cost every neighbor read), and kernels index only below the
    /// count the host sized the view to, which the CPU backend, running the same kernels
    /// checked, tests.
    #[inline(always)]
    pub fn at(&self, i: usize) -> T {
        check_index(i, self.len);
        // SAFETY: `i < len` (checked off the device; on it, the invariant above), and `ptr`
        // holds `len` initialised elements.
        unsafe { *self.ptr.add(i) }
    }
}

/// A view through which each kernel invocation writes the entries it owns.
#[repr(C)]
#[derive(Debug)]
pub struct ViewMut<'a, T> {
    pub(crate) ptr: *mut T,
    pub(crate) len: usize,
    _life: PhantomData<&'a mut [T]>,
}

impl<T> Clone for ViewMut<'_, T> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<T> Copy for ViewMut<'_, T> {}
// SAFETY: concurrent invocations write disjoint indices (see the module docs).
unsafe impl<T: Send> Send for ViewMut<'_, T> {}
unsafe impl<T: Send> Sync for ViewMut<'_, T> {}

impl<'a, T: Copy> ViewMut<'a, T> {
    #[inline(always)]
    pub fn new(s: &'a mut [T]) -> Self {
        Self { ptr: s.as_mut_ptr(), len: s.len(), _life: PhantomData }
    }

    /// A view of device memory.
    ///
    /// # Safety
    /// `ptr` must point to `len` elements that outlive the view.
    #[inline(always)]
    pub unsafe fn from_raw(ptr: *mut T, len: usize) -> Self {
        Self { ptr, len, _life: PhantomData }
    }

    #[inline(always)]
    pub fn len(&self) -> usize {
        self.len
    }

    #[inline(always)]
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Entry `i`, checked as [`View::at`] is.
    #[inline(always)]
    pub fn at(&self, i: usize) -> T {
        check_index(i, self.len);
        // SAFETY: as for `View::at`.
        unsafe { *self.ptr.add(i) }
    }

    /// The `len` elements from `start`, for a pass over part of the array.
    pub fn range(&self, start: usize, len: usize) -> Self {
        assert!(start + len <= self.len, "a range beyond the view");
        // SAFETY: within this view's elements.
        unsafe { Self::from_raw(self.ptr.add(start), len) }
    }

    /// The same array, read-only: what a later pass reads of what this one wrote.
    #[inline(always)]
    pub fn read(&self) -> View<'a, T> {
        // SAFETY: the array outlives 'a; backends run passes one after another.
        unsafe { View::from_raw(self.ptr, self.len) }
    }

    /// Writes entry `i`.
    ///
    /// # Safety
    /// No other invocation may read or write entry `i` concurrently.
    #[inline(always)]
    pub unsafe fn write(&self, i: usize, v: T) {
        debug_assert!(i < self.len);
        *self.ptr.add(i) = v;
    }
}

/// Three arrays holding the x, y, z components of a per-particle vector.
#[repr(C)]
#[derive(Debug)]
pub struct Vec3View<'a, T> {
    pub x: View<'a, T>,
    pub y: View<'a, T>,
    pub z: View<'a, T>,
}
impl<T> Clone for Vec3View<'_, T> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<T> Copy for Vec3View<'_, T> {}

impl<'a, T: Copy> Vec3View<'a, T> {
    #[inline(always)]
    pub fn new(x: &'a [T], y: &'a [T], z: &'a [T]) -> Self {
        Self { x: View::new(x), y: View::new(y), z: View::new(z) }
    }
    #[inline(always)]
    pub fn at(&self, i: usize) -> [T; 3] {
        [self.x.at(i), self.y.at(i), self.z.at(i)]
    }
}

/// Mutable counterpart of [`Vec3View`].
#[repr(C)]
#[derive(Debug)]
pub struct Vec3ViewMut<'a, T> {
    pub x: ViewMut<'a, T>,
    pub y: ViewMut<'a, T>,
    pub z: ViewMut<'a, T>,
}
impl<T> Clone for Vec3ViewMut<'_, T> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<T> Copy for Vec3ViewMut<'_, T> {}

impl<'a, T: Copy> Vec3ViewMut<'a, T> {
    #[inline(always)]
    pub fn new(x: &'a mut [T], y: &'a mut [T], z: &'a mut [T]) -> Self {
        Self { x: ViewMut::new(x), y: ViewMut::new(y), z: ViewMut::new(z) }
    }
    #[inline(always)]
    pub fn at(&self, i: usize) -> [T; 3] {
        [self.x.at(i), self.y.at(i), self.z.at(i)]
    }
    /// # Safety
    /// As for [`ViewMut::write`].
    #[inline(always)]
    pub unsafe fn write(&self, i: usize, v: [T; 3]) {
        self.x.write(i, v[0]);
        self.y.write(i, v[1]);
        self.z.write(i, v[2]);
    }

    /// The same arrays, read-only.
    #[inline(always)]
    pub fn read(&self) -> Vec3View<'a, T> {
        Vec3View { x: self.x.read(), y: self.y.read(), z: self.z.read() }
    }
}

/// Six arrays holding the independent components of a per-particle symmetric tensor.
#[repr(C)]
#[derive(Debug)]
pub struct SymTensorView<'a, T> {
    pub xx: View<'a, T>,
    pub yy: View<'a, T>,
    pub zz: View<'a, T>,
    pub xy: View<'a, T>,
    pub xz: View<'a, T>,
    pub yz: View<'a, T>,
}
impl<T> Clone for SymTensorView<'_, T> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<T> Copy for SymTensorView<'_, T> {}

impl<T: Copy> SymTensorView<'_, T> {
    /// Entry `i` as a tensor.
    #[inline(always)]
    pub fn at(&self, i: usize) -> SymTensor<T> {
        SymTensor {
            xx: self.xx.at(i),
            yy: self.yy.at(i),
            zz: self.zz.at(i),
            xy: self.xy.at(i),
            xz: self.xz.at(i),
            yz: self.yz.at(i),
        }
    }
}

/// Mutable counterpart of [`SymTensorView`].
#[repr(C)]
#[derive(Debug)]
pub struct SymTensorViewMut<'a, T> {
    pub xx: ViewMut<'a, T>,
    pub yy: ViewMut<'a, T>,
    pub zz: ViewMut<'a, T>,
    pub xy: ViewMut<'a, T>,
    pub xz: ViewMut<'a, T>,
    pub yz: ViewMut<'a, T>,
}
impl<T> Clone for SymTensorViewMut<'_, T> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<T> Copy for SymTensorViewMut<'_, T> {}

impl<'a, T: Copy> SymTensorViewMut<'a, T> {
    /// Writes entry `i`.
    ///
    /// # Safety
    /// No other invocation may read or write entry `i` concurrently.
    #[inline(always)]
    pub unsafe fn write(&self, i: usize, t: SymTensor<T>) {
        self.xx.write(i, t.xx);
        self.yy.write(i, t.yy);
        self.zz.write(i, t.zz);
        self.xy.write(i, t.xy);
        self.xz.write(i, t.xz);
        self.yz.write(i, t.yz);
    }

    /// The same arrays, read-only: what a later pass reads of what this one wrote.
    #[inline(always)]
    pub fn read(&self) -> SymTensorView<'a, T> {
        // SAFETY: the arrays outlive 'a; backends run passes one after another.
        unsafe {
            SymTensorView {
                xx: View::from_raw(self.xx.ptr, self.xx.len),
                yy: View::from_raw(self.yy.ptr, self.yy.len),
                zz: View::from_raw(self.zz.ptr, self.zz.len),
                xy: View::from_raw(self.xy.ptr, self.xy.len),
                xz: View::from_raw(self.xz.ptr, self.xz.len),
                yz: View::from_raw(self.yz.ptr, self.yz.len),
            }
        }
    }
}

/// Nine arrays holding a per-particle 3x3 matrix by rows, `rows[a]` its row a.
#[repr(C)]
#[derive(Debug)]
pub struct Mat3View<'a, T> {
    pub rows: [Vec3View<'a, T>; 3],
}
impl<T> Clone for Mat3View<'_, T> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<T> Copy for Mat3View<'_, T> {}

impl<T: Copy> Mat3View<'_, T> {
    #[inline(always)]
    pub fn at(&self, i: usize) -> [[T; 3]; 3] {
        [self.rows[0].at(i), self.rows[1].at(i), self.rows[2].at(i)]
    }
}

/// Mutable counterpart of [`Mat3View`].
#[repr(C)]
#[derive(Debug)]
pub struct Mat3ViewMut<'a, T> {
    pub rows: [Vec3ViewMut<'a, T>; 3],
}
impl<T> Clone for Mat3ViewMut<'_, T> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<T> Copy for Mat3ViewMut<'_, T> {}

impl<'a, T: Copy> Mat3ViewMut<'a, T> {
    /// # Safety
    /// As for [`ViewMut::write`].
    #[inline(always)]
    pub unsafe fn write(&self, i: usize, m: [[T; 3]; 3]) {
        self.rows[0].write(i, m[0]);
        self.rows[1].write(i, m[1]);
        self.rows[2].write(i, m[2]);
    }

    /// The same arrays, read-only: what a later pass reads of what this one wrote.
    #[inline(always)]
    pub fn read(&self) -> Mat3View<'a, T> {
        Mat3View { rows: self.rows.map(|r| r.read()) }
    }
}
