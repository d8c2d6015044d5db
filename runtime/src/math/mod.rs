//! Elementary functions for `no_std` without libm: [`exp`], [`sqrt`], [`atan`]
//! (and [`atan2`]), [`sin`], [`cos`] (and [`sinc`]), [`exprel`], each for
//! `f64`, with `f32` variants ([`expf`], [`sqrtf`], [`atanf`], [`sinf`],
//! [`cosf`], [`sincf`], [`exprelf`]) evaluated in binary32 only (no double
//! operation: what a single-precision FPU runs; see `single.rs`).
//!
//! The algorithms are described step by step so that the C generator can emit
//! the same arithmetic (every operation below is one IEEE-754 binary64
//! operation, round to nearest, evaluated left to right, no fused
//! multiply-add).
//!
//! # Error bounds (measured by the tests against Rust's `std`, i.e. the
//! platform libm, over millions of random and edge arguments)
//!
//! | function | bound claimed | note |
//! |---|---|---|
//! | `sqrt` | correctly rounded (0 ulp) | identical to IEEE `sqrt` and C `sqrt` |
//! | `exp`  | < 1 ulp | subnormal results: < 1 ulp of the subnormal grid |
//! | `atan` | < 1 ulp | |
//! | `atan2`| < 2 ulp | via `atan(y/x)` plus quadrant fix |
//! | `sin`, `cos` | <= 1 ulp | every finite argument (Cody-Waite below `2^20 pi/2`, Payne-Hanek above); NaN/inf -> NaN |
//! | `sinc` | <= 2 ulp | `sin(v)/v`; `1 - v^2/6` for `|v| < 2^-13` |
//! | `exprel` | <= 2 ulp | `(exp(v) - 1)/v`; its Taylor polynomial (degree 14) for `|v| < 0.5` |
//! | `f32` variants | `sqrtf` 0 ulp; `expf`, `atanf` <= 1; `sinf`, `cosf` <= 2; `sincf`, `exprelf` <= 3 (f32 ulp) | binary32 arithmetic only (`single.rs`) |
//!
//! The C runtime (`runtime/c/tsf_runtime.c`) mirrors this arithmetic operation
//! by operation, with the same constants, so its `tsf_exp`, `tsf_sin`, ...
//! equal these functions bit for bit (C's `sqrt` and `fabs` are correctly
//! rounded and exact, so it calls them).

/// `ln 2` split: `LN2_HI` has 42 significant bits, so `k * LN2_HI` is exact for
/// `|k| < 2^11`; `LN2_HI + LN2_LO` equals `ln 2` to ~1e-30.
const LN2_HI: f64 = 0.6931471805598903; // 0x1.62e42fefa38p-1
const LN2_LO: f64 = 5.497923018708371e-14;
const INV_LN2: f64 = core::f64::consts::LOG2_E;
/// Largest `x` whose `exp(x)` rounds to a finite value.
const EXP_OVERFLOW: f64 = 709.782712893384;
/// Largest `x` whose `exp(x)` (<= 2^-1075) rounds to zero.
const EXP_UNDERFLOW: f64 = -745.1332191019412;

/// Taylor coefficients of `R(r) = r coth(r/2) = 2 + sum_n P_n r^(2n)`,
/// `P_n = 2 B_2n / (2n)!` (Bernoulli numbers): 1/6, -1/360, 1/15120,
/// -1/604800, 1/23950080, -691/653837184000. The first omitted term is
/// below 1e-17 relative for |r| <= ln2/2.
const EXP_P: [f64; 6] = [
    0.16666666666666666,
    -0.002777777777777778,
    6.613756613756614e-05,
    -1.6534391534391535e-06,
    4.17535139757362e-08,
    -1.0568380277374986e-09,
];

/// `2^k` for `-1022 <= k <= 1023` built from the exponent bits.
#[inline]
fn pow2(k: i32) -> f64 {
    // k is clamped by every caller; clamp again so the shift cannot misbehave.
    let k = k.clamp(-1022, 1023);
    f64::from_bits(((k + 1023) as u64) << 52)
}

