//! The model error on one box in affine arithmetic: z(x), A(x), B(x), D(x)
//! from the tape's graph, the rules' memberships and normalized firing
//! strengths h_i(z(x)) from their definitions on the same noise symbols, and
//! per entry the form of `sum_i h_i M_i - M(x)`, bounded in absolute value.
//!
//! The blend is defined where every premise value lies in its declared range
//! (as in the consistency check): a box whose premise ranges miss a declared
//! range has no such state ([`Outcome::Empty`]); elsewhere the memberships'
//! piecewise-linear pieces are chosen on the premise's range clipped to the
//! declared one, so the bound holds at every state of the box whose premise
//! values are in range.

use crate::model::premise::TermSpec;
use crate::tape::affine::{self, recip, recip_within, unary, Affine, Form, Noise, Unbounded};
use crate::tape::{Builder, Id, Unary};
use nalgebra::DMatrix;
use tsf_lang::spec::SetShape;

/// A target matrix: its shape and the rules' matrices.
pub(super) type Target<'a> = ((usize, usize), Vec<&'a DMatrix<f64>>);

/// What the error bound evaluates: the graph and the rules.
pub(super) struct Problem<'a> {
    /// The graph of z(x) and the plant's matrices.
    pub builder: Builder,
    /// Its outputs: z, then each target matrix column-major.
    pub outputs: Vec<Id>,
    /// Number of premise values.
    pub nz: usize,
    /// Per target (A, B, then D when bounded): shape and the rules' matrices.
    pub targets: Vec<Target<'a>>,
    /// Declared range of each premise value.
    pub ranges: Vec<(f64, f64)>,
    /// Per rule: its premise terms.
    pub terms: &'a [Vec<TermSpec>],
    /// The rules as a full grid over their premise factors, when they are one.
    pub grid: Option<super::grid::Grid>,
}

/// The bound on one box.
pub(super) enum Outcome {
    /// No state of the box has its premise values in range.
    Empty,
    /// Some entry could not be bounded (a division by a range containing 0).
    Unbounded,
    /// Per target: entrywise bounds of |sum_i h_i M_i - M(x)|.
    Bounded(Vec<DMatrix<f64>>),
}

