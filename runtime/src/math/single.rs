//! Single-precision elementary functions ([`super::expf`], [`super::sqrtf`],
//! [`super::atanf`], [`super::sinf`], [`super::cosf`], [`super::sincf`],
//! [`super::exprelf`]): every floating-point operation is one IEEE-754
//! binary32 operation (round to nearest, left to right, no fused
//! multiply-add), the rest integer arithmetic, so a Cortex-M4F evaluates them
//! on its single-precision FPU without a double-precision routine. The C
//! runtime's `tsf_<f>f` functions are these, operation by operation.
//!
//! Error bounds (`f32_functions_vs_f64` measures them against the binary64
//! functions rounded once, over every f32 of the ranges it lists): `sqrtf`
//! correctly rounded; `expf`, `atanf` <= 1 ulp; `sinf`, `cosf` <= 2 ulp;
//! `sincf`, `exprelf` <= 3 ulp. The stored-precision certificate uses
//! [`F32_ELEMENTARY_ULP`].

/// The bound, in ulp of the result, that the stored-precision certificate
/// assumes for `expf` (the only function of a membership degree): twice the
/// largest error measured.
pub const F32_ELEMENTARY_ULP: f64 = 2.0;

/// `ln 2` split for f32: `LN2_HI` has 16 significant bits (`k * LN2_HI` exact
/// for `|k| < 2^8`), `LN2_HI + LN2_LO` is `ln 2` to ~1e-14 (fdlibm `e_expf.c`).
const LN2_HI: f32 = f32::from_bits(0x3f31_7200);
const LN2_LO: f32 = f32::from_bits(0x35bf_be8e);
const INV_LN2: f32 = core::f32::consts::LOG2_E;
/// Minimax coefficients of `r coth(r/2) - 2 = P1 r^2 + P2 r^4` on
/// `[-ln2/2, ln2/2]` (musl `expf.c`, error < 2^-27.7).
const EXPF_P1: f32 = f32::from_bits(0x3e2a_aa8f);
const EXPF_P2: f32 = f32::from_bits(0xbb35_5215);
/// Largest `x` with a finite `expf(x)` (`0x42b17217`).
const EXPF_OVERFLOW: f32 = f32::from_bits(0x42b1_7217);
/// `expf(x)` is `+0` for `x <= -103.972084` (`0x42cff1b5`).
const EXPF_UNDERFLOW: f32 = f32::from_bits(0xc2cf_f1b5);

/// `2^k` for `-126 <= k <= 127` built from the exponent bits.
#[inline]
fn pow2f(k: i32) -> f32 {
    let k = k.clamp(-126, 127);
    f32::from_bits(((k + 127) as u32) << 23)
}

/// Absolute value by clearing the sign bit.
#[inline]
fn fabsf(x: f32) -> f32 {
    f32::from_bits(x.to_bits() & 0x7fff_ffff)
}

/// `e^x` in binary32.
///
/// 1. NaN -> NaN; `x > 88.72283` -> `+inf`; `x <= -103.97208` -> `+0`;
///    `|x| < 2^-14` -> `1 + x`.
/// 2. `k = trunc(x * INV_LN2 + copysign(1/2, x))`, `hi = x - k*LN2_HI`
///    (exact), `lo = k*LN2_LO`, `r = hi - lo`.
/// 3. `s = r*r`, `c = r - s*(P1 + s*P2)`, `y = 1 - ((lo - (r*c)/(2 - c)) - hi)`.
/// 4. `k > 127`: `y * 2 * 2^(k-1)`; `k < -125`: `(y * 2^(k+100)) * 2^-100`;
///    otherwise `y * 2^k`.
pub fn expf(x: f32) -> f32 {
    if x.is_nan() {
        return x;
    }
    if x > EXPF_OVERFLOW {
        return f32::INFINITY;
    }
    if x <= EXPF_UNDERFLOW {
        return 0.0;
    }
    if fabsf(x) < 1.0 / 16_384.0 {
        // 2^-14: e^x = 1 + x + x^2/2, x^2/2 < 2^-29.
        return 1.0 + x;
    }
    let half = if x < 0.0 { -0.5 } else { 0.5 };
    // |x * INV_LN2| < 151: the cast truncates exactly.
    let k = (x * INV_LN2 + half) as i32;
    let kf = k as f32;
    let hi = x - kf * LN2_HI;
    let lo = kf * LN2_LO;
    let r = hi - lo;
    let s = r * r;
    let c = r - s * (EXPF_P1 + s * EXPF_P2);
    let y = 1.0 - ((lo - (r * c) / (2.0 - c)) - hi);
    if k > 127 {
        y * 2.0 * pow2f(k - 1)
    } else if k < -125 {
        y * pow2f(k + 100) * pow2f(-100)
    } else {
        y * pow2f(k)
    }
}

