//! The membership drift over one sampling period on a state box (issue 36):
//! rigorous bounds of |h_i(x(t)) - h_i(x(t_k))| for t in [t_k, t_k + T],
//! the data of the synthesis stage's sampled observer certificate (its
//! `observer::drift` module; this stage does not depend on it).
//!
//! Data: the box R of the `region` settings (every state bounded), the period
//! T and an input bound U (|u_k| <= U, which the certificate imposes).
//!
//! 1. Rates. For x in R and |u| <= U, the T-S plant's derivative
//!    x'_s = sum_i h_i (A_i x + B_i u)_s is a convex combination, so
//!    |x'_s| <= rate_s = max_i (sum_k |A_i[s,k]| max(|lo_k|, |hi_k|)
//!    + sum_l |B_i[s,l]| U) (widened by 1e-12 relative).
//! 2. Sample box. R' = R shrunk by step_s = T rate_s on each side. If
//!    x(t_k) is in R' then x(t) stays in R for the whole period: while x is in
//!    R, |x_s(t) - x_s(t_k)| <= (t - t_k) rate_s <= step_s, so x cannot reach
//!    the boundary of R before t_k + T (continuity: the first exit time would
//!    have x on the boundary, at distance < step_s from x(t_k) in R').
//! 3. Drift. R' is cut into a uniform grid of sub-boxes B along the states
//!    the premises read (the others keep their whole interval). For x(t_k) in
//!    B, x(t) lies in B+ = B grown by step (inside R). The premise values are
//!    enclosed on B and on B+ (affine arithmetic, outward rounding), the
//!    normalized memberships bounded on those intervals
//!    ([`super::membership_bounds`]), and h_i(t) - h_i(t_k) lies in
//!    [lo_i(B+) - hi_i(B), hi_i(B+) - lo_i(B)]: delta_i is the largest
//!    magnitude over the grid.
//!
//! Soundness rests on the enclosures (sound on every box) and on the region
//! check of the model stage, which proves every premise value on R inside its
//! declared range (so the memberships are those of the rules there).

use super::membership_bounds;
use crate::model::consistency::StateGraph;
use crate::model::error_bound::premise_range;
use crate::model::TsModel;
use crate::tape::affine;
use serde::Serialize;

/// Largest number of sub-boxes of the drift grid.
pub const MAX_DRIFT_BOXES: usize = 16384;
/// Relative outward widening of the rates (rounding of the sums).
const WIDEN: f64 = 1e-12;

/// The membership drift bound of one period on a state box.
#[derive(Debug, Clone, PartialEq, Serialize, schemars::JsonSchema)]
pub struct DriftBound {
    /// The period T (s).
    pub period: f64,
    /// The box R of the `region` settings, per state component.
    pub region: Vec<(f64, f64)>,
    /// The input bound U (|u_k| <= U on the certified set).
    pub input_bound: f64,
    /// rate_s: sup |x_s'| on R with |u| <= U (T-S model).
    pub rates: Vec<f64>,
    /// step_s = T rate_s: how far x_s moves within a period.
    pub steps: Vec<f64>,
    /// The sample box R' (R shrunk by the steps): x(t_k) in R' keeps x(t) in R.
    pub samples: Vec<(f64, f64)>,
    /// Per rule: the bound of |h_i(t) - h_i(t_k)| over a period.
    pub delta: Vec<f64>,
    /// Sub-boxes of the grid.
    pub boxes: usize,
}

/// The state box of `model`'s `region` settings when every state component is
/// bounded by one (`None` otherwise).
pub fn state_box(model: &TsModel) -> Option<Vec<(f64, f64)>> {
    let mut bx: Vec<Option<(f64, f64)>> = vec![None; model.n];
    for b in &model.spec.trigger_region {
        let (first, len) = b.state?;
        for slot in bx.iter_mut().skip(first).take(len) {
            *slot = Some(b.range);
        }
    }
    bx.into_iter().collect()
}

/// Per state: (a_s, b_s) with rate_s = a_s + b_s U on the box `bx`.
fn rate_terms(model: &TsModel, bx: &[(f64, f64)]) -> Vec<(f64, f64)> {
    let mag: Vec<f64> = bx.iter().map(|(lo, hi)| lo.abs().max(hi.abs())).collect();
    (0..model.n)
        .map(|s| {
            model.rules.iter().fold((0.0f64, 0.0f64), |(a, b), r| {
                let ra: f64 = (0..model.n).map(|k| r.a[(s, k)].abs() * mag[k]).sum();
                let rb: f64 = (0..model.m).map(|l| r.b[(s, l)].abs()).sum();
                (a.max(ra), b.max(rb))
            })
        })
        .collect()
}