impl Problem<'_> {
    /// The bound on the box `bx`, and whether a function's argument was
    /// clipped to its domain.
    /// With `contracted`, the grid's contracted blend is bounded too
    /// ([`super::grid`]) and the smaller bound kept per entry.
    pub fn evaluate(&self, bx: &[(f64, f64)], contracted: bool) -> (Outcome, bool) {
        let mut noise = Noise::new(bx.len() as u32);
        let outcome = match self.forms(bx, contracted, &mut noise) {
            Ok(Some(m)) => Outcome::Bounded(m),
            Ok(None) => Outcome::Empty,
            Err(Unbounded) => Outcome::Unbounded,
        };
        (outcome, noise.clipped)
    }

    fn forms(
        &self,
        bx: &[(f64, f64)],
        contracted: bool,
        noise: &mut Noise,
    ) -> Result<Option<Vec<DMatrix<f64>>>, Unbounded> {
        let inputs: Vec<Form> = bx
            .iter()
            .enumerate()
            .map(|(k, &(lo, hi))| Affine::input(lo, hi, k as u32))
            .collect();
        let forms = affine::enclose(&self.builder, &self.outputs, &inputs, noise);
        let mut z = Vec::with_capacity(self.nz);
        let mut clip = Vec::with_capacity(self.nz);
        for (f, &(plo, phi)) in forms[..self.nz].iter().zip(&self.ranges) {
            let f = f.clone()?;
            let (lo, hi) = f.range();
            let (lo, hi) = (lo.max(plo), hi.min(phi));
            if lo > hi {
                return Ok(None);
            }
            z.push(f);
            clip.push((lo, hi));
        }
        let mut cache: Vec<(&TermSpec, Affine)> = Vec::new();
        let mut weights = Vec::with_capacity(self.terms.len());
        // Interval bounds of the total weight: degrees lie in [0, 1].
        let (mut s_lo, mut s_hi) = (0.0f64, 0.0f64);
        for rule in self.terms {
            let (mut p_lo, mut p_hi) = (1.0f64, 1.0f64);
            let mut w = Affine::constant(1.0)?;
            for t in rule {
                let d = match cache.iter().find(|(u, _)| *u == t) {
                    Some((_, d)) => d.clone(),
                    None => {
                        let d = degree(t, &z, &clip, noise)?;
                        cache.push((t, d.clone()));
                        d
                    }
                };
                let (lo, hi) = d.range();
                p_lo = (p_lo * lo.clamp(0.0, 1.0)).next_down().max(0.0);
                p_hi = affine::mul_up(p_hi, hi.clamp(0.0, 1.0));
                w = w.mul(&d, noise)?;
            }
            s_lo = (s_lo + p_lo).next_down();
            s_hi = affine::add_up(s_hi, p_hi);
            weights.push(w);
        }
        let parts: Vec<(f64, &Affine)> = weights.iter().map(|w| (1.0, w)).collect();
        let total = Affine::combine(&parts, 0.0, noise)?;
        let (lo, hi) = total.range();
        let (s_lo, s_hi) = (lo.max(s_lo), hi.min(s_hi));
        let inv = recip_within(&total, (s_lo, s_hi), noise)?;
        let dense = Dense::new(&weights);
        let grid = self.grid.as_ref().filter(|_| contracted).and_then(|g| {
            let degree = |t: &TermSpec| cache.iter().find(|(u, _)| *u == t).map(|(_, d)| d.clone());
            g.normalized(degree, noise).map(|nu| (g, nu))
        });
        let mut at = self.nz;
        let mut out = Vec::with_capacity(self.targets.len());
        for ((rows, cols), locals) in &self.targets {
            let mut m = DMatrix::zeros(*rows, *cols);
            for e in 0..rows * cols {
                let exact = forms[at + e].as_ref().map_err(|u| *u)?;
                let flat = (&total, &inv, s_lo);
                let by_grid = grid.as_ref().map(|(g, nu)| (*g, nu.as_slice()));
                m.as_mut_slice()[e] = entry_bound(&dense, locals, e, exact, flat, by_grid, noise)?;
            }
            at += rows * cols;
            out.push(m);
        }
        Ok(Some(out))
    }
}

/// The bound of `|sum_i h_i M_i[e] - M(x)[e]|` with `h_i = w_i / S` (`s`
/// encloses S, `inv` 1 / S, `s_lo` is a lower bound of S > 0). As `sum_i h_i = 1`,
/// the error is `N / S - (M(x)[e] - C)` with `N = sum_i w_i (M_i[e] - C)`
/// for any constant C (the centre of M(x)[e]: rules equal to a constant
/// M(x) give 0), and also `(N - S (M(x)[e] - C)) / S`, bounded by
/// `max |numerator| / s_lo`; with `grid` (the rules as a full grid and its
/// normalized degrees) also `|blend - (M(x)[e] - C)|` with the blend
/// contracted factor by factor ([`super::grid`]); the smallest bound is
/// returned.
fn entry_bound(
    weights: &Dense,
    locals: &[&DMatrix<f64>],
    e: usize,
    exact: &Affine,
    (s, inv, s_lo): (&Affine, &Affine, f64),
    grid: Option<(&super::grid::Grid, &[Vec<Affine>])>,
    noise: &mut Noise,
) -> Result<f64, Unbounded> {
    let c = exact.center();
    let diffs: Vec<f64> = locals
        .iter()
        .map(|l| l.as_slice().get(e).map_or(-c, |v| v - c))
        .collect();
    // The rounding of the differences: as sum_i w_i / S = 1 (w_i >= 0), it
    // adds at most the largest to the error.
    let rounded = diffs
        .iter()
        .map(|d| affine::rounding(d.abs(), 0))
        .fold(0.0, f64::max);
    if exact.is_constant() && diffs.iter().all(|d| *d == 0.0) {
        // Every rule has the plant's constant entry: exact.
        return Ok(0.0);
    }
    let n = weights.combine(&diffs, noise)?;
    let shifted = exact.add_const(-c, noise)?;
    let a =
        Affine::combine(&[(1.0, &n.mul(inv, noise)?), (-1.0, &shifted)], 0.0, noise)?.abs_bound();
    let num = Affine::combine(&[(1.0, &n), (-1.0, &s.mul(&shifted, noise)?)], 0.0, noise)?;
    let b = num.abs_bound() / s_lo * (1.0 + 4.0 * f64::EPSILON);
    // The contracted blend (an unbounded form there leaves the flat bound).
    let g = grid
        .and_then(|(g, nu)| {
            let blend = g.blend(nu, &diffs, noise).ok()?;
            Affine::combine(&[(1.0, &blend), (-1.0, &shifted)], 0.0, noise).ok()
        })
        .map_or(f64::INFINITY, |f| f.abs_bound());
    Ok(affine::add_up(a.min(b).min(g), rounded))
}

