//! Table-driven PDC controller: premise terms, firing strengths, blend,
//! saturation, and the edge-case policy.
//!
//! Pipeline of [`Controller::step`] (each stage is also a public function so
//! generated code and the C mirror can follow the same order of operations):
//!
//! 1. [`premises_linear`]: `z = L x` (or premises supplied by the caller);
//! 2. fault check: any non-finite `x_k` or `z_p` -> `u = 0`, `h = 0`, flag;
//! 3. [`rule_weights`]: `w_i = prod_t degree_t(z)` (product t-norm);
//! 4. [`normalize`]: `h_i = w_i / sum w`; if `sum w` is not `> 0` and finite,
//!    [`nearest_rule`] `i*` gets `h = e_{i*}` and [`Flags::NO_RULE_FIRED`];
//! 5. [`blend`]: `u = sum_j h_j (F_j x)`;
//! 6. [`saturate`]: `|u_s| <= u_bar_s`, non-finite commands removed.

use crate::membership::{about_degree, Membership};
use crate::Real;

/// One conjunct of a rule premise.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Term<'a, T> {
    /// `z[var] is set`. An out-of-range `var` has degree 0.
    Is {
        /// Index into the premise vector `z`.
        var: usize,
        /// The fuzzy set.
        set: Membership<T>,
    },
    /// `z[first .. first + point.len()] is about point` with width `sigma`
    /// (see [`about_degree`]). A range outside `z` has degree 0.
    About {
        /// Index of the first premise component.
        first: usize,
        /// The rule's operating point for these components.
        point: &'a [T],
        /// Width of the Gaussian bump.
        sigma: T,
    },
}

impl<T: Real> Term<'_, T> {
    /// Degree of this term at premise vector `z`, in `[0, 1]`, never NaN.
    #[inline(always)]
    pub fn degree(&self, z: &[T]) -> T {
        match *self {
            Term::Is { var, set } => match z.get(var) {
                Some(&v) => set.degree(v),
                None => T::ZERO,
            },
            Term::About {
                first,
                point,
                sigma,
            } => first
                .checked_add(point.len())
                .and_then(|end| z.get(first..end))
                .map_or(T::ZERO, |zs| about_degree(zs, point, sigma)),
        }
    }
}

/// A rule premise: the conjunction (product t-norm) of its terms. A rule
/// with no terms always has weight 1.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rule<'a, T> {
    /// The conjuncts, multiplied in order.
    pub terms: &'a [Term<'a, T>],
}

impl<'a, T: Real> Rule<'a, T> {
    /// A rule from its terms.
    pub const fn new(terms: &'a [Term<'a, T>]) -> Self {
        Rule { terms }
    }

    /// Weight `w = ((1 * d_1) * d_2) * ...`, in `[0, 1]`. Stops at the first
    /// zero factor (degrees are never NaN or infinite, so the product is 0
    /// exactly as if every term were evaluated): most rules do not fire.
    pub fn weight(&self, z: &[T]) -> T {
        let mut acc = T::ONE;
        for term in self.terms {
            acc = acc * term.degree(z);
            if acc == T::ZERO {
                break;
            }
        }
        acc
    }
}

/// Status bits reported by a controller step (a plain bit set).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Flags(pub u8);

impl Flags {
    /// No condition raised.
    pub const NONE: Flags = Flags(0);
    /// No rule fired (sum of weights 0 or not finite): the nearest rule's
    /// gain was used alone.
    pub const NO_RULE_FIRED: Flags = Flags(1);
    /// A state component was NaN or infinite: command forced to zero.
    pub const STATE_NONFINITE: Flags = Flags(2);
    /// A premise value was NaN or infinite: command forced to zero.
    pub const PREMISE_NONFINITE: Flags = Flags(4);
    /// The blended command had a NaN/inf channel (e.g. from NaN/inf gains or
    /// overflow); that channel was replaced (NaN -> 0, +-inf -> +-u_bar).
    pub const COMMAND_NONFINITE: Flags = Flags(8);
    /// At least one channel was clipped to its saturation level.
    pub const SATURATED: Flags = Flags(16);
    /// The mode index given to a [`ModalController`](crate::ModalController)
    /// was not one of its modes: mode 0's gains were used.
    pub const MODE_OUT_OF_RANGE: Flags = Flags(32);
    /// An [`Observer`](crate::Observer)'s estimate was NaN or infinite, or
    /// its update overflowed: the estimate was reset to 0.
    pub const ESTIMATE_RESET: Flags = Flags(64);