/// Square root, correctly rounded (binary32), computed with integers.
///
/// NaN, `+-0`, `+inf` return themselves; `x < 0` -> NaN. `x = M 2^E` with
/// integer `M` in `[2^23, 2^24)` (subnormals normalised); if `E` is odd,
/// `M *= 2`, `E -= 1`; `(q, rem) = isqrt(M 2^23)`, round up iff `rem > q`.
/// Equal bit for bit to IEEE `sqrtf` (the C runtime calls C's `sqrtf`).
pub fn sqrtf(x: f32) -> f32 {
    if x.is_nan() || x == 0.0 || x == f32::INFINITY {
        return x;
    }
    if x < 0.0 {
        return f32::NAN;
    }
    let bits = x.to_bits();
    let mut e = ((bits >> 23) & 0xff) as i32;
    let mut m = bits & 0x007f_ffff;
    if e == 0 {
        let shift = m.leading_zeros() as i32 - 8;
        m <<= shift;
        e = 1 - shift;
    } else {
        m |= 0x0080_0000;
    }
    // x = m * 2^(e - 150)
    let mut big_e = e - 150;
    let mut mm = u64::from(m);
    if big_e & 1 == 0 {
        // sqrt(m 2^23) 2^((E - 23)/2) needs E - 23 even.
        mm <<= 1;
        big_e -= 1;
    }
    let (mut q, rem) = isqrt_rem64(mm << 23);
    if rem > q {
        q += 1;
    }
    let res_exp = (big_e - 23) / 2 + 23 + 127;
    f32::from_bits(((res_exp as u32) << 23).wrapping_add(q as u32 - 0x0080_0000))
}

/// Floor of the square root of `n` and the remainder (digit by digit).
fn isqrt_rem64(n: u64) -> (u64, u64) {
    let mut bit: u64 = 1 << 62;
    while bit > n {
        bit >>= 2;
    }
    let (mut rem, mut res) = (n, 0u64);
    while bit != 0 {
        if rem >= res + bit {
            rem -= res + bit;
            res = (res >> 1) + bit;
        } else {
            res >>= 1;
        }
        bit >>= 2;
    }
    (res, rem)
}

/// [`super::ATAN_J16`] in binary32: `hi = atan(j/16)` rounded, `lo` the rest.
#[allow(clippy::indexing_slicing)]
pub const ATANF_J16: [(f32, f32); 40] = {
    let mut out = [(0.0f32, 0.0f32); 40];
    let mut j = 0;
    while j < 40 {
        let (hi, lo) = super::ATAN_J16[j];
        let h = hi as f32;
        out[j] = (h, ((hi - h as f64) + lo) as f32);
        j += 1;
    }
    out
};

/// [`super::ATAN_COMP_J16`] in binary32 (`pi/2 - atan(j/16)`).
#[allow(clippy::indexing_slicing)]
pub const ATANF_COMP_J16: [(f32, f32); 8] = {
    let mut out = [(0.0f32, 0.0f32); 8];
    let mut j = 0;
    while j < 8 {
        let (hi, lo) = super::ATAN_COMP_J16[j];
        let h = hi as f32;
        out[j] = (h, ((hi - h as f64) + lo) as f32);
        j += 1;
    }
    out
};

/// `-1/3, 1/5, -1/7, 1/9`: `atan(t)/t - 1 = s Q(s)` to 2^-30 for `|t| <= 1/8`.
pub const ATANF_Q: [f32; 4] = [-0.333_333_34, 0.2, -0.142_857_15, 0.111_111_11];

/// `atan(t) - t` for `|t| <= 1/8`: `t * (s * Q(s))`, Horner innermost first.
#[inline]
fn atanf_tail(t: f32) -> f32 {
    let [q1, q2, q3, q4] = ATANF_Q;
    let s = t * t;
    let q = q1 + s * (q2 + s * (q3 + s * q4));
    t * (s * q)
}

