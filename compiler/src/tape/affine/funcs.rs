//! The tape's scalar functions on affine forms. A smooth function is
//! linearized at the centre c of its argument (first-order Taylor form
//! f(c) + f'(c) (x - c)) with the remainder bounded by `M r^2 / 2`, M an
//! upper bound of |f''| on the argument's range and r its radius; when the
//! function's range on the argument's interval (monotone functions,
//! [-1, 1] for sin and cos) is narrower, that interval is taken instead.
//! `abs`, `min` and `max` use the Chebyshev (min-max) linear approximation
//! of a piecewise-linear function ([`chebyshev`]). The values of the
//! library's `sin`, `exp`, ... are taken with a relative slack of 16 EPS
//! (glibc documents errors below 1 ulp for these).

use super::{add_up, mul_up, rounding, Affine, Form, Noise, Unbounded, EPS};
use crate::tape::{Binary, Unary};
use std::f64::consts::PI;

/// Upper bound of pi.
const PI_UP: f64 = 3.141_592_653_589_794;
/// Lower bound of the minimum of sinc (-0.21723362821...).
const SINC_MIN: f64 = -0.217_233_7;

/// Error bound of a library function's value `v`.
fn value_err(v: f64) -> f64 {
    rounding(v.abs(), 14)
}

/// A first-order Taylor form: f(c) (error `fc_err`), slope f'(c) (error
/// `slope_err`) and `m2 >= |f''|` on the argument's range.
struct Taylor {
    fc: f64,
    fc_err: f64,
    slope: f64,
    slope_err: f64,
    m2: f64,
}

fn taylor(x: &Affine, t: Taylor, noise: &mut Noise) -> Form {
    if !(t.m2.is_finite() && t.slope.is_finite() && t.fc.is_finite()) {
        return Err(Unbounded);
    }
    let r = x.radius();
    let rem = mul_up(0.5 * t.m2.abs(), mul_up(r, r));
    let err = add_up(add_up(t.fc_err, mul_up(t.slope_err, r)), rem);
    x.linear().scale(t.slope, noise)?.shift(t.fc, err, noise)
}

/// The narrower of two enclosures (both sound).
fn best(a: Form, b: Form) -> Form {
    match (a, b) {
        (Ok(a), Ok(b)) => Ok(if a.radius() <= b.radius() { a } else { b }),
        (Ok(a), Err(_)) => Ok(a),
        (Err(_), b) => b,
    }
}

/// The interval of a monotone `f` on `[lo, hi]`, widened by the value errors.
fn monotone(f: impl Fn(f64) -> f64, lo: f64, hi: f64, noise: &mut Noise) -> Form {
    let (a, b) = (f(lo), f(hi));
    let (a, b) = (a.min(b), a.max(b));
    Affine::interval(a - value_err(a), b + value_err(b), noise)
}

/// The Chebyshev enclosure of a piecewise-linear `f` of `x`: `f(z)` lies in
/// `alpha z + [min e_j, max e_j]` with `e_j = f_j - alpha z_j` over the
/// candidate points `(z_j, f_j, err_j)` (the ends of the range of z where
/// it is taken and both one-sided values at every breakpoint inside; `err_j`
/// bounds the error of `f_j`). Exact (to rounding) where f is linear.
pub fn chebyshev(x: &Affine, alpha: f64, points: &[(f64, f64, f64)], noise: &mut Noise) -> Form {
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for &(z, f, err) in points {
        let az = alpha * z;
        let e = f - az;
        let slack = add_up(err, rounding(f.abs() + az.abs(), 2));
        lo = lo.min(e - slack);
        hi = hi.max(e + slack);
    }
    if !(lo.is_finite() && hi.is_finite()) {
        return Err(Unbounded);
    }
    let mid = 0.5 * lo + 0.5 * hi;
    let half = (hi - mid).max(mid - lo).next_up();
    x.scale(alpha, noise)?.shift(mid, half, noise)
}

/// `|x|`.
fn abs(x: &Affine, noise: &mut Noise) -> Form {
    let (lo, hi) = x.range();
    if lo >= 0.0 {
        return Ok(x.clone());
    }
    if hi <= 0.0 {
        return Ok(x.neg());
    }
    let alpha = (hi + lo) / (hi - lo);
    chebyshev(
        x,
        alpha,
        &[(lo, -lo, 0.0), (0.0, 0.0, 0.0), (hi, hi, 0.0)],
        noise,
    )
}

/// `1 / x` (`Unbounded` when the range of x contains 0).
pub fn recip(x: &Affine, noise: &mut Noise) -> Form {
    let (lo, hi) = x.range();
    recip_within(x, (lo, hi), noise)
}

