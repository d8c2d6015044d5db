//! Enclosure of every operation against dense point sampling on random
//! boxes, cancellation, the sector blend and the unbounded cases.

use super::*;
use crate::tape::{Binary, Builder, Unary};
use proptest::prelude::*;

/// The form of input 0 over `[lo, hi]` and a second input over `[lo2, hi2]`.
fn inputs(lo: f64, hi: f64, lo2: f64, hi2: f64) -> (Affine, Affine) {
    let x = Affine::input(lo, hi, 0).expect("finite");
    let y = Affine::input(lo2, hi2, 1).expect("finite");
    (x, y)
}

/// The point of `[lo, hi]` at noise coordinate `t` in [-1, 1], clamped to the
/// box (`lo + (hi - lo)` can round above `hi`: such a point is not in the box
/// the form encloses).
fn at(lo: f64, hi: f64, t: f64) -> f64 {
    (lo + (hi - lo) * 0.5 * (t + 1.0)).clamp(lo, hi)
}

/// Asserts that the range of `form` holds `v`.
fn holds(form: &Affine, v: f64, what: &str) {
    let (lo, hi) = form.range();
    assert!(
        v >= lo && v <= hi,
        "{what}: {v} outside [{lo}, {hi}] ({form:?})"
    );
}

const UNARY: [Unary; 12] = [
    Unary::Neg,
    Unary::Sqrt,
    Unary::Sin,
    Unary::Cos,
    Unary::Tan,
    Unary::Atan,
    Unary::Exp,
    Unary::Ln,
    Unary::Abs,
    Unary::Sign,
    Unary::Sinc,
    Unary::Exprel,
];

const BINARY: [Binary; 9] = [
    Binary::Add,
    Binary::Sub,
    Binary::Mul,
    Binary::Div,
    Binary::DivChecked,
    Binary::Pow,
    Binary::Atan2,
    Binary::Min,
    Binary::Max,
];

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// Every unary function's form holds f(x) at 201 points of the box
    /// (or is Unbounded where f is not finite on it).
    #[test]
    fn unary_forms_enclose_the_function(c in -4.0f64..4.0, r in 0.0f64..2.0) {
        let (lo, hi) = (c - r, c + r);
        let (x, _) = inputs(lo, hi, 0.0, 1.0);
        for f in UNARY {
            let mut noise = Noise::new(2);
            let Ok(form) = unary(f, &x, &mut noise) else {
                // Unbounded only where the function has no finite bound.
                prop_assert!(matches!(f, Unary::Sqrt | Unary::Ln | Unary::Tan | Unary::Exprel),
                    "{f:?} unbounded on [{lo}, {hi}]");
                continue;
            };
            for i in 0..=200 {
                let v = at(lo, hi, -1.0 + i as f64 / 100.0);
                let fv = f.apply(v);
                if fv.is_finite() {
                    holds(&form, fv, &format!("{f:?}({v})"));
                }
            }
        }
    }

    /// Every binary function's form holds f(x, y) on a 41 x 41 grid.
    #[test]
    fn binary_forms_enclose_the_function(
        c in -3.0f64..3.0, r in 0.0f64..1.5, c2 in -3.0f64..3.0, r2 in 0.0f64..1.5,
    ) {
        let (x, y) = inputs(c - r, c + r, c2 - r2, c2 + r2);
        for f in BINARY {
            let mut noise = Noise::new(2);
            let Ok(form) = binary(f, &x, &y, &mut noise) else {
                continue;
            };
            for i in 0..=40 {
                for j in 0..=40 {
                    let u = at(c - r, c + r, -1.0 + i as f64 / 20.0);
                    let v = at(c2 - r2, c2 + r2, -1.0 + j as f64 / 20.0);
                    let fv = f.apply(u, v);
                    if fv.is_finite() {
                        holds(&form, fv, &format!("{f:?}({u}, {v})"));
                    }
                }
            }
        }
    }

    /// A constant exponent: powers by squaring, roots, negative powers.
    #[test]
    fn constant_powers_enclose(c in 0.2f64..3.0, r in 0.0f64..0.15, k in 0usize..7) {
        let p = [2.0, 3.0, -1.0, -2.0, 0.5, 1.5, 7.0][k];
        let (x, _) = inputs(c - r, c + r, 0.0, 1.0);
        let mut noise = Noise::new(2);
        let form = binary(Binary::Pow, &x, &Affine::constant(p).expect("finite"), &mut noise)
            .expect("bounded away from 0");
        for i in 0..=100 {
            let v = at(c - r, c + r, -1.0 + i as f64 / 50.0);
            holds(&form, v.powf(p), &format!("{v}^{p}"));
        }
    }
}

