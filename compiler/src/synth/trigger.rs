//! Event-trigger synthesis for fixed PDC gains (the "two-step" method; the
//! derivation is in docs/event_trigger.md).
//!
//! Step 1 (the rest of this crate) designs F_j and the sector gains G_j for the
//! continuous loop. Step 2, here, keeps F_j and G_j and finds, for the
//! aperiodically sampled, event-triggered loop with sampling intervals in
//! [h_min, h_max], a Lyapunov-Krasovskii functional
//!
//!   V = x' P x + (s + h - t) int_s^t e^{-phi (t - a)} x'(a)' Y x'(a) da,
//!
//! free matrices L_1, L_2, a diagonal sector multiplier T > 0 and the trigger
//! weight W = Upsilon > 0 such that, while the
//! event condition e' W e <= nu x(t_k)' W x(t_k) holds between transmissions,
//! V' + phi V - xi tau' tau < 0 on E(P, 1 + xi tau_bar^2 / phi) (which lies in
//! the linear region of the sector condition), and ||y||_inf < gamma ||tau||_inf.
//! Every term is linear in the unknowns because F_j and G_j are constants, so
//! x' is substituted (no descriptor slacks). One SDP at the certified threshold
//! (the adaptive ceiling); the largest certified nu is bisected only to explain
//! an infeasible threshold.

use super::achieved::Quantity;
use super::advice::round_down;
pub use super::design::TriggerPlan;
use super::design::{Design, SynthError, TriggerDesign};
use super::l2_channel::output_energy;
use super::loop_error::{robust_lambda, LoopMultipliers, Selectors};
use super::objective::BuildError;
use super::observer::drift;
use super::observer::sampled_bounds;
use super::reduction::Reduction;
use super::search::Runner;
use super::solved::{names, Solved as _};
use super::trigger_region::impose_regions;
pub use super::trigger_region::joint_level;
pub use super::trigger_request::{
    certified_threshold, codesign_rounds, transmission_points, wanted,
};
pub use super::trigger_scale::{lyapunov_scale, scaled_plan};
use super::trigger_scale::{unscale_values, LoopedSolve};
use super::vertices::{self, PlantVertex};
use crate::model::TsModel;
use nalgebra::DMatrix;
use std::time::Instant;
use tsf_lang::spec::Trigger;
use tsf_lmi::{Expr, LmiError, Problem, Relation, SolveStatus, Var};

/// The variables of the sampled-loop problem (`None`: the part is absent).
#[derive(Debug, Clone)]
pub struct TriggerVars {
    /// P of V1 = x' P x (`None` when known: the gain step).
    pub p: Option<Var>,
    /// Trigger weight Upsilon (event triggers).
    pub w: Option<Var>,
    /// L-inf gain gamma (with the L-inf channel).
    pub gamma: Option<Var>,
    /// xi (with the L-inf channel).
    pub xi: Option<Var>,
}

/// A built trigger problem.
#[derive(Debug)]
pub struct TriggerBuilt {
    /// The LMI problem.
    pub problem: Problem,
    /// Its main variables.
    pub vars: TriggerVars,
    /// Reductions applied.
    pub reductions: Vec<Reduction>,
    /// Constraints non-strict in the theory.
    pub nonstrict: Vec<String>,
}

/// A solved looped-functional problem: the problem and every variable's value.
pub(super) type Solved = (TriggerBuilt, Vec<(String, DMatrix<f64>)>);

/// A factor of an LMI term: an unknown of the problem, or a known matrix
/// (the trigger step knows the gains, the gain step the Lyapunov matrices).
#[derive(Debug, Clone, Copy)]
pub(super) enum Factor<'a> {
    /// An unknown.
    Var(Var),
    /// A known value.
    Val(&'a DMatrix<f64>),
}

impl Factor<'_> {
    /// `left * self * right`.
    pub(super) fn between(
        self,
        left: &DMatrix<f64>,
        right: &DMatrix<f64>,
    ) -> Result<Expr, LmiError> {
        match self {
            Factor::Var(v) => Expr::product(left, v, right),
            Factor::Val(m) => Expr::constant(&(left * m * right)),
        }
    }

    /// `self` as an expression.
    pub(super) fn expr(self) -> Result<Expr, LmiError> {
        match self {
            Factor::Var(v) => Ok(Expr::var(v)),
            Factor::Val(m) => Expr::constant(m),
        }
    }
}

/// `left * a * mid * b * right`: linear when at most one of `a`, `b` is unknown.
fn chain(
    left: &DMatrix<f64>,
    a: Factor<'_>,
    mid: &DMatrix<f64>,
    b: Factor<'_>,
    right: &DMatrix<f64>,
) -> Result<Expr, LmiError> {
    match (a, b) {
        (Factor::Val(a), b) => b.between(&(left * a * mid), right),
        (a, Factor::Val(b)) => a.between(left, &(mid * b * right)),
        _ => Err(LmiError::Variable {
            what: "a product of two unknowns is not linear (co-design fixes one side)".into(),
        }),
    }
}

