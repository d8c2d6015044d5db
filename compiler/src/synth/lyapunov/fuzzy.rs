//! A fuzzy Lyapunov function V = x' P(h) x, P(h) = sum_k h_k P_k, for the PDC
//! law u = sum_j h_j F_j x (Tanaka, Hori & Wang, *A multiple Lyapunov function
//! approach to stabilization of fuzzy control systems*, IEEE TFS 2003), made
//! an LMI problem by Finsler's lemma with the slack pair (R, mu R), as in
//! Mozelli, Palhares, Souza & Mendes (*Reducing conservativeness in recent
//! stability conditions of TS fuzzy systems*, Automatica 2009).
//!
//! With the closed loop x' = A_cl(h) x, A_cl = sum_ij h_i h_j (A_i + B_i F_j),
//! dV/dt = x' (sum_k h'_k P_k + He(P(h) A_cl)) x. Because sum_k h'_k = 0,
//! sum_k h'_k P_k = sum_k h'_k (P_k + Y) <= sum_k phi_k (P_k + Y) for any Y with
//! P_k + Y >= 0, when |h'_k| <= phi_k. Finsler's lemma on [x; x'] with
//! [A_cl, -I] [x; x'] = 0 and the congruence by G = R^{-T} turn dV/dt + 2 alpha V < 0 into
//!
//!   sum_k h_k sum_ij h_i h_j Q^k_ij < 0,
//!   Q^k_ij = [ Phi + 2 alpha P~_k + He(N_ij),  P~_k - G + mu N_ij' ]
//!            [ *,                              -mu He(G)          ],
//!   N_ij = A_i G + B_i Z_j,  Phi = sum_k phi_k (P~_k + Y~),
//!
//! in G (full), Z_j = F_j G, P~_k = G' P_k G > 0 and Y~ = G' Y G, for a fixed
//! scalar mu > 0 (a grid search, [`MU_GRID`]). For each k the double sum is
//! relaxed by the spec's relaxation, which is sufficient for the triple sum.
//! He(G) > 0 makes G invertible: F_j = Z_j G^{-1}, P_k = G^{-T} P~_k G^{-1}.
//! With P~_k = X, Y~ = -X, G = X this contains the quadratic conditions for
//! small mu, so the fuzzy function is never more conservative at a given phi.
//!
//! The certificate holds only where |dh_k/dt| <= phi_k: [`super::region`]
//! checks that a posteriori on a level set of V.

use crate::model::TsModel;
use crate::synth::blocks::{common_b, nonstrict_psd};
use crate::synth::build::Built;
use crate::synth::objective::{BuildError, GainTerm};
use crate::synth::plan::Plan;
use crate::synth::relaxation::Family;
use crate::synth::relaxations::Relaxer;
use crate::synth::solved::names;
use nalgebra::DMatrix;
use serde::Serialize;
use tsf_lang::spec::{Lyapunov, Relaxation};
use tsf_lmi::{Expr, LmiError, Problem, Var};

/// The values of mu tried, in order, until the conditions are feasible.
pub const MU_GRID: [f64; 11] = [1.0, 0.3, 0.1, 0.03, 0.01, 3e-3, 1e-3, 3e-4, 1e-4, 3.0, 10.0];

/// mu when a plan has none set.
pub const DEFAULT_MU: f64 = 1.0;

/// The phi_k of a spec with a fuzzy Lyapunov function.
pub fn phi(model: &TsModel) -> Option<&[f64]> {
    match &model.spec.lyapunov.node {
        Lyapunov::Fuzzy { phi } => Some(phi),
        Lyapunov::Quadratic => None,
    }
}

/// The variables of a fuzzy Lyapunov problem beyond G (`X`) and Z_j (`M_j`).
#[derive(Debug, Clone)]
pub struct FuzzyVars {
    /// P~_k = G' P_k G.
    pub p: Vec<Var>,
    /// Y~.
    pub y: Var,
    /// The Finsler scalar mu of this problem.
    pub mu: f64,
}