#[test]
fn correlated_terms_cancel() {
    let (x, y) = inputs(-3.0, 5.0, 1.0, 2.0);
    let mut noise = Noise::new(2);
    let d = x.sub(&x, &mut noise).expect("bounded");
    assert!(d.abs_bound() <= 1e-14, "x - x = {d:?}");
    // (x + y) - y - x: linear forms cancel to rounding.
    let s = x.add(&y, &mut noise).expect("bounded");
    let t =
        Affine::combine(&[(1.0, &s), (-1.0, &y), (-1.0, &x)], 0.0, &mut noise).expect("bounded");
    assert!(t.abs_bound() <= 1e-13, "{t:?}");
    // A product is not linear: x * y - y * x still cancels (one node's form).
    let p = x.mul(&y, &mut noise).expect("bounded");
    assert!(p.sub(&p, &mut noise).expect("bounded").abs_bound() <= 1e-13);
    // Independent intervals do not cancel.
    let other = Affine::input(-3.0, 5.0, 7).expect("finite");
    assert!(x.sub(&other, &mut noise).expect("bounded").abs_bound() >= 8.0);
}

/// The sector blend h1 * (-d) + h2 * d of z = x1 on [-d, d], with
/// h1 = (z + d) / 2d, h2 = (d - z) / 2d normalized by their (affine) sum,
/// equals -z within rounding: the sector construction's cancellation.
#[test]
fn sector_blend_cancels() {
    let d = 25.0;
    let x = Affine::input(-d, d, 0).expect("finite");
    let mut noise = Noise::new(1);
    let points = |f: &dyn Fn(f64) -> f64| vec![(-d, f(-d), 0.0), (d, f(d), 0.0)];
    let h1 = chebyshev(
        &x,
        1.0 / (2.0 * d),
        &points(&|z| (z + d) / (2.0 * d)),
        &mut noise,
    )
    .expect("bounded");
    let h2 = chebyshev(
        &x,
        -1.0 / (2.0 * d),
        &points(&|z| (d - z) / (2.0 * d)),
        &mut noise,
    )
    .expect("bounded");
    let s = h1.add(&h2, &mut noise).expect("bounded");
    let inv = recip(&s, &mut noise).expect("near 1");
    let blend = Affine::combine(&[(-d, &h1), (d, &h2)], 0.0, &mut noise)
        .expect("bounded")
        .mul(&inv, &mut noise)
        .expect("bounded");
    let e = blend.add(&x, &mut noise).expect("bounded");
    assert!(e.abs_bound() <= 1e-12 * d, "blend + z = {e:?}");
}

#[test]
fn unbounded_cases() {
    let mut noise = Noise::new(2);
    let (x, y) = inputs(-1.0, 1.0, 1.0, 2.0);
    assert_eq!(recip(&x, &mut noise), Err(Unbounded), "1 / [-1, 1]");
    assert_eq!(
        binary(Binary::DivChecked, &y, &x, &mut noise),
        Err(Unbounded)
    );
    assert_eq!(unary(Unary::Ln, &x, &mut noise), Err(Unbounded));
    let neg = Affine::input(-2.0, -1.0, 3).expect("finite");
    assert_eq!(unary(Unary::Sqrt, &neg, &mut noise), Err(Unbounded));
    let wide = Affine::input(0.0, 3.0, 4).expect("finite");
    assert_eq!(
        unary(Unary::Tan, &wide, &mut noise),
        Err(Unbounded),
        "a pole at pi/2"
    );
    let big = Affine::input(700.0, 800.0, 5).expect("finite");
    assert_eq!(
        unary(Unary::Exp, &big, &mut noise),
        Err(Unbounded),
        "overflow"
    );
    assert_eq!(Affine::input(0.0, f64::INFINITY, 6), Err(Unbounded));
    assert_eq!(Affine::constant(f64::NAN), Err(Unbounded));
}

/// The graph: a node shared by two outputs has one form, so their
/// difference is 0 to rounding; an input no output reads is not a dependency.
#[test]
fn graph_shares_node_forms() {
    let mut b = Builder::new(3);
    let (x, y) = (b.input(0), b.input(1));
    let s = b.un(Unary::Sin, x);
    let p = b.bin(Binary::Mul, s, y);
    let q = b.bin(Binary::Mul, s, y);
    let e = b.bin(Binary::Sub, p, q);
    let ins = vec![
        Affine::input(0.1, 0.9, 0),
        Affine::input(-2.0, 3.0, 1),
        Affine::input(0.0, 1.0, 2),
    ];
    let mut noise = Noise::new(3);
    let out = enclose(&b, &[p, e], &ins, &mut noise);
    // 0 up to the rounding slack of the subtraction (the values are near 3).
    assert!(out[1].as_ref().expect("bounded").abs_bound() <= 1e-13);
    let (lo, hi) = out[0].as_ref().expect("bounded").range();
    assert!(lo <= -2.0 * 0.9f64.sin() && hi >= 3.0 * 0.9f64.sin());
    assert_eq!(depends_on(&b, &[p]), vec![true, true, false]);
}
