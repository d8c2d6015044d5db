//! The rounding of the membership degrees and rule weights that generated
//! code computes in its precision (docs/precision.md, "Membership degrees"):
//! a bound on the relative error of every rule weight, from the runtime's
//! evaluation order of each set over the premise ranges, the error of its
//! `exp` and the product t-norm.
//!
//! Model (Higham, "Accuracy and Stability of Numerical Algorithms", 2002,
//! section 2.2): every operation is `fl(a op b) = (a op b)(1 + d)`, `|d| <= u`,
//! no underflow; `gamma_k = k u / (1 - k u)`; `exp` within
//! [`F32_ELEMENTARY_ULP`] ulp, i.e. relative `2 u` per ulp (the runtime's
//! `expf` is measured within half of that, and so is its `exp`, which the
//! C runtime's `tsf_exp` repeats bit for bit). Clamping into `[0, 1]` never increases the error of a
//! degree whose exact value is in `[0, 1]`.

use super::stored::unit_roundoff;
use crate::model::{PremiseLayout, TermSpec, TsModel};
use tsf_lang::spec::{Precision, SetShape};
use tsf_runtime::math::F32_ELEMENTARY_ULP;

/// gamma_k = k u / (1 - k u) (Higham 2002, section 3.1).
pub(super) fn gamma(k: usize, u: f64) -> f64 {
    let ku = k as f64 * u;
    ku / (1.0 - ku)
}

/// Range of premise component `k` (the whole line when it is not laid out).
fn range(layout: &PremiseLayout, k: usize) -> (f64, f64) {
    layout
        .slots
        .iter()
        .find(|s| k >= s.first && k < s.first + s.dim)
        .map_or((f64::NEG_INFINITY, f64::INFINITY), |s| s.range)
}

/// Largest `|z - c|` over the range of component `k`.
fn reach(layout: &PremiseLayout, k: usize, c: f64) -> f64 {
    let (lo, hi) = range(layout, k);
    (lo - c).abs().max((hi - c).abs())
}

/// Relative error of `exp(-e~)` against `exp(-e)` when `e~ = e (1 + t)`,
/// `|t| <= g`, `0 <= e <= e_max`, and `exp` adds its own error.
fn exp_error(e_max: f64, g: f64, u: f64) -> f64 {
    let eps_exp = F32_ELEMENTARY_ULP * 2.0 * u;
    (1.0 + eps_exp) * (e_max * g).exp() - 1.0
}

/// Bound on the relative error of one term's computed degree over the
/// premise ranges (infinite when it cannot be bounded: an unbounded range
/// under a Gaussian, or a degree that may leave the normal range).
pub fn degree_error(term: &TermSpec, layout: &PremiseLayout, precision: Precision) -> f64 {
    let u = unit_roundoff(precision);
    // The smallest exponent `e` of exp(-e) whose result stays normal.
    let normal_limit = match precision {
        Precision::F32 => 87.0,
        Precision::F64 => 708.0,
    };
    let bounded = |e_max: f64, eps: f64| {
        if e_max.is_finite() && e_max < normal_limit {
            eps
        } else {
            f64::INFINITY
        }
    };
    match term {
        TermSpec::Is { var, set } => match *set {
            // (z - a)/(b - a) or (d - z)/(d - c): two subtractions, one
            // division; 0 and 1 are exact.
            SetShape::Tri(..) | SetShape::Trap(..) => gamma(3, u),
            // w = (z - c)/sigma, w*w, times 1/2 (exact): e~ = e (1 + t), |t| <= gamma_5.
            SetShape::Gauss(c, sigma) => {
                let w = reach(layout, *var, c) / sigma.abs();
                let e_max = 0.5 * w * w;
                bounded(e_max, exp_error(e_max, gamma(5, u), u))
            }
            // kz = slope (z - c) (gamma_2), e = exp(-kz), then 1 + e and 1/(1 + e),
            // one rounding each; degree >= 1/(1 + e^K).
            SetShape::Sigmoid(slope, c) => {
                let k_max = (slope * reach(layout, *var, c)).abs();
                let eps_e = exp_error(k_max, gamma(2, u), u);
                let eps_sum = (1.0 + eps_e) * (1.0 + u) - 1.0;
                let eps = (1.0 + u) / (1.0 - eps_sum) - 1.0;
                bounded(k_max, if eps_sum < 1.0 { eps } else { f64::INFINITY })
            }
        },
        // d_k = z_k - p_k, d_k^2 (gamma_3), sum of L non-negative terms from 0
        // (gamma_{L+2}), / (sigma*sigma) (gamma_{L+4}), times 1/2 (exact).
        TermSpec::About {
            first,
            point,
            sigma,
        } => {
            let sum: f64 = point
                .iter()
                .enumerate()
                .map(|(j, p)| reach(layout, first + j, *p).powi(2))
                .sum();
            let e_max = 0.5 * sum / (sigma * sigma);
            bounded(e_max, exp_error(e_max, gamma(point.len() + 4, u), u))
        }
    }
}

/// Bound on the relative error of every computed rule weight: rule `i`'s
/// weight `((1 * mu_1) * mu_2) * ...` over its `k` terms has relative error at
/// most `prod_j (1 + eps_j) (1 + u)^(k - 1) - 1`; the largest over the rules.
pub fn weight_relative_error(model: &TsModel, precision: Precision) -> f64 {
    let u = unit_roundoff(precision);
    model
        .terms
        .iter()
        .map(|terms| {
            let products = terms.len().saturating_sub(1) as i32;
            terms
                .iter()
                .map(|t| 1.0 + degree_error(t, &model.premises, precision))
                .product::<f64>()
                * (1.0 + u).powi(products)
                - 1.0
        })
        .fold(0.0, f64::max)
}

/// Bound on `sum_i |h'_i - h_i|` when every weight has relative error at
/// most `eps` (`h'` the exact normalization of the computed weights, `h` of
/// the exact ones): `h'_i / h_i = (1 + a_i)/(1 + a)` with `a` a convex
/// combination of the `a_k`, so `|h'_i - h_i| <= h_i 2 eps / (1 - eps)`.
pub fn normalized_weight_error(eps: f64) -> f64 {
    if eps < 1.0 {
        2.0 * eps / (1.0 - eps)
    } else {
        f64::INFINITY
    }
}