/// Exponential `e^x` (binary64).
///
/// Algorithm (fdlibm-style, coefficients derived from the Bernoulli series):
/// 1. NaN -> NaN; `x > 709.782712893384` -> `+inf`;
///    `x <= -745.1332191019412` -> `+0`; `|x| < 2^-28` -> `1 + x`.
/// 2. `k = trunc(x * INV_LN2 + copysign(0.5, x))` (nearest integer to
///    `x / ln2`), `hi = x - k*LN2_HI` (exact), `lo = k*LN2_LO`,
///    `r = hi - lo`, `|r| <= 0.3466`.
/// 3. `s = r*r`, `c = r - s*(P1 + s*(P2 + s*(P3 + s*(P4 + s*(P5 + s*P6)))))`
///    (Horner, innermost first). Since `R(r) - r = 2 - c` and
///    `e^r = 1 + 2r/(R(r) - r)`: `y = 1 - ((lo - (r*c)/(2 - c)) - hi)`.
/// 4. Scale by `2^k`: for `k > 1023`: `y * 2 * 2^(k-1)`;
///    for `k < -1021`: `(y * 2^(k+1000)) * 2^-1000` (the only rounding is the
///    last product, into the subnormal range); otherwise `y * 2^k`.
pub fn exp(x: f64) -> f64 {
    if x.is_nan() {
        return x;
    }
    if x > EXP_OVERFLOW {
        return f64::INFINITY;
    }
    if x <= EXP_UNDERFLOW {
        return 0.0;
    }
    if fabs(x) < 3.725290298461914e-09 {
        // 2^-28: e^x = 1 + x + O(2^-57), the rounding of 1 + x is exact enough.
        return 1.0 + x;
    }
    let half = if x < 0.0 { -0.5 } else { 0.5 };
    // |x * INV_LN2| < 1076, so the cast is exact truncation toward zero.
    let k = (x * INV_LN2 + half) as i32;
    let kf = k as f64;
    let hi = x - kf * LN2_HI;
    let lo = kf * LN2_LO;
    let r = hi - lo;
    let s = r * r;
    // Horner from the innermost coefficient (0 * s + P6 = P6 exactly).
    let p = EXP_P.iter().rev().fold(0.0, |acc, &coef| coef + s * acc);
    let c = r - s * p;
    let y = 1.0 - ((lo - (r * c) / (2.0 - c)) - hi);
    if k > 1023 {
        y * 2.0 * pow2(k - 1)
    } else if k < -1021 {
        y * pow2(k + 1000) * pow2(-1000)
    } else {
        y * pow2(k)
    }
}