/// The rules' weights as a dense table over the union of their symbols
/// (linear combinations of them, one per matrix entry, are the hot path).
struct Dense {
    symbols: Vec<u32>,
    centers: Vec<f64>,
    /// Per rule: its coefficient of each symbol.
    rows: Vec<Vec<f64>>,
}

impl Dense {
    fn new(weights: &[Affine]) -> Dense {
        let mut symbols: Vec<u32> = weights
            .iter()
            .flat_map(|w| w.terms().iter().map(|t| t.0))
            .collect();
        symbols.sort_unstable();
        symbols.dedup();
        let rows = weights
            .iter()
            .map(|w| {
                let mut row = vec![0.0; symbols.len()];
                for &(s, a) in w.terms() {
                    if let Ok(k) = symbols.binary_search(&s) {
                        row[k] = a;
                    }
                }
                row
            })
            .collect();
        Dense {
            centers: weights.iter().map(Affine::center).collect(),
            symbols,
            rows,
        }
    }

    /// `sum_i d_i w_i`, with the rounding of each centre and coefficient
    /// (`r` products and sums) in a fresh symbol.
    fn combine(&self, d: &[f64], noise: &mut Noise) -> Form {
        let r = d.len();
        let (mut c, mut mag) = (0.0, 0.0);
        for (di, ci) in d.iter().zip(&self.centers) {
            c += di * ci;
            mag += (di * ci).abs();
        }
        let mut err = affine::rounding(mag, r);
        let mut terms = Vec::with_capacity(self.symbols.len());
        for (k, &s) in self.symbols.iter().enumerate() {
            let (mut a, mut m) = (0.0, 0.0);
            for (di, row) in d.iter().zip(&self.rows) {
                let t = di * row[k];
                a += t;
                m += t.abs();
            }
            if m > 0.0 {
                err = affine::add_up(err, affine::rounding(m, r));
                terms.push((s, a));
            }
        }
        Affine::from_parts(c, terms, err, noise)
    }
}

