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
use super::blocks::{nonstrict_psd, region_block};
pub use super::design::TriggerPlan;
use super::design::{Design, SynthError, TriggerDesign};
use super::objective::BuildError;
use super::objectives::{Linf, Saturation};
use super::reduction::Reduction;
use super::relaxation::Family;
use super::relaxations::Relaxer;
use super::search::Runner;
use crate::model::TsModel;
use nalgebra::DMatrix;
use std::time::Instant;
use tsf_lang::spec::{InitialSet, Trigger, TriggerSynthesis, Weight};
use tsf_lmi::{Expr, LmiError, Problem, Relation, SolveStatus, Var};

/// The variables of the sampled-loop problem (`None`: the part is absent).
#[derive(Debug, Clone)]
pub struct TriggerVars {
    /// P of V1 = x' P x.
    pub p: Var,
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

/// The unknowns entering Lambda_{ij r}(h).
#[derive(Debug, Clone, Copy)]
struct LoopVars {
    p: Var,
    y: Var,
    l: [Var; 2],
    w: Option<Var>,
    t: Option<Var>,
    xi: Option<Var>,
}

/// Selector of rows `at .. at + len` of a vector of length `k`, as a `len x k` matrix.
fn pick(len: usize, at: usize, k: usize) -> DMatrix<f64> {
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
        let dz = (!plan.levels.is_empty()).then(|| take(model.m));
        let q = plan.d.first().map_or(0, |d| d.ncols());
        let tau = (plan.linf && q > 0).then(|| (take(q), q));
        Layout { k, e, dz, tau }
    }
}

/// Lambda_{ij r}(h) with the derivative eliminated (gains fixed, so
/// x' = Phi_ij psi with a constant Phi_ij and every term is linear in the
/// unknowns). psi = [x; x(s); e; dz; tau] (the parts the plan has):
///
///   Xi = He(E_x' P Phi) + phi E_x' P E_x + He([E_x; E_s]' L (E_x - E_s))
///        + nu (E_s - E_e)' W (E_s - E_e) - E_e' W E_e
///        + He(E_dz' T G_j (E_s - E_e)) - 2 E_dz' T E_dz - xi E_tau' E_tau,
///   r = 1: Xi + h Phi' Y Phi,
///   r = 2: [Xi, sqrt(h) (E_x' L1 + E_s' L2); *, -e^{-phi h_max} Y].
///
/// Plant rule i and controller rule j differ (membership mismatch), so the
/// bound Phi(h)' Y Phi(h) <= sum h_i h_j Phi_ij' Y Phi_ij (convexity, Y > 0)
/// makes the vertex conditions sufficient.
fn lambda(
    model: &TsModel,
    plan: &TriggerPlan,
    v: &LoopVars,
    (i, j): (usize, usize),
    h: f64,
    r: u8,
) -> Result<Expr, LmiError> {
    let (n, m) = (model.n, model.m);
    let lay = Layout::of(model, plan);
    let k = lay.k;
    let (ex, es) = (pick(n, 0, k), pick(n, n, k));
    let b = &model.rules[i].b;
    // x(t_k) = x(s) - e: the state the controller holds.
    let xk = match lay.e {
        Some(at) => &es - pick(n, at, k),
        None => es.clone(),
    };
    let mut phi_m = &model.rules[i].a * &ex + b * &plan.gains[j] * &xk;
    if let Some(at) = lay.dz {
        phi_m -= b * pick(m, at, k);
    }
    if let Some((at, q)) = lay.tau {
        phi_m += &plan.d[i] * pick(q, at, k);
    }
    let exs = &ex - &es;
    let mut xi_block = Expr::product(&ex.transpose(), v.p, &phi_m)?
        .he()?
        .add(Expr::product(&ex.transpose(), v.p, &ex)?.scale(plan.phi)?)?
        .add(
            Expr::product(&ex.transpose(), v.l[0], &exs)?
                .add(Expr::product(&es.transpose(), v.l[1], &exs)?)?
                .he()?,
        )?;
    if let (Some(at), Some(w)) = (lay.e, v.w) {
        let ee = pick(n, at, k);
        xi_block = xi_block
            .add(Expr::product(&xk.transpose(), w, &xk)?.scale(plan.nu)?)?
            .sub(Expr::product(&ee.transpose(), w, &ee)?)?;
    }
    if let (Some(at), Some(t)) = (lay.dz, v.t) {
        let edz = pick(m, at, k);
        xi_block = xi_block
            .add(Expr::product(&edz.transpose(), t, &(&plan.sector[j] * &xk))?.he()?)?
            .sub(Expr::product(&edz.transpose(), t, &edz)?.scale(2.0)?)?;
    }
    if let (Some((at, q)), Some(xi)) = (lay.tau, v.xi) {
        let etau = pick(q, at, k);
        xi_block = xi_block.sub(Expr::scaled(xi, &(etau.transpose() * &etau))?)?;
    }
    if r == 1 {
        return xi_block.add(Expr::product(&phi_m.transpose(), v.y, &phi_m)?.scale(h)?);
    }
    let id = DMatrix::identity(n, n);
    let col = Expr::product(&ex.transpose(), v.l[0], &id)?
        .add(Expr::product(&es.transpose(), v.l[1], &id)?)?
        .scale(h.sqrt())?;
    let (_, h_max) = plan.sampling;
    Expr::sym_blocks(vec![
        vec![Some(xi_block), Some(col)],
        vec![
            None,
            Some(Expr::var(v.y).scale(-(-plan.phi * h_max).exp())?),
        ],
    ])
}

