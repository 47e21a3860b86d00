//! Small fixed-size linear algebra for the kernels (glam stays on the host: its no_std path
//! pulls in libm, which is slow software math on the device).

use crate::real::Real;
use core::ops::{Add, AddAssign, Mul, Neg, Sub};

/// A 3-vector.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C)]
pub struct Vec3<R> {
    pub x: R,
    pub y: R,
    pub z: R,
}

impl<R: Real> Vec3<R> {
    #[inline(always)]
    pub const fn new(x: R, y: R, z: R) -> Self {
        Self { x, y, z }
    }
    #[inline(always)]
    pub fn zero() -> Self {
        Self::new(R::ZERO, R::ZERO, R::ZERO)
    }
    /// `d` rounded to `R`.
    #[inline(always)]
    pub fn from_f64(d: [f64; 3]) -> Self {
        Self::new(R::from_f64(d[0]), R::from_f64(d[1]), R::from_f64(d[2]))
    }
    #[inline(always)]
    pub fn dot(self, o: Self) -> R {
        self.x * o.x + self.y * o.y + self.z * o.z
    }
    #[inline(always)]
    pub fn norm2(self) -> R {
        self.dot(self)
    }
    #[inline(always)]
    pub fn norm(self) -> R {
        self.norm2().sqrt()
    }
}

impl<R: Real> Add for Vec3<R> {
    type Output = Self;
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        Self::new(self.x + o.x, self.y + o.y, self.z + o.z)
    }
}
impl<R: Real> AddAssign for Vec3<R> {
    #[inline(always)]
    fn add_assign(&mut self, o: Self) {
        *self = *self + o;
    }
}
impl<R: Real> Sub for Vec3<R> {
    type Output = Self;
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        Self::new(self.x - o.x, self.y - o.y, self.z - o.z)
    }
}
impl<R: Real> Mul<R> for Vec3<R> {
    type Output = Self;
    #[inline(always)]
    fn mul(self, s: R) -> Self {
        Self::new(self.x * s, self.y * s, self.z * s)
    }
}
impl<R: Real> Neg for Vec3<R> {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        Self::new(-self.x, -self.y, -self.z)
    }
}

/// A general 3x3 matrix, row-major: `m[a][b]`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Mat3<R> {
    pub m: [[R; 3]; 3],
}

impl<R: Real> Mat3<R> {
    #[inline(always)]
    pub fn zero() -> Self {
        Self { m: [[R::ZERO; 3]; 3] }
    }

    /// Adds `a ⊗ b` (`m[r][c] += a_r b_c`). Written out so the device keeps the matrix in
    /// registers rather than a local-memory array.
    #[inline(always)]
    pub fn add_outer(&mut self, a: Vec3<R>, b: Vec3<R>) {
        let m = &mut self.m;
        m[0][0] += a.x * b.x;
        m[0][1] += a.x * b.y;
        m[0][2] += a.x * b.z;
        m[1][0] += a.y * b.x;
        m[1][1] += a.y * b.y;
        m[1][2] += a.y * b.z;
        m[2][0] += a.z * b.x;
        m[2][1] += a.z * b.y;
        m[2][2] += a.z * b.z;
    }

    #[inline(always)]
    pub fn scaled(mut self, s: R) -> Self {
        for row in self.m.iter_mut() {
            for cell in row.iter_mut() {
                *cell *= s;
            }
        }
        self
    }

    /// The product `M · v`.
    #[inline(always)]
    pub fn dot(self, v: Vec3<R>) -> Vec3<R> {
        let m = self.m;
        Vec3::new(
            m[0][0] * v.x + m[0][1] * v.y + m[0][2] * v.z,
            m[1][0] * v.x + m[1][1] * v.y + m[1][2] * v.z,
            m[2][0] * v.x + m[2][1] * v.y + m[2][2] * v.z,
        )
    }

    /// `M^-1`, or `None` when `M` is too close to singular: |det M| below 1e-3 of the product
    /// of its row norms (1 for a rotation; the moment matrix of a particle with its neighbors
    /// on one line or one plane has 0).
    #[inline(always)]
    pub fn inverse(self) -> Option<Self> {
        let m = self.m;
        let c00 = m[1][1] * m[2][2] - m[1][2] * m[2][1];
        let c01 = m[1][2] * m[2][0] - m[1][0] * m[2][2];
        let c02 = m[1][0] * m[2][1] - m[1][1] * m[2][0];
        let det = m[0][0] * c00 + m[0][1] * c01 + m[0][2] * c02;
        let norm = |r: [R; 3]| (r[0] * r[0] + r[1] * r[1] + r[2] * r[2]).sqrt();
        if !(det.abs() > R::from_f64(1e-3) * norm(m[0]) * norm(m[1]) * norm(m[2])) {
            return None;
        }
        let inv = R::ONE / det;
        Some(Self {
            m: [
                [c00 * inv, (m[0][2] * m[2][1] - m[0][1] * m[2][2]) * inv, (m[0][1] * m[1][2] - m[0][2] * m[1][1]) * inv],
                [c01 * inv, (m[0][0] * m[2][2] - m[0][2] * m[2][0]) * inv, (m[0][2] * m[1][0] - m[0][0] * m[1][2]) * inv],
                [c02 * inv, (m[0][1] * m[2][0] - m[0][0] * m[2][1]) * inv, (m[0][0] * m[1][1] - m[0][1] * m[1][0]) * inv],
            ],
        })
    }

