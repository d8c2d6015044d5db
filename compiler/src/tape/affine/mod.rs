//! Affine arithmetic (Stolfi and de Figueiredo, "Self-validated numerical
//! methods and applications", 1997; de Figueiredo and Stolfi, "Affine
//! arithmetic: concepts and applications", 2004): a quantity is an
//! [`Affine`] form `c + sum_k a_k e_k` over noise symbols `e_k` in [-1, 1]
//! shared between quantities, so correlated terms cancel (`x - x` is 0, a
//! blend affine in a premise z(x) equals the entry of A(x) it interpolates).
//!
//! Every operation is a sound enclosure of the real operation: the rounding
//! error of each computed centre and coefficient (bounded by `(k + 2) EPS`
//! times the magnitude of the `k` terms it sums, accumulated with upward
//! rounding) and the error of a nonlinear function's linear approximation go
//! into one fresh noise symbol of the result. A result that cannot be bounded
//! (a division by a range containing 0, `sqrt` or `log` of a range reaching
//! below 0, an overflow) is [`Unbounded`], never a NaN or infinity inside a
//! form. The elementary functions are in `funcs.rs`, the evaluation of a
//! tape's graph in `graph.rs`.

mod funcs;
mod graph;
#[cfg(test)]
mod tests;

pub use funcs::{binary, chebyshev, recip, recip_within, unary};
pub use graph::{depends_on, enclose};

/// Relative slack of one rounding step (twice the unit roundoff).
pub(crate) const EPS: f64 = f64::EPSILON;
/// Absolute slack of one rounding step (covers underflow).
pub(crate) const TINY: f64 = f64::MIN_POSITIVE;

/// A quantity that could not be bounded (division by a range containing 0,
/// the square root or logarithm of a range reaching below 0, an overflow).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Unbounded;

/// An affine form, or [`Unbounded`].
pub type Form = Result<Affine, Unbounded>;

/// The source of fresh noise symbols (one per operation with an error term).
#[derive(Debug, Clone)]
pub struct Noise {
    next: u32,
    /// Symbols below this one (the inputs') are never condensed.
    first: u32,
    /// Set when a function's argument range reached outside its domain and
    /// was clipped to it (`sqrt` of a range reaching below 0): the enclosure
    /// then holds where the expression is real.
    pub clipped: bool,
    /// Prefer the narrowest range over correlation where a function has
    /// both (sinc near 0): for range checks, whose result is an interval.
    pub tight_ranges: bool,
}

impl Noise {
    /// Fresh symbols from `first` on (symbols below it name the inputs).
    pub fn new(first: u32) -> Self {
        Noise {
            next: first,
            first,
            clipped: false,
            tight_ranges: false,
        }
    }

    fn fresh(&mut self) -> u32 {
        let s = self.next;
        self.next = self.next.saturating_add(1);
        s
    }
}

/// `a + b` rounded upward (exact sums stay exact: the error-free
/// transformation TwoSum gives the rounding error's sign).
pub(crate) fn add_up(a: f64, b: f64) -> f64 {
    let s = a + b;
    if !s.is_finite() {
        return s;
    }
    let bb = s - a;
    let e = (a - (s - bb)) + (b - bb);
    if e > 0.0 {
        s.next_up()
    } else {
        s
    }
}

/// `a - b` rounded downward.
pub(crate) fn sub_down(a: f64, b: f64) -> f64 {
    -add_up(-a, b)
}

/// `a * b` rounded upward, for `a, b >= 0` (a nonzero product is moved one
/// ulp up: cheaper than an FMA test, which has no hardware form here).
pub(crate) fn mul_up(a: f64, b: f64) -> f64 {
    let p = a * b;
    if p == 0.0 && (a == 0.0 || b == 0.0) {
        0.0
    } else {
        p.next_up()
    }
}

/// Bound of the rounding error of a quantity computed from `k` terms of
/// total magnitude `mag` (one product each and `k - 1` sums, or fewer).
pub(crate) fn rounding(mag: f64, k: usize) -> f64 {
    add_up(mul_up(mag, (k as f64 + 2.0) * EPS), TINY)
}

/// Most noise symbols of operations (not inputs) a form keeps: the smallest
/// beyond these are folded into the result's fresh symbol (sound: their sum
/// is bounded by the sum of their magnitudes; only correlation is lost).
const KEEP: usize = 24;