/// The largest input bound that leaves a sample box (every step below the
/// nearer face of R), or infinity when u moves no state.
pub fn largest_input(model: &TsModel, bx: &[(f64, f64)], period: f64) -> f64 {
    rate_terms(model, bx)
        .iter()
        .zip(bx)
        .filter(|((_, b), _)| *b > 0.0)
        .map(|((a, b), (lo, hi))| ((-lo).min(*hi) / period - a) / b)
        .fold(f64::INFINITY, f64::min)
}

/// The drift bound of `model` on its state box at `period` with |u| <= `input`.
pub fn drift_bound(model: &TsModel, period: f64, input: f64) -> Result<DriftBound, String> {
    let region = state_box(model).ok_or_else(|| {
        "the membership drift needs a box on every state (`region x = lo .. hi;` for each state)"
            .to_string()
    })?;
    let rates: Vec<f64> = rate_terms(model, &region)
        .iter()
        .map(|(a, b)| (a + if *b > 0.0 { b * input } else { 0.0 }) * (1.0 + WIDEN))
        .collect();
    let steps: Vec<f64> = rates.iter().map(|r| r * period * (1.0 + WIDEN)).collect();
    let samples: Vec<(f64, f64)> = region
        .iter()
        .zip(&steps)
        .map(|((lo, hi), d)| (lo + d, hi - d))
        .collect();
    if let Some(s) = samples
        .iter()
        .position(|(lo, hi)| !(*lo < 0.0 && *hi > 0.0))
    {
        return Err(format!(
            "state {} moves up to {:.6} within a period (|x'| <= {:.6} with |u| <= {input}), more than its box leaves around 0: widen the box, shorten the period or lower the input bound",
            s + 1,
            steps[s],
            rates[s]
        ));
    }
    let graph = StateGraph::lower(&model.spec, &[])
        .map_err(|e| format!("the premises have no tape form ({})", e.0))?;
    let z = &graph.outputs[..graph.nz];
    let reads = affine::depends_on(&graph.builder, z);
    let split: Vec<usize> = (0..model.n).filter(|&s| reads[s]).collect();
    let per = match split.len() {
        0 => 1,
        k => (MAX_DRIFT_BOXES as f64)
            .powf(1.0 / k as f64)
            .floor()
            .max(1.0) as usize,
    };
    let ranges = model.premises.component_ranges();
    let bounds = |bx: &[(f64, f64)]| -> Result<Vec<(f64, f64)>, String> {
        let zs = premise_range::on_box(&graph.builder, z, bx)
            .into_iter()
            .zip(&ranges)
            .map(|(r, (lo, hi))| match r {
                Some((a, b)) if a.is_finite() && b.is_finite() => {
                    Ok((a.clamp(*lo, *hi), b.clamp(*lo, *hi)))
                }
                _ => Err("a premise value is unbounded on a sub-box of the region".to_string()),
            })
            .collect::<Result<Vec<_>, _>>()?;
        membership_bounds(&model.terms, &zs)
    };
    let boxes = per.pow(split.len() as u32);
    let mut delta = vec![0.0f64; model.r()];
    for index in 0..boxes {
        let mut b = samples.clone();
        let mut rest = index;
        for &s in &split {
            let (lo, hi) = samples[s];
            let w = (hi - lo) / per as f64;
            let c = rest % per;
            rest /= per;
            b[s] = (
                lo + w * c as f64,
                if c + 1 == per {
                    hi
                } else {
                    lo + w * (c + 1) as f64
                },
            );
        }
        let grown: Vec<(f64, f64)> = b
            .iter()
            .zip(&steps)
            .zip(&region)
            .map(|(((lo, hi), d), (rlo, rhi))| ((lo - d).max(*rlo), (hi + d).min(*rhi)))
            .collect();
        let (h, g) = (bounds(&b)?, bounds(&grown)?);
        for (i, ((lo, hi), (glo, ghi))) in h.iter().zip(&g).enumerate() {
            delta[i] = delta[i].max(ghi - lo).max(hi - glo);
        }
    }
    Ok(DriftBound {
        period,
        region,
        input_bound: input,
        rates,
        steps,
        samples,
        delta,
        boxes,
    })
}