/// Arc tangent (binary32): [`super::atan`]'s algorithm with binary32 tables
/// and a 4-term tail; `|x| < 2^-12` -> `x`, `|x| > 2^26` -> `+-pi/2`.
pub fn atanf(x: f32) -> f32 {
    if x.is_nan() {
        return x;
    }
    let a = fabsf(x);
    if a < 1.0 / 4_096.0 {
        return x;
    }
    let r = if a > 67_108_864.0 {
        ATANF_COMP_J16[0].0 + ATANF_COMP_J16[0].1
    } else if a < 0.125 {
        a + atanf_tail(a)
    } else if a <= 2.4375 {
        let j = (a * 16.0 + 0.5) as usize;
        let c = j as f32 * 0.0625;
        let t = (a - c) / (1.0 + a * c);
        let (hi, lo) = ATANF_J16.get(j).copied().unwrap_or((0.0, 0.0));
        hi + (lo + (t + atanf_tail(t)))
    } else {
        let j = (16.0 / a + 0.5) as usize;
        let c = j as f32 * 0.0625;
        let t = (1.0 - a * c) / (a + c);
        let (hi, lo) = ATANF_COMP_J16.get(j).copied().unwrap_or((0.0, 0.0));
        hi + (lo - (t + atanf_tail(t)))
    };
    if x.is_sign_negative() {
        -r
    } else {
        r
    }
}

/// 64 bits of `2/pi` from 0-based bit position `pos` (bit 0 is the weight
/// 2^-1); positions before 0 are the zero integer bits.
#[inline]
fn two_over_pi_bits(pos: i32) -> u64 {
    let word = |k: i32| super::two_over_pi_word(i64::from(k));
    if pos < 0 {
        let sh = (-pos) as u32;
        if sh >= 64 {
            0
        } else {
            word(0) >> sh
        }
    } else {
        let (k, sh) = (pos / 64, (pos % 64) as u32);
        if sh == 0 {
            word(k)
        } else {
            (word(k) << sh) | (word(k + 1) >> (64 - sh))
        }
    }
}

/// `pi/2` in Q31 fixed point, rounded down (`0xC90FDAA2`).
const PIO2_Q31: u64 = 0xc90f_daa2;

/// Reduction `x = n pi/2 + y`, `|y| <= ~pi/4`, for finite `|x| > pi/4`
/// (only `n mod 4` is meaningful), with integers: `|x| = m 2^e` (24-bit
/// `m`); the 96 bits `W` of `2/pi` from bit `e - 2` on give
/// `|x| 2/pi mod 4 = m W 2^-94` to 2^-70; bits 94-95 of `m W` are the
/// quadrant, the next 64 the fraction `f`, rounded to the nearest quadrant
/// (`f >= 1/2`: `n + 1`, `f - 1`); `|f| 2^64` normalised (`lz` leading
/// zeros shifted out), its top 32 bits times `pi/2` in Q31 give a 64-bit `P`
/// and `|y| = float(P) 2^(-63 - lz)` (one rounding, the truncations < 2^-30
/// relative).
fn rem_pio2f(x: f32) -> (i32, f32) {
    let bits = x.to_bits();
    let e = ((bits >> 23) & 0xff) as i32 - 150;
    let m = u64::from((bits & 0x007f_ffff) | 0x0080_0000);
    let hi64 = two_over_pi_bits(e - 2);
    let lo32 = two_over_pi_bits(e + 62) >> 32;
    // m W with W = hi64 2^32 + lo32, in three 32-bit limbs.
    let p2 = m * lo32;
    let p1 = m * (hi64 & 0xffff_ffff) + (p2 >> 32);
    let p0 = m * (hi64 >> 32) + (p1 >> 32);
    let mut n = ((p0 >> 30) & 3) as i32;
    let frac = ((p0 & 0x3fff_ffff) << 34) | ((p1 & 0xffff_ffff) << 2) | ((p2 & 0xffff_ffff) >> 30);
    let (neg, mag) = if frac >> 63 != 0 {
        n += 1;
        (true, frac.wrapping_neg())
    } else {
        (false, frac)
    };
    let y = if mag == 0 {
        0.0
    } else {
        let lz = mag.leading_zeros() as i32;
        let top = (mag << lz) >> 32;
        (top * PIO2_Q31) as f32 * pow2f(-63 - lz)
    };
    let y = if neg { -y } else { y };
    if x < 0.0 {
        (-n, -y)
    } else {
        (n, y)
    }
}

/// Taylor coefficients of `sin`: `-1/6, 1/120, -1/5040, 1/362880`.
const SINF_S: [f32; 4] = [-0.166_666_67, 8.333_334e-3, -1.984_127e-4, 2.755_731_8e-6];
/// Taylor coefficients of `cos` beyond `1 - z/2`: `1/24, -1/720, 1/40320, -1/3628800`.
const COSF_C: [f32; 4] = [
    4.166_666_8e-2,
    -1.388_888_9e-3,
    2.480_158_7e-5,
    -2.755_731_8e-7,
];

