//! Builds the LMI problem of one [`Plan`]: the builder declares X = P^{-1} and
//! M_j = F_j X, then every objective of the plan declares its variables and
//! imposes its conditions (in the orders of [`objectives::DECLARE_ORDER`] and
//! [`objectives::IMPOSE_ORDER`], so that the same plan always gives the same
//! problem). When no objective contains the Lyapunov decrease, plain
//! stability is imposed.

use super::blocks::{initial_set_block, nonstrict_psd};
use super::objectives::{self, Decay, Objective};
use super::plan::Plan;
use super::reduction::Reduction;
use super::relaxations::{Family, Relaxer};
use crate::model::TsModel;
use nalgebra::DMatrix;
use tsf_lang::spec::{InitialSet, Relaxation};
use tsf_lmi::{Expr, LmiError, Problem, Var};

/// Why a problem could not be built.
#[derive(Debug, Clone, PartialEq)]
pub enum BuildError {
    /// The objectives of the plan cannot be combined (the checker should
    /// have said so with a span; this is the last line of defence).
    Unsupported(String),
    /// An LMI expression was malformed: a bug in tsfc.
    Lmi(LmiError),
}

impl From<LmiError> for BuildError {
    fn from(e: LmiError) -> Self {
        BuildError::Lmi(e)
    }
}

impl std::fmt::Display for BuildError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            BuildError::Unsupported(m) => f.write_str(m),
            BuildError::Lmi(e) => write!(f, "internal LMI construction error: {e}"),
        }
    }
}

/// S = T^{-1} (diagonal, m x m) and Z_j = G_j X (m x n) of the generalized
/// sector condition for actuator saturation.
#[derive(Debug, Clone)]
pub struct Sector {
    /// S.
    pub s: Var,
    /// Z_j, one per rule.
    pub z: Vec<Var>,
}

/// Read-only context of the conditions: model, plan and the shared variables.
pub struct Ctx<'a> {
    /// The model.
    pub model: &'a TsModel,
    /// The plan being built (objectives may read each other's parameters).
    pub plan: &'a Plan,
    /// X = P^{-1}.
    pub x: Var,
    /// M_j = F_j X.
    pub m: Vec<Var>,
    /// The sector variables, if the saturation objective declared them.
    pub sector: Option<Sector>,
}

impl Ctx<'_> {
    /// Upsilon_ij = He(A_i X + B_i M_j) (+ shift * X).
    pub fn upsilon(&self, i: usize, j: usize, shift: f64) -> Result<Expr, LmiError> {
        let n = self.model.n;
        let (a, b) = (&self.model.rules[i].a, &self.model.rules[i].b);
        let ax = Expr::product(a, self.x, &DMatrix::identity(n, n))?;
        let bm = Expr::product(b, self.m[j], &DMatrix::identity(n, n))?;
        let he = ax.add(bm)?.he()?;
        if shift == 0.0 {
            Ok(he)
        } else {
            he.add(Expr::var(self.x).scale(shift)?)
        }
    }

    /// Adds the dead-zone signal psi of the generalized sector condition to a
    /// block: [[U, -B_i S + Z_j', (W)], [*, -2S, 0], [*, *, (-xi I)]], or
    /// returns `[[U, W], [*, -xi I]]` / `U` unchanged without saturation.
    pub fn with_sector(
        &self,
        i: usize,
        j: usize,
        ups: Expr,
        w: Option<(Expr, Expr)>,
    ) -> Result<Expr, LmiError> {
        let Some(sector) = &self.sector else {
            return match w {
                Some((d, xi)) => {
                    Expr::sym_blocks(vec![vec![Some(ups), Some(d)], vec![None, Some(xi)]])
                }
                None => Ok(ups),
            };
        };
        let m = self.model.m;
        let b = &self.model.rules[i].b;
        let cross = Expr::product(b, sector.s, &DMatrix::identity(m, m))?
            .scale(-1.0)?
            .add(Expr::var(sector.z[j]).transpose())?;
        let psi = Expr::var(sector.s).scale(-2.0)?;
        match w {
            Some((d, xi)) => Expr::sym_blocks(vec![
                vec![Some(ups), Some(cross), Some(d)],
                vec![None, Some(psi), None],
                vec![None, None, Some(xi)],
            ]),
            None => Expr::sym_blocks(vec![vec![Some(ups), Some(cross)], vec![None, Some(psi)]]),
        }
    }
}

/// The growing problem: constraints, relaxation and bookkeeping.
pub struct Lmis<'m> {
    /// The LMI problem.
    pub problem: Problem,
    /// Margin of strict LMIs.
    pub eps: f64,
    /// Sector variables (declared by the saturation objective).
    pub sector: Option<Sector>,
    relaxer: Relaxer<'m>,
    named: Vec<(String, Var)>,
    initial_sets: Vec<InitialSet>,
}

impl Lmis<'_> {
    /// Declares a scalar variable owned by an objective.
    pub fn scalar(&mut self, name: &str) -> Result<Var, LmiError> {
        let v = self.problem.scalar(name)?;
        self.named.push((name.to_string(), v));
        Ok(v)
    }

    /// A variable declared by [`Lmis::scalar`], by name.
    pub fn var(&self, name: &str) -> Option<Var> {
        self.named.iter().find(|(n, _)| n == name).map(|(_, v)| *v)
    }

    /// `e > 0`, strict (solved as `e >= eps I`).
    pub fn strict(&mut self, name: &str, e: Expr) -> Result<(), LmiError> {
        self.problem.psd(name, e, self.eps)?;
        Ok(())
    }

    /// `e >= 0`, non-strict in the theory (solved with the margin too).
    pub fn nonstrict(&mut self, name: &str, e: Expr) -> Result<(), LmiError> {
        nonstrict_psd(
            &mut self.problem,
            &mut self.relaxer.nonstrict,
            name,
            e,
            self.eps,
        )
    }

    /// Imposes `sum_ij h_i h_j Q_ij < 0` under the spec's relaxation.
    pub fn impose(&mut self, fam: &Family<'_>) -> Result<(), LmiError> {
        self.relaxer.impose(&mut self.problem, fam)
    }

    /// Puts `init` inside E(P, 1) (once per distinct initial set).
    pub fn contain(&mut self, x: Var, init: &InitialSet, what: &str) -> Result<(), LmiError> {
        if self.initial_sets.contains(init) {
            return Ok(());
        }
        self.initial_sets.push(init.clone());
        let (name, e) = initial_set_block(x, init)?;
        self.nonstrict(&format!("{what}: {name}"), e)
    }
}

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