/// Folds all but the [`KEEP`] largest operation symbols (`>= first`) of
/// `terms` out; returns the sum of their magnitudes (rounded up).
fn condense(terms: &mut Vec<(u32, f64)>, first: u32) -> f64 {
    let ops = terms.iter().filter(|t| t.0 >= first).count();
    if ops <= KEEP {
        return 0.0;
    }
    let mut mags: Vec<f64> = terms
        .iter()
        .filter(|t| t.0 >= first)
        .map(|t| t.1.abs())
        .collect();
    let (_, cut, _) = mags.select_nth_unstable_by(KEEP - 1, |a, b| b.total_cmp(a));
    let cut = *cut;
    let mut kept = 0;
    let mut folded = 0.0;
    terms.retain(|t| {
        if t.0 < first {
            return true;
        }
        if t.1.abs() >= cut && kept < KEEP {
            kept += 1;
            true
        } else {
            folded = add_up(folded, t.1.abs());
            false
        }
    });
    folded
}

/// `c + sum_k a_k e_k`, the `(symbol, a_k)` sorted by symbol, all finite.
#[derive(Debug, Clone, PartialEq)]
pub struct Affine {
    center: f64,
    terms: Vec<(u32, f64)>,
}

impl Affine {
    /// The exact constant `v` (`Unbounded` when not finite).
    pub fn constant(v: f64) -> Form {
        if v.is_finite() {
            Ok(Affine {
                center: v,
                terms: Vec::new(),
            })
        } else {
            Err(Unbounded)
        }
    }

    /// A quantity ranging over `[lo, hi]`, with noise symbol `symbol`.
    pub fn input(lo: f64, hi: f64, symbol: u32) -> Form {
        if !(lo.is_finite() && hi.is_finite() && lo <= hi) {
            return Err(Unbounded);
        }
        if lo == hi {
            return Affine::constant(lo);
        }
        let center = 0.5 * lo + 0.5 * hi;
        let r = add_up(hi, -center).max(add_up(center, -lo));
        Affine::with_error(center, vec![(symbol, r)], 0.0, None)
    }

    /// The form `center + terms`, plus a fresh symbol of radius `err` (when
    /// positive; `noise` must then be given). `Unbounded` when not finite.
    fn with_error(
        center: f64,
        mut terms: Vec<(u32, f64)>,
        err: f64,
        noise: Option<&mut Noise>,
    ) -> Form {
        let mut err = err;
        if let Some(n) = &noise {
            err = add_up(err, condense(&mut terms, n.first));
        }
        if err > 0.0 {
            match noise {
                Some(n) => terms.push((n.fresh(), err)),
                None => return Err(Unbounded),
            }
        }
        if !(center.is_finite() && err.is_finite() && terms.iter().all(|t| t.1.is_finite())) {
            return Err(Unbounded);
        }
        terms.retain(|t| t.1 != 0.0);
        Ok(Affine { center, terms })
    }

    /// The form `center + sum terms` (sorted by symbol, distinct) plus a
    /// fresh symbol of radius `err`, which must bound the rounding errors of
    /// the centre and the coefficients the caller computed.
    pub fn from_parts(center: f64, terms: Vec<(u32, f64)>, err: f64, noise: &mut Noise) -> Form {
        Affine::with_error(center, terms, err, Some(noise))
    }

    /// The `(symbol, coefficient)` pairs, sorted by symbol.
    pub fn terms(&self) -> &[(u32, f64)] {
        &self.terms
    }

    /// The central value.
    pub fn center(&self) -> f64 {
        self.center
    }

    /// `true` for a constant (no noise symbol).
    pub fn is_constant(&self) -> bool {
        self.terms.is_empty()
    }

    /// The coefficient of noise symbol `symbol` (0 when absent).
    pub fn coefficient(&self, symbol: u32) -> f64 {
        self.terms
            .binary_search_by_key(&symbol, |t| t.0)
            .map_or(0.0, |i| self.terms[i].1)
    }

    /// Number of noise symbols.
    pub fn symbols(&self) -> usize {
        self.terms.len()
    }

    /// An upper bound of `sum_k |a_k|`.
    pub fn radius(&self) -> f64 {
        self.terms.iter().fold(0.0, |r, t| add_up(r, t.1.abs()))
    }

    /// An interval `[lo, hi]` holding every value of the form.
    pub fn range(&self) -> (f64, f64) {
        let r = self.radius();
        (sub_down(self.center, r), add_up(self.center, r))
    }

    /// An upper bound of the form's absolute value.
    pub fn abs_bound(&self) -> f64 {
        let (lo, hi) = self.range();
        lo.abs().max(hi.abs())
    }

    /// The form holding every value of `[lo, hi]` (a fresh symbol).
    pub fn interval(lo: f64, hi: f64, noise: &mut Noise) -> Form {
        if !(lo.is_finite() && hi.is_finite() && lo <= hi) {
            return Err(Unbounded);
        }
        let center = 0.5 * lo + 0.5 * hi;
        let r = add_up(hi, -center).max(add_up(center, -lo));
        Affine::with_error(center, Vec::new(), r, Some(noise))
    }

