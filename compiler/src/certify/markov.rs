//! The certificate of a design with Markov-switching modes: every condition
//! (P) of `synth/markov` rebuilt in P variables, with P_a = X_a^{-1} and the
//! design's gains F_aj as constants,
//!
//! sum_k w_k G_{a i_k j_k} + c P_a Y_a P_a < 0,
//! G_aij = He(P_a (A_i + B_ai F_aj)) + sum_b pi_ab P_b + 2 alpha P_a,
//!
//! for every mode a and every condition of the relaxation (the relaxation seam's conditions as data),
//! with P_a > 0 and (tanaka) P_a Y_a P_a >= 0; margins under the rule of every
//! certificate ([`super::RULE`]). The stored-precision re-check rebuilds the
//! same conditions with the gains as generated code stores them.
//!
//! A sampled loop (`synth/markov/sampled.rs`) adds its conditions, rebuilt
//! with the same gains at every vertex (h_min and h_max), at the solved
//! P_a, Y, L1_a, L2_a of the functional.

use super::stored::{membership_bound, stored, StoredPrecision};
use super::{margins_of, summarize, Certificate, LmiMargin};
use crate::model::TsModel;
use crate::synth::markov::problem::{
    condition_name, diagonal_shift, input_matrices, PerfMatrices, Performance,
};
use crate::synth::markov::sampled::ModesSampled;
use crate::synth::markov::ModesDesign;
use crate::synth::relaxation::PairCondition;
use crate::synth::relaxations::conditions;
use crate::synth::{Design, SynthError};
use nalgebra::DMatrix;
use tsf_lang::modes::Modes;
use tsf_lang::spec::Precision;
use tsf_lmi::{Expr, Problem};

/// The name of P_a in the certified problem.
fn p_name(mode: &str) -> String {
    format!("P_{mode}")
}

/// The conditions (P) for `gains` (per mode, per rule), and the names of the
/// non-strict ones.
fn p_problem(
    model: &TsModel,
    modes: &Modes,
    md: &ModesDesign,
    gains: &[Vec<DMatrix<f64>>],
    conds: &[PairCondition],
    eps: f64,
) -> Result<(Problem, Vec<String>), SynthError> {
    let n = model.n;
    let lmi = |e: tsf_lmi::LmiError| SynthError::Internal(format!("internal error: {e}"));
    let mut problem = Problem::new();
    let mut nonstrict = Vec::new();
    let p = modes
        .modes
        .iter()
        .map(|m| problem.symmetric(&p_name(&m.name), n))
        .collect::<Result<Vec<_>, _>>()
        .map_err(lmi)?;
    let id = DMatrix::identity(n, n);
    let shift = diagonal_shift(md.alpha, &md.performance);
    let mats = PerfMatrices::of(model, &md.performance);
    let ftb = md.finite_time();
    if matches!(md.performance, Performance::FiniteTime(_)) && ftb.is_none() {
        return Err(SynthError::Internal(
            "internal error: the finite-time numbers of the design are not defined (P_a or R not positive definite)".into(),
        ));
    }
    for (a, mode) in modes.modes.iter().enumerate() {
        problem
            .psd(&format!("{} > 0", p_name(&mode.name)), Expr::var(p[a]), eps)
            .map_err(lmi)?;
        if let Some((f, numbers)) = &ftb {
            let (lower, upper) = (
                format!("mode {} P >= lambda1 R", mode.name),
                format!("mode {} P <= lambda2 R", mode.name),
            );
            let r = |s: f64| Expr::constant(&(&f.r * s));
            let e = Expr::var(p[a])
                .sub(r(numbers.lambda1).map_err(lmi)?)
                .map_err(lmi)?;
            problem.psd(&lower, e, 0.0).map_err(lmi)?;
            let e = r(numbers.lambda2)
                .map_err(lmi)?
                .sub(Expr::var(p[a]))
                .map_err(lmi)?;
            problem.psd(&upper, e, 0.0).map_err(lmi)?;
            nonstrict.push(lower);
            nonstrict.push(upper);
        }
        let y = match &md.slack[a] {
            Some(_) => {
                let y = problem
                    .symmetric(&format!("PYP_{}", mode.name), n)
                    .map_err(lmi)?;
                let name = format!("mode {} Y >= 0", mode.name);
                problem.psd(&name, Expr::var(y), eps).map_err(lmi)?;
                nonstrict.push(name);
                Some(y)
            }
            None => None,
        };
        let b = input_matrices(model, modes, a);
        let g = |i: usize, j: usize| -> Result<Expr, tsf_lmi::LmiError> {
            let acl = &model.rules[i].a + &b[i] * &gains[a][j];
            let mut e = Expr::product(&id, p[a], &acl)?.he()?;
            e = e.add(Expr::var(p[a]).scale(shift)?)?;
            for (c, pc) in p.iter().enumerate() {
                let pi = modes.rates[(a, c)];
                if pi != 0.0 {
                    e = e.add(Expr::var(*pc).scale(pi)?)?;
                }
            }
            Ok(e)
        };
        for c in conds {
            let mut e = Expr::zeros(n, n);
            for &(i, j, w) in &c.terms {
                e = e
                    .add(g(i, j).map_err(lmi)?.scale(w).map_err(lmi)?)
                    .map_err(lmi)?;
            }
            if let (Some(y), true) = (y, c.slack != 0.0) {
                e = e
                    .add(Expr::var(y).scale(c.slack).map_err(lmi)?)
                    .map_err(lmi)?;
            }
            if let Some(mats) = &mats {
                e = performance_blocks(e, mats, md, p[a], &gains[a], &c.terms, n).map_err(lmi)?;
            }
            let name = condition_name(&mode.name, c);
            problem.nsd(&name, e, eps).map_err(lmi)?;
            if !c.strict {
                nonstrict.push(name);
            }
        }
    }
    Ok((problem, nonstrict))
}