/// Builds the sampled-loop LMIs. With `reduce`, the h = h_min vertices are
/// left out: every Lambda_r(h) is Xi + h Pi_r with Pi_r >= 0, so h_max
/// implies them.
pub fn build(
    model: &TsModel,
    plan: &TriggerPlan,
    eps: f64,
    reduce: bool,
) -> Result<TriggerBuilt, BuildError> {
    Ok(build_inner(model, plan, eps, reduce)?)
}

fn build_inner(
    model: &TsModel,
    plan: &TriggerPlan,
    eps: f64,
    reduce: bool,
) -> Result<TriggerBuilt, LmiError> {
    let (n, m, r) = (model.n, model.m, model.r());
    let sector = !plan.levels.is_empty();
    let mut problem = Problem::new();
    let p = problem.symmetric("Ptr", n)?;
    let y = problem.symmetric("Ytr", n)?;
    let w = if plan.event {
        Some(problem.symmetric("Upsilon", n)?)
    } else {
        None
    };
    let l = [problem.full("L1", n, n)?, problem.full("L2", n, n)?];
    let t = if sector {
        Some(problem.diagonal("T", m)?)
    } else {
        None
    };
    let (gamma, xi) = if plan.linf {
        (
            Some(problem.scalar("gamma_tr")?),
            Some(problem.scalar("xi_tr")?),
        )
    } else {
        (None, None)
    };
    let mut relaxer = Relaxer::every_pair(model, eps);
    problem.psd("trigger P > 0", Expr::var(p), eps)?;
    problem.psd("trigger Y > 0", Expr::var(y), eps)?;
    if let Some(w) = w {
        problem.psd("trigger Upsilon > 0", Expr::var(w), eps)?;
    }
    if let Some(t) = t {
        problem.psd("trigger T > 0", Expr::var(t), eps)?;
    }
    let vars = LoopVars { p, y, l, w, t, xi };
    let (h_min, h_max) = plan.sampling;
    let hs: &[f64] = if reduce || h_min == h_max {
        &[h_max]
    } else {
        &[h_min, h_max]
    };
    if reduce && h_min < h_max {
        relaxer.reductions.push(Reduction::Implied(format!("trigger: the {} LMIs at h = h_min = {h_min} are implied by those at h_max = {h_max} (Lambda_r(h) = Xi + h Pi_r with Pi_r >= 0) and left out of the solved problem; the certificate checks them", 2 * r * r)));
    }
    for &h in hs {
        for rr in [1u8, 2] {
            let fam = Family {
                name: format!("trigger r={rr} h={h}"),
                q: Box::new(move |i, j| lambda(model, plan, &vars, (i, j), h, rr)),
            };
            relaxer.impose(&mut problem, &fam)?;
        }
    }
    // E(P, c) inside the linear region |(F_j - G_j)_s x| <= u_bar_s, c = 1 + xi tau_bar^2 / phi.
    let level = if plan.linf {
        1.0 + plan.xi_max * plan.tau_bar * plan.tau_bar / plan.phi
    } else {
        1.0
    };
    for j in (0..r).filter(|_| sector) {
        let fg = &plan.gains[j] - &plan.sector[j];
        for (s, ub) in plan.levels.iter().enumerate() {
            let row = Expr::constant(&DMatrix::from_iterator(1, n, fg.row(s).iter().copied()))?;
            let rhs = Expr::constant(&DMatrix::from_element(1, 1, ub * ub / level))?;
            let e = region_block(Expr::var(p), row, rhs)?;
            nonstrict_psd(
                &mut problem,
                &mut relaxer.nonstrict,
                &format!("trigger linear region [{},{}]", j + 1, s + 1),
                e,
                eps,
            )?;
        }
    }
    for (name, e) in &plan.contain {
        nonstrict_psd(
            &mut problem,
            &mut relaxer.nonstrict,
            &format!("sampled region of attraction: {name}"),
            contain_block(p, e)?,
            eps,
        )?;
    }
    if let (Some(gamma), Some(xi)) = (gamma, xi) {
        peak(&mut problem, plan, p, gamma, xi, eps)?;
        problem.minimize(Expr::var(gamma))?;
    }
    Ok(TriggerBuilt {
        problem,
        vars: TriggerVars { p, w, gamma, xi },
        reductions: relaxer.reductions,
        nonstrict: relaxer.nonstrict,
    })
}

