//! The observer gains L_i: with measured premises the error e = x - x_hat
//! obeys e' = sum_i h_i (A_i - L_i C) e, a single sum, so the vertex
//! conditions He(P2 A_i - N_i C) + 2 alpha_o P2 < 0 (N_i = P2 L_i) are
//! exactly the common-quadratic conditions (no relaxation is needed).
//! Synthesis adds P2 >= I and minimizes kappa with ||N_i|| <= kappa, which
//! keeps the gains moderate; the certificate rebuilds the decay conditions
//! and P2 > 0 with N_i = P2 L_i from the shipped L_i.

use crate::model::TsModel;
use crate::synth::{Runner, SynthError};
use nalgebra::DMatrix;
use tsf_lmi::{Expr, LmiError, Problem, SolveStatus, Var};

/// The variable P2.
pub const P2: &str = "P2_obs";
/// kappa, the bound on ||N_i|| (synthesis only).
pub const KAPPA: &str = "kappa_obs";

/// The observer LMIs are solved with this many times the spec's margin eps.
pub const OBSERVER_MARGIN_FACTOR: f64 = 10.0;

/// N_i = P2 L_i of rule `i` (0-based).
pub fn product(i: usize) -> String {
    format!("N{}_obs", i + 1)
}

/// The observer problem: variables P2, N_i; `synthesis` adds the gain bound.
pub struct ObserverProblem {
    /// The problem.
    pub problem: Problem,
    /// P2.
    pub p2: Var,
    /// N_i.
    pub n: Vec<Var>,
    /// Constraints non-strict in the theory.
    pub nonstrict: Vec<String>,
}

/// Builds the observer LMIs for `c` and decay `alpha`.
pub fn problem(
    model: &TsModel,
    c: &DMatrix<f64>,
    alpha: f64,
    eps: f64,
    synthesis: bool,
) -> Result<ObserverProblem, LmiError> {
    let n = model.n;
    let p = c.nrows();
    let mut problem = Problem::new();
    let p2 = problem.symmetric(P2, n)?;
    let nv = (0..model.r())
        .map(|i| problem.full(&product(i), n, p))
        .collect::<Result<Vec<_>, _>>()?;
    let mut nonstrict = Vec::new();
    problem.psd("observer P2 > 0", Expr::var(p2), eps)?;
    for (i, rule) in model.rules.iter().enumerate() {
        let q = Expr::var(p2)
            .right_mul(&rule.a)?
            .sub(Expr::var(nv[i]).right_mul(c)?)?
            .he()?
            .add(Expr::var(p2).scale(2.0 * alpha)?)?;
        problem.nsd(&format!("observer decay[{}]", i + 1), q, eps)?;
    }
    if synthesis {
        let name = "observer P2 >= I".to_string();
        problem.psd(
            &name,
            Expr::var(p2).add_constant(&(-DMatrix::identity(n, n)))?,
            eps,
        )?;
        nonstrict.push(name);
        let kappa = problem.scalar(KAPPA)?;
        for (i, v) in nv.iter().enumerate() {
            let block = Expr::sym_blocks(vec![
                vec![
                    Some(Expr::scaled(kappa, &DMatrix::identity(n, n))?),
                    Some(Expr::var(*v)),
                ],
                vec![None, Some(Expr::scaled(kappa, &DMatrix::identity(p, p))?)],
            ])?;
            let name = format!("observer ||N[{}]|| <= kappa", i + 1);
            problem.psd(&name, block, 0.0)?;
            nonstrict.push(name);
        }
        problem.minimize(Expr::var(kappa))?;
    }
    Ok(ObserverProblem {
        problem,
        p2,
        n: nv,
        nonstrict,
    })
}

/// The solved observer: P2 and L_i = P2^-1 N_i, with every value by name.
pub struct SolvedObserver {
    /// P2.
    pub p2: DMatrix<f64>,
    /// L_i.
    pub gains: Vec<DMatrix<f64>>,
}

/// Solves the observer problem; an infeasible one is refused with advice.
pub fn solve(
    runner: &mut Runner<'_>,
    c: &DMatrix<f64>,
    alpha: f64,
) -> Result<SolvedObserver, SynthError> {
    let model = runner.model;
    let eps = runner.settings.eps;
    // Solved with 10 times the margin: minimizing kappa drives the decay
    // conditions to their margin, and the certificate rebuilds them with
    // N_i = P2 L_i from the rounded L_i.
    let built = problem(model, c, alpha, OBSERVER_MARGIN_FACTOR * eps, true)
        .map_err(|e| SynthError::Internal(format!("internal error: observer problem: {e}")))?;
    let sol = runner.solve(&built.problem, "observer problem")?;
    if sol.status != SolveStatus::Solved {
        return Err(SynthError::Infeasible {
            message: format!(
                "no fuzzy observer with decay rate {alpha} for these measurements: the observer LMIs He(P2 A_i - N_i C) + 2 alpha_o P2 < 0 are {}",
                sol.status.describe()
            ),
            achievable: vec![
                "lower the observer's decay rate (`control observer_based(decay = ..)`) or measure more states".into(),
            ],
        });
    }
    let value = |v: Var| {
        sol.value(v)
            .cloned()
            .map_err(|e| SynthError::Internal(format!("internal error: {e}")))
    };
    let p2 = value(built.p2)?;
    let Some(chol) = p2.clone().cholesky() else {
        return Err(SynthError::Internal(
            "internal error: the observer's P2 is not positive definite".into(),
        ));
    };
    let gains = built
        .n
        .iter()
        .map(|v| value(*v).map(|n| chol.solve(&n)))
        .collect::<Result<Vec<_>, _>>()?;
    Ok(SolvedObserver { p2, gains })
}