/// The condition's top-left block `top` bordered by the performance rows, in
/// P variables: H-inf [[top, P_a D, (C + E F_aj)'], [*, -gamma^2 I, G'],
/// [*, *, -I]], finite time [[top, P_a D], [*, -lambda3 I]], summed over the
/// condition's terms (weights w_k, total k).
fn performance_blocks(
    top: Expr,
    mats: &PerfMatrices,
    md: &ModesDesign,
    p: tsf_lmi::Var,
    gains: &[DMatrix<f64>],
    terms: &[(usize, usize, f64)],
    n: usize,
) -> Result<Expr, tsf_lmi::LmiError> {
    let q = mats.q();
    let k: f64 = terms.iter().map(|t| t.2).sum();
    let pd = Expr::product(&DMatrix::identity(n, n), p, &mats.d_sum(terms))?;
    let weight = |w: f64| Expr::constant(&(DMatrix::identity(q, q) * (-k * w)));
    match (&md.performance, &mats.output) {
        (Performance::Hinf { gamma, .. }, Some((c, e, g))) => {
            let gamma = gamma.unwrap_or(f64::NAN);
            let out = terms
                .iter()
                .fold(DMatrix::zeros(c.nrows(), n), |acc, &(_, j, w)| {
                    acc + (c + e * &gains[j]) * w
                });
            Expr::sym_blocks(vec![
                vec![Some(top), Some(pd), Some(Expr::constant(&out.transpose())?)],
                vec![
                    None,
                    Some(weight(gamma * gamma)?),
                    Some(Expr::constant(&(g.transpose() * k))?),
                ],
                vec![None, None, Some(Expr::identity(c.nrows()).scale(-k)?)],
            ])
        }
        (Performance::FiniteTime(_), _) if q > 0 => Expr::sym_blocks(vec![
            vec![Some(top), Some(pd)],
            vec![None, Some(weight(md.lambda3)?)],
        ]),
        _ => Ok(top),
    }
}

