//! The bytes of a checkpoint: little-endian fields appended in order, and read back in order
//! with every shortfall an error naming what was cut off.

use coil_kernels::Real;

/// Appends fields to a checkpoint's bytes.
pub(super) struct Writer(pub(super) Vec<u8>);

impl Writer {
    pub(super) fn u8(&mut self, v: u8) {
        self.0.push(v);
    }
    pub(super) fn u32(&mut self, v: u32) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    pub(super) fn u64(&mut self, v: u64) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    pub(super) fn f64(&mut self, v: f64) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    /// `None` as NaN, which no time or dt of a run can be.
    pub(super) fn optional_f64(&mut self, v: Option<f64>) {
        self.f64(v.unwrap_or(f64::NAN));
    }
    pub(super) fn f64s(&mut self, v: &[f64]) {
        for &x in v {
            self.f64(x);
        }
    }
    /// Reals at their own width: an f32 goes through f64 and back exactly.
    pub(super) fn reals<R: Real>(&mut self, v: &[R]) {
        for &x in v {
            match std::mem::size_of::<R>() {
                4 => self.0.extend_from_slice(&(x.to_f64() as f32).to_le_bytes()),
                _ => self.f64(x.to_f64()),
            }
        }
    }
}

/// Reads a checkpoint's fields in order; every shortfall is an error naming what was cut off.
pub(super) struct Reader<'a> {
    pub(super) bytes: &'a [u8],
    pub(super) at: usize,
}

impl<'a> Reader<'a> {
    pub(super) fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8], String> {
        let end = self.at.checked_add(n).filter(|&e| e <= self.bytes.len()).ok_or_else(|| format!("ends inside {what}"))?;
        let out = &self.bytes[self.at..end];
        self.at = end;
        Ok(out)
    }
    pub(super) fn u8(&mut self, what: &str) -> Result<u8, String> {
        Ok(self.take(1, what)?[0])
    }
    pub(super) fn u32(&mut self, what: &str) -> Result<u32, String> {
        Ok(u32::from_le_bytes(self.take(4, what)?.try_into().expect("4 bytes")))
    }
    pub(super) fn u64(&mut self, what: &str) -> Result<u64, String> {
        Ok(u64::from_le_bytes(self.take(8, what)?.try_into().expect("8 bytes")))
    }
    pub(super) fn f64(&mut self, what: &str) -> Result<f64, String> {
        Ok(f64::from_le_bytes(self.take(8, what)?.try_into().expect("8 bytes")))
    }
    pub(super) fn optional_f64(&mut self, what: &str) -> Result<Option<f64>, String> {
        let v = self.f64(what)?;
        Ok((!v.is_nan()).then_some(v))
    }
    /// A count of `size`-byte items that must fit in what is left.
    pub(super) fn count(&mut self, size: usize, what: &str) -> Result<usize, String> {
        let n = self.u64(what)?;
        usize::try_from(n)
            .ok()
            .filter(|&n| n.checked_mul(size).is_some_and(|b| b <= self.bytes.len() - self.at))
            .ok_or_else(|| format!("claims {n} {what}, more than the file holds"))
    }
}
