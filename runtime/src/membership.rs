//! Scalar fuzzy sets ([`Membership`]) and the vector `about` set
//! ([`about_degree`]).
//!
//! Every degree returned here lies in `[0, 1]` and is never NaN: a NaN
//! argument, NaN parameters or an undefined intermediate (e.g. `0/0` for
//! `sigma = 0` at the centre) give degree `0`.

use crate::Real;

/// Maps any value into `[0, 1]`; NaN -> 0.
#[inline(always)]
pub(crate) fn clamp01<T: Real>(v: T) -> T {
    if v >= T::ONE {
        T::ONE
    } else if v > T::ZERO {
        v
    } else {
        T::ZERO
    }
}

/// `(num)/(den)` for an edge of a trapezoid, evaluated as `(p - q)/(r - s)`;
/// if the denominator overflows (edge wider than `T::MAX`), all four operands
/// are halved first so the ratio stays meaningful.
#[inline(always)]
fn edge_ratio<T: Real>(p: T, q: T, r: T, s: T) -> T {
    let den = r - s;
    if den.is_finite() {
        (p - q) / den
    } else {
        (p * T::HALF - q * T::HALF) / (r * T::HALF - s * T::HALF)
    }
}

/// A scalar fuzzy set: the premise term `z is <set>` of the `.tsf` language.
///
/// Const-constructible (`Membership::Tri { a: -0.1, b: 0.0, c: 0.1 }` or
/// [`Membership::tri`]) so generated code and the compiler's coverage checker
/// can share tables. [`Membership::degree`] is the language's semantics.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Membership<T> {
    /// Triangle `tri(a, b, c)`, `a <= b <= c`: 0 outside `[a, c]`, rising
    /// linearly on `[a, b]`, 1 at `b`, falling linearly on `[b, c]`.
    /// `a == b` or `b == c` is a vertical edge (a shoulder): e.g.
    /// `tri(-0.1, -0.1, 0)` is 1 at `-0.1`, falls to 0 at `0`, and is 0 below
    /// `-0.1`. Identical to `trap(a, b, b, c)`.
    Tri {
        /// Left foot.
        a: T,
        /// Peak.
        b: T,
        /// Right foot.
        c: T,
    },
    /// Trapezoid `trap(a, b, c, d)`, `a <= b <= c <= d`: 0 outside `[a, d]`,
    /// 1 on `[b, c]`, `(z-a)/(b-a)` on `[a, b)`, `(d-z)/(d-c)` on `(c, d]`.
    /// Equal consecutive corners are vertical edges.
    Trap {
        /// Left foot.
        a: T,
        /// Left shoulder.
        b: T,
        /// Right shoulder.
        c: T,
        /// Right foot.
        d: T,
    },
    /// Gaussian `gauss(center, sigma)` = `exp(-0.5 ((z - center)/sigma)^2)`.
    Gauss {
        /// Centre (degree 1).
        center: T,
        /// Width, `> 0` (checked by the compiler).
        sigma: T,
    },
    /// Sigmoid `sigmoid(slope, center)` = `1/(1 + exp(-slope (z - center)))`.
    Sigmoid {
        /// Slope; positive opens to the right.
        slope: T,
        /// Crossover point (degree 1/2).
        center: T,
    },
}

impl<T: Real> Membership<T> {
    /// `tri(a, b, c)`.
    pub const fn tri(a: T, b: T, c: T) -> Self {
        Membership::Tri { a, b, c }
    }

    /// `trap(a, b, c, d)`.
    pub const fn trap(a: T, b: T, c: T, d: T) -> Self {
        Membership::Trap { a, b, c, d }
    }

    /// `gauss(center, sigma)`.
    pub const fn gauss(center: T, sigma: T) -> Self {
        Membership::Gauss { center, sigma }
    }

    /// `sigmoid(slope, center)`.
    pub const fn sigmoid(slope: T, center: T) -> Self {
        Membership::Sigmoid { slope, center }
    }

    /// Degree of membership of `z`, in `[0, 1]`, never NaN (NaN `z` -> 0).
    ///
    /// Evaluation order (mirrored by the C generator):
    /// - trap/tri: `z < a` or `z > d` -> 0; `b <= z <= c` -> 1;
    ///   `z < b` -> `(z - a)/(b - a)`; otherwise `(d - z)/(d - c)`;
    /// - gauss: `v = (z - center)/sigma`, `exp(-0.5 * (v * v))`;
    /// - sigmoid: `1/(1 + exp(-(slope * (z - center))))`;
    ///
    /// each result then clamped into `[0, 1]` with NaN -> 0.
    #[inline(always)]
    pub fn degree(&self, z: T) -> T {
        let v = match *self {
            Membership::Tri { a, b, c } => trap_degree(z, a, b, b, c),
            Membership::Trap { a, b, c, d } => trap_degree(z, a, b, c, d),
            Membership::Gauss { center, sigma } => {
                let v = (z - center) / sigma;
                (-(T::HALF * (v * v))).exp()
            }
            Membership::Sigmoid { slope, center } => {
                T::ONE / (T::ONE + (-(slope * (z - center))).exp())
            }
        };
        clamp01(v)
    }
}

/// Trapezoid evaluation shared by `Tri` and `Trap` (closed support `[a, d]`).
#[inline(always)]
fn trap_degree<T: Real>(z: T, a: T, b: T, c: T, d: T) -> T {
    if !(z >= a && z <= d) {
        // Outside the support, or NaN.
        T::ZERO
    } else if z >= b && z <= c {
        T::ONE
    } else if z < b {
        edge_ratio(z, a, b, a)
    } else {
        edge_ratio(d, z, d, c)
    }
}