/// The unknowns entering Lambda_{ij r}(h) and the conditions around it;
/// `Val` factors are fixed by the other step of the co-design.
#[derive(Debug, Clone)]
pub(super) struct LoopVars<'a> {
    /// P of V1 = x' P x.
    pub p: Factor<'a>,
    /// Y of the looped term.
    pub y: Factor<'a>,
    /// The free matrices L1, L2 (always unknown).
    pub l: [Var; 2],
    /// The trigger weight Upsilon (event triggers).
    pub w: Option<Factor<'a>>,
    /// The threshold as an unknown (else `plan.nu`; needs a known weight).
    pub nu: Option<Var>,
    /// The diagonal sector multiplier T (with saturation).
    pub t: Option<Factor<'a>>,
    /// xi of the L-inf channel (declared by [`impose`]).
    pub xi: Option<Var>,
    /// F_j per controller rule.
    pub gains: Vec<Factor<'a>>,
    /// G_j per controller rule.
    pub sector: Vec<Factor<'a>>,
    /// The model-error multipliers of Lambda_1 and Lambda_2 (declared by
    /// [`impose`] when the plan carries a model error).
    pub robust: [LoopMultipliers; 2],
}

impl<'a> LoopVars<'a> {
    /// The gains of the trigger step: those of the plan.
    pub fn plan_gains(plan: &'a TriggerPlan) -> (Vec<Factor<'a>>, Vec<Factor<'a>>) {
        (
            plan.gains.iter().map(Factor::Val).collect(),
            plan.sector.iter().map(Factor::Val).collect(),
        )
    }
}

/// Selector of rows `at .. at + len` of a vector of length `k`, as a `len x k` matrix.
pub(super) fn pick(len: usize, at: usize, k: usize) -> DMatrix<f64> {
    DMatrix::from_fn(len, k, |r, c| if c == at + r { 1.0 } else { 0.0 })
}

/// Where the parts of psi = [x; x(s); e; dz; tau] sit; absent parts are `None`.
struct Layout {
    k: usize,
    e: Option<usize>,
    dz: Option<usize>,
    tau: Option<(usize, usize)>,
}

impl Layout {
    fn of(model: &TsModel, plan: &TriggerPlan) -> Self {
        let mut k = 2 * model.n;
        let mut take = |len: usize| {
            let at = k;
            k += len;
            at
        };
        let e = plan.event.then(|| take(model.n));
        let dz = (!plan.levels.is_empty()).then(|| take(plan.levels.len()));
        let q = plan.d.first().map_or(0, |d| d.ncols());
        let tau = ((plan.linf || plan.l2.is_some()) && q > 0).then(|| (take(q), q));
        Layout { k, e, dz, tau }
    }
}