    /// `true` if every bit of `other` is set in `self`.
    pub const fn contains(self, other: Flags) -> bool {
        self.0 & other.0 == other.0
    }

    /// Union of two flag sets.
    #[must_use]
    pub const fn union(self, other: Flags) -> Flags {
        Flags(self.0 | other.0)
    }

    /// `true` if the command was forced to zero by a non-finite input.
    pub const fn is_fault(self) -> bool {
        self.0 & (Self::STATE_NONFINITE.0 | Self::PREMISE_NONFINITE.0) != 0
    }
}

impl core::ops::BitOr for Flags {
    type Output = Flags;
    fn bitor(self, rhs: Flags) -> Flags {
        self.union(rhs)
    }
}

impl core::ops::BitOrAssign for Flags {
    fn bitor_assign(&mut self, rhs: Flags) {
        *self = self.union(rhs);
    }
}

/// Output of one controller evaluation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Step<T, const M: usize, const R: usize> {
    /// Saturated command, `|u_s| <= u_bar_s`, never NaN.
    pub u: [T; M],
    /// Normalised firing strengths actually used (one-hot at the nearest rule
    /// if no rule fired; all zero on a fault).
    pub h: [T; R],
    /// What happened.
    pub flags: Flags,
}

/// Dot product `sum_k a_k b_k`, accumulated in index order starting from
/// the first product (0 for empty slices). Starting from `0 +` instead would
/// only turn a result of `-0` into `+0`.
#[inline]
fn dot<T: Real>(a: &[T], b: &[T]) -> T {
    let mut terms = a.iter().zip(b).map(|(&ai, &bi)| ai * bi);
    let first = terms.next().unwrap_or(T::ZERO);
    terms.fold(first, |acc, t| acc + t)
}

/// Premise values of the linear form: `z_p = sum_k L[p][k] x_k` (index order).
#[inline]
pub fn premises_linear<T: Real, const N: usize, const P: usize>(
    l: &[[T; N]; P],
    x: &[T; N],
) -> [T; P] {
    let mut z = [T::ZERO; P];
    for (zp, row) in z.iter_mut().zip(l) {
        *zp = dot(row, x);
    }
    z
}