/// `sin(y)` for `|y| <= ~pi/4`: `z = y*y`, `y + (y*z) * (S1 + z(S2 + z(S3 + z S4)))`.
#[inline]
fn kernel_sinf(y: f32) -> f32 {
    let [s1, s2, s3, s4] = SINF_S;
    let z = y * y;
    let p = s1 + z * (s2 + z * (s3 + z * s4));
    y + (y * z) * p
}

/// `cos(y)` for `|y| <= ~pi/4`: `z = y*y`, `q = (z*z) (C1 + z(C2 + z(C3 + z C4)))`,
/// `1 - (z/2 - q)`.
#[inline]
fn kernel_cosf(y: f32) -> f32 {
    let [c1, c2, c3, c4] = COSF_C;
    let z = y * y;
    let q = (z * z) * (c1 + z * (c2 + z * (c3 + z * c4)));
    1.0 - (0.5 * z - q)
}

/// `pi/4` rounded down to binary32.
const PIO4F: f32 = f32::from_bits(0x3f49_0fda);

/// Sine (binary32): NaN/inf -> NaN; `|x| < 2^-12` -> `x`; `|x| <= pi/4`
/// the kernel; else [`rem_pio2f`] and `[ks, kc, -ks, -kc][n mod 4]`.
pub fn sinf(x: f32) -> f32 {
    if !x.is_finite() {
        return f32::NAN;
    }
    let a = fabsf(x);
    if a < 1.0 / 4_096.0 {
        return x;
    }
    if a <= PIO4F {
        return kernel_sinf(x);
    }
    let (n, y) = rem_pio2f(x);
    match n & 3 {
        0 => kernel_sinf(y),
        1 => kernel_cosf(y),
        2 => -kernel_sinf(y),
        _ => -kernel_cosf(y),
    }
}

/// Cosine (binary32): NaN/inf -> NaN; `|x| < 2^-12` -> 1; `|x| <= pi/4` the
/// kernel; else `[kc, -ks, -kc, ks][n mod 4]`.
pub fn cosf(x: f32) -> f32 {
    if !x.is_finite() {
        return f32::NAN;
    }
    let a = fabsf(x);
    if a < 1.0 / 4_096.0 {
        return 1.0;
    }
    if a <= PIO4F {
        return kernel_cosf(x);
    }
    let (n, y) = rem_pio2f(x);
    match n & 3 {
        0 => kernel_cosf(y),
        1 => -kernel_sinf(y),
        2 => -kernel_cosf(y),
        _ => kernel_sinf(y),
    }
}

/// Below this `|v|`, [`sincf`] is `1 - v*v/6` (`v^4/120 < 2^-30`).
pub const SINCF_SMALL: f32 = 0.015_625; // 2^-6

/// `sin(v)/v`, 1 at 0 (binary32): `|v| < 2^-6`: `1 - (v*v)/6`, else `sinf(v)/v`.
pub fn sincf(v: f32) -> f32 {
    if fabsf(v) < SINCF_SMALL {
        1.0 - (v * v) / 6.0
    } else {
        sinf(v) / v
    }
}

/// `1/(k+1)!`, `k = 0..=8`, rounded to binary32 ([`exprelf`]'s series).
pub const EXPRELF_COEFFS: [f32; 9] = [
    1.0,
    0.5,
    0.166_666_67,
    0.041_666_668,
    8.333_334e-3,
    1.388_888_9e-3,
    1.984_127e-4,
    2.480_158_7e-5,
    2.755_731_8e-6,
];

/// `(e^v - 1)/v`, 1 at 0 (binary32): `|v| < 0.5`: `sum_{k<=8} v^k/(k+1)!` by
/// Horner from the highest coefficient (`p = p*v + c_k`; truncation below
/// 2^-30 relative); `+inf` -> `+inf`; otherwise `(expf(v) - 1)/v`.
pub fn exprelf(v: f32) -> f32 {
    if fabsf(v) < 0.5 {
        let mut p = 0.0f32;
        for c in EXPRELF_COEFFS.iter().rev() {
            let t = p * v;
            p = t + c;
        }
        p
    } else if v == f32::INFINITY {
        v
    } else {
        (expf(v) - 1.0) / v
    }
}