/// `1 / x` where every true value of x is known to lie in `[lo, hi]` (a
/// range narrower than the form's, from other knowledge), `Unbounded` when
/// it contains 0.
pub fn recip_within(x: &Affine, (lo, hi): (f64, f64), noise: &mut Noise) -> Form {
    if !(lo > 0.0 || hi < 0.0) {
        return Err(Unbounded);
    }
    let near = lo.abs().min(hi.abs());
    let c = x.center();
    let fc = 1.0 / c;
    let t = taylor(
        x,
        Taylor {
            fc,
            fc_err: rounding(fc.abs(), 1),
            slope: -(fc * fc),
            slope_err: rounding(fc * fc, 3),
            m2: mul_up(2.0, 1.0 / (near * near * near)) * (1.0 + 8.0 * EPS),
        },
        noise,
    );
    best(t, monotone(|v| 1.0 / v, lo, hi, noise))
}

/// sinc(c) = sin(c)/c and its error bound.
fn sinc_value(c: f64) -> (f64, f64) {
    if c.abs() < 1e-3 {
        let c2 = c * c;
        (1.0 - c2 / 6.0, add_up(c2 * c2 / 120.0, rounding(1.0, 3)))
    } else {
        let v = c.sin() / c;
        (v, value_err(v))
    }
}

/// sinc'(c) = (c cos c - sin c) / c^2 and its error bound (a series below 0.5).
fn sinc_slope(c: f64) -> (f64, f64) {
    if c.abs() < 0.5 {
        let c2 = c * c;
        // -c/3 + c^3/30 - c^5/840 + c^7/45360 - c^9/3991680 (alternating,
        // decreasing terms: the next one bounds the truncation).
        let terms = [
            -1.0 / 3.0,
            1.0 / 30.0,
            -1.0 / 840.0,
            1.0 / 45_360.0,
            -1.0 / 3_991_680.0,
        ];
        let (mut v, mut p, mut mag) = (0.0, c, 0.0);
        for k in terms {
            v += k * p;
            mag += (k * p).abs();
            p *= c2;
        }
        let trunc = 2.0 * p.abs() / 518_918_400.0;
        (v, add_up(rounding(mag, 12), trunc))
    } else {
        let (s, co) = c.sin_cos();
        let v = (c * co - s) / (c * c);
        let mag = ((c * co).abs() + s.abs()) / (c * c);
        (v, rounding(mag, 30))
    }
}

/// `f(x)` for a unary function of the tape.
pub fn unary(f: Unary, x: &Affine, noise: &mut Noise) -> Form {
    let (lo, hi) = x.range();
    let c = x.center();
    let with = |fc: f64, slope: f64, m2: f64| Taylor {
        fc,
        fc_err: value_err(fc),
        slope,
        slope_err: value_err(slope),
        m2,
    };
    match f {
        Unary::Neg => Ok(x.neg()),
        Unary::Abs => abs(x, noise),
        Unary::Sign => {
            let a = if lo > 0.0 {
                1.0
            } else if lo < 0.0 {
                -1.0
            } else {
                0.0
            };
            let b = if hi < 0.0 {
                -1.0
            } else if hi > 0.0 {
                1.0
            } else {
                0.0
            };
            Affine::interval(a, b, noise)
        }
        Unary::Sqrt => {
            if hi < 0.0 {
                return Err(Unbounded);
            }
            let lo0 = lo.max(0.0);
            let i = monotone(f64::sqrt, lo0, hi, noise);
            if lo > 0.0 {
                let fc = c.sqrt();
                let m2 = 0.25 / (lo * lo.sqrt()) * (1.0 + 8.0 * EPS);
                best(taylor(x, with(fc, 0.5 / fc, m2), noise), i)
            } else {
                if lo < 0.0 {
                    noise.clipped = true;
                }
                i
            }
        }
        Unary::Ln => {
            if lo <= 0.0 {
                return Err(Unbounded);
            }
            let m2 = 1.0 / (lo * lo) * (1.0 + 8.0 * EPS);
            let t = taylor(x, with(c.ln(), 1.0 / c, m2), noise);
            best(t, monotone(f64::ln, lo, hi, noise))
        }
        Unary::Exp => {
            let m2 = hi.exp() * (1.0 + 32.0 * EPS);
            let fc = c.exp();
            best(
                taylor(x, with(fc, fc, m2), noise),
                monotone(f64::exp, lo, hi, noise),
            )
        }
        Unary::Sin => {
            let m2 = lo.abs().max(hi.abs()).min(1.0);
            let t = taylor(x, with(c.sin(), c.cos(), m2), noise);
            best(t, Affine::interval(-1.0, 1.0, noise))
        }
        Unary::Cos => {
            let t = taylor(x, with(c.cos(), -c.sin(), 1.0), noise);
            best(t, Affine::interval(-1.0, 1.0, noise))
        }
        Unary::Tan => {
            // No pole inside: cos has one sign at both ends of a range
            // narrower than pi (two zeros would need a width of pi).
            let (cl, ch) = (lo.cos(), hi.cos());
            if !(hi - lo < 3.0 && cl * ch > 0.0 && cl.abs() > 1e-9 && ch.abs() > 1e-9) {
                return Err(Unbounded);
            }
            let (tl, th) = (lo.tan(), hi.tan());
            let m2 = [tl, th]
                .iter()
                .map(|t| 2.0 * t.abs() * (1.0 + t * t))
                .fold(0.0, f64::max)
                * (1.0 + 64.0 * EPS);
            let fc = c.tan();
            let t = taylor(x, with(fc, 1.0 + fc * fc, m2), noise);
            best(t, monotone(f64::tan, lo, hi, noise))
        }
        Unary::Atan => {
            // |atan''| <= 3 sqrt(3) / 8 = 0.6495...
            let t = taylor(x, with(c.atan(), 1.0 / (1.0 + c * c), 0.65), noise);
            best(t, monotone(f64::atan, lo, hi, noise))
        }
        Unary::Sinc => {
            let (fc, fc_err) = sinc_value(c);
            let (slope, slope_err) = sinc_slope(c);
            // |sinc''| <= 1/3: sinc(x) = int_0^1 cos(x t) dt.
            let t = Taylor {
                fc,
                fc_err,
                slope,
                slope_err,
                m2: 1.0 / 3.0 + EPS,
            };
            // With `tight_ranges` (a range check, not a correlated bound):
            // the narrowest interval of the straddling and touching cases.
            let tight = noise.tight_ranges;
            let i = if (lo > 0.0 || tight && lo == 0.0) && hi < PI
                || (hi < 0.0 || tight && hi == 0.0) && lo > -PI
            {
                // Monotone on either side of 0 within (-pi, pi).
                let (a, ea) = sinc_value(lo);
                let (b, eb) = sinc_value(hi);
                Affine::interval(a.min(b) - ea.max(eb), a.max(b) + ea.max(eb), noise)
            } else if tight && lo > -PI && hi < PI {
                // Straddles 0 within (-pi, pi): sinc decreases in |x| there,
                // its maximum is sinc(0) = 1.
                let (a, ea) = sinc_value(lo);
                let (b, eb) = sinc_value(hi);
                Affine::interval(a.min(b) - ea.max(eb), 1.0, noise)
            } else {
                Affine::interval(SINC_MIN, 1.0, noise)
            };
            best(taylor(x, t, noise), i)
        }
        Unary::Exprel => {
            // Increasing: exprel(x) = int_0^1 exp(x t) dt.
            let g = tsf_runtime::math::exprel;
            let (a, b) = (g(lo), g(hi));
            if !b.is_finite() {
                return Err(Unbounded);
            }
            Affine::interval(a - rounding(a, 62), b + rounding(b, 62), noise)
        }
    }
}

