//! Builds the LMI problem of one [`Plan`]: the builder declares X = P^{-1} and
//! M_j = F_j X (or, when the rules give their gains, substitutes F_j X for
//! M_j: the same conditions, now for fixed gains), then every objective of the plan declares its variables and
//! imposes its conditions (in the orders of [`objectives::DECLARE_ORDER`] and
//! [`objectives::IMPOSE_ORDER`], so that the same plan always gives the same
//! problem). When no objective contains the Lyapunov decrease, plain
//! stability is imposed.

use super::objective::{
    declare_model_error, BuildError, Ctx, GainTerm, Lmis, ModelError, Objective,
};
use super::objectives::{self, Decay};
use super::plan::Plan;
use super::reduction::Reduction;
use super::relaxations::Relaxer;
use super::solved::names;
use crate::model::TsModel;
use nalgebra::{Cholesky, DMatrix, Dyn};
use tsf_lang::spec::Relaxation;
use tsf_lmi::{Expr, Problem, Var};

/// A problem built for one plan.
#[derive(Debug)]
pub struct Built {
    /// The LMI problem.
    pub problem: Problem,
    /// X = P^{-1}.
    pub x: Var,
    /// M_j = F_j X: variables, or the given gains.
    pub m: Vec<GainTerm>,
    /// Reductions applied (empty for the full build).
    pub reductions: Vec<Reduction>,
    /// Names of the constraints that are non-strict in the theory (`>= 0`).
    /// They are solved with the margin too, so that the numeric solution
    /// satisfies them with room, and certified as non-strict.
    pub nonstrict: Vec<String>,
    /// The Lyapunov matrices of a fuzzy Lyapunov function (then `x` is the
    /// full slack G and `m` holds Z_j = F_j G; [`super::lyapunov::fuzzy`]).
    pub fuzzy: Option<super::lyapunov::fuzzy::FuzzyVars>,
    /// The spec's given gains when the LMIs are imposed at a region's
    /// vertices (`m` then holds one term per vertex): the gains emitted.
    pub given: Option<Vec<DMatrix<f64>>>,
}

impl Built {
    /// The PDC gains of a solution: F_j = M_j X^{-1} from the solved M_j
    /// (`value` reads a variable, `x` is the Cholesky factor of the solved
    /// X), or the given F_j as they are, bit for bit.
    pub fn gains<E>(
        &self,
        value: impl Fn(Var) -> Result<DMatrix<f64>, E>,
        x: &Cholesky<f64, Dyn>,
    ) -> Result<Vec<DMatrix<f64>>, E> {
        if let Some(given) = &self.given {
            return Ok(given.clone());
        }
        self.m
            .iter()
            .map(|g| match g {
                GainTerm::Free(mv) => value(*mv).map(|m| x.solve(&m.transpose()).transpose()),
                GainTerm::Given(f) => Ok(f.clone()),
            })
            .collect()
    }
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
    if let Some(phi) = super::lyapunov::fuzzy::phi(model) {
        return super::lyapunov::fuzzy::build(model, plan, relaxation, eps, reduce, phi);
    }
    // With a premise region and one common given gain, the continuous loop
    // is certified on the box: the LMIs at the vertices of the blended model,
    // and E(P, c) inside the box (below).
    let regional =
        crate::model::region::continuous_model(model).map_err(BuildError::Unsupported)?;
    let given = regional.as_ref().and_then(|_| model.spec.given_gains());
    let model = regional.as_ref().map_or(model, |(m, _)| m);
    let (n, m, r) = (model.n, model.m, model.r());
    let mut problem = Problem::new();
    let x = problem.symmetric(names::X, n)?;
    let mv = match model.spec.given_gains() {
        Some(given) => given.into_iter().map(GainTerm::Given).collect(),
        None => (0..r)
            .map(|j| {
                problem
                    .full(&names::gain_product(j), m, n)
                    .map(GainTerm::Free)
            })
            .collect::<Result<Vec<_>, _>>()?,
    };
    // A discrete-time design's B_di differ between rules even when B is common.
    let pair_reduce = reduce
        && super::blocks::common_b(model)
        && super::objectives::discrete::period(model).is_none();
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
    let implied = plan
        .objectives()
        .any(|o| o.implies_stability() || o.decay_rate().is_some());
    // The decrease block's multiplier (the H-inf and L-inf blocks declare
    // their own); the model error is carried by the context either way.
    let decrease = !implied || plan.objectives().any(|o| o.decay_rate().is_some());
    let model_error = match &model.plant_error {
        Some(e) if !e.is_zero() => Some(ModelError {
            eps: match decrease {
                true => declare_model_error(model, &mut lmis, names::MODEL_ERROR, false)?,
                false => Default::default(),
            },
            a2: e.a * e.a,
            b2: e.b * e.b,
            d2: e.d.map_or(0.0, |d| d * d),
        }),
        _ => None,
    };
    let ctx = Ctx {
        model_error,
        model,
        plan,
        x,
        m: mv,
        sector: lmis.sector.clone(),
    };
    lmis.strict("X > 0", Expr::var(x))?;
    if !implied {
        Decay::stability().impose(&ctx, &mut lmis)?;
    }
    for o in plan.ordered(objectives::IMPOSE_ORDER) {
        o.impose(&ctx, &mut lmis)?;
    }
    if let Some((_, region)) = &regional {
        // E(P, c) inside |c_k x| <= b_k: c c_k X c_k' <= b_k^2 (X = P^{-1}),
        // c the saturation objective's level, max(1, xi tau_bar^2 / phi): the
        // set the continuous claims speak of (a region comes with a
        // synthesized trigger weight, which the checker pairs with it).
        let Some(sat) = plan.saturation() else {
            return Err(BuildError::Unsupported(
                "region: the regional continuous certificate needs `objective saturation region` (its level sizes E(P, c))".into(),
            ));
        };
        let level = sat.level(plan)?;
        for face in &region.faces {
            let inside = Expr::constant(&DMatrix::from_element(
                1,
                1,
                face.bound * face.bound / level,
            ))?
            .sub(Expr::product(&face.row, x, &face.row.transpose())?)?;
            lmis.nonstrict(&format!("premise region {}", face.name), inside)?;
        }
    }
    Ok(Built {
        problem: lmis.problem,
        x,
        m: ctx.m,
        reductions: lmis.relaxer.reductions,
        nonstrict: lmis.relaxer.nonstrict,
        fuzzy: None,
        given,
    })
}
