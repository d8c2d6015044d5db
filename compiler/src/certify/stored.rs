//! The certificate of the design as stored: every LMI of the certificate
//! (continuous problem and sampled/event-triggered loops) re-checked with
//! the quantities generated code stores, rounded exactly as it stores them,
//! and a bound on the arithmetic of membership evaluation, normalization and
//! blending in that precision (docs/precision.md).
//!
//! Stored quantities: the gains F_j, the saturation levels, an observer's
//! gains L_i (its conditions rebuilt by `output.rs`), and for a sensor
//! module the trigger weight Upsilon, the threshold ceiling nu and the
//! sampling bounds. Generated Rust and C print f64 literals in shortest
//! round-trip form, so `precision f64` stores every value exactly; with
//! `precision f32` both store `v as f32` (Rust prints the f32 in its own
//! shortest form, C converts the double literal to `float`, round to
//! nearest). Lyapunov matrices, multipliers and sector gains are proof
//! artefacts, not stored: they keep their solved values.

use super::degree_rounding::{gamma, normalized_weight_error, weight_relative_error};
use super::{loop_margins, margins_of, summarize, Values};
use crate::model::TsModel;
use crate::synth::build::Built;
use crate::synth::solved::Solved;
use crate::synth::{build, Design, SynthError};
use nalgebra::DMatrix;
use serde::Serialize;
use tsf_lang::spec::Precision;

/// The bound on membership evaluation, normalization and blending in the
/// stored precision, and the margin it asks of the continuous loop's LMIs.
#[derive(Debug, Clone, Serialize, PartialEq, schemars::JsonSchema)]
pub struct MembershipBound {
    /// Unit roundoff u of the precision (2^-24 or 2^-53).
    pub unit_roundoff: f64,
    /// Bound on the relative error of every computed rule weight (membership
    /// degrees evaluated in this precision over the premise ranges, and the
    /// product t-norm).
    pub degree_error: f64,
    /// Bound on sum_j |h~_j - h_j| of the normalized weights:
    /// 2 e / (1 - e) + gamma_R with e = `degree_error`.
    pub weight_error: f64,
    /// Bound eps_h on the blended gain's error relative to max_j ||F_j||_F,
    /// normalization and blend arithmetic together.
    pub relative_gain_error: f64,
    /// Bound delta = eps_h max_j ||F_j||_F on the spectral norm of the
    /// blended gain's error.
    pub gain_error: f64,
    /// Margin the closed-loop LMIs need: 2 r max_i ||B_i|| delta ||X||.
    pub required_margin: f64,
    /// Least margin of the continuous loop's closed-loop LMIs as stored.
    pub available_margin: f64,
    /// Whether `available_margin > required_margin`.
    pub holds: bool,
}

/// The stored-precision certificate.
#[derive(Debug, Clone, Serialize, PartialEq, schemars::JsonSchema)]
pub struct StoredPrecision {
    /// `f32` or `f64`.
    pub precision: &'static str,
    /// Every LMI holds with the stored quantities and the membership bound holds.
    pub certified: bool,
    /// Least margin over the strict LMIs re-checked with the stored quantities.
    pub worst_margin: f64,
    /// The condition closest to failing (or failing); `membership rounding`
    /// when only the membership bound fails.
    pub worst_lmi: String,
    /// Conditions re-checked.
    pub conditions: usize,
    /// Largest change of a stored quantity by rounding, relative to its size.
    pub max_relative_rounding: f64,
    /// Membership normalization and blending in this precision.
    pub membership_rounding_bound: MembershipBound,
}

/// A value as generated code stores it.
pub fn stored(v: f64, precision: Precision) -> f64 {
    match precision {
        Precision::F64 => v,
        Precision::F32 => f64::from(v as f32),
    }
}

/// A matrix as generated code stores it.
fn stored_mat(m: &DMatrix<f64>, precision: Precision) -> DMatrix<f64> {
    m.map(|v| stored(v, precision))
}

/// The unit roundoff of a precision.
pub fn unit_roundoff(precision: Precision) -> f64 {
    match precision {
        Precision::F64 => f64::EPSILON / 2.0,
        Precision::F32 => f64::from(f32::EPSILON) / 2.0,
    }
}

/// Whether a constraint carries the closed-loop matrix (not a positivity
/// constraint `... > 0` on one variable).
fn closed_loop(name: &str) -> bool {
    !name.ends_with("> 0")
}

/// The membership bound for `gains` (stored) with `x` the solved X.
pub(super) fn membership_bound(
    model: &TsModel,
    gains: &[DMatrix<f64>],
    x: &DMatrix<f64>,
    precision: Precision,
    available_margin: f64,
) -> MembershipBound {
    let (n, r) = (model.n, model.r());
    let u = unit_roundoff(precision);
    let degree_error = weight_relative_error(model, precision);
    let weight_error = normalized_weight_error(degree_error) + gamma(r, u);
    let relative_gain_error = weight_error + gamma(n + r + 1, u) * (1.0 + weight_error);
    let f_max = gains.iter().map(|f| f.norm()).fold(0.0, f64::max);
    let b_max = model
        .rules
        .iter()
        .map(|l| spectral_norm(&l.b))
        .fold(0.0, f64::max);
    let gain_error = relative_gain_error * f_max;
    let required_margin = 2.0 * r as f64 * b_max * gain_error * spectral_norm(x);
    MembershipBound {
        unit_roundoff: u,
        degree_error,
        weight_error,
        relative_gain_error,
        gain_error,
        required_margin,
        available_margin,
        holds: available_margin > required_margin,
    }
}