/// The degree of one premise term as a form over the box's noise symbols.
fn degree(t: &TermSpec, z: &[Affine], clip: &[(f64, f64)], noise: &mut Noise) -> Form {
    match t {
        TermSpec::Is { var, set } => {
            let x = z.get(*var).ok_or(Unbounded)?;
            let range = clip[*var];
            match *set {
                SetShape::Tri(a, b, c) => trapezoid(x, range, [a, b, b, c], noise),
                SetShape::Trap(a, b, c, d) => trapezoid(x, range, [a, b, c, d], noise),
                SetShape::Gauss(c, sigma) => {
                    let v = x.add_const(-c, noise)?.div_const(sigma, noise)?;
                    let e = v.sqr(noise)?.scale(-0.5, noise)?;
                    unary(Unary::Exp, &e, noise)
                }
                SetShape::Sigmoid(slope, c) => {
                    let v = x.add_const(-c, noise)?.scale(-slope, noise)?;
                    let e = unary(Unary::Exp, &v, noise)?.add_const(1.0, noise)?;
                    recip(&e, noise)
                }
            }
        }
        TermSpec::About {
            first,
            point,
            sigma,
        } => {
            let mut parts = Vec::with_capacity(point.len());
            for (k, p) in point.iter().enumerate() {
                let d = z.get(first + k).ok_or(Unbounded)?.add_const(-p, noise)?;
                parts.push(d.sqr(noise)?);
            }
            let refs: Vec<(f64, &Affine)> = parts.iter().map(|p| (1.0, p)).collect();
            let d2 = Affine::combine(&refs, 0.0, noise)?;
            let e = d2
                .div_const(*sigma, noise)?
                .div_const(*sigma, noise)?
                .scale(-0.5, noise)?;
            unary(Unary::Exp, &e, noise)
        }
    }
}

/// A trapezoid's degree (the runtime's `trap_degree`, in the reals) at `z`
/// and its rounding error.
fn trap_value(z: f64, [a, b, c, d]: [f64; 4]) -> (f64, f64) {
    if !(z >= a && z <= d) {
        (0.0, 0.0)
    } else if z >= b && z <= c {
        (1.0, 0.0)
    } else if z < b {
        ramp(z - a, b - a)
    } else {
        ramp(d - z, d - c)
    }
}

/// `num / den` and its error (two roundings of the differences, one of the quotient).
fn ramp(num: f64, den: f64) -> (f64, f64) {
    let v = num / den;
    (v, affine::rounding(v.abs(), 4))
}

/// The one-sided limits of the trapezoid at `p`: (left, right).
fn trap_limits(p: f64, [a, b, c, d]: [f64; 4]) -> [(f64, f64); 2] {
    let left = if p <= a {
        (0.0, 0.0)
    } else if p <= b {
        ramp(p - a, b - a)
    } else if p <= c {
        (1.0, 0.0)
    } else if p <= d {
        ramp(d - p, d - c)
    } else {
        (0.0, 0.0)
    };
    let right = if p < a {
        (0.0, 0.0)
    } else if p < b {
        ramp(p - a, b - a)
    } else if p < c {
        (1.0, 0.0)
    } else if p < d {
        ramp(d - p, d - c)
    } else {
        (0.0, 0.0)
    };
    [left, right]
}

/// The trapezoid `corners` of `x` for x in `range` (the premise's range
/// clipped to the declared one): its Chebyshev enclosure, exact to rounding
/// on a linear piece.
fn trapezoid(x: &Affine, (lo, hi): (f64, f64), corners: [f64; 4], noise: &mut Noise) -> Form {
    let mut points = Vec::with_capacity(12);
    for z in [lo, hi] {
        let (f, e) = trap_value(z, corners);
        points.push((z, f, e));
    }
    for p in corners {
        if p > lo && p < hi {
            points.push((p, trap_value(p, corners).0, trap_value(p, corners).1));
            // Both one-sided values, a vertical edge included (only the
            // sides inside the range count).
            for (f, e) in trap_limits(p, corners) {
                points.push((p, f, e));
            }
        } else if p == lo && p < hi {
            let (f, e) = trap_limits(p, corners)[1];
            points.push((p, f, e));
        } else if p == hi && p > lo {
            let (f, e) = trap_limits(p, corners)[0];
            points.push((p, f, e));
        }
    }
    let alpha = if hi > lo {
        (points[1].1 - points[0].1) / (hi - lo)
    } else {
        0.0
    };
    affine::chebyshev(x, alpha, &points, noise)
}
