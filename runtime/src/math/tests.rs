//! Tests of the elementary functions against `std` (the platform libm).
use super::*;
use std::println;

/// SplitMix64, enough for test sampling.
struct Rng(core::cell::Cell<u64>);
fn rng(seed: u64) -> Rng {
    Rng(core::cell::Cell::new(seed))
}
impl Rng {
    fn next(&self) -> u64 {
        self.0.set(self.0.get().wrapping_add(0x9E37_79B9_7F4A_7C15));
        let mut z = self.0.get();
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn uniform(&self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * ((self.next() >> 11) as f64 / (1u64 << 53) as f64)
    }
    /// Random finite double of any magnitude (uniform bit pattern).
    fn any_finite(&self) -> f64 {
        loop {
            let v = f64::from_bits(self.next());
            if v.is_finite() {
                return v;
            }
        }
    }
}

/// Distance in units in the last place (number of representable doubles
/// between a and b); 0 for equal values incl. both NaN.
fn ulps(a: f64, b: f64) -> u64 {
    if a.is_nan() && b.is_nan() {
        return 0;
    }
    if a.is_nan() || b.is_nan() {
        return u64::MAX;
    }
    let key = |v: f64| {
        let bits = v.to_bits() as i64;
        if bits < 0 {
            i64::MIN - bits
        } else {
            bits
        }
    };
    key(a).abs_diff(key(b))
}

fn check(
    name: &str,
    f: impl Fn(f64) -> f64,
    g: impl Fn(f64) -> f64,
    xs: &mut dyn Iterator<Item = f64>,
    tol: u64,
) {
    let (mut worst, mut at, mut n, mut off) = (0u64, 0.0, 0usize, 0usize);
    for x in xs {
        let d = ulps(f(x), g(x));
        off += usize::from(d > 0);
        if d > worst {
            worst = d;
            at = x;
        }
        n += 1;
    }
    println!("{name}: {n} samples, max {worst} ulp (at {at:e}), {off} differ from std");
    assert!(
        worst <= tol,
        "{name}: {worst} ulp at x = {at:e}: {} vs {}",
        f(at),
        g(at)
    );
}

const SPECIAL: [f64; 16] = [
    0.0,
    -0.0,
    f64::INFINITY,
    f64::NEG_INFINITY,
    f64::NAN,
    f64::MIN_POSITIVE,
    -f64::MIN_POSITIVE,
    5e-324,
    -5e-324,
    f64::MAX,
    f64::MIN,
    1.0,
    -1.0,
    0.5,
    2.4375,
    1e-300,
];

#[test]
fn exp_vs_std() {
    let r = rng(1);
    let mut xs = SPECIAL
        .into_iter()
        .chain([
            EXP_OVERFLOW,
            EXP_UNDERFLOW,
            709.78,
            -708.39,
            -745.13,
            -745.0,
            3.725e-9,
            -3.8e-9,
        ])
        .chain((0..1_000_000).map(|_| r.uniform(-746.0, 710.0)))
        .chain((0..1_000_000).map(|_| r.uniform(-2.0, 2.0)))
        .chain((0..200_000).map(|_| r.uniform(-745.2, -708.0))) // subnormal results
        .chain((0..200_000).map(|_| r.uniform(-1e-6, 1e-6)))
        .chain((0..200_000).map(|_| r.any_finite()))
        .chain((0..1000).map(|i| i as f64 * core::f64::consts::LN_2 * 0.5 - 250.0));
    check("exp", exp, f64::exp, &mut xs, 1);
    assert_eq!(exp(0.0), 1.0);
    assert!(ulps(exp(1.0), core::f64::consts::E) <= 1);
    assert_eq!(exp(f64::NEG_INFINITY), 0.0);
    assert_eq!(exp(f64::INFINITY), f64::INFINITY);
    assert!(exp(f64::NAN).is_nan());
    assert_eq!(exp(EXP_OVERFLOW + 1e-13), f64::INFINITY);
    assert!(exp(EXP_OVERFLOW).is_finite());
    assert_eq!(exp(-745.2), 0.0);
    assert_eq!(exp(-745.13), 5e-324);
}

#[test]
fn sqrt_is_correctly_rounded() {
    let r = rng(2);
    let mut xs = SPECIAL
        .into_iter()
        .chain((0..2_000_000).map(|_| r.any_finite().abs()))
        .chain((0..200_000).map(|_| f64::from_bits(r.next() >> 12))) // subnormals
        .chain((0..200_000).map(|_| r.uniform(0.0, 4.0)))
        .chain((0..1000).map(|i| (i * i) as f64));
    check("sqrt", sqrt, f64::sqrt, &mut xs, 0);
    assert!(sqrt(-1.0).is_nan());
    assert!(sqrt(f64::NEG_INFINITY).is_nan());
    assert_eq!(sqrt(-0.0).to_bits(), (-0.0f64).to_bits());
}

#[test]
fn atan_vs_std() {
    let r = rng(3);
    let mut xs = SPECIAL
        .into_iter()
        .chain([
            0.125,
            -0.125,
            0.124999,
            2.43751,
            7.4e-9,
            7.5e-9,
            7.378697629483821e19,
            1e20,
        ])
        .chain((0..1_000_000).map(|_| r.uniform(-3.0, 3.0)))
        .chain((0..500_000).map(|_| r.uniform(-0.2, 0.2)))
        .chain((0..500_000).map(|_| r.uniform(-100.0, 100.0)))
        .chain((0..500_000).map(|_| r.any_finite()))
        .chain((0..=640).map(|j| j as f64 / 256.0));
    check("atan", atan, f64::atan, &mut xs, 1);
    assert_eq!(atan(1.0), core::f64::consts::FRAC_PI_4);
    assert_eq!(atan(f64::INFINITY), core::f64::consts::FRAC_PI_2);
    assert_eq!(atan(f64::NEG_INFINITY), -core::f64::consts::FRAC_PI_2);
    assert_eq!(atan(-0.0).to_bits(), (-0.0f64).to_bits());
}

#[test]
fn atan2_vs_std() {
    let r = rng(4);
    let (mut worst, mut at) = (0u64, (0.0, 0.0));
    let specials = SPECIAL;
    let pairs = specials
        .iter()
        .flat_map(|&y| specials.iter().map(move |&x| (y, x)))
        .chain((0..500_000).map(|_| (r.uniform(-5.0, 5.0), r.uniform(-5.0, 5.0))))
        .collect::<std::vec::Vec<_>>();
    let r = rng(5);
    let more = (0..300_000).map(|_| (r.any_finite(), r.any_finite()));
    for (y, x) in pairs.into_iter().chain(more) {
        let d = ulps(atan2(y, x), y.atan2(x));
        if d > worst {
            worst = d;
            at = (y, x);
        }
    }
    println!("atan2: max {worst} ulp at {at:?}");
    assert!(worst <= 2, "atan2 {worst} ulp at {at:?}");
}

#[test]
fn sin_cos_vs_std() {
    let r = rng(7);
    let near_multiples = (1..=20_000i64).flat_map(|k| {
        let c = k as f64 * core::f64::consts::FRAC_PI_2;
        [c, -c, next_up(c), next_down(c)]
    });
    // Large arguments known to be close to multiples of pi/2.
    let hard = [
        5209945343388523.0 * 2f64.powi(-40),
        1.0e22,
        CODY_WAITE_LIMIT,
        next_down(CODY_WAITE_LIMIT),
        PIO4,
        next_up(PIO4),
        1.4901161193847656e-08,
        7.450580596923828e-09,
        355.0,
        103_993.0,
        1_146_408.0,
    ];
    let xs: std::vec::Vec<f64> = SPECIAL
        .into_iter()
        .chain(hard.iter().flat_map(|&h| [h, -h]))
        .chain((0..600_000).map(|_| r.uniform(-10.0, 10.0)))
        .chain((0..300_000).map(|_| r.uniform(-2e6, 2e6)))
        .chain((0..200_000).map(|_| r.uniform(-1e-3, 1e-3)))
        .chain((0..200_000).map(|_| r.uniform(-1e12, 1e12)))
        .chain((0..300_000).map(|_| r.any_finite()))
        .chain(near_multiples)
        .collect();
    check("sin", sin, f64::sin, &mut xs.iter().copied(), 1);
    check("cos", cos, f64::cos, &mut xs.iter().copied(), 1);
    check(
        "sinc",
        sinc,
        |v| if v == 0.0 { 1.0 } else { v.sin() / v },
        &mut xs.iter().copied(),
        2,
    );
    // The worst case of argument reduction for doubles (Muller,
    // "Elementary Functions"): x mod pi/2 = 4.6871659242546276e-19,
    // n = 1 mod 4. glibc 2.36's cos is 8 ulp off here; the exact value
    // (computed with 1500-bit pi) rounds to 0x1.14ae72e6ba22fp-61.
    let worst = 6381956970095103.0 * 2f64.powi(797);
    let exact = f64::from_bits(0x3C21_4AE7_2E6B_A22F);
    assert_eq!(cos(worst), -exact);
    assert_eq!(cos(-worst), -exact);
    assert_eq!(sin(worst), 1.0);
    assert_eq!(sin(-worst), -1.0);
    assert_eq!(sin(1e22), -0.8522008497671888);
    assert_eq!(sin(-0.0).to_bits(), (-0.0f64).to_bits());
    assert_eq!(cos(0.0), 1.0);
    assert!(sin(f64::INFINITY).is_nan() && cos(f64::NEG_INFINITY).is_nan());
    assert!(sin(f64::NAN).is_nan() && cos(f64::NAN).is_nan() && sinc(f64::NAN).is_nan());
    assert_eq!(sinc(0.0), 1.0);
    assert_eq!(sinc(-0.0), 1.0);
    assert_eq!(sinc(5e-324), 1.0);
    assert!(sinc(f64::INFINITY).is_nan());
    // Both branches of sinc agree at the switch point to < 1 ulp of 1.
    let below = sinc(next_down(SINC_SMALL));
    let at = sinc(SINC_SMALL);
    assert!(ulps(below, at) <= 2, "{below} vs {at}");
}

fn next_up(v: f64) -> f64 {
    f64::from_bits(v.to_bits() + 1)
}

fn next_down(v: f64) -> f64 {
    f64::from_bits(v.to_bits() - 1)
}

/// Largest error, in ulp of the binary32 grid at the reference, of `f`
/// against `reference` (the binary64 function, < 1 ulp of binary64) over the
/// f32 in `[lo, hi]`, every `stride`-th bit pattern; NaN must match NaN.
fn f32_worst(f: fn(f32) -> f32, reference: fn(f64) -> f64, lo: f32, hi: f32, stride: u32) -> f64 {
    let mut worst = 0.0f64;
    let mut check = |x: f32| {
        let (got, want) = (f(x), reference(f64::from(x)));
        if want.is_nan() {
            assert!(got.is_nan(), "{x:e}: {got:e} for NaN");
            return;
        }
        let r = want as f32;
        let ulp = if r == 0.0 || !r.is_finite() {
            f64::from(f32::from_bits(1))
        } else {
            let e = ((r.to_bits() >> 23) & 0xff) as i32;
            f64::powi(2.0, e.max(1) - 150)
        };
        let err = if got == r {
            0.0
        } else {
            (f64::from(got) - want).abs() / ulp
        };
        assert!(
            err.is_finite() || got == r,
            "{x:e}: {got:e} against {want:e}"
        );
        worst = worst.max(err);
    };
    for v in [lo, hi] {
        check(v);
    }
    // Walk the bit patterns of [lo, hi] (split at zero).
    let walk = |a: f32, b: f32, check: &mut dyn FnMut(f32)| {
        let (ua, ub) = (a.to_bits(), b.to_bits());
        let mut u = ua.min(ub);
        while u <= ua.max(ub) {
            check(f32::from_bits(u));
            u = match u.checked_add(stride) {
                Some(v) => v,
                None => break,
            };
        }
    };
    if lo < 0.0 && hi > 0.0 {
        walk(-0.0, lo, &mut check);
        walk(0.0, hi, &mut check);
    } else {
        walk(lo, hi, &mut check);
    }
    worst
}

/// The binary32 functions against the binary64 ones over dense samples of
/// their ranges (stride 97 over the bit patterns: ~2e7 arguments each for
/// the wide ranges; `TSF_F32_STRIDE=1` walks every f32, the measurement
/// behind the bounds of `single.rs`).
#[test]
fn f32_functions_vs_f64() {
    let stride = std::env::var("TSF_F32_STRIDE")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(97u32);
    let big = 1.0e30f32;
    let e = f32_worst(expf, exp, -87.3, 88.7, stride);
    let s = f32_worst(sqrtf, sqrt, 0.0, f32::MAX, stride);
    let a = f32_worst(atanf, atan, -f32::MAX, f32::MAX, stride);
    let si = f32_worst(sinf, sin, -big, big, stride);
    let co = f32_worst(cosf, cos, -big, big, stride);
    let sc = f32_worst(sincf, sinc, -1.0e4, 1.0e4, stride);
    let er = f32_worst(exprelf, exprel, -80.0, 80.0, stride);
    println!("f32 worst ulp (stride {stride}): exp {e:.3}, sqrt {s:.3}, atan {a:.3}, sin {si:.3}, cos {co:.3}, sinc {sc:.3}, exprel {er:.3}");
    assert!(s <= 0.5, "sqrtf is correctly rounded");
    assert!(
        e <= F32_ELEMENTARY_ULP / 2.0,
        "expf within half the certificate's bound"
    );
    assert!(a <= 1.0 && si <= 2.0 && co <= 2.0 && sc <= 3.0 && er <= 3.0);
    // Special values.
    assert!(expf(f32::NAN).is_nan() && sinf(f32::INFINITY).is_nan() && cosf(f32::NAN).is_nan());
    assert_eq!(expf(f32::INFINITY), f32::INFINITY);
    assert_eq!(expf(f32::NEG_INFINITY), 0.0);
    assert_eq!(expf(89.0), f32::INFINITY);
    assert!(sqrtf(-1.0).is_nan());
    assert_eq!(sqrtf(f32::from_bits(1)), f32::from_bits(1).sqrt());
    assert_eq!(atanf(f32::INFINITY), core::f32::consts::FRAC_PI_2);
    assert_eq!(atanf(-0.0).to_bits(), (-0.0f32).to_bits());
    assert_eq!(sincf(0.0), 1.0);
}

/// A double-double `(hi, lo)`, `hi + lo` exact to ~2^-106 relative.
type Dd = (f64, f64);

fn dd_add(a: Dd, b: Dd) -> Dd {
    let s = a.0 + b.0;
    let bb = s - a.0;
    let e = (a.0 - (s - bb)) + (b.0 - bb) + a.1 + b.1;
    let hi = s + e;
    (hi, e - (hi - s))
}

fn dd_mul_f(a: Dd, v: f64) -> Dd {
    let p = a.0 * v;
    let e = a.0.mul_add(v, -p) + a.1 * v;
    let hi = p + e;
    (hi, e - (hi - p))
}

fn dd_div_f(a: Dd, d: f64) -> Dd {
    let q = a.0 / d;
    let r = (-q).mul_add(d, a.0) + a.1;
    let q2 = r / d;
    let hi = q + q2;
    (hi, q2 - (hi - q))
}

/// `exprel(v)` from its Taylor series in double-double (60 terms), rounded
/// once: an independent reference for `|v| <= 2` (no Horner, no shared
/// coefficients: the terms are `v^k/(k+1)!` built by the recurrence).
fn exprel_series_dd(v: f64) -> f64 {
    let (mut term, mut sum): (Dd, Dd) = ((1.0, 0.0), (1.0, 0.0));
    for k in 1..60 {
        term = dd_div_f(dd_mul_f(term, v), (k + 1) as f64);
        sum = dd_add(sum, term);
    }
    sum.0 + sum.1
}

/// `exprel(v)` from std's `exp_m1` (an independent libm implementation),
/// the quotient corrected by its remainder: the error is `exp_m1`'s (< 1 ulp).
fn exprel_std(v: f64) -> f64 {
    if v == 0.0 {
        return 1.0;
    }
    let e = v.exp_m1();
    let q = e / v;
    if !q.is_finite() {
        return q;
    }
    q + (-q).mul_add(v, e) / v
}

#[test]
fn exprel_vs_independent_references() {
    let r = rng(7);
    let half = EXPREL_SMALL;
    let edges = [
        half,
        next_up(half),
        next_down(half),
        next_down(next_down(half)),
        1e-300,
        5e-324,
        2.2250738585072014e-308,
        1e-17,
        1e-9,
        1.4901161193847656e-08,
        0.25,
        1.0,
        2.0,
    ];
    let small: std::vec::Vec<f64> = [0.0, -0.0]
        .into_iter()
        .chain(edges.iter().flat_map(|&h| [h, -h]))
        .chain((0..400_000).map(|_| r.uniform(-0.5, 0.5)))
        .chain((0..200_000).map(|_| r.uniform(-2.0, 2.0)))
        .chain((0..100_000).map(|_| r.uniform(-1e-6, 1e-6)))
        .chain((0..50_000).map(|_| f64::from_bits(r.next() >> 13) * 0.5f64.powi(8)))
        .collect();
    check(
        "exprel (series branch vs series dd)",
        exprel,
        exprel_series_dd,
        &mut small.iter().copied().filter(|v| v.abs() < half),
        1,
    );
    check(
        "exprel (series dd)",
        exprel,
        exprel_series_dd,
        &mut small.iter().copied(),
        2,
    );
    let wide: std::vec::Vec<f64> = small
        .iter()
        .copied()
        .chain((0..300_000).map(|_| r.uniform(-40.0, 40.0)))
        .chain((0..200_000).map(|_| r.uniform(-745.0, 709.0)))
        .chain((0..100_000).map(|_| -r.uniform(0.0, 1.0) * 1e300))
        .collect();
    check(
        "exprel (std exp_m1)",
        exprel,
        exprel_std,
        &mut wide.iter().copied(),
        3,
    );
    // Special values.
    assert!(exprel(f64::NAN).is_nan() && exprelf(f32::NAN).is_nan());
    assert_eq!(exprel(f64::INFINITY), f64::INFINITY);
    assert_eq!(exprel(f64::NEG_INFINITY).to_bits(), 0.0f64.to_bits());
    assert_eq!(exprel(0.0), 1.0);
    assert_eq!(exprel(-0.0), 1.0);
    assert_eq!(exprel(5e-324), 1.0);
    assert_eq!(exprel(-5e-324), 1.0);
    assert_eq!(exprel(-1e300), 1e-300);
    assert_eq!(exprelf(0.0), 1.0);
    assert_eq!(exprelf(f32::INFINITY), f32::INFINITY);
    // Both branches agree at the switch, on each side, to <= 2 ulp.
    for (below, at) in [(next_down(half), half), (next_up(-half), -half)] {
        let (b, a) = (exprel(below), exprel(at));
        println!("exprel switch at {at}: {b:e} vs {a:e}, {} ulp", ulps(b, a));
        assert!(ulps(b, a) <= 2, "{b} vs {a}");
    }
}