    /// `sum_j w_j x_j + k`, one rounding bound for the whole combination.
    pub fn combine(parts: &[(f64, &Affine)], k: f64, noise: &mut Noise) -> Form {
        let mut center = k;
        let mut mag = k.abs();
        for (w, x) in parts {
            let t = w * x.center;
            center += t;
            mag += t.abs();
        }
        let mut err = rounding(mag, parts.len() + 1);
        // Merge the sorted terms: (symbol, sum, magnitude, count).
        let mut acc: Vec<(u32, f64, f64, usize)> = Vec::new();
        let mut next = Vec::new();
        for (w, x) in parts {
            if *w == 0.0 || x.terms.is_empty() {
                continue;
            }
            next.clear();
            let (mut i, mut j) = (0, 0);
            while i < acc.len() || j < x.terms.len() {
                let take_acc = j >= x.terms.len() || (i < acc.len() && acc[i].0 < x.terms[j].0);
                if take_acc {
                    next.push(acc[i]);
                    i += 1;
                    continue;
                }
                let (s, a) = x.terms[j];
                let t = w * a;
                if i < acc.len() && acc[i].0 == s {
                    let (_, sum, m, k) = acc[i];
                    next.push((s, sum + t, m + t.abs(), k + 1));
                    i += 1;
                } else {
                    next.push((s, t, t.abs(), 1));
                }
                j += 1;
            }
            std::mem::swap(&mut acc, &mut next);
        }
        let mut terms: Vec<(u32, f64)> = Vec::with_capacity(acc.len() + 1);
        for (s, sum, m, k) in acc {
            err = add_up(err, rounding(m, k));
            terms.push((s, sum));
        }
        Affine::with_error(center, terms, err, Some(noise))
    }

    /// `x + y`.
    pub fn add(&self, y: &Affine, noise: &mut Noise) -> Form {
        Affine::combine(&[(1.0, self), (1.0, y)], 0.0, noise)
    }

    /// `x - y`.
    pub fn sub(&self, y: &Affine, noise: &mut Noise) -> Form {
        Affine::combine(&[(1.0, self), (-1.0, y)], 0.0, noise)
    }

    /// `x + k`.
    pub fn add_const(&self, k: f64, noise: &mut Noise) -> Form {
        Affine::combine(&[(1.0, self)], k, noise)
    }

    /// `w x`.
    pub fn scale(&self, w: f64, noise: &mut Noise) -> Form {
        Affine::combine(&[(w, self)], 0.0, noise)
    }

    /// `-x` (exact).
    pub fn neg(&self) -> Affine {
        Affine {
            center: -self.center,
            terms: self.terms.iter().map(|&(s, a)| (s, -a)).collect(),
        }
    }

    /// `x / k` for a constant `k` (`Unbounded` for `k == 0`).
    pub fn div_const(&self, k: f64, noise: &mut Noise) -> Form {
        if k == 0.0 || !k.is_finite() {
            return Err(Unbounded);
        }
        let center = self.center / k;
        let mut err = rounding(center.abs(), 1);
        let terms = self
            .terms
            .iter()
            .map(|&(s, a)| {
                let q = a / k;
                err = add_up(err, rounding(q.abs(), 1));
                (s, q)
            })
            .collect();
        Affine::with_error(center, terms, err, Some(noise))
    }

    /// `x y`: the product of the linear parts is bounded by the product of
    /// the radii (by `[0, r^2]` for a square, [`Affine::sqr`]).
    pub fn mul(&self, y: &Affine, noise: &mut Noise) -> Form {
        if self.is_constant() {
            return y.scale(self.center, noise);
        }
        if y.is_constant() {
            return self.scale(y.center, noise);
        }
        let lin = Affine::combine(
            &[(y.center, &self.linear()), (self.center, &y.linear())],
            0.0,
            noise,
        )?;
        let c = self.center * y.center;
        let err = add_up(rounding(c.abs(), 1), mul_up(self.radius(), y.radius()));
        lin.shift(c, err, noise)
    }

    /// `x^2`: `c^2 + 2 c s + s^2` with `s^2` in `[0, r^2]`.
    pub fn sqr(&self, noise: &mut Noise) -> Form {
        let r = self.radius();
        let r2 = mul_up(r, r);
        let lin = self.linear().scale(2.0 * self.center, noise)?;
        let c = self.center * self.center;
        let half = 0.5 * r2;
        let err = add_up(rounding(c + half, 2), half);
        lin.shift(c + half, err, noise)
    }

    /// The form without its centre.
    fn linear(&self) -> Affine {
        Affine {
            center: 0.0,
            terms: self.terms.clone(),
        }
    }

    /// `x + c` plus a fresh symbol of radius `err` (and the rounding of the sum).
    fn shift(mut self, c: f64, err: f64, noise: &mut Noise) -> Form {
        let total = add_up(err, rounding(self.center.abs() + c.abs(), 1));
        self.center += c;
        Affine::with_error(self.center, self.terms, total, Some(noise))
    }
}