/// The fuzzy Lyapunov function of a design.
#[derive(Debug, Clone, Serialize, PartialEq, schemars::JsonSchema)]
pub struct FuzzyDesign {
    /// phi_k, the assumed bounds on |dh_k/dt|.
    pub phi: Vec<f64>,
    /// The Finsler scalar mu used.
    pub mu: f64,
    /// P_k (n x n), V = x' (sum_k h_k P_k) x.
    #[serde(skip)]
    pub p: Vec<DMatrix<f64>>,
    /// Where the assumption was checked to hold, if anywhere.
    pub region: Option<super::Region>,
}

/// The problem of `plan` with a fuzzy Lyapunov function (`phi` its bounds).
pub fn build(
    model: &TsModel,
    plan: &Plan,
    relaxation: Relaxation,
    eps: f64,
    reduce: bool,
    phi: &[f64],
) -> Result<Built, BuildError> {
    let (n, m, r) = (model.n, model.m, model.r());
    if phi.len() != r {
        return Err(BuildError::Unsupported(format!(
            "the fuzzy Lyapunov function has {} bounds phi for {r} rules",
            phi.len()
        )));
    }
    let mu = plan.mu.unwrap_or(DEFAULT_MU);
    let alpha = plan.decay().map_or(0.0, |d| d.alpha);
    let name = if plan.decay().is_some() {
        "decay"
    } else {
        "stability"
    };
    let mut problem = Problem::new();
    let g = problem.full(names::X, n, n)?;
    let z = (0..r)
        .map(|j| problem.full(&names::gain_product(j), m, n))
        .collect::<Result<Vec<_>, _>>()?;
    let p = (0..r)
        .map(|k| problem.symmetric(&format!("P{}", k + 1), n))
        .collect::<Result<Vec<_>, _>>()?;
    let y = problem.symmetric("Y", n)?;
    let mut relaxer = Relaxer::new(model, relaxation, eps, reduce && common_b(model));
    problem.psd("He(X) > 0", Expr::var(g).he()?, eps)?;
    for (k, pk) in p.iter().enumerate() {
        problem.psd(&format!("P{} > 0", k + 1), Expr::var(*pk), eps)?;
        nonstrict_psd(
            &mut problem,
            &mut relaxer.nonstrict,
            &format!("P{} + Y >= 0", k + 1),
            Expr::var(*pk).add(Expr::var(y))?,
            eps,
        )?;
    }
    let id = DMatrix::identity(n, n);
    let big_phi = p
        .iter()
        .zip(phi)
        .try_fold(Expr::zeros(n, n), |acc, (pk, f)| {
            acc.add(Expr::var(*pk).add(Expr::var(y))?.scale(*f)?)
        })?;
    let n_ij = |i: usize, j: usize| -> Result<Expr, LmiError> {
        let rule = &model.rules[i];
        Expr::product(&rule.a, g, &id)?.add(Expr::product(&rule.b, z[j], &id)?)
    };
    for (k, pk) in p.iter().enumerate() {
        let q = |i: usize, j: usize| -> Result<Expr, LmiError> {
            let nij = n_ij(i, j)?;
            let b11 = big_phi
                .clone()
                .add(Expr::var(*pk).scale(2.0 * alpha)?)?
                .add(nij.clone().he()?)?;
            let b12 = Expr::var(*pk)
                .sub(Expr::var(g))?
                .add(nij.transpose().scale(mu)?)?;
            let b22 = Expr::var(g).he()?.scale(-mu)?;
            Expr::sym_blocks(vec![vec![Some(b11), Some(b12)], vec![None, Some(b22)]])
        };
        let fam = Family {
            name: format!("{name} k{}", k + 1),
            q: Box::new(q),
        };
        relaxer.impose(&mut problem, &fam)?;
    }
    Ok(Built {
        problem,
        x: g,
        m: z.into_iter().map(GainTerm::Free).collect(),
        reductions: relaxer.reductions,
        nonstrict: relaxer.nonstrict,
        fuzzy: Some(FuzzyVars { p, y, mu }),
        given: None,
    })
}

/// PDC gains F_j, in rule order.
pub type Gains = Vec<DMatrix<f64>>;

