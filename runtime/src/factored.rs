//! The controller generated code runs: [`Controller`](crate::Controller)'s
//! pipeline with the rule premises factored into distinct terms.
//!
//! T-S rules share their premise terms: in a grid of rules every
//! `(premise, set)` pair appears in many rules (Zhang & Zeng's 9 rules use
//! 6 distinct pairs 18 times). [`FactoredController`] evaluates each distinct
//! term once per step and forms every rule weight as the product of its
//! terms' degrees, in the rule's order, so the weights are bit-identical to
//! [`Rule::weight`](crate::Rule::weight)'s. Normalisation, the nearest-rule
//! fallback, the blend and saturation are the shared stages of
//! [`crate::controller`]; rules of weight exactly 0 cost no division and no
//! gain product.

use crate::controller::{premises_linear, run, Step, Term};
use crate::Real;

/// A T-S PDC controller whose rule premises index a table of distinct terms.
///
/// `N` states, `M` inputs, `P` premise variables, `R` rules, `D` distinct
/// premise terms. [`FactoredController::step`] computes exactly what
/// [`Controller::step`](crate::Controller::step) computes for the same rules
/// (same operations in the same order, bit for bit).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FactoredController<
    'a,
    T,
    const N: usize,
    const M: usize,
    const P: usize,
    const R: usize,
    const D: usize,
> {
    /// Linear premise map `z = L x` used by [`FactoredController::step`].
    pub premise_map: [[T; N]; P],
    /// The distinct premise terms, each evaluated once per step.
    pub terms: [Term<'a, T>; D],
    /// Rule premises: indices into `terms`, multiplied in order (product
    /// t-norm; an empty list is weight 1, an index out of range degree 0).
    pub rules: [&'a [usize]; R],
    /// Rule centres in premise space (for the no-rule-fired fallback).
    pub centres: [[T; P]; R],
    /// PDC gains `F_i` (`M x N`, row-major), one per rule.
    pub gains: [[[T; N]; M]; R],
    /// Saturation levels `u_bar_s` (`+inf` for an unlimited channel).
    pub u_max: [T; M],
}

/// Degree of term `k` into `d[k]` (nothing when `k` is out of range).
#[inline(always)]
fn degree_at<T: Real, const D: usize>(d: &mut [T; D], terms: &[Term<'_, T>; D], z: &[T], k: usize) {
    if let (Some(dk), Some(term)) = (d.get_mut(k), terms.get(k)) {
        *dk = term.degree(z);
    }
}

/// Degrees of the distinct terms at `z`, each in `[0, 1]`.
///
/// The first 16 terms are written out one call each (the calls past `D`
/// fold away), so that when the terms are constants (a `static` table) the
/// compiler specializes every degree to its set's formula instead of
/// dispatching on the set kind in a loop.
#[inline]
pub fn term_degrees<T: Real, const D: usize>(terms: &[Term<'_, T>; D], z: &[T]) -> [T; D] {
    let mut d = [T::ZERO; D];
    macro_rules! unrolled {
        ($($k:literal)*) => { $(degree_at(&mut d, terms, z, $k);)* };
    }
    unrolled!(0 1 2 3 4 5 6 7 8 9 10 11 12 13 14 15);
    for k in 16..D {
        degree_at(&mut d, terms, z, k);
    }
    d
}

/// Rule weights from term degrees: `w_i = ((1 * d[k_1]) * d[k_2]) * ...`
/// over the rule's indices (an index out of range is degree 0), the
/// operations of [`Rule::weight`](crate::Rule::weight).
#[inline]
pub fn factored_weights<T: Real, const D: usize, const R: usize>(
    degrees: &[T; D],
    rules: &[&[usize]; R],
) -> [T; R] {
    let mut w = [T::ZERO; R];
    for (wi, rule) in w.iter_mut().zip(rules) {
        let mut acc = T::ONE;
        for &k in rule.iter() {
            acc = acc * degrees.get(k).copied().unwrap_or(T::ZERO);
        }
        *wi = acc;
    }
    w
}

impl<T: Real, const N: usize, const M: usize, const P: usize, const R: usize, const D: usize>
    FactoredController<'_, T, N, M, P, R, D>
{
    /// Evaluate with premises from the linear map: `z = L x`.
    #[inline]
    pub fn step(&self, x: &[T; N]) -> Step<T, M, R> {
        let z = premises_linear(&self.premise_map, x);
        self.step_with_premises(x, &z)
    }

    /// Rule weights at premise vector `z` (distinct terms evaluated once).
    #[inline]
    pub fn weights(&self, z: &[T; P]) -> [T; R] {
        factored_weights(&term_degrees(&self.terms, z), &self.rules)
    }

    /// Evaluate with premise values `z` computed by the caller; the edge
    /// cases are [`Controller::step_with_premises`](crate::Controller::step_with_premises)'s.
    #[inline]
    pub fn step_with_premises(&self, x: &[T; N], z: &[T; P]) -> Step<T, M, R> {
        run(
            x,
            z,
            |z| self.weights(z),
            &self.centres,
            &self.gains,
            &self.u_max,
        )
    }
}