/// Lambda_{ij r}(h) with the derivative eliminated (x' = Phi_ij psi, every
/// term linear in the unknowns because either the gains or P, Y, T are
/// known). psi = [x; x(s); e; dz; tau] (the parts the plan has):
///
///   Xi = He(E_x' P Phi) + phi E_x' P E_x + He([E_x; E_s]' L (E_x - E_s))
///        + nu (E_s - E_e)' W (E_s - E_e) - E_e' W E_e
///        + He(E_dz' T G_j (E_s - E_e)) - 2 E_dz' T E_dz - xi E_tau' E_tau,
///   r = 1: Xi + h Phi' Y Phi (gains known), or its Schur complement
///          [Xi, sqrt(h) Phi' Y; *, -Y] (Y known, gains unknown),
///   r = 2: [Xi, sqrt(h) (E_x' L1 + E_s' L2); *, -e^{-phi h_max} Y].
///
/// Plant rule i and controller rule j differ (membership mismatch), so the
/// bound Phi(h)' Y Phi(h) <= sum h_i h_j Phi_ij' Y Phi_ij (convexity, Y > 0)
/// makes the vertex conditions sufficient. With saturation the plant gets
/// -B M_q dz ([`TriggerPlan::dz_map`] of controller vertex `q`).
fn lambda(
    model: &TsModel,
    plan: &TriggerPlan,
    v: &LoopVars<'_>,
    (plant, q, (f, g)): (&PlantVertex, usize, (Factor<'_>, Factor<'_>)),
    h: f64,
    r: u8,
) -> Result<Expr, LmiError> {
    let (n, m) = (model.n, model.m);
    let lay = Layout::of(model, plan);
    let m_dz = plan.levels.len();
    // The dead zone as it enters the held input: M_q dz.
    let dz_in = lay.dz.map(|at| plan.dz_map(q, m) * pick(m_dz, at, lay.k));
    let k = lay.k;
    let (ex, es) = (pick(n, 0, k), pick(n, n, k));
    let b = &plant.b;
    let id_n = DMatrix::identity(n, n);
    // x(t_k) = x(s) - e: the state the controller holds.
    let xk = match lay.e {
        Some(at) => &es - pick(n, at, k),
        None => es.clone(),
    };
    // Phi = phi_c + B F_j x(t_k): the part without the gain is known.
    let mut phi_c = &plant.a * &ex;
    if let Some(dz_in) = &dz_in {
        phi_c -= b * dz_in;
    }
    if let Some((at, q)) = lay.tau {
        phi_c += &plant.d * pick(q, at, k);
    }
    let exs = &ex - &es;
    let mut xi_block =
        v.p.between(&ex.transpose(), &phi_c)?
            .add(chain(&ex.transpose(), v.p, b, f, &xk)?)?
            .he()?
            .add(v.p.between(&ex.transpose(), &ex)?.scale(plan.phi)?)?
            .add(
                Expr::product(&ex.transpose(), v.l[0], &exs)?
                    .add(Expr::product(&es.transpose(), v.l[1], &exs)?)?
                    .he()?,
            )?;
    if let (Some(at), Some(w)) = (lay.e, v.w) {
        let ee = pick(n, at, k);
        let held = match (v.nu, w) {
            (Some(nu), Factor::Val(w)) => Expr::scaled(nu, &(xk.transpose() * w * &xk))?,
            (Some(_), Factor::Var(_)) => {
                return Err(LmiError::Variable {
                    what: "the threshold nu and the weight cannot both be unknown".into(),
                })
            }
            (None, w) => w.between(&xk.transpose(), &xk)?.scale(plan.nu)?,
        };
        xi_block = xi_block.add(held)?.sub(w.between(&ee.transpose(), &ee)?)?;
    }
    if let (Some(at), Some(t)) = (lay.dz, v.t) {
        let edz = pick(m_dz, at, k);
        xi_block = xi_block
            .add(chain(&edz.transpose(), t, &DMatrix::identity(m_dz, m_dz), g, &xk)?.he()?)?
            .sub(t.between(&edz.transpose(), &edz)?.scale(2.0)?)?;
    }
    if let (Some((at, q)), Some(xi)) = (lay.tau, v.xi) {
        let etau = pick(q, at, k);
        xi_block = xi_block.sub(Expr::scaled(xi, &(etau.transpose() * &etau))?)?;
    }
    if let Some(ch) = &plan.l2 {
        let energy = output_energy(ch, (lay.tau, lay.k), &ex, &xk, f)?;
        xi_block = xi_block.add(Expr::constant(&energy)?)?;
    }
    // With a model error the gains must be known (N_b is data).
    let robust =
        match (plan.model_error.is_zero(), f) {
            (true, _) => None,
            (false, Factor::Val(f)) => Some(Selectors {
                ex: &ex,
                phi: &phi_c + b * f * &xk,
                sat_u: match &dz_in {
                    Some(dz_in) => f * &xk - dz_in,
                    None => f * &xk,
                },
                tau: lay.tau.map(|(at, q)| pick(q, at, k)),
            }),
            (false, Factor::Var(_)) => return Err(LmiError::Variable {
                what:
                    "the loop's model-error blocks need known gains (not the co-design's gain step)"
                        .into(),
            }),
        };
    if let (Some(sel), 1) = (&robust, r) {
        let y_phi = v.y.between(&id_n, &sel.phi)?.scale(h.sqrt())?;
        let top = Expr::sym_blocks(vec![
            vec![Some(xi_block), Some(y_phi.transpose())],
            vec![None, Some(v.y.expr()?.scale(-1.0)?)],
        ])?;
        return robust_lambda(plan, v, top, sel, h, r);
    }
    if r == 1 {
        if let Factor::Val(f) = f {
            let phi_m = &phi_c + b * f * &xk;
            return xi_block.add(v.y.between(&phi_m.transpose(), &phi_m)?.scale(h)?);
        }
        // Gains unknown, Y known: Schur complement of h Phi' Y Y^-1 Y Phi.
        let y_phi =
            v.y.between(&id_n, &phi_c)?
                .add(chain(&id_n, v.y, b, f, &xk)?)?
                .scale(h.sqrt())?;
        return Expr::sym_blocks(vec![
            vec![Some(xi_block), Some(y_phi.transpose())],
            vec![None, Some(v.y.expr()?.scale(-1.0)?)],
        ]);
    }
    let col = Expr::product(&ex.transpose(), v.l[0], &id_n)?
        .add(Expr::product(&es.transpose(), v.l[1], &id_n)?)?
        .scale(h.sqrt())?;
    let (_, h_max) = plan.sampling;
    let top = Expr::sym_blocks(vec![
        vec![Some(xi_block), Some(col)],
        vec![None, Some(v.y.expr()?.scale(-(-plan.phi * h_max).exp())?)],
    ])?;
    match &robust {
        Some(sel) => robust_lambda(plan, v, top, sel, h, r),
        None => Ok(top),
    }
}