/// `E(P, 1)` contains the initial set: `1 - x0' P x0 >= 0` for a point,
/// `R - P >= 0` for the ellipsoid `x' R x <= 1`.
fn contain_block(p: Var, set: &InitialSet) -> Result<Expr, LmiError> {
    match set {
        InitialSet::Point(x0) => {
            let x = DMatrix::from_column_slice(x0.len(), 1, x0);
            Expr::constant(&DMatrix::identity(1, 1))?.sub(Expr::product(&x.transpose(), p, &x)?)
        }
        InitialSet::Ellipsoid(r) => Expr::constant(r)?.sub(Expr::var(p)),
    }
}

/// The output peak: [phi P, 0, C'; *, (gamma - xi) I, G'; *, *, gamma I] > 0
/// and 0 < xi <= xi_max.
fn peak(
    problem: &mut Problem,
    plan: &TriggerPlan,
    p: Var,
    gamma: Var,
    xi: Var,
    eps: f64,
) -> Result<(), LmiError> {
    let q = plan.d.first().map_or(0, |d| d.ncols());
    let pdim = plan.c.nrows();
    let block = Expr::sym_blocks(vec![
        vec![
            Some(Expr::var(p).scale(plan.phi)?),
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

/// Whether the spec asks for a synthesized trigger weight with the two-step
/// method (`weight = synthesize;`, the default, or `weight = synthesize two_step;`).
pub fn wanted(model: &TsModel) -> bool {
    matches!(
        model.spec.trigger.as_ref().map(|t| &t.node),
        Some(Trigger::Aperiodic {
            weight: Weight::Synthesize,
            ..
        })
    ) && matches!(
        model.spec.trigger_synthesis,
        None | Some(TriggerSynthesis::TwoStep)
    )
}

/// The trigger problem for the gains of `design` (threshold 0: the caller sets nu).
pub fn plan_for(model: &TsModel, design: &Design) -> Result<TriggerPlan, SynthError> {
    let unsupported = |m: &str| SynthError::Unsupported(format!("event-trigger synthesis: {m}"));
    let Some(Trigger::Aperiodic { sampling, .. }) = model.spec.trigger.as_ref().map(|t| &t.node)
    else {
        return Err(unsupported("needs an aperiodic trigger"));
    };
    let (Some(linf), Some(sat)) = (design.plan.get::<Linf>(), design.plan.get::<Saturation>())
    else {
        return Err(unsupported(
            "needs an L-inf objective and `objective saturation region` (the shipped method is Xu & Huang's setting)",
        ));
    };
    let out = &model.spec.outputs[linf.to];
    if out.e.iter().any(|v| *v != 0.0) {
        return Err(unsupported("the L-inf output must not depend on u"));
    }
    let sig = &model.spec.disturbances[linf.from];
    let value = |name: &str| {
        design
            .values
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, v)| v.clone())
            .ok_or_else(|| unsupported(&format!("step-1 variable `{name}` missing")))
    };
    // G_j = Z_j X^{-1} = Z_j P.
    let sector = (0..model.r())
        .map(|j| value(&format!("Z{}", j + 1)).map(|z| z * &design.p))
        .collect::<Result<Vec<_>, _>>()?;
    let xi1 = design.achieved.get(Quantity::LinfXi).unwrap_or(0.0);
    Ok(TriggerPlan {
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
    })
}

/// xi of the event-triggered loop may be up to this multiple of step 1's xi
/// (the region level 1 + xi tau_bar^2 / phi is computed with the bound).
pub const XI_FACTOR: f64 = 4.0;

impl Runner<'_> {
    /// Builds and solves the looped-functional problem of `plan` (reduced):
    /// the built problem and every variable's value, or None when not solved.
    pub(super) fn solve_looped(
        &mut self,
        plan: &TriggerPlan,
        what: &str,
    ) -> Result<Option<Solved>, SynthError> {
        let t0 = Instant::now();
        let built = build(self.model, plan, self.settings.eps, true)?;
        self.log.build_time += t0.elapsed();
        let sol = self.solve(&built.problem, what)?;
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
    fn trigger_attempt(&mut self, plan: &TriggerPlan) -> Result<Option<TriggerDesign>, SynthError> {
        let Some((built, all)) = self.solve_looped(plan, "trigger problem")? else {
            return Ok(None);
        };
        Ok(Some(TriggerDesign {
            plan: plan.clone(),
            method: "two_step",
            weight: named(&all, "Upsilon")?,
            p: named(&all, "Ptr")?,
            gamma: named(&all, "gamma_tr")?[(0, 0)],
            xi: named(&all, "xi_tr")?[(0, 0)],
            values: all,
            reductions: built.reductions,
        }))
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
            return Err(SynthError::Infeasible {
                message: format!(
                    "event trigger: the gains of the continuous design are not certified for {sampling} even with nu = 0 (every sample transmitted)"
                ),
                achievable: vec!["shorten h_max or weaken the objectives that set the gains".into()],
            });
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

/// The threshold the trigger LMIs are solved for: the adaptive law's ceiling,
/// else the static nu, else 0 (no threshold: every sample transmitted).
pub fn certified_threshold(model: &TsModel) -> f64 {
    match model.spec.trigger.as_ref().map(|t| &t.node) {
        Some(Trigger::Aperiodic {
            threshold: Some(t), ..
        }) => t.ceiling(),
        _ => 0.0,
    }
}

/// The value of the variable `name` of a solved problem.
pub(super) fn named(
    values: &[(String, DMatrix<f64>)],
    name: &str,
) -> Result<DMatrix<f64>, SynthError> {
    values
        .iter()
        .find(|(n, _)| n == name)
        .map(|(_, v)| v.clone())
        .ok_or_else(|| SynthError::Internal(format!("internal error: `{name}` has no value")))
}