/// The last finite-time condition, e^{alpha T} (lambda2 c1 + lambda3 w2) /
/// lambda1 < c2 for the claimed c2 (the bound, or the SDP's minimum), as a
/// margin c2 - (that bound).
fn finite_time_margin(md: &ModesDesign) -> Option<LmiMargin> {
    let (f, numbers) = md.finite_time()?;
    let claimed = f.c2.unwrap_or(f64::NAN);
    let margin = claimed - numbers.c2;
    let error_bound = 1e-12 * claimed.abs().max(numbers.c2.abs());
    Some(LmiMargin {
        name: "finite time: e^(alpha T) (lambda2 c1 + lambda3 w2) / lambda1 < c2".into(),
        margin,
        error_bound,
        strict: true,
        size: 1,
        ok: margin > error_bound,
    })
}

/// Margins of every condition (P) with `gains` (`eps` marks the strict ones;
/// the certificate does not ask for it).
fn margins(
    model: &TsModel,
    modes: &Modes,
    md: &ModesDesign,
    gains: &[Vec<DMatrix<f64>>],
    sampled: Option<&ModesSampled>,
    eps: f64,
) -> Result<Vec<LmiMargin>, SynthError> {
    let Some(conds) = conditions(model, model.spec.relaxation.node).map(|c| c.list) else {
        return Err(SynthError::Unsupported(
            "this relaxation is not supported with `modes`".into(),
        ));
    };
    let modes = &with_exact_rows(modes);
    let (problem, nonstrict) = p_problem(model, modes, md, gains, &conds, eps)?;
    let mut values: Vec<(String, DMatrix<f64>)> = Vec::new();
    for (a, mode) in modes.modes.iter().enumerate() {
        values.push((p_name(&mode.name), md.p[a].clone()));
        if let Some(y) = &md.slack[a] {
            values.push((format!("PYP_{}", mode.name), y.clone()));
        }
    }
    let mut out = margins_of(&problem, &nonstrict, &values, &[], &|_| {})?;
    out.extend(finite_time_margin(md));
    if let Some(s) = sampled {
        // The sampled loop, every vertex (h_min too), with the same `gains`.
        let problem =
            crate::synth::markov::sampled::build(model, modes, gains, s.sampling, eps, false)
                .map_err(|e| SynthError::Internal(format!("internal error: {e}")))?;
        out.extend(margins_of(&problem, &[], &s.values, &[], &|_| {})?);
    }
    Ok(out)
}

/// The rates the certificate uses: each diagonal entry pi_aa replaced by the
/// larger of itself and -sum_{b != a} pi_ab. The checker lets a row sum to 0
/// within a relative tolerance; a diagonal below the exact one would count
/// the defect (pi_aa + sum_b pi_ab) P_a < 0 as decay. With the larger one the
/// conditions imply those of the exact generator (P_a > 0), whichever
/// diagonal the written one rounds.
pub fn with_exact_rows(modes: &Modes) -> Modes {
    let mut out = modes.clone();
    let k = out.rates.nrows();
    for a in 0..k {
        let off: f64 = (0..k).filter(|&b| b != a).map(|b| out.rates[(a, b)]).sum();
        out.rates[(a, a)] = out.rates[(a, a)].max(-off);
    }
    out
}

/// The certificate of a mode design, with its stored-precision re-check.
pub fn certify(
    model: &TsModel,
    design: &Design,
    modes: &Modes,
    md: &ModesDesign,
) -> Result<Certificate, SynthError> {
    let sampled = design.loop_design.sampled_modes();
    let mut cert = summarize(margins(model, modes, md, &md.gains, sampled, design.eps)?);
    if cert.ok {
        let s = stored_check(model, modes, md, sampled, design.eps)?;
        if !s.certified {
            cert.ok = false;
            cert.worst = s.worst_lmi.clone();
        }
        cert.stored = Some(s);
    }
    Ok(cert)
}