/// Largest singular value.
fn spectral_norm(m: &DMatrix<f64>) -> f64 {
    m.singular_values().iter().copied().fold(0.0, f64::max)
}

/// The largest relative change rounding makes to the entries of `m`.
fn relative_rounding(m: &DMatrix<f64>, precision: Precision) -> f64 {
    m.iter()
        .filter(|v| v.is_finite() && **v != 0.0)
        .map(|v| ((stored(*v, precision) - v) / v).abs())
        .fold(0.0, f64::max)
}

/// The model with its given gains (if any) as stored.
fn stored_model(model: &TsModel, precision: Precision) -> TsModel {
    let mut m = model.clone();
    for rule in &mut m.spec.rules {
        if let Some((f, _)) = &mut rule.gain {
            *f = stored_mat(f, precision);
        }
    }
    m
}

/// Re-checks every LMI of the certificate of `design` with the stored
/// quantities, and the membership bound. `certified` is the problem the
/// certificate built from `model` and the design's plan: in f64 every stored
/// quantity equals the solved one, so it is the same problem and is reused.
pub fn check(
    model: &TsModel,
    design: &Design,
    certified: &Built,
) -> Result<StoredPrecision, SynthError> {
    let precision = model.spec.precision;
    let gains: Vec<DMatrix<f64>> = design
        .gains
        .iter()
        .map(|f| stored_mat(f, precision))
        .collect();
    let max_relative_rounding = design
        .gains
        .iter()
        .map(|f| relative_rounding(f, precision))
        .fold(0.0, f64::max);
    // Continuous loop: given gains rounded in the spec; designed gains enter
    // as M_j = F_j X, so M_j is replaced by (stored F_j) X.
    let stored_model = stored_model(model, precision);
    let mut plan = design.plan.clone();
    if let Some(s) = plan.saturation_mut() {
        s.levels = s.levels.iter().map(|v| stored(*v, precision)).collect();
    }
    let rebuilt;
    let built = match precision {
        Precision::F64 => certified,
        Precision::F32 => {
            rebuilt = build(
                &stored_model,
                &plan,
                model.spec.relaxation.node,
                design.eps,
                false,
            )?;
            &rebuilt
        }
    };
    let x_value = std::cell::RefCell::new(None);
    let substitute_gains = |values: &mut Values| {
        let x = values.x().cloned();
        if let Some(x) = &x {
            for (j, f) in gains.iter().enumerate() {
                if let Some(m) = values.gain_product_mut(j) {
                    *m = f * x;
                }
            }
        }
        *x_value.borrow_mut() = x;
    };
    let mut lmis = margins_of(
        &built.problem,
        &built.nonstrict,
        &design.values,
        &design.reductions,
        &substitute_gains,
    )?;
    let available = lmis
        .iter()
        .filter(|l| l.strict && closed_loop(&l.name))
        .map(|l| l.margin)
        .fold(f64::INFINITY, f64::min);
    let Some(x) = x_value.into_inner() else {
        return Err(SynthError::Internal(
            "internal error: the certified problem has no X".into(),
        ));
    };
    let mut membership = membership_bound(model, &gains, &x, precision, available);
    if let Some(f) = &design.fuzzy {
        // The gain error also enters the Finsler block mu N_ij': ||E|| <= (2 + mu) ||B dF G||.
        membership.required_margin *= 1.0 + 0.5 * f.mu;
        membership.holds = membership.available_margin > membership.required_margin;
    }
    // The loop that ships: gains, levels, threshold ceiling, sampling bounds
    // of a sensor module and the trigger weight as stored.
    let max_relative_rounding = design
        .loop_design
        .certificate()
        .map_or_else(Vec::new, |l| l.stored_matrices())
        .into_iter()
        .map(|m| relative_rounding(m, precision))
        .fold(max_relative_rounding, f64::max);
    let round = |v: f64| stored(v, precision);
    lmis.extend(loop_margins(&stored_model, design, &gains, Some(&round))?);
    lmis.extend(super::output::margins(
        &stored_model,
        design,
        Some((&gains, &round)),
    )?);
    let cert = summarize(lmis);
    let certified = cert.ok && membership.holds;
    let worst_lmi = if cert.ok && !membership.holds {
        "membership rounding".to_string()
    } else {
        cert.worst
    };
    Ok(StoredPrecision {
        precision: match precision {
            Precision::F32 => "f32",
            Precision::F64 => "f64",
        },
        certified,
        worst_margin: cert.min_margin,
        worst_lmi,
        conditions: cert.lmis.len(),
        max_relative_rounding,
        membership_rounding_bound: membership,
    })
}