/// Builds the sampled-loop LMIs. With `reduce`, the h = h_min vertices are
/// left out (every Lambda_r(h) is Xi + h Pi_r with Pi_r >= 0, so h_max
/// implies them), and so are the pairs of repeated plant rules and of
/// repeated (known) controller gains, which equal conditions kept.
pub fn build(
    model: &TsModel,
    plan: &TriggerPlan,
    eps: f64,
    reduce: bool,
) -> Result<TriggerBuilt, BuildError> {
    Ok(build_inner(model, plan, eps, reduce)?)
}

/// The unknowns the trigger step declares (gains known).
fn declare_trigger_step<'a>(
    problem: &mut Problem,
    model: &TsModel,
    plan: &'a TriggerPlan,
) -> Result<LoopVars<'a>, LmiError> {
    let n = model.n;
    let p = problem.symmetric(names::LOOP_P, n)?;
    let y = problem.symmetric(names::LOOP_Y, n)?;
    let w = if plan.event {
        Some(Factor::Var(problem.symmetric(names::TRIGGER_WEIGHT, n)?))
    } else {
        None
    };
    let l = [
        problem.full(names::LOOP_L1, n, n)?,
        problem.full(names::LOOP_L2, n, n)?,
    ];
    let (gains, mut sector) = LoopVars::plan_gains(plan);
    let t = match (&plan.sector_multiplier, plan.levels.len()) {
        (_, 0) => None,
        // T known: the sector gains are the unknowns, one per vertex.
        (Some(t), m) => {
            let name = |q| format!("{}{q}", names::LOOP_SECTOR_GAIN);
            sector = (1..=plan.gains.len())
                .map(|q| problem.full(&name(q), m, n).map(Factor::Var))
                .collect::<Result<_, _>>()?;
            Some(Factor::Val(t))
        }
        (None, m) => Some(Factor::Var(problem.diagonal(names::LOOP_SECTOR, m)?)),
    };
    Ok(LoopVars {
        p: Factor::Var(p),
        y: Factor::Var(y),
        l,
        w,
        nu: None,
        t,
        xi: None,
        gains,
        sector,
        robust: Default::default(),
    })
}

fn build_inner(
    model: &TsModel,
    plan: &TriggerPlan,
    eps: f64,
    reduce: bool,
) -> Result<TriggerBuilt, LmiError> {
    let mut problem = Problem::new();
    let vars = declare_trigger_step(&mut problem, model, plan)?;
    impose(problem, model, plan, vars, eps, reduce)
}