/// Rule weights `w_i` (product t-norm), each in `[0, 1]`.
pub fn rule_weights<T: Real, const R: usize>(rules: &[Rule<'_, T>; R], z: &[T]) -> [T; R] {
    let mut w = [T::ZERO; R];
    for (wi, rule) in w.iter_mut().zip(rules) {
        *wi = rule.weight(z);
    }
    w
}

/// Normalised strengths `h_i = w_i / s`, `s = ((0 + w_1) + w_2) + ...`.
///
/// Returns `None` if no rule fires (`s` not `> 0` or not finite). Negative or
/// NaN weights (impossible from [`rule_weights`]) are treated as 0. When
/// `Some`, every `h_i` is in `[0, 1]` and `sum h = 1` up to rounding. One
/// branch-free pass clamps and sums, one pass divides (a zero weight gives
/// `0 / s = 0`).
#[inline]
pub fn normalize<T: Real, const R: usize>(w: &[T; R]) -> Option<[T; R]> {
    let mut h = [T::ZERO; R];
    let mut s = T::ZERO;
    for (hi, &wi) in h.iter_mut().zip(w) {
        *hi = if wi > T::ZERO { wi } else { T::ZERO };
        s += *hi;
    }
    // `s > 0` and finite; NaN fails both comparisons.
    if !(s > T::ZERO && s <= T::MAX) {
        return None;
    }
    for hi in h.iter_mut() {
        // w_i <= s (sum of non-negatives, monotone rounding) => h_i <= 1.
        *hi = *hi / s;
    }
    Some(h)
}

/// Squared Euclidean distance between `z` and `c`, each operand first
/// multiplied by `scale` (1 or [`Real::TINY_SCALE`]).
#[inline]
fn dist2<T: Real>(z: &[T], c: &[T], scale: T) -> T {
    z.iter().zip(c).fold(T::ZERO, |acc, (&zi, &ci)| {
        let d = zi * scale - ci * scale;
        acc + d * d
    })
}

/// Index of the rule centre nearest to `z` (Euclidean distance in premise
/// space). Ties and NaN distances go to the lowest index; if the distances
/// overflow, they are recomputed with operands scaled by
/// [`Real::TINY_SCALE`]. Returns 0 when `R == 0` (callers never index then).
pub fn nearest_rule<T: Real, const P: usize, const R: usize>(
    centres: &[[T; P]; R],
    z: &[T; P],
) -> usize {
    let search = |scale: T| {
        let mut best = 0usize;
        let mut best_d: Option<T> = None;
        for (i, c) in centres.iter().enumerate() {
            let d = dist2(z, c, scale);
            let better = match best_d {
                None => !d.is_nan(), // first non-NaN distance
                Some(bd) => d < bd,
            };
            if better {
                best = i;
                best_d = Some(d);
            }
        }
        (best, best_d)
    };
    match search(T::ONE) {
        (_, Some(d)) if !d.is_finite() => search(T::TINY_SCALE).0,
        (i, _) => i,
    }
}

/// PDC blend `u = sum_j h_j (F_j x)`: rule-major, rules whose `h_j` is not
/// `> 0` skipped before any gain product (so NaN/inf gains of rules that do
/// not fire cannot leak; strengths from [`normalize`] are never negative or
/// NaN), each `(F_j x)_s` a [`premises_linear`]-style dot product,
/// accumulated as `u_s = u_s + h_j * (F_j x)_s` starting from 0.
#[inline]
pub fn blend<T: Real, const N: usize, const M: usize, const R: usize>(
    h: &[T; R],
    gains: &[[[T; N]; M]; R],
    x: &[T; N],
) -> [T; M] {
    let mut u = [T::ZERO; M];
    for (&hj, fj) in h.iter().zip(gains) {
        if hj > T::ZERO {
            for (us, row) in u.iter_mut().zip(fj) {
                *us += hj * dot(row, x);
            }
        }
    }
    u
}

/// Per-channel saturation `sat(u_s) = sign(u_s) min(|u_s|, b_s)` with
/// `b_s = u_bar_s` if `u_bar_s >= 0` (including `+inf` = unlimited), else 0
/// (negative or NaN bounds pin the channel to 0).
///
/// Non-finite commands: NaN -> 0; `+-inf` -> `+-b_s` (or 0 if `b_s` is
/// infinite); both raise [`Flags::COMMAND_NONFINITE`]. Clipping a finite value
/// or an infinity to a finite bound raises [`Flags::SATURATED`].
#[inline]
pub fn saturate<T: Real, const M: usize>(u: &[T; M], u_bar: &[T; M]) -> ([T; M], Flags) {
    let mut out = [T::ZERO; M];
    let mut flags = Flags::NONE;
    for ((o, &v), &ub) in out.iter_mut().zip(u).zip(u_bar) {
        let b = if ub >= T::ZERO { ub } else { T::ZERO };
        let mut v = v;
        if !v.is_finite() {
            flags |= Flags::COMMAND_NONFINITE;
            v = if !v.is_nan() && b.is_finite() {
                // +-inf with a finite bound: clip below.
                v
            } else {
                T::ZERO
            };
        }
        *o = if v > b {
            flags |= Flags::SATURATED;
            b
        } else if v < -b {
            flags |= Flags::SATURATED;
            -b
        } else {
            v
        };
    }
    (out, flags)
}

/// Normalised strengths of weights `w` (stage 4): `(h, Flags::NONE)` if
/// some rule fires, else the one-hot vector of [`nearest_rule`] at `z` with
/// [`Flags::NO_RULE_FIRED`].
#[inline]
pub(crate) fn strengths<T: Real, const P: usize, const R: usize>(
    w: &[T; R],
    centres: &[[T; P]; R],
    z: &[T; P],
) -> ([T; R], Flags) {
    match normalize(w) {
        Some(h) => (h, Flags::NONE),
        None => (one_hot(nearest_rule(centres, z)), Flags::NO_RULE_FIRED),
    }
}

/// `e_i` (all zero if `i >= R`); out of line: the no-rule-fired path is cold.
#[inline(never)]
fn one_hot<T: Real, const R: usize>(i: usize) -> [T; R] {
    let mut h = [T::ZERO; R];
    if let Some(hi) = h.get_mut(i) {
        *hi = T::ONE;
    }
    h
}

/// Stages 2-6 of the pipeline with the rule weights from `weights` (called
/// only when `x` and `z` are finite): the fault check, strengths, blend and
/// saturation shared by [`Controller`] and
/// [`FactoredController`](crate::FactoredController).
#[inline]
pub(crate) fn run<T: Real, const N: usize, const M: usize, const P: usize, const R: usize>(
    x: &[T; N],
    z: &[T; P],
    weights: impl FnOnce(&[T; P]) -> [T; R],
    centres: &[[T; P]; R],
    gains: &[[[T; N]; M]; R],
    u_max: &[T; M],
) -> Step<T, M, R> {
    let mut flags = Flags::NONE;
    if !x.iter().all(|v| v.is_finite()) {
        flags |= Flags::STATE_NONFINITE;
    }
    if !z.iter().all(|v| v.is_finite()) {
        flags |= Flags::PREMISE_NONFINITE;
    }
    if flags.is_fault() {
        return Step {
            u: [T::ZERO; M],
            h: [T::ZERO; R],
            flags,
        };
    }
    let (h, f) = strengths(&weights(z), centres, z);
    let raw = blend(&h, gains, x);
    let (u, g) = saturate(&raw, u_max);
    Step {
        u,
        h,
        flags: flags | f | g,
    }
}

/// A table-driven T-S PDC controller: everything is plain data, so generated
/// code can declare it as a `static`/`const` and call [`Controller::step`].
///
/// `N` states, `M` inputs, `P` premise variables, `R` rules.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Controller<'a, T, const N: usize, const M: usize, const P: usize, const R: usize> {
    /// Linear premise map `z = L x` used by [`Controller::step`]
    /// (ignored by [`Controller::step_with_premises`]).
    pub premise_map: [[T; N]; P],
    /// Rule premises.
    pub rules: [Rule<'a, T>; R],
    /// Rule centres in premise space (for the no-rule-fired fallback).
    pub centres: [[T; P]; R],
    /// PDC gains `F_i` (`M x N`, row-major), one per rule.
    pub gains: [[[T; N]; M]; R],
    /// Saturation levels `u_bar_s` (`+inf` for an unlimited channel).
    pub u_max: [T; M],
}

impl<T: Real, const N: usize, const M: usize, const P: usize, const R: usize>
    Controller<'_, T, N, M, P, R>
{
    /// Evaluate with premises from the linear map: `z = L x`.
    pub fn step(&self, x: &[T; N]) -> Step<T, M, R> {
        let z = premises_linear(&self.premise_map, x);
        self.step_with_premises(x, &z)
    }

    /// Firing strengths at premise vector `z` (stage 3-4 of the pipeline):
    /// `(h, Flags::NONE)` if some rule fires, else the one-hot vector of
    /// [`nearest_rule`] with [`Flags::NO_RULE_FIRED`].
    pub fn strengths(&self, z: &[T; P]) -> ([T; R], Flags) {
        strengths(&rule_weights(&self.rules, z), &self.centres, z)
    }

    /// Evaluate with premise values `z` computed by the caller.
    ///
    /// Any non-finite `x_k` ([`Flags::STATE_NONFINITE`]) or `z_p`
    /// ([`Flags::PREMISE_NONFINITE`]) gives `u = 0` and `h = 0` (the
    /// runtime is stateless; a caller wanting "hold last command" can do so
    /// on [`Flags::is_fault`]).
    pub fn step_with_premises(&self, x: &[T; N], z: &[T; P]) -> Step<T, M, R> {
        run(
            x,
            z,
            |z| rule_weights(&self.rules, z),
            &self.centres,
            &self.gains,
            &self.u_max,
        )
    }
}