/// The gains F_j = Z_j G^{-1} and the Lyapunov matrices P_k = G^{-T} P~_k G^{-1}
/// of a solution (`g` the solved G, `z` the Z_j, `pt` the P~_k); `None` when G
/// is numerically singular.
pub fn recover(
    g: &DMatrix<f64>,
    z: &[DMatrix<f64>],
    pt: &[DMatrix<f64>],
) -> Option<(Gains, Vec<DMatrix<f64>>)> {
    let ginv = g.clone().try_inverse()?;
    if ginv.iter().any(|v| !v.is_finite()) {
        return None;
    }
    let gains = z.iter().map(|zj| zj * &ginv).collect();
    let p = pt
        .iter()
        .map(|pk| {
            let v = ginv.transpose() * pk * &ginv;
            (&v + v.transpose()) * 0.5
        })
        .collect();
    Some((gains, p))
}

/// dV/dt of the closed loop at memberships `h` and membership derivatives
/// `hdot`, as the symmetric matrix sum_k hdot_k P_k + He(P(h) A_cl(h)) (the
/// design is certified where it is negative definite for every admissible
/// h, hdot); used by the report's independent checks and the tests.
pub fn derivative_matrix(
    model: &TsModel,
    gains: &[DMatrix<f64>],
    p: &[DMatrix<f64>],
    h: &[f64],
    hdot: &[f64],
) -> DMatrix<f64> {
    let n = model.n;
    let mut acl = DMatrix::zeros(n, n);
    let f: DMatrix<f64> = gains
        .iter()
        .zip(h)
        .fold(DMatrix::zeros(model.m, n), |acc, (fj, hj)| acc + fj * *hj);
    for (rule, hi) in model.rules.iter().zip(h) {
        acl += (&rule.a + &rule.b * &f) * *hi;
    }
    let ph = p
        .iter()
        .zip(h)
        .fold(DMatrix::zeros(n, n), |acc, (pk, hk)| acc + pk * *hk);
    let pdot = p
        .iter()
        .zip(hdot)
        .fold(DMatrix::zeros(n, n), |acc, (pk, dk)| acc + pk * *dk);
    let pa = &ph * &acl;
    pdot + &pa + pa.transpose()
}

/// The first mu of [`MU_GRID`] at which `plan` (at decay rate 0 when the
/// rate is maximized) is feasible; [`DEFAULT_MU`] when none is (the run then
/// fails and is diagnosed as usual).
pub(in crate::synth) fn choose_mu(
    runner: &mut crate::synth::search::Runner<'_>,
    plan: &Plan,
    goal: crate::synth::Goal,
) -> Result<f64, crate::synth::SynthError> {
    use crate::synth::search::Attempt;
    for mu in MU_GRID {
        let mut p = if goal == crate::synth::Goal::MaxDecay {
            plan.with_decay(0.0)
        } else {
            plan.clone()
        };
        p.mu = Some(mu);
        if let Attempt::Solved(_) = runner.attempt(&p)? {
            return Ok(mu);
        }
    }
    Ok(DEFAULT_MU)
}

/// A maximized decay rate with a fuzzy Lyapunov function: the bisection at
/// every mu of [`MU_GRID`] feasible at rate 0 (the best rate needs its own mu:
/// the quadratic limit needs a small one), keeping the largest rate (the
/// first mu on ties). `plan.mu` is feasible at rate 0 when any is.
pub(in crate::synth) fn max_decay_over_mu(
    runner: &mut crate::synth::search::Runner<'_>,
    plan: &Plan,
) -> Result<Option<crate::synth::Design>, crate::synth::SynthError> {
    use crate::synth::{Goal, Quantity};
    let rate = |d: &crate::synth::Design| d.achieved.get(Quantity::DecayRate).unwrap_or(0.0);
    let mut best: Option<crate::synth::Design> = runner.run(plan, Goal::MaxDecay)?;
    if best.is_none() {
        return Ok(None);
    }
    for mu in MU_GRID {
        if Some(mu) == plan.mu {
            continue;
        }
        let mut p = plan.clone();
        p.mu = Some(mu);
        // A mu at which the solver stalls is skipped, not fatal.
        if let Ok(Some(d)) = runner.run(&p, Goal::MaxDecay) {
            if best.as_ref().is_none_or(|b| rate(&d) > rate(b)) {
                best = Some(d);
            }
        }
    }
    Ok(best)
}