/// Degree of the vector set `about p` with width `sigma`:
/// `exp(-0.5 * ||z - p||^2 / sigma^2)`, in `[0, 1]`, never NaN.
///
/// `||z - p||^2` is summed in index order over `zip(z, p)` (extra components
/// of the longer slice are ignored), then `exp(-0.5 * (d2 / (sigma * sigma)))`.
/// Used by `w is about [0.5, 0.5, 0.5]`.
pub fn about_degree<T: Real>(z: &[T], p: &[T], sigma: T) -> T {
    let d2 = z.iter().zip(p).fold(T::ZERO, |acc, (&zi, &pi)| {
        let d = zi - pi;
        acc + d * d
    });
    clamp01((-(T::HALF * (d2 / (sigma * sigma)))).exp())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() <= 1e-15
    }

    #[test]
    fn tri_hand_values() {
        let m = Membership::tri(-0.1, 0.0, 0.1);
        for (z, want) in [
            (-0.2, 0.0),
            (-0.1, 0.0),
            (-0.05, 0.5),
            (0.0, 1.0),
            (0.025, 0.75),
            (0.1, 0.0),
            (0.3, 0.0),
        ] {
            assert!(close(m.degree(z), want), "tri({z}) = {}", m.degree(z));
        }
        assert_eq!(m.degree(f64::NAN), 0.0);
        assert_eq!(m.degree(f64::INFINITY), 0.0);
    }

    #[test]
    fn tri_shoulders() {
        let neg = Membership::tri(-0.1, -0.1, 0.0);
        assert_eq!(neg.degree(-0.1), 1.0);
        assert!(close(neg.degree(-0.05), 0.5));
        assert_eq!(neg.degree(0.0), 0.0);
        assert_eq!(neg.degree(-0.1000001), 0.0, "0 beyond the outer point");
        let pos = Membership::tri(0.0, 0.1, 0.1);
        assert_eq!(pos.degree(0.1), 1.0);
        assert!(close(pos.degree(0.075), 0.75));
        assert_eq!(pos.degree(0.2), 0.0);
        let spike = Membership::tri(1.0, 1.0, 1.0);
        assert_eq!(spike.degree(1.0), 1.0);
        assert_eq!(spike.degree(1.0 + f64::EPSILON), 0.0);
    }

    #[test]
    fn trap_hand_values() {
        let m = Membership::trap(0.0, 1.0, 2.0, 4.0);
        for (z, want) in [
            (-1.0, 0.0),
            (0.0, 0.0),
            (0.5, 0.5),
            (1.0, 1.0),
            (1.5, 1.0),
            (2.0, 1.0),
            (3.0, 0.5),
            (3.5, 0.25),
            (4.0, 0.0),
            (5.0, 0.0),
        ] {
            assert!(close(m.degree(z), want), "trap({z})");
        }
        let shoulder = Membership::trap(f64::NEG_INFINITY, f64::NEG_INFINITY, 0.0, 1.0);
        assert_eq!(shoulder.degree(-1e308), 1.0);
        assert_eq!(shoulder.degree(0.5), 0.5);
        let wide = Membership::trap(-f64::MAX, 0.0, 0.0, f64::MAX);
        assert!(close(wide.degree(-f64::MAX / 2.0), 0.5));
        assert!(close(wide.degree(f64::MAX / 4.0), 0.75));
    }

    #[test]
    fn gauss_sigmoid_hand_values() {
        let g = Membership::gauss(1.0, 2.0);
        assert_eq!(g.degree(1.0), 1.0);
        assert!(close(g.degree(3.0), (-0.5f64).exp()));
        assert!(close(g.degree(-3.0), (-2.0f64).exp()));
        assert_eq!(g.degree(f64::INFINITY), 0.0);
        assert_eq!(g.degree(f64::NAN), 0.0);
        assert_eq!(Membership::gauss(0.0, 0.0).degree(0.0), 0.0, "0/0 -> 0");
        let s = Membership::sigmoid(10.0, 0.5);
        assert_eq!(s.degree(0.5), 0.5);
        assert!(close(s.degree(0.6), 1.0 / (1.0 + (-1.0f64).exp())));
        assert_eq!(s.degree(f64::INFINITY), 1.0);
        assert_eq!(s.degree(f64::NEG_INFINITY), 0.0);
        assert_eq!(s.degree(-1e300), 0.0);
        assert_eq!(s.degree(f64::NAN), 0.0);
        let f: Membership<f32> = Membership::sigmoid(-2.0, 0.0);
        assert!((f.degree(1.0) - 0.119_202_92).abs() < 1e-7);
    }

    #[test]
    fn about_hand_values() {
        let p = [0.5, 0.5, 0.5];
        assert_eq!(about_degree(&p, &p, 0.2), 1.0);
        let z = [0.5, 0.7, 0.5];
        assert!(close(about_degree(&z, &p, 0.2), (-0.5f64).exp()));
        let z = [0.7, 0.7, 0.5];
        assert!(close(about_degree(&z, &p, 0.2), (-1.0f64).exp()));
        assert_eq!(about_degree(&[f64::NAN, 0.5, 0.5], &p, 0.2), 0.0);
        assert_eq!(about_degree(&[1e300, 0.5, 0.5], &p, 0.2), 0.0);
    }
}