/// Imposes every condition of the sampled loop on `problem` for `vars`
/// (positivity of the unknown P, Y, Upsilon, T; Lambda_{ij r}(h); the linear
/// region; initial sets; the L-inf peak, minimizing gamma).
pub(super) fn impose(
    mut problem: Problem,
    model: &TsModel,
    plan: &TriggerPlan,
    mut vars: LoopVars<'_>,
    eps: f64,
    reduce: bool,
) -> Result<TriggerBuilt, LmiError> {
    let (gamma, xi) = if plan.linf {
        (
            Some(problem.scalar(names::LOOP_GAMMA)?),
            Some(problem.scalar(names::LOOP_XI)?),
        )
    } else {
        (None, None)
    };
    vars.xi = xi;
    if let Some(ch) = &plan.l2 {
        let g = problem.scalar(names::LOOP_HINF)?;
        let bound = ch.gamma * ch.gamma;
        problem.add_scalar("trigger H-inf g", Expr::var(g), Relation::Le, bound)?;
        if ch.minimize {
            problem.minimize(Expr::var(g))?;
        }
        vars.xi = Some(g);
    }
    if !plan.model_error.is_zero() {
        vars.robust = [
            plan.model_error.declare(&mut problem, 1)?,
            plan.model_error.declare(&mut problem, 2)?,
        ];
    }
    let mut reductions = Vec::new();
    let mut nonstrict = Vec::new();
    for (name, f) in [
        ("trigger P > 0", Some(vars.p)),
        ("trigger Y > 0", Some(vars.y)),
        ("trigger Upsilon > 0", vars.w),
        ("trigger T > 0", vars.t),
    ] {
        if let Some(Factor::Var(v)) = f {
            problem.psd(name, Expr::var(v), eps)?;
        }
    }
    let (h_min, h_max) = plan.sampling;
    let hs: &[f64] = if reduce || h_min == h_max {
        &[h_max]
    } else {
        &[h_min, h_max]
    };
    let (plant, _) = vertices::plant_vertices(model, plan)?;
    let blended = vertices::controller_vertices(plan, &vars.gains, &vars.sector)?;
    let ctrl = blended.pairs();
    let pairs = plant.len() * ctrl.len();
    let tag = if plan.region.is_some() { "V" } else { "Q" };
    if reduce && h_min < h_max {
        reductions.push(Reduction::Implied(format!("trigger: the {} LMIs at h = h_min = {h_min} are implied by those at h_max = {h_max} (Lambda_r(h) = Xi + h Pi_r with Pi_r >= 0) and left out of the solved problem; the certificate checks them", 2 * pairs)));
    }
    let (kept, kept_ctrl) = if reduce && plan.drift.is_none() {
        (
            vertices::kept_plant_rules(&plant),
            vertices::distinct_controller_rules(&ctrl),
        )
    } else {
        ((0..plant.len()).collect(), (0..ctrl.len()).collect())
    };
    if kept.len() * kept_ctrl.len() < pairs {
        let distinct = if reduce {
            vertices::distinct_plant_rules(&plant).len()
        } else {
            plant.len()
        };
        reductions.push(Reduction::Implied(format!(
            "trigger: {} of the {pairs} plant/controller pairs per condition repeat kept ones or are implied by them (plant {} with the same A_i, B_i, D_i: {distinct} distinct, of which {} lie on a segment between two kept ones, where Lambda is convex in (A_i, B_i, D_i); controller {} with the same F_j, G_j: {} distinct) and are left out of the solved problem; the certificate checks them",
            pairs - kept.len() * kept_ctrl.len(),
            if plan.region.is_some() { "vertices" } else { "rules" },
            distinct - kept.len(),
            if plan.region.is_some() { "vertices" } else { "rules" },
            kept_ctrl.len()
        )));
    }
    for &h in hs {
        for rr in [1u8, 2] {
            if let Some(d) = &plan.drift {
                let pre = format!("trigger r={rr} h={h}"); // paired: no pair dropped
                drift::impose_pairs(&mut problem, d, &plant, &pre, eps, |pv, q| {
                    lambda(model, plan, &vars, (pv, q, ctrl[q]), h, rr)
                })?;
                continue;
            }
            for &i in &kept {
                for &j in &kept_ctrl {
                    let name = format!("trigger r={rr} h={h} {tag}[{},{}]", i + 1, j + 1);
                    let e = lambda(model, plan, &vars, (&plant[i], j, ctrl[j]), h, rr)?;
                    problem.nsd(&name, e, eps)?;
                }
            }
        }
    }
    impose_regions(&mut problem, &mut nonstrict, model, plan, &vars, &ctrl, eps)?;
    let nu = sampled_bounds::impose(&mut problem, &mut nonstrict, plan, vars.p, eps)?;
    if let (Some(gamma), Some(xi)) = (gamma, xi) {
        peak(&mut problem, plan, vars.p, gamma, xi, eps)?;
        problem.minimize(Expr::var(gamma))?;
    } else if let Some(nu) = nu {
        problem.minimize(Expr::var(nu))?;
    }
    let p = match vars.p {
        Factor::Var(p) => Some(p),
        Factor::Val(_) => None,
    };
    let w = match vars.w {
        Some(Factor::Var(w)) => Some(w),
        _ => None,
    };
    Ok(TriggerBuilt {
        problem,
        vars: TriggerVars { p, w, gamma, xi },
        reductions,
        nonstrict,
    })
}

/// The output peak: [phi P, 0, C'; *, (gamma - xi) I, G'; *, *, gamma I] > 0
/// and 0 < xi <= xi_max.
fn peak(
    problem: &mut Problem,
    plan: &TriggerPlan,
    p: Factor<'_>,
    gamma: Var,
    xi: Var,
    eps: f64,
) -> Result<(), LmiError> {
    let q = plan.d.first().map_or(0, |d| d.ncols());
    let pdim = plan.c.nrows();
    let block = Expr::sym_blocks(vec![
        vec![
            Some(p.expr()?.scale(plan.phi)?),
            None,
            Some(Expr::constant(&plan.c.transpose())?),
        ],
        vec![
            None,
            Some(
                Expr::scaled(gamma, &DMatrix::identity(q, q))?
                    .sub(Expr::scaled(xi, &DMatrix::identity(q, q))?)?,
            ),
            Some(Expr::constant(&plan.g.transpose())?),
        ],
        vec![
            None,
            None,
            Some(Expr::scaled(gamma, &DMatrix::identity(pdim, pdim))?),
        ],
    ])?;
    problem.psd("trigger linf peak", block, eps)?;
    problem.add_scalar("trigger xi > 0", Expr::var(xi), Relation::Ge, eps)?;
    problem.add_scalar(
        "trigger xi <= xi_max",
        Expr::var(xi),
        Relation::Le,
        plan.xi_max,
    )?;
    Ok(())
}