/// `x ^ p` for a constant `p`.
fn pow_const(x: &Affine, p: f64, noise: &mut Noise) -> Form {
    if p == 0.0 {
        return Affine::constant(1.0);
    }
    if p == 1.0 {
        return Ok(x.clone());
    }
    if p == 2.0 {
        return x.sqr(noise);
    }
    if p == 0.5 {
        return unary(Unary::Sqrt, x, noise);
    }
    if p.fract() == 0.0 && p.abs() <= 64.0 {
        // Binary powering.
        // A negative power is a power of 1 / x (whose range stays away from 0).
        let mut k = p.abs() as u32;
        let mut base = if p < 0.0 { recip(x, noise)? } else { x.clone() };
        let mut acc: Option<Affine> = None;
        while k > 0 {
            if k & 1 == 1 {
                acc = Some(match acc {
                    None => base.clone(),
                    Some(a) => a.mul(&base, noise)?,
                });
            }
            k >>= 1;
            if k > 0 {
                base = base.sqr(noise)?;
            }
        }
        return acc.ok_or(Unbounded);
    }
    let l = unary(Unary::Ln, x, noise)?;
    unary(Unary::Exp, &l.scale(p, noise)?, noise)
}

/// `f(x, y)` for a binary function of the tape.
pub fn binary(f: Binary, x: &Affine, y: &Affine, noise: &mut Noise) -> Form {
    match f {
        Binary::Add => x.add(y, noise),
        Binary::Sub => x.sub(y, noise),
        Binary::Mul => x.mul(y, noise),
        Binary::Div | Binary::DivChecked => {
            if y.is_constant() {
                x.div_const(y.center(), noise)
            } else {
                x.mul(&recip(y, noise)?, noise)
            }
        }
        Binary::Pow => {
            if y.is_constant() {
                pow_const(x, y.center(), noise)
            } else {
                let l = unary(Unary::Ln, x, noise)?;
                unary(Unary::Exp, &l.mul(y, noise)?, noise)
            }
        }
        Binary::Atan2 => {
            if y.range().0 > 0.0 {
                unary(Unary::Atan, &x.mul(&recip(y, noise)?, noise)?, noise)
            } else {
                Affine::interval(-PI_UP, PI_UP, noise)
            }
        }
        Binary::Min | Binary::Max => {
            // min, max = (x + y -+ |x - y|) / 2
            let d = abs(&x.sub(y, noise)?, noise)?;
            let s = if f == Binary::Max { 0.5 } else { -0.5 };
            Affine::combine(&[(0.5, x), (0.5, y), (s, &d)], 0.0, noise)
        }
    }
}