    /// The product `self · o`.
    #[inline(always)]
    pub fn matmul(self, o: Self) -> Self {
        let (a, b) = (self.m, o.m);
        let mut m = [[R::ZERO; 3]; 3];
        for (r, row) in m.iter_mut().enumerate() {
            for (c, cell) in row.iter_mut().enumerate() {
                *cell = a[r][0] * b[0][c] + a[r][1] * b[1][c] + a[r][2] * b[2][c];
            }
        }
        Self { m }
    }

    /// The product `M^T · v`.
    #[inline(always)]
    pub fn transpose_dot(self, v: Vec3<R>) -> Vec3<R> {
        let m = self.m;
        Vec3::new(
            m[0][0] * v.x + m[1][0] * v.y + m[2][0] * v.z,
            m[0][1] * v.x + m[1][1] * v.y + m[2][1] * v.z,
            m[0][2] * v.x + m[1][2] * v.y + m[2][2] * v.z,
        )
    }

    /// `M + M^T`.
    #[inline(always)]
    pub fn symmetric_sum(self) -> SymTensor<R> {
        let m = self.m;
        SymTensor {
            xx: m[0][0] + m[0][0],
            yy: m[1][1] + m[1][1],
            zz: m[2][2] + m[2][2],
            xy: m[0][1] + m[1][0],
            xz: m[0][2] + m[2][0],
            yz: m[1][2] + m[2][1],
        }
    }
}

/// The sum `M + N`, written out like `add_outer`.
impl<R: Real> Add for Mat3<R> {
    type Output = Self;
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        let (a, b) = (self.m, o.m);
        Self {
            m: [
                [a[0][0] + b[0][0], a[0][1] + b[0][1], a[0][2] + b[0][2]],
                [a[1][0] + b[1][0], a[1][1] + b[1][1], a[1][2] + b[1][2]],
                [a[2][0] + b[2][0], a[2][1] + b[2][1], a[2][2] + b[2][2]],
            ],
        }
    }
}

/// A symmetric 3x3 tensor stored by its six independent components.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C)]
pub struct SymTensor<R> {
    pub xx: R,
    pub yy: R,
    pub zz: R,
    pub xy: R,
    pub xz: R,
    pub yz: R,
}

impl<R: Real> SymTensor<R> {
    #[inline(always)]
    pub fn zero() -> Self {
        let z = R::ZERO;
        Self { xx: z, yy: z, zz: z, xy: z, xz: z, yz: z }
    }

    /// `tr(T·T)`, the sum of the squares of all nine entries.
    #[inline(always)]
    pub fn double_contraction(self) -> R {
        let two = R::ONE + R::ONE;
        self.xx * self.xx
            + self.yy * self.yy
            + self.zz * self.zz
            + two * (self.xy * self.xy + self.xz * self.xz + self.yz * self.yz)
    }

    #[inline(always)]
    pub fn scaled(self, s: R) -> Self {
        Self { xx: self.xx * s, yy: self.yy * s, zz: self.zz * s, xy: self.xy * s, xz: self.xz * s, yz: self.yz * s }
    }

    /// The matrix-vector product `T · v`.
    #[inline(always)]
    pub fn dot(self, v: Vec3<R>) -> Vec3<R> {
        Vec3::new(
            self.xx * v.x + self.xy * v.y + self.xz * v.z,
            self.xy * v.x + self.yy * v.y + self.yz * v.z,
            self.xz * v.x + self.yz * v.y + self.zz * v.z,
        )
    }

    /// `v v^T`.
    #[inline(always)]
    pub fn outer(v: Vec3<R>) -> Self {
        Self { xx: v.x * v.x, yy: v.y * v.y, zz: v.z * v.z, xy: v.x * v.y, xz: v.x * v.z, yz: v.y * v.z }
    }

    #[inline(always)]
    pub fn trace(self) -> R {
        self.xx + self.yy + self.zz
    }

    /// `T^-1 b` for a positive semi-definite `T`, or `None` when `T` is too close to singular:
    /// its determinant below 1e-4 (tr T)^3, some 400 times below that of an isotropic tensor
    /// of the same trace (whose ratio is 1/27).
    #[inline(always)]
    pub fn solve(self, b: Vec3<R>) -> Option<Vec3<R>> {
        let Self { xx: a, yy: e, zz: i, xy: d, xz: g, yz: h } = self;
        let c00 = e * i - h * h;
        let c01 = g * h - d * i;
        let c02 = d * h - e * g;
        let det = a * c00 + d * c01 + g * c02;
        let tr = self.trace();
        if !(det > R::from_f64(1e-4) * tr * tr * tr) {
            return None;
        }
        let c11 = a * i - g * g;
        let c12 = d * g - a * h;
        let c22 = a * e - d * d;
        let inv = R::ONE / det;
        Some(Vec3::new(
            (c00 * b.x + c01 * b.y + c02 * b.z) * inv,
            (c01 * b.x + c11 * b.y + c12 * b.z) * inv,
            (c02 * b.x + c12 * b.y + c22 * b.z) * inv,
        ))
    }
}

impl<R: Real> Add for SymTensor<R> {
    type Output = Self;
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        Self {
            xx: self.xx + o.xx,
            yy: self.yy + o.yy,
            zz: self.zz + o.zz,
            xy: self.xy + o.xy,
            xz: self.xz + o.xz,
            yz: self.yz + o.yz,
        }
    }
}