/// The trigger problem for the gains of `design` (threshold 0: the caller sets nu).
pub fn plan_for(model: &TsModel, design: &Design) -> Result<TriggerPlan, SynthError> {
    let unsupported = |m: &str| SynthError::Unsupported(format!("event-trigger synthesis: {m}"));
    let Some(Trigger::Aperiodic { sampling, .. }) = model.spec.trigger.as_ref().map(|t| &t.node)
    else {
        return Err(unsupported("needs an aperiodic trigger"));
    };
    let (Some(linf), Some(sat)) = (design.plan.linf(), design.plan.saturation()) else {
        return Err(unsupported(
            "needs an L-inf objective and `objective saturation region` (the shipped method is Xu & Huang's setting)",
        ));
    };
    let out = &model.spec.outputs[linf.to];
    if out.e.iter().any(|v| *v != 0.0) {
        return Err(unsupported("the L-inf output must not depend on u"));
    }
    let sig = &model.spec.disturbances[linf.from];
    let region = crate::model::region::premise_box(model).map_err(SynthError::Unsupported)?;
    // G_j = Z_j X^{-1} = Z_j P. With a premise region G = 0 (any G is a valid
    // choice of the generalized sector condition; the controller never uses
    // it): the LMIs then keep E(P, c) where |F(h)_s x| <= u_bar_s, so the
    // actuator does not saturate on the certified set. Step 1's G_j, made for
    // the whole premise range, certify far less there (Xu & Huang with a soft
    // gain: nu 0.034 against 0.25 with G = 0).
    let sector = (0..model.r())
        .map(|j| match region {
            Some(_) => Ok(DMatrix::zeros(model.m, model.n)),
            None => design
                .values
                .sector_product(j)
                .map(|z| z * &design.p)
                .ok_or_else(|| unsupported("step-1 sector variable Z_j missing")),
        })
        .collect::<Result<Vec<_>, _>>()?;
    // gamma >= xi; where step 1 is not balanced (gamma above xi, set by
    // 1 / (phi lambda_min(P))) the sampled loop's optimum may trade a larger xi
    // for a smaller gamma, so the cap follows the larger of the two.
    let xi1 = design.achieved.get(Quantity::LinfXi).unwrap_or(0.0);
    let xi1 = xi1.max(design.achieved.get(Quantity::LinfGamma).unwrap_or(0.0));
    let plan = TriggerPlan {
        sampling: *sampling,
        event: true,
        linf: true,
        contain: Vec::new(),
        nu: 0.0,
        phi: linf.phi,
        xi_max: XI_FACTOR * xi1.max(f64::EPSILON),
        tau_bar: sat.disturbance_bound.unwrap_or(0.0),
        levels: sat.levels.clone(),
        gains: design.gains.clone(),
        sector,
        d: model
            .rules
            .iter()
            .map(|r| r.d.columns(sig.offset, sig.len).into_owned())
            .collect(),
        c: out.c.clone(),
        g: out.g.columns(sig.offset, sig.len).into_owned(),
        region,
        model_error: super::loop_error::LoopError::of(model),
        dz_input: Vec::new(),
        sector_multiplier: None,
        drift: None,
        observer_bounds: None,
        l2: None,
    };
    // A region's vertex sets, checked before any SDP (too many is a refusal).
    vertices::describe(model, &plan).map_err(|e| match e {
        LmiError::Dimension { what } => SynthError::Unsupported(what),
        e => SynthError::Internal(e.to_string()),
    })?;
    Ok(plan)
}

/// Duality-gap tolerance (relative and absolute) of the trigger step's SDP:
/// gamma is the objective, so the gap bounds its excess (1e-7 of ~0.6 on Xu
/// & Huang, 3 of 30 iterations saved); feasibility keeps the solver's tolerance
/// and the certificate re-checks every LMI with its margin.
const TRIGGER_GAP_TOL: f64 = 1e-7;

/// xi of the event-triggered loop may be up to this multiple of step 1's xi
/// or gamma, the larger (the region level is computed with the bound).
pub const XI_FACTOR: f64 = 4.0;

