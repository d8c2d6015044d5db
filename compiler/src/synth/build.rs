//! Builds the LMI problem of one [`Plan`]: the builder declares X = P^{-1} and
//! M_j = F_j X, then every objective of the plan declares its variables and
//! imposes its conditions (in the orders of [`objectives::DECLARE_ORDER`] and
//! [`objectives::IMPOSE_ORDER`], so that the same plan always gives the same
//! problem). When no objective contains the Lyapunov decrease, plain
//! stability is imposed.

use super::objective::{BuildError, Ctx, Lmis, Objective};
use super::objectives::{self, Decay};
use super::plan::Plan;
use super::reduction::Reduction;
use super::relaxations::Relaxer;
use crate::model::TsModel;
use tsf_lang::spec::Relaxation;
use tsf_lmi::{Expr, Problem, Var};

/// A problem built for one plan.
#[derive(Debug)]
pub struct Built {
    /// The LMI problem.
    pub problem: Problem,
    /// X = P^{-1}.
    pub x: Var,
    /// M_j = F_j X.
    pub m: Vec<Var>,
    /// Reductions applied (empty for the full build).
    pub reductions: Vec<Reduction>,
    /// Names of the constraints that are non-strict in the theory (`>= 0`).
    /// They are solved with the margin too, so that the numeric solution
    /// satisfies them with room, and certified as non-strict.
    pub nonstrict: Vec<String>,
}

/// Builds the problem for `plan`. With `reduce`, constraints provably implied
/// by others are left out (each as a [`Reduction`] the certificate inverts).
pub fn build(
    model: &TsModel,
    plan: &Plan,
    relaxation: Relaxation,
    eps: f64,
    reduce: bool,
) -> Result<Built, BuildError> {
    let (n, m, r) = (model.n, model.m, model.r());
    let mut problem = Problem::new();
    let x = problem.symmetric("X", n)?;
    let mv = (0..r)
        .map(|j| problem.full(&format!("M{}", j + 1), m, n))
        .collect::<Result<Vec<_>, _>>()?;
    let pair_reduce = reduce && super::blocks::common_b(model);
    let mut lmis = Lmis {
        problem,
        eps,
        sector: None,
        relaxer: Relaxer::new(model, relaxation, eps, pair_reduce),
        named: Vec::new(),
        initial_sets: Vec::new(),
    };
    for o in plan.ordered(objectives::DECLARE_ORDER) {
        o.declare(model, &mut lmis)?;
    }
    let ctx = Ctx {
        model,
        plan,
        x,
        m: mv,
        sector: lmis.sector.clone(),
    };
    lmis.strict("X > 0", Expr::var(x))?;
    let implied = plan
        .objectives()
        .any(|o| o.implies_stability() || o.as_any().is::<Decay>());
    if !implied {
        Decay::stability().impose(&ctx, &mut lmis)?;
    }
    for o in plan.ordered(objectives::IMPOSE_ORDER) {
        o.impose(&ctx, &mut lmis)?;
    }
    Ok(Built {
        problem: lmis.problem,
        x,
        m: ctx.m,
        reductions: lmis.relaxer.reductions,
        nonstrict: lmis.relaxer.nonstrict,
    })
}