/// The conditions re-checked with every F_aj as generated code stores it,
/// and the membership rounding bound of the worst mode (P form: the blended
/// gain's error enters as He(P_a B_ai dF), so the bound is taken with P_a).
fn stored_check(
    model: &TsModel,
    modes: &Modes,
    md: &ModesDesign,
    sampled: Option<&ModesSampled>,
    eps: f64,
) -> Result<StoredPrecision, SynthError> {
    let precision = model.spec.precision;
    let round = |f: &DMatrix<f64>| f.map(|v| stored(v, precision));
    let gains: Vec<Vec<DMatrix<f64>>> = md
        .gains
        .iter()
        .map(|g| g.iter().map(round).collect())
        .collect();
    let max_relative_rounding = md
        .gains
        .iter()
        .flatten()
        .flat_map(|f| f.iter().copied())
        .filter(|v| v.is_finite() && *v != 0.0)
        .map(|v| ((stored(v, precision) - v) / v).abs())
        .fold(0.0, f64::max);
    let lmis = margins(model, modes, md, &gains, sampled, eps)?;
    let mut worst_membership = None;
    for (a, mode) in modes.modes.iter().enumerate() {
        let prefix = format!("mode {} ", mode.name);
        // The continuous conditions (P) only: the bound is taken with their P_a.
        let available = lmis
            .iter()
            .filter(|l| l.strict && l.name.starts_with(&prefix) && !l.name.contains(" sampled "))
            .map(|l| l.margin)
            .fold(f64::INFINITY, f64::min);
        let mut mode_model = model.clone();
        for (rule, b) in mode_model
            .rules
            .iter_mut()
            .zip(input_matrices(model, modes, a))
        {
            rule.b = b;
        }
        let bound = membership_bound(&mode_model, &gains[a], &md.p[a], precision, available);
        let worse = worst_membership
            .as_ref()
            .is_none_or(|w: &super::MembershipBound| {
                (bound.required_margin - bound.available_margin)
                    > (w.required_margin - w.available_margin)
            });
        if worse {
            worst_membership = Some(bound);
        }
    }
    let Some(membership) = worst_membership else {
        return Err(SynthError::Internal("internal error: no mode".into()));
    };
    let cert = summarize(lmis);
    let certified = cert.ok && membership.holds;
    Ok(StoredPrecision {
        precision: match precision {
            Precision::F32 => "f32",
            Precision::F64 => "f64",
        },
        certified,
        worst_margin: cert.min_margin,
        worst_lmi: if cert.ok && !membership.holds {
            "membership rounding".to_string()
        } else {
            cert.worst
        },
        conditions: cert.lmis.len(),
        max_relative_rounding,
        membership_rounding_bound: membership,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_certificate_never_counts_a_row_defect_as_decay() {
        let two =
            "modes { mode a { } mode b { } rates = [-1000000.0019, 1000000; 3, -2.9999999999]; }";
        let src = format!(
            "tsf 1; controller c; state x1; input u; A = -1; B = 1;\n\
             premise x1 range -1 .. 1 {{ all = trap(-1, -1, 1, 1); }}\n\
             rule R: x1 is all => A = -2;\n{two}\n"
        );
        let (spec, diags) = tsf_lang::check_source(&src);
        let modes = spec
            .and_then(|s| s.modes)
            .unwrap_or_else(|| panic!("{diags:#?}")); // ok: test
        let exact = with_exact_rows(&modes);
        // Row 1 is more negative than its rates: the exact diagonal is used.
        assert_eq!(exact.rates[(0, 0)], -1_000_000.0);
        // Row 2 is less negative (conservative): kept as written.
        assert_eq!(exact.rates[(1, 1)], -2.9999999999);
        for a in 0..2 {
            let sum: f64 = exact.rates.row(a).iter().sum();
            assert!(sum >= 0.0, "row {a} sums to {sum}");
        }
    }
}