impl Runner<'_> {
    /// Builds and solves the looped-functional problem of `plan` (reduced):
    /// the built problem and every variable's value, or None when not solved.
    /// `how`: gap tolerance and equilibration ([`LoopedSolve`]).
    pub(super) fn solve_looped(
        &mut self,
        plan: &TriggerPlan,
        what: &str,
        how: LoopedSolve,
    ) -> Result<Option<Solved>, SynthError> {
        let model = self.model;
        self.solve_looped_on(model, plan, what, how)
    }

    /// [`Runner::solve_looped`] for `model` (e.g. [`super::observer::sampled`]).
    pub(super) fn solve_looped_on(
        &mut self,
        model: &TsModel,
        plan: &TriggerPlan,
        what: &str,
        how: LoopedSolve,
    ) -> Result<Option<Solved>, SynthError> {
        let t0 = Instant::now();
        let built = build(model, plan, self.settings.eps, true)?;
        self.log.build_time += t0.elapsed();
        let mut settings = self.settings.solver.clone();
        if how.rescaled {
            settings.equilibrate = false;
        }
        let gap_tol = how.gap_tol;
        if let Some(tol) = gap_tol {
            settings.tol_gap_rel = settings.tol_gap_rel.max(tol);
            settings.tol_gap_abs = settings.tol_gap_abs.max(tol);
        }
        let mut sol = self.solve_with(&built.problem, what, &settings)?;
        if sol.status != SolveStatus::Solved
            && settings.equilibrate != self.settings.solver.equilibrate
        {
            settings.equilibrate = self.settings.solver.equilibrate;
            sol = self.solve_with(&built.problem, what, &settings)?;
        }
        if sol.status != SolveStatus::Solved {
            return Ok(None);
        }
        let internal = |e: LmiError| SynthError::Internal(format!("{e}"));
        let values = sol.assignment().map_err(internal)?;
        let all = built
            .problem
            .vars()
            .map(|(name, v)| {
                values
                    .value(v)
                    .cloned()
                    .map(|m| (name.to_string(), m))
                    .map_err(internal)
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Some((built, all)))
    }

    /// One trigger SDP at threshold `nu`: the design, or None when not solved.
    /// The SDP is solved in scaled units ([`lyapunov_scale`], [`scaled_plan`]);
    /// the design holds the values in the units of `plan`.
    pub(super) fn trigger_attempt(
        &mut self,
        plan: &TriggerPlan,
    ) -> Result<Option<TriggerDesign>, SynthError> {
        let sigma = lyapunov_scale(plan);
        let solved = scaled_plan(plan, sigma);
        let how = LoopedSolve {
            gap_tol: Some(TRIGGER_GAP_TOL),
            rescaled: sigma > 1.0,
        };
        let Some((built, mut all)) = self.solve_looped(&solved, "trigger problem", how)? else {
            return Ok(None);
        };
        unscale_values(&mut all, sigma);
        let xi = all.required(names::LOOP_XI)?[(0, 0)];
        // With a premise region the cap does not set the level (joint_level):
        // tighten it to the xi found, for the gain step of a co-design that
        // follows (its level is the cap's).
        let xi_max = if joint_level(plan).is_some() {
            plan.xi_max.min(XI_FACTOR * xi)
        } else {
            plan.xi_max
        };
        Ok(Some(TriggerDesign {
            plan: TriggerPlan {
                xi_max,
                ..plan.clone()
            },
            method: "two_step",
            weight: all.required(names::TRIGGER_WEIGHT)?,
            p: all.required(names::LOOP_P)?,
            gamma: all.required(names::LOOP_GAMMA)?[(0, 0)],
            xi,
            values: all,
            reductions: built.reductions,
            rounds: Vec::new(),
            search: Vec::new(),
            region_scale: None,
        }))
    }

    /// The refusal when the gains of `design` are not certified for the
    /// spec's sampling even with every sample transmitted (nu = 0): the
    /// unstable plant/controller pair when there is one (no interval can
    /// certify it), else the longest h_max (intervals scaled together) that
    /// certifies with nu = 0, re-solved at the spec's threshold too.
    fn no_threshold_refusal(
        &mut self,
        design: &Design,
        base: &TriggerPlan,
        target: f64,
        sampling: &str,
    ) -> SynthError {
        let message = format!(
            "event trigger: the gains of the continuous design are not certified for {sampling} even with nu = 0 (every sample transmitted)"
        );
        if let Some(w) = super::pair_stability::worst(self.model, &design.gains)
            .filter(|w| w.abscissa >= 0.0 || w.abscissa.is_nan())
        {
            return SynthError::Infeasible {
                message: format!(
                    "{message}: the loop holds the memberships of the last transmission, so its conditions impose every plant/controller rule pair, and {}: no sampling interval certifies these gains",
                    w.describe(self.model)
                ),
                achievable: vec![self.every_pair_advice()],
            };
        }
        let (h_min, h_max) = base.sampling;
        let at = |s: f64, nu: f64| TriggerPlan {
            sampling: (h_min * s, h_max * s),
            nu,
            ..base.clone()
        };
        let scale = super::sampling::longest_scale_from_above(|s| {
            Ok(self.trigger_attempt(&at(s, 0.0))?.is_some())
        });
        let advice = match scale {
            Ok(Some(s)) => {
                let h = round_down(h_max * s);
                let s = h / h_max;
                let write = super::sampling::write_sampling(base.sampling, h);
                match self.trigger_attempt(&at(s, target)) {
                    Ok(Some(_)) => format!(
                        "the longest certified h_max is about {h} s (intervals scaled together): write {write} (re-solved: certified with nu = {target}), or weaken the objectives that set the gains"
                    ),
                    _ => format!(
                        "with every sample transmitted the longest certified h_max is about {h} s ({write}, re-solved), but not with nu = {target} there: lower the threshold too, or weaken the objectives that set the gains"
                    ),
                }
            }
            _ => format!(
                "not even intervals 1024 times shorter certify with nu = 0: weaken the objectives that set the gains{}",
                self.slower_decay_advice().map_or_else(String::new, |a| format!("; {a}"))
            ),
        };
        SynthError::Infeasible {
            message,
            achievable: vec![advice],
        }
    }

    /// The trigger for the gains of `design` at the spec's certified threshold
    /// (the adaptive ceiling `max`, else `nu`; 0 without a threshold). When that
    /// threshold is not certified, the largest one that is (bisection) goes into
    /// the error.
    pub(super) fn trigger(
        &mut self,
        design: &Design,
    ) -> Result<(TriggerDesign, Vec<String>), SynthError> {
        let base = plan_for(self.model, design)?;
        let with = |nu: f64| TriggerPlan { nu, ..base.clone() };
        let target = certified_threshold(self.model);
        if let Some(d) = self.trigger_attempt(&with(target))? {
            let mut notes = vec![format!(
                "event trigger certified for nu(t_k) <= {target} with the fixed gains: L-inf gamma of the event-triggered loop = {:.6} (xi = {:.6})",
                d.gamma, d.xi
            )];
            notes.extend(
                INTERPRETATIONS
                    .iter()
                    .map(|s| format!("interpretation: {s}")),
            );
            return Ok((d, notes));
        }
        let sampling = format!(
            "aperiodic sampling in [{}, {}] s",
            base.sampling.0, base.sampling.1
        );
        if target == 0.0 || self.trigger_attempt(&with(0.0))?.is_none() {
            return Err(self.no_threshold_refusal(design, &base, target, &sampling));
        }
        let (mut lo, mut hi) = (0.0, target);
        while hi - lo > TRIGGER_NU_REL_TOL * hi {
            let mid = 0.5 * (lo + hi);
            if self.trigger_attempt(&with(mid))?.is_some() {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        // Advise a short value below the certified one, re-solved at exactly
        // that value: the advice certifies when written.
        let mut advice = round_down(lo);
        let mut verified = false;
        for _ in 0..4 {
            if advice > 0.0 && self.trigger_attempt(&with(advice))?.is_some() {
                verified = true;
                break;
            }
            advice = round_down(advice * 0.9);
        }
        let write = if verified {
            format!(
                "write `threshold nu = {advice}` (or `adaptive(.., max = {advice})`), certified"
            )
        } else {
            "no short threshold value re-solved as certified: lower nu further".to_string()
        };
        Err(SynthError::Infeasible {
            message: format!(
                "event trigger: threshold nu = {target} is not certified for the gains with {sampling}"
            ),
            achievable: vec![format!(
                "the largest certified threshold is about {lo:.4e}: {write}"
            )],
        })
    }
}

/// Readings of Xu & Huang (2020) the two-step trigger design rests on
/// (docs/event_trigger.md), repeated in the report.
pub const INTERPRETATIONS: [&str; 5] = [
    "two-step route instead of Theorem 2 (37)-(41): gains F_j and sector gains G_j from the continuous design, then Upsilon, P, Y, L1, L2, T, xi for every sampling interval in [h_min, h_max] with the looped functional (21)",
    "sector condition evaluated at x(t_k) (the paper's N x(t_k^l) does not match u = F x(t_k))",
    "the event condition is used with the certified ceiling nu_c of the adaptive law (the proof's (25) needs nu(t_k) <= nu_c; the printed law is unbounded above), so generated code clamps nu(t_k) to [nu, nu_c]",
    "membership mismatch: every plant/controller rule pair (i, j) is imposed (sufficient for any mismatch): the controller's memberships are held from the last transmitted sample, so no kappa bounds the mismatch and kappa is not used",
    "(41)'s (gamma - rho) I read as (gamma - xi) I, from (20) and (35)",
];

/// Relative width at which the diagnostic nu bisection stops.
const TRIGGER_NU_REL_TOL: f64 = 0.05;
