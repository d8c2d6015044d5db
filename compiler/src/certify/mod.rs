//! The certificate: every LMI of the *unreduced* problem is rebuilt from the
//! numeric solution (variable values, not solver slacks) and its extreme
//! eigenvalue computed with a dense symmetric eigen-solver. Gains are emitted
//! only if every strict LMI holds beyond its floating-point error bound.

pub mod degree_rounding;
mod markov;
mod output;
pub mod stored;

use crate::model::TsModel;
use crate::synth::loops::{Condition, Rounding};
use crate::synth::{build, Design, Reduction, SynthError};
use serde::Serialize;
use tsf_lmi::ConstraintKind;

pub use stored::{MembershipBound, StoredPrecision};

/// Named values of the variables of a problem.
type Values = Vec<(String, nalgebra::DMatrix<f64>)>;

/// The margin of one constraint.
#[derive(Debug, Clone, Serialize, PartialEq, schemars::JsonSchema)]
pub struct LmiMargin {
    /// Constraint name (e.g. `hinf Q[2,5]`).
    pub name: String,
    /// Strict-feasibility measure: lambda_min(E) for E > 0, -lambda_max(E) for E < 0
    /// (e - rhs for scalar constraints). Positive means the condition holds.
    pub margin: f64,
    /// Bound on the rounding error of `margin`.
    pub error_bound: f64,
    /// Whether the condition is strict (`< 0`, `> 0`).
    pub strict: bool,
    /// Matrix size (1 for scalars).
    pub size: usize,
    /// Whether this constraint passes.
    pub ok: bool,
}

/// What the certificate certifies, in words (also in the report).
pub const RULE: &str = "a strict LMI holds when its margin exceeds its rounding-error bound (margin > error_bound > 0); a non-strict one when its margin is at least -error_bound; the solver's margin lmi_margin_eps is what the SDP asked for, not what the certificate requires";

/// The certificate of a design.
#[derive(Debug, Clone, Serialize, PartialEq, schemars::JsonSchema)]
pub struct Certificate {
    /// What passing means ([`RULE`]).
    pub rule: &'static str,
    /// Smallest margin over the strict LMIs.
    pub min_margin: f64,
    /// Whether every constraint passes.
    pub ok: bool,
    /// The constraint closest to failing (or failing).
    pub worst: String,
    /// Every constraint.
    pub lmis: Vec<LmiMargin>,
    /// The re-check with the tables as generated code stores them (reported
    /// at the top of the report, not inside `certificate`); `None` when the
    /// certificate at the solved values already fails.
    #[serde(skip)]
    pub stored: Option<StoredPrecision>,
}

/// Margins of every constraint of the full `problem` at the solved values.
/// The reductions applied to the solved problem are inverted first (they
/// restore the variables it did not have); a variable still without a value
/// is an error, never silently zero. `substitute` then replaces values (the
/// stored-precision check puts the stored gains and weight in).
fn margins_of(
    problem: &tsf_lmi::Problem,
    nonstrict: &[String],
    solved: &[(String, nalgebra::DMatrix<f64>)],
    reductions: &[Reduction],
    substitute: &dyn Fn(&mut Values),
) -> Result<Vec<LmiMargin>, SynthError> {
    let mut named = solved.to_vec();
    for r in reductions {
        r.invert(&mut named);
    }
    substitute(&mut named);
    let mut values = problem.assignment();
    for (name, v) in problem.vars() {
        let Some((_, value)) = named.iter().find(|(n, _)| n == name) else {
            return Err(SynthError::Internal(format!(
                "internal error: variable `{name}` of the certified problem has no value (a reduction was not inverted)"
            )));
        };
        values
            .set(v, value.clone())
            .map_err(|e| SynthError::Internal(format!("internal error: {e}")))?;
    }
    let margins = problem
        .margins(&values)
        .map_err(|e| SynthError::Internal(format!("internal error: {e}")))?;
    Ok(margins
        .into_iter()
        .map(|m| {
            let (strict, size) = match m.kind {
                ConstraintKind::Lmi { margin, size, .. } => {
                    (margin > 0.0 && !nonstrict.contains(&m.name), size)
                }
                ConstraintKind::Scalar { .. } => (false, 1),
            };
            let ok = if strict {
                m.slack > m.error_bound
            } else {
                m.slack >= -m.error_bound
            };
            LmiMargin {
                name: m.name,
                margin: m.slack,
                error_bound: m.error_bound,
                strict,
                size,
                ok,
            }
        })
        .collect())
}