/// Floor of the square root of `n` and the remainder `n - q^2`
/// (binary digit-by-digit method, at most 64 iterations).
fn isqrt_rem(n: u128) -> (u128, u128) {
    let mut bit: u128 = 1 << 126;
    while bit > n {
        bit >>= 2;
    }
    let mut rem = n;
    let mut res: u128 = 0;
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

/// Square root, correctly rounded (binary64), computed with integers.
///
/// Algorithm: NaN, `+-0`, `+inf` return themselves; `x < 0` -> NaN.
/// Write `x = M * 2^E` with integer `M` in `[2^52, 2^53)` (subnormals
/// normalised); if `E` is odd, `M *= 2`, `E -= 1`. Then
/// `(q, rem) = isqrt(M * 2^52)` gives a 53-bit `q` with
/// `sqrt(x) ~= q * 2^((E-52)/2)`; round up iff `rem > q` (ties impossible).
/// Equal bit for bit to IEEE `sqrt` (C's `sqrt` is required to be correctly
/// rounded, so the C mirror may call it).
pub fn sqrt(x: f64) -> f64 {
    if x.is_nan() || x == 0.0 || x == f64::INFINITY {
        return x;
    }
    if x < 0.0 {
        return f64::NAN;
    }
    let bits = x.to_bits();
    let mut e = ((bits >> 52) & 0x7ff) as i32;
    let mut m = bits & ((1u64 << 52) - 1);
    if e == 0 {
        // Subnormal: normalise (m != 0 since x != 0).
        let shift = m.leading_zeros() as i32 - 11;
        m <<= shift;
        e = 1 - shift;
    } else {
        m |= 1u64 << 52;
    }
    // x = m * 2^(e - 1075)
    let mut big_e = e - 1075;
    let mut mm = m as u128;
    if big_e & 1 != 0 {
        mm <<= 1;
        big_e -= 1;
    }
    let (mut q, rem) = isqrt_rem(mm << 52);
    if rem > q {
        q += 1;
    }
    // result = q * 2^((big_e - 52)/2), q in [2^52, 2^53]; compose via bits
    // (q == 2^53 carries into the exponent field).
    let res_exp = (big_e - 52) / 2 + 52 + 1023; // biased exponent of q's leading bit
    let q = q as u64;
    f64::from_bits(((res_exp as u64) << 52).wrapping_add(q - (1u64 << 52)))
}

/// `(atan(j/16)` high, low`)`, j = 0..=39; `hi + lo` = atan(j/16) to ~1e-33.
/// Public so code generators emit the very constants [`atan`] uses.
pub const ATAN_J16: [(f64, f64); 40] = [
    (0.0, 0.0),
    (0.06241880999595735, -1.5490756308295046e-18),
    (0.12435499454676144, -3.1253241424539383e-18),
    (0.18534794999569476, 4.180692268843079e-18),
    (0.24497866312686414, 1.0698755618734451e-17),
    (0.3028848683749714, -1.1010827903001369e-17),
    (0.35877067027057225, -2.4623815582638635e-17),
    (0.4124104415973873, -1.587652227770689e-17),
    (0.4636476090008061, 2.2698777452961687e-17),
    (0.5123894603107377, -2.5462781472855804e-17),
    (0.5585993153435624, -5.4556305485916264e-18),
    (0.6022873461349642, 2.950430737228402e-17),
    (0.6435011087932844, 1.5834785051444286e-17),
    (0.6823165548747481, 6.943223671560008e-18),
    (0.7188299996216245, -2.1478388444456983e-17),
    (0.7531512809621944, -2.4256934659182068e-17),
    (core::f64::consts::FRAC_PI_4, 3.061616997868383e-17),
    (0.8156919233162234, -1.071456562778743e-17),
    (0.844153986113171, -4.841337011934917e-17),
    (0.870903457075653, -2.269823590747287e-17),
    (0.8960553845713439, 2.923876285774305e-17),
    (0.9197196053504169, -4.057439412852768e-17),
    (0.9420000403794636, 5.4608374858466876e-17),
    (0.9629943306809362, -3.9866605952107524e-18),
    (0.982793723247329, 1.3903311031230998e-17),
    (1.0014831356942346, 9.438308023545392e-17),
    (1.0191413442663497, 1.0004018869366799e-17),
    (1.0358412530088001, 3.194313981784504e-17),
    (1.0516502125483738, -9.650564731467514e-17),
    (1.0666303653157436, -5.956589637160375e-17),
    (1.0808390005411683, -1.5676322511359073e-17),
    (1.09432890732119, -5.490676155022364e-18),
    (1.1071487177940904, 9.40447137356638e-17),
    (1.1193432352423422, 6.954284199374601e-17),
    (1.1309537439791604, 7.123833804538446e-17),
    (1.1420182993488803, -9.642430524429942e-17),
    (1.1525719972156676, -9.159738508900379e-17),
    (1.1626472230398073, 6.255046986097143e-17),
    (1.1722738811284763, 8.385188614028674e-17),
    (1.1814796049617557, 1.511867738554561e-17),
];

/// `(pi/2 - atan(j/16))` high, low, j = 0..=7 (public like [`ATAN_J16`]).
pub const ATAN_COMP_J16: [(f64, f64); 8] = [
    (core::f64::consts::FRAC_PI_2, 6.123233995736766e-17),
    (1.5083775167989393, -6.6075234508751206e-18),
    (1.446441332248135, 9.211323971545052e-17),
    (1.3854483767992019, 1.540496457266753e-18),
    (1.3258176636680326, -8.824429373951136e-17),
    (1.2679114584199251, 7.224316786036903e-17),
    (1.2120256565243244, 3.034500430874847e-17),
    (1.1583858851975093, 2.1597711003816724e-17),
];

/// Taylor coefficients of `atan(t)/t - 1 = s*Q(s)`, `s = t^2`:
/// `Q_k = (-1)^(k+1) / (2k+1)`, k = 1..=11 (`-1/3, 1/5, ..., -1/23`). Used
/// for `|t| <= 1/8`; the first omitted term is below 2^-72 relative.
/// Public like [`ATAN_J16`].
pub const ATAN_Q: [f64; 11] = [
    -0.3333333333333333,
    0.2,
    -0.14285714285714285,
    0.1111111111111111,
    -0.09090909090909091,
    0.07692307692307693,
    -0.06666666666666667,
    0.058823529411764705,
    -0.05263157894736842,
    0.047619047619047616,
    -0.043478260869565216,
];

/// `atan(t) - t` for `|t| <= 1/8`: `t * (s * Q(s))`, Horner innermost first.
#[inline]
fn atan_poly_tail(t: f64) -> f64 {
    let s = t * t;
    let q = ATAN_Q.iter().rev().fold(0.0, |acc, &coef| coef + s * acc);
    t * (s * q)
}

/// Arc tangent (binary64), result in `[-pi/2, pi/2]`.
///
/// Algorithm on `a = |x|` (sign restored at the end, `atan(-0) = -0`):
/// 1. NaN -> NaN; `a < 2^-27` -> `x`; `a > 2^66` -> `+-(PIO2_HI + PIO2_LO)`.
/// 2. `a < 1/8`: `a + tail(a)` where `tail(t) = t*(s*Q(s))`, `s = t*t`,
///    `Q` the 11-term Taylor polynomial (Horner).
/// 3. `a <= 39/16`: `j = trunc(16a + 0.5)` (2..=39), `c = j/16`,
///    `t = (a - c)/(1 + a*c)` (numerator exact), `|t| <= 1/32`;
///    result `hi_j + (lo_j + (t + tail(t)))` with `(hi_j, lo_j)` = atan(j/16).
/// 4. `a > 39/16`: `j = trunc(16/a + 0.5)` (0..=7), `c = j/16`,
///    `t = (1 - a*c)/(a + c)` (= (1/a - c)/(1 + c/a)), `|t| <= 1/32`;
///    result `hi'_j + (lo'_j - (t + tail(t)))`, `(hi'_j, lo'_j)` =
///    pi/2 - atan(j/16).
pub fn atan(x: f64) -> f64 {
    if x.is_nan() {
        return x;
    }
    let a = fabs(x);
    if a < 7.450580596923828e-09 {
        // 2^-27: atan(x) = x (1 - x^2/3 + ...), the correction is < 2^-55 x.
        return x;
    }
    let r = if a > 7.378697629483821e19 {
        ATAN_COMP_J16[0].0 + ATAN_COMP_J16[0].1
    } else if a < 0.125 {
        a + atan_poly_tail(a)
    } else if a <= 2.4375 {
        // 2 <= j <= 39 since 0.125 <= a <= 2.4375.
        let j = (a * 16.0 + 0.5) as usize;
        let c = j as f64 * 0.0625;
        let t = (a - c) / (1.0 + a * c);
        let (hi, lo) = ATAN_J16.get(j).copied().unwrap_or((0.0, 0.0));
        hi + (lo + (t + atan_poly_tail(t)))
    } else {
        // 0 <= j <= 7 since 2.4375 < a <= 2^66.
        let j = (16.0 / a + 0.5) as usize;
        let c = j as f64 * 0.0625;
        let t = (1.0 - a * c) / (a + c);
        let (hi, lo) = ATAN_COMP_J16.get(j).copied().unwrap_or((0.0, 0.0));
        hi + (lo - (t + atan_poly_tail(t)))
    };
    if x.is_sign_negative() {
        -r
    } else {
        r
    }
}

/// `pi` split as high + low parts.
const PI_HI: f64 = core::f64::consts::PI;
const PI_LO: f64 = 1.2246467991473532e-16;

/// Two-argument arc tangent `atan2(y, x)` in `[-pi, pi]` (binary64).
///
/// Special values follow C99 Annex F (signed zeros, infinities); NaN in,
/// NaN out. Finite nonzero case: `x > 0` -> `atan(y/x)`;
/// `x < 0` -> `+-(PI_HI - (atan(|y/x|) - PI_LO))`. Error < 2 ulp (the
/// division `y/x` is rounded before `atan`); quotient overflow/underflow is
/// handled by `atan`'s own limits.
pub fn atan2(y: f64, x: f64) -> f64 {
    if x.is_nan() || y.is_nan() {
        return x + y;
    }
    let yneg = y.is_sign_negative();
    let sign = |v: f64| if yneg { -v } else { v };
    let pio2 = ATAN_COMP_J16[0].0;
    if y == 0.0 {
        return if x.is_sign_negative() { sign(PI_HI) } else { y };
    }
    if x == 0.0 {
        return sign(pio2);
    }
    if x.is_infinite() {
        if y.is_infinite() {
            let q = if x > 0.0 { 0.25 * PI_HI } else { 0.75 * PI_HI };
            return sign(q);
        }
        return if x > 0.0 { sign(0.0) } else { sign(PI_HI) };
    }
    if y.is_infinite() {
        return sign(pio2);
    }
    let q = atan(fabs(y / x));
    if x > 0.0 {
        sign(q)
    } else {
        sign(PI_HI - (q - PI_LO))
    }
}

/// `2/pi` as 64-bit words, most significant first: bit `i` (from 1) of the
/// binary expansion `2/pi = sum b_i 2^-i` is bit `63 - (i-1) % 64` of word
/// `(i-1) / 64`. 1280 bits; the largest double needs bits up to ~1165.
const TWO_OVER_PI: [u64; 20] = [
    0xA2F9_836E_4E44_1529,
    0xFC27_57D1_F534_DDC0,
    0xDB62_9599_3C43_9041,
    0xFE51_63AB_DEBB_C561,
    0xB724_6E3A_424D_D2E0,
    0x0649_2EEA_09D1_921C,
    0xFE1D_EB1C_B129_A73E,
    0xE882_35F5_2EBB_4484,
    0xE99C_7026_B45F_7E41,
    0x3991_D639_8353_39F4,
    0x9C84_5F8B_BDF9_283B,
    0x1FF8_97FF_DE05_980F,
    0xEF2F_118B_5A0A_6D1F,
    0x6D36_7ECF_27CB_09B7,
    0x4F46_3F66_9E5F_EA2D,
    0x7527_BAC7_EBE5_F17B,
    0x3D07_39F7_8A52_92EA,
    0x6BFB_5FB1_1F8D_5D08,
    0x5603_3046_FC7B_6BAB,
    0xF0CF_BC20_9AF4_361D,
];

/// `2/pi` rounded to nearest.
const INV_PIO2: f64 = f64::from_bits(0x3FE4_5F30_6DC9_C883);
/// Cody-Waite split of `pi/2` (fdlibm): `PIO2_1`, `PIO2_2`, `PIO2_3` hold 33
/// bits each (so `n * PIO2_k` is exact for `|n| < 2^20`), `PIO2_kT` is the
/// rest of `pi/2` after the first `k` parts.
const PIO2_1: f64 = f64::from_bits(0x3FF9_21FB_5440_0000);
const PIO2_1T: f64 = f64::from_bits(0x3DD0_B461_1A62_6331);
const PIO2_2: f64 = f64::from_bits(0x3DD0_B461_1A60_0000);
const PIO2_2T: f64 = f64::from_bits(0x3BA3_198A_2E03_7073);
const PIO2_3: f64 = f64::from_bits(0x3BA3_198A_2E00_0000);
const PIO2_3T: f64 = f64::from_bits(0x397B_839A_2520_49C1);
/// `pi/2 = PIO2_HI + PIO2_LO` to ~1e-33 (for the Payne-Hanek path).
const PIO2_HI: f64 = core::f64::consts::FRAC_PI_2;
const PIO2_LO: f64 = 6.123233995736766e-17;
/// Cody-Waite is used for `|x| < 2^20 * pi/2` (~1.647e6); beyond, Payne-Hanek.
const CODY_WAITE_LIMIT: f64 = 1_647_099.331_725_909;

/// Biased exponent field of `x`.
#[inline]
fn exponent_bits(x: f64) -> i32 {
    ((x.to_bits() >> 52) & 0x7ff) as i32
}

/// Splits `a` into `hi + lo` with 26-bit `hi` (Veltkamp; `|a| <= 2^996`).
#[inline]
fn split(a: f64) -> (f64, f64) {
    let c = 134_217_729.0 * a; // 2^27 + 1
    let hi = c - (c - a);
    (hi, a - hi)
}

/// `a * b = p + e` exactly (Dekker, no fused multiply-add).
#[inline]
fn two_prod(a: f64, b: f64) -> (f64, f64) {
    let p = a * b;
    let (ah, al) = split(a);
    let (bh, bl) = split(b);
    let e = (((ah * bh - p) + ah * bl) + al * bh) + al * bl;
    (p, e)
}

/// Word `k` of [`TWO_OVER_PI`], 0 outside the table (`k = -1` is the
/// all-zero integer part).
#[inline]
fn two_over_pi_word(k: i64) -> u64 {
    usize::try_from(k)
        .ok()
        .and_then(|k| TWO_OVER_PI.get(k))
        .copied()
        .unwrap_or(0)
}

/// Argument reduction `x = n pi/2 + (y0 + y1)`, `|y0 + y1| <= pi/4` (up to
/// rounding), `|y1| <= ulp(y0)/2`; returns `(n, y0, y1)` (only `n mod 4` is
/// meaningful). `x` must be finite and `|x| > pi/4`.
///
/// - `|x| < 2^20 pi/2`: Cody-Waite (fdlibm's `__ieee754_rem_pio2` medium
///   case): `n = trunc(x * 2/pi +- 1/2)`, `r = x - n PIO2_1` (exact),
///   `w = n PIO2_1T`, `y0 = r - w`; if more than 16 bits cancelled, a second
///   step with `PIO2_2`/`PIO2_2T`, and if more than 49, a third with
///   `PIO2_3`/`PIO2_3T`; `y1 = (r - y0) - w`. Good to ~85/118/151 bits.
/// - Larger `|x|`: Payne-Hanek with 192 bits of `2/pi` (see [`rem_pio2_large`]).
fn rem_pio2(x: f64) -> (i32, f64, f64) {
    if fabs(x) >= CODY_WAITE_LIMIT {
        return rem_pio2_large(x);
    }
    let half = if x < 0.0 { -0.5 } else { 0.5 };
    // |x * 2/pi| < 2^20: the cast truncates exactly.
    let n = (x * INV_PIO2 + half) as i32;
    let fnn = n as f64;
    let mut r = x - fnn * PIO2_1;
    let mut w = fnn * PIO2_1T;
    let mut y0 = r - w;
    let j = exponent_bits(x);
    if j - exponent_bits(y0) > 16 {
        let t = r;
        w = fnn * PIO2_2;
        r = t - w;
        w = fnn * PIO2_2T - ((t - r) - w);
        y0 = r - w;
        if j - exponent_bits(y0) > 49 {
            let t = r;
            w = fnn * PIO2_3;
            r = t - w;
            w = fnn * PIO2_3T - ((t - r) - w);
            y0 = r - w;
        }
    }
    let y1 = (r - y0) - w;
    (n, y0, y1)
}

/// Payne-Hanek reduction for finite `|x| >= 2^20 pi/2`.
///
/// Write `|x| = m 2^e` (`m` the 53-bit integer significand, `e >= -32`). The
/// bits `b_i` of `2/pi` with `i < e - 1` contribute multiples of 4 to
/// `|x| 2/pi` and are dropped; the next 192 bits form an integer `W`, and
/// `P = m W` (245 bits, exact in four 64-bit limbs) is `|x| 2/pi mod 4`
/// scaled by `2^190`. Bits 190-191 are the quadrant, the 190 bits below the
/// fraction `f` (rounded to nearest quadrant: `f in [-1/2, 1/2)`). Doubles
/// are never closer than ~2^-61 to a multiple of `pi/2`, so the top 128
/// fraction bits keep >= 64 significant bits; they are converted to a
/// double-double and multiplied by `PIO2_HI + PIO2_LO` (Dekker product).
fn rem_pio2_large(x: f64) -> (i32, f64, f64) {
    let bits = x.to_bits();
    let e = i64::from(exponent_bits(x)) - 1075;
    let m = (bits & ((1u64 << 52) - 1)) | (1u64 << 52);
    // Bit index (0-based from 2^-1) of the first kept bit: i - 1 = e - 2.
    let q = e - 2;
    let (k, s) = (q.div_euclid(64), q.rem_euclid(64) as u32);
    let word = |j: i64| {
        let a = two_over_pi_word(k + j);
        if s == 0 {
            a
        } else {
            (a << s) | (two_over_pi_word(k + j + 1) >> (64 - s))
        }
    };
    let (w0, w1, w2) = (word(0), word(1), word(2));
    let m = u128::from(m);
    let p2 = m * u128::from(w2);
    let p1 = m * u128::from(w1) + (p2 >> 64);
    let p0 = m * u128::from(w0) + (p1 >> 64);
    // P = p0 * 2^128 + (p1 mod 2^64) * 2^64 + (p2 mod 2^64), p0 < 2^117.
    let limb2 = p0 as u64;
    let limb3 = (p0 >> 64) as u64;
    let mut n = (((limb3 << 2) | (limb2 >> 62)) & 3) as i32;
    // Top 128 of the 190 fraction bits.
    let frac = (u128::from(limb2 & ((1u64 << 62) - 1)) << 66)
        | (u128::from(p1 as u64) << 2)
        | u128::from((p2 as u64) >> 62);
    let (neg, mag) = if frac >> 127 != 0 {
        n += 1;
        (true, frac.wrapping_neg())
    } else {
        (false, frac)
    };
    let (y0, y1) = if mag == 0 {
        (0.0, 0.0)
    } else {
        let lz = mag.leading_zeros();
        let norm = mag << lz;
        let a = (norm >> 64) as u64;
        let b = norm as u64;
        let hi = a as f64;
        // a - hi is exact in i128 (|a - hi| < 2^11).
        let lo = (i128::from(a) - hi as i128) as f64 * 18_446_744_073_709_551_616.0 + b as f64;
        // |f| = (hi * 2^64 + lo) * 2^(-128 - lz), lz <= 127: the scale
        // factors are normal powers of two, so the products are exact.
        let lz = lz as i32;
        let (fh, fl) = (hi * pow2(-64 - lz), lo * pow2(-128 - lz));
        let (ph, pe) = two_prod(fh, PIO2_HI);
        let tail = pe + (fh * PIO2_LO + fl * PIO2_HI);
        let y0 = ph + tail;
        let y1 = tail - (y0 - ph);
        if neg {
            (-y0, -y1)
        } else {
            (y0, y1)
        }
    };
    if x < 0.0 {
        (-n, -y0, -y1)
    } else {
        (n, y0, y1)
    }
}

/// Minimax coefficients of `sin` on `[-pi/4, pi/4]` (fdlibm `k_sin.c`).
const SIN_S: [f64; 6] = [
    f64::from_bits(0xBFC5_5555_5555_5549),
    f64::from_bits(0x3F81_1111_1110_F8A6),
    f64::from_bits(0xBF2A_01A0_19C1_61D5),
    f64::from_bits(0x3EC7_1DE3_57B1_FE7D),
    f64::from_bits(0xBE5A_E5E6_8A2B_9CEB),
    f64::from_bits(0x3DE5_D93A_5ACF_D57C),
];
/// Minimax coefficients of `cos` on `[-pi/4, pi/4]` (fdlibm `k_cos.c`).
const COS_C: [f64; 6] = [
    f64::from_bits(0x3FA5_5555_5555_554C),
    f64::from_bits(0xBF56_C16C_16C1_5177),
    f64::from_bits(0x3EFA_01A0_19CB_1590),
    f64::from_bits(0xBE92_7E4F_809C_52AD),
    f64::from_bits(0x3E21_EE9E_BDB4_B1C4),
    f64::from_bits(0xBDA8_FAE9_BE88_38D4),
];

/// `sin(x + y)` for `|x + y| <= ~pi/4`, `y` the tail of `x` (fdlibm/musl
/// `__sin`): `z = x^2`, `w = z^2`, `r = S2 + z(S3 + z S4) + z w (S5 + z S6)`,
/// `v = z x`, `x - ((z (y/2 - v r) - y) - v S1)`.
#[inline]
fn kernel_sin(x: f64, y: f64) -> f64 {
    let [s1, s2, s3, s4, s5, s6] = SIN_S;
    let z = x * x;
    let w = z * z;
    let r = s2 + z * (s3 + z * s4) + z * w * (s5 + z * s6);
    let v = z * x;
    x - ((z * (0.5 * y - v * r) - y) - v * s1)
}

/// `cos(x + y)` for `|x + y| <= ~pi/4` (fdlibm/musl `__cos`):
/// `r = z(C1 + z(C2 + z C3)) + w^2 (C4 + z(C5 + z C6))`, `hz = z/2`,
/// `t = 1 - hz`, `t + (((1 - t) - hz) + (z r - x y))`.
#[inline]
fn kernel_cos(x: f64, y: f64) -> f64 {
    let [c1, c2, c3, c4, c5, c6] = COS_C;
    let z = x * x;
    let w = z * z;
    let r = z * (c1 + z * (c2 + z * c3)) + w * w * (c4 + z * (c5 + z * c6));
    let hz = 0.5 * z;
    let t = 1.0 - hz;
    t + (((1.0 - t) - hz) + (z * r - x * y))
}

/// `pi/4` rounded down: below it no reduction is needed.
const PIO4: f64 = f64::from_bits(0x3FE9_21FB_5444_2D18);

/// Sine (binary64).
///
/// `x` NaN or infinite -> NaN; `|x| < 2^-26` -> `x`; `|x| <= pi/4` ->
/// kernel; otherwise [`rem_pio2`] to `n pi/2 + (y0 + y1)` and
/// `[ks, kc, -ks, -kc][n mod 4]` of the kernels at `(y0, y1)`. Valid (< 1
/// ulp typical, tested <= 1 ulp vs glibc) for every finite `x`: Cody-Waite
/// reduction up to `2^20 pi/2`, Payne-Hanek beyond. Never panics.
pub fn sin(x: f64) -> f64 {
    if !x.is_finite() {
        return f64::NAN;
    }
    let a = fabs(x);
    if a < 1.4901161193847656e-08 {
        // 2^-26: sin(x) = x (1 - x^2/6 ...), correction < 2^-53 x.
        return x;
    }
    if a <= PIO4 {
        return kernel_sin(x, 0.0);
    }
    let (n, y0, y1) = rem_pio2(x);
    match n & 3 {
        0 => kernel_sin(y0, y1),
        1 => kernel_cos(y0, y1),
        2 => -kernel_sin(y0, y1),
        _ => -kernel_cos(y0, y1),
    }
}

/// Cosine (binary64).
///
/// `x` NaN or infinite -> NaN; `|x| < 2^-27` -> 1; `|x| <= pi/4` ->
/// kernel; otherwise [`rem_pio2`] and `[kc, -ks, -kc, ks][n mod 4]`. Same
/// range and accuracy as [`sin`].
pub fn cos(x: f64) -> f64 {
    if !x.is_finite() {
        return f64::NAN;
    }
    let a = fabs(x);
    if a < 7.450580596923828e-09 {
        // 2^-27: cos(x) = 1 - x^2/2, x^2/2 < 2^-55 rounds away.
        return 1.0;
    }
    if a <= PIO4 {
        return kernel_cos(x, 0.0);
    }
    let (n, y0, y1) = rem_pio2(x);
    match n & 3 {
        0 => kernel_cos(y0, y1),
        1 => -kernel_sin(y0, y1),
        2 => -kernel_cos(y0, y1),
        _ => kernel_sin(y0, y1),
    }
}

/// `sign(v)`: 1 above 0, -1 below, 0 at (either) zero; NaN gives 0 (the
/// language's `sign`, shared by its evaluator and the simulator's tape).
pub fn sign(v: f64) -> f64 {
    if v > 0.0 {
        1.0
    } else if v < 0.0 {
        -1.0
    } else {
        0.0
    }
}

/// Below this `|v|`, [`sinc`] uses `1 - v^2/6` (the next Taylor term
/// `v^4/120 < 2^-59` is below a quarter ulp of 1).
pub const SINC_SMALL: f64 = 1.220703125e-4; // 2^-13

/// `sinc(v) = sin(v)/v`, 1 at 0 (binary64).
///
/// `|v| < 2^-13` ([`SINC_SMALL`]): `1 - (v*v)/6` (Taylor, truncation error
/// `< v^4/120 < 2^-59`, so < 1 ulp); otherwise `sin(v)/v` (< 2 ulp). NaN
/// and `+-inf` give NaN (as `sin`). The C runtime's `tsf_sinc` is the same
/// branch around its mirror of [`sin`].
pub fn sinc(v: f64) -> f64 {
    if fabs(v) < SINC_SMALL {
        1.0 - (v * v) / 6.0
    } else {
        sin(v) / v
    }
}

/// Below this `|v|`, [`exprel`] evaluates its Taylor series ([`EXPREL_COEFFS`]);
/// at and above it, `(exp(v) - 1)/v`.
pub const EXPREL_SMALL: f64 = 0.5;

/// Taylor coefficients of `exprel(v) = sum_k v^k / (k+1)!`, `k = 0..=14`:
/// `1/(k+1)!` as binary64 literals (each the correctly rounded quotient; the
/// C runtime's `tsf_exprel_c` holds the same literals).
pub const EXPREL_COEFFS: [f64; 15] = [
    1.0,
    0.5,
    0.16666666666666666,
    0.041666666666666664,
    0.008333333333333333,
    0.001388888888888889,
    0.0001984126984126984,
    2.48015873015873e-05,
    2.7557319223985893e-06,
    2.755731922398589e-07,
    2.505210838544172e-08,
    2.08767569878681e-09,
    1.6059043836821613e-10,
    1.1470745597729725e-11,
    7.647163731819816e-13,
];

/// `exprel(v) = (e^v - 1)/v`, 1 at 0 (binary64).
///
/// `|v| < 0.5` ([`EXPREL_SMALL`]): the Taylor polynomial of degree 14,
/// `sum_{k=0}^{14} v^k/(k+1)!`, by Horner from the highest coefficient
/// ([`EXPREL_COEFFS`]; `p = p*v + c_k`, one product then one sum, no fused
/// multiply-add). Its truncation error is below
/// `0.5^15/16! / (1 - 0.5/17) < 1.6e-18` absolute, and `exprel(v) >= 0.78`
/// there, so below `2^-58` relative (under 2^-54 as required). Otherwise
/// `(exp(v) - 1)/v` with [`exp`] (the C runtime's `tsf_exp` mirrors it). NaN gives NaN, `+inf` gives `+inf`, `-inf` gives 0;
/// once `exp(v)` overflows (`v > 709.78`) the result is `+inf` (the true
/// value overflows a little later, near `v = 716`).
pub fn exprel(v: f64) -> f64 {
    if fabs(v) < EXPREL_SMALL {
        // From 0: the first step gives c_14 exactly (0 * v + c_14), as the
        // C runtime's start at c_14.
        let mut p = 0.0;
        for c in EXPREL_COEFFS.iter().rev() {
            let t = p * v;
            p = t + c;
        }
        p
    } else if v == f64::INFINITY {
        v
    } else {
        (exp(v) - 1.0) / v
    }
}

/// Absolute value by clearing the sign bit (usable without `std`).
#[inline]
fn fabs(x: f64) -> f64 {
    f64::from_bits(x.to_bits() & !(1u64 << 63))
}

mod single;
pub use single::{
    atanf, cosf, expf, exprelf, sincf, sinf, sqrtf, ATANF_COMP_J16, ATANF_J16, ATANF_Q,
    EXPRELF_COEFFS, F32_ELEMENTARY_ULP, SINCF_SMALL,
};

#[cfg(test)]
mod tests;
