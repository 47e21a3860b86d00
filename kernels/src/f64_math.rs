//! `exp2` and `log2` in f64 from arithmetic alone: PTX has `ex2` and `lg2` only in f32 (and
//! approximate), and libm would compile to slow table-driven code on the device. Each is a
//! range reduction on the exponent bits and a short series, within a few ulp of the correctly
//! rounded result over the whole range (tested against the host's `std` in `tests/integration/kernels.rs`),
//! so that an f64 run's Cross exponent (K D)^n is computed in f64 on every backend.

/// ln 2.
const LN_2: f64 = core::f64::consts::LN_2;
/// 1 / ln 2.
const LOG2_E: f64 = core::f64::consts::LOG2_E;
const EXPONENT_BIAS: i64 = 1023;
const MANTISSA_BITS: u32 = 52;
const MANTISSA_MASK: u64 = (1 << MANTISSA_BITS) - 1;

/// 2^n for an integer n of a normal f64's exponent range, -1022 to 1023.
#[inline(always)]
fn power_of_two(n: i64) -> f64 {
    f64::from_bits(((n + EXPONENT_BIAS) as u64) << MANTISSA_BITS)
}

/// 2^x. With n the integer nearest x and f = x - n in [-1/2, 1/2], 2^x = 2^n e^(f ln 2): the
/// Taylor series of e^y for |y| <= ln 2 / 2 to y^13 leaves a relative error below 1e-17.
#[inline(always)]
pub fn exp2(x: f64) -> f64 {
    if x.is_nan() {
        return x;
    }
    if x >= 1024.0 {
        return f64::INFINITY;
    }
    if x < -1075.0 {
        return 0.0;
    }
    let n = (if x >= 0.0 { x + 0.5 } else { x - 0.5 }) as i64;
    let y = (x - n as f64) * LN_2;
    let mut series = 1.0;
    let mut k = 13;
    while k > 0 {
        series = 1.0 + series * y / k as f64;
        k -= 1;
    }
    // Beyond a normal exponent the scale is taken in two steps, so that each factor is normal.
    if n < -1022 {
        series * power_of_two(n + 600) * power_of_two(-600)
    } else if n > 1023 {
        series * power_of_two(n - 1) * 2.0
    } else {
        series * power_of_two(n)
    }
}

/// log2 x. With x = m 2^e, m in [sqrt(1/2), sqrt(2)), and s = (m - 1) / (m + 1) (|s| <= 0.172),
/// ln m = 2 atanh s = 2 (s + s^3 / 3 + s^5 / 5 + ...), to s^23 a relative error below 1e-17;
/// then log2 x = e + ln m / ln 2. Subnormal x is scaled into the normal range first.
#[inline(always)]
pub fn log2(x: f64) -> f64 {
    if x.is_nan() || x < 0.0 {
        return f64::NAN;
    }
    if x == 0.0 {
        return f64::NEG_INFINITY;
    }
    if x == f64::INFINITY {
        return x;
    }
    let (x, shift) = if x < f64::MIN_POSITIVE { (x * power_of_two(54), -54) } else { (x, 0) };
    let bits = x.to_bits();
    let mut e = ((bits >> MANTISSA_BITS) as i64) - EXPONENT_BIAS + shift;
    let mut m = f64::from_bits((bits & MANTISSA_MASK) | ((EXPONENT_BIAS as u64) << MANTISSA_BITS));
    if m > core::f64::consts::SQRT_2 {
        m *= 0.5;
        e += 1;
    }
    let s = (m - 1.0) / (m + 1.0);
    let s2 = s * s;
    let mut series = 0.0;
    let mut k = 23;
    while k > 1 {
        series = s2 * (1.0 / k as f64 + series);
        k -= 2;
    }
    let ln_m = 2.0 * s * (1.0 + series);
    e as f64 + ln_m * LOG2_E
}