/// Checks `design` against the full set of conditions of its plan. With
/// given gains the conditions are rebuilt with the rules' F_j (never a gain
/// recovered from the solution), and the design must carry exactly those.
pub fn certify(model: &TsModel, design: &Design) -> Result<Certificate, SynthError> {
    if let (Some(modes), Some(md)) = (&model.spec.modes, &design.modes) {
        return markov::certify(model, design, modes, md);
    }
    let model = &*crate::synth::codesign::analysis_model(model, design);
    if let Some(given) = model.spec.given_gains() {
        let same = given.len() == design.gains.len()
            && given.iter().zip(&design.gains).all(|(f, g)| {
                f.shape() == g.shape()
                    && f.iter()
                        .zip(g.iter())
                        .all(|(a, b)| a.to_bits() == b.to_bits())
            });
        if !same {
            return Err(SynthError::Internal(
                "internal error: the design's gains are not the rules' given gains".into(),
            ));
        }
    }
    let built = build(
        model,
        &design.plan,
        model.spec.relaxation.node,
        design.eps,
        false,
    )?;
    let mut lmis = margins_of(
        &built.problem,
        &built.nonstrict,
        &design.values,
        &design.reductions,
        &|_| {},
    )?;
    // The loop that ships (sampled, event-triggered, mixed): rebuilt with
    // the design's gains (the ones emitted), not a copy.
    lmis.extend(loop_margins(model, design, &design.gains, None)?);
    lmis.extend(fuzzy_region(design));
    lmis.extend(output::margins(model, design, None)?);
    let mut cert = summarize(lmis);
    if cert.ok {
        let stored = stored::check(model, design, &built)?;
        if !stored.certified {
            cert.ok = false;
            cert.worst = stored.worst_lmi.clone();
        }
        cert.stored = Some(stored);
    }
    Ok(cert)
}

/// The certificate's verdict on `design` (what the driver hands synthesis as
/// [`crate::synth::Settings::verifier`]).
pub fn verdict(model: &TsModel, design: &Design) -> Result<bool, SynthError> {
    certify(model, design).map(|c| c.ok)
}

/// Margins of every condition of the loop the design ships (its
/// [`LoopCertificate`]), rebuilt with `gains`, rounded as stored with `stored`.
fn loop_margins(
    model: &TsModel,
    design: &Design,
    gains: &[nalgebra::DMatrix<f64>],
    stored: Option<Rounding<'_>>,
) -> Result<Vec<LmiMargin>, SynthError> {
    let Some(law) = design.loop_design.certificate() else {
        return Ok(Vec::new());
    };
    let mut lmis = Vec::new();
    for c in law.conditions(model, design.eps, gains, stored)? {
        match c {
            Condition::Problem {
                problem,
                nonstrict,
                values,
                reductions,
            } => lmis.extend(margins_of(
                &problem,
                &nonstrict,
                &values,
                &reductions,
                &|_| {},
            )?),
            Condition::Margin {
                name,
                margin,
                error_bound,
                size,
                strict,
                ok,
            } => lmis.push(LmiMargin {
                name,
                margin,
                error_bound,
                strict,
                size,
                ok,
            }),
        }
    }
    Ok(lmis)
}

/// The name of the certificate's entry for the region of a fuzzy Lyapunov function.
pub const FUZZY_REGION: &str = "fuzzy Lyapunov: |dh_k/dt| <= phi_k on a level set of V (sampled)";

/// The entry of a fuzzy Lyapunov design's region: its level c as the margin,
/// passing when a level c > 0 was found (synth/lyapunov/region.rs).
fn fuzzy_region(design: &Design) -> Option<LmiMargin> {
    let f = design.fuzzy.as_ref()?;
    let level = f.region.as_ref().map_or(0.0, |r| r.level);
    Some(LmiMargin {
        name: FUZZY_REGION.into(),
        margin: level,
        error_bound: 0.0,
        strict: false,
        size: 1,
        ok: level > 0.0,
    })
}

/// The certificate of a list of margins: the least strict margin, whether
/// every condition passes, and the worst condition (a failing one if any,
/// else the strict one with the least room).
fn summarize(lmis: Vec<LmiMargin>) -> Certificate {
    let min_margin = lmis
        .iter()
        .filter(|l| l.strict)
        .map(|l| l.margin)
        .fold(f64::INFINITY, f64::min);
    let ok = lmis.iter().all(|l| l.ok);
    // The worst: a failing one if any, else the strict one with the least room.
    let worst = lmis
        .iter()
        .min_by(|a, b| {
            let key = |l: &LmiMargin| {
                (
                    l.ok,
                    if l.strict {
                        l.margin - l.error_bound
                    } else {
                        f64::INFINITY
                    },
                )
            };
            let (ka, kb) = (key(a), key(b));
            ka.0.cmp(&kb.0).then(ka.1.total_cmp(&kb.1))
        })
        .map(|l| l.name.clone())
        .unwrap_or_default();
    Certificate {
        rule: RULE,
        min_margin,
        ok,
        worst,
        lmis,
        stored: None,
    }
}
