//! Xu & Huang (2020) Theorem 2, LMIs (37)-(41), as printed, under three OCR
//! readings (docs/event_trigger.md lists every interpretation):
//!
//! 1. as printed: block (1,2) = -eps1 Qh' + eps2 Qh A_i' - Lh1 + Lh2' (no Uh);
//!    the sector term Nh_j' M of block (3,5) is bilinear in the unknowns Nh_j
//!    and M, so M = I is fixed (the only way to keep the printed blocks linear);
//! 2. block (1,2) from the derivation of (22): Uh - eps1 Qh' + eps2 Qh A_i'; M = I;
//! 3. reading 2 with the sector rows brought in by the congruence
//!    diag{Qh, Qh, Qh, Qh, M^{-1}, I}: S = M^{-1} diagonal unknown, blocks
//!    -eps_k B_i S, Nh_j', -2 S (linear).
//!
//! Common to all readings: (41) "(gamma - rho) I" is (gamma - xi) I (from (20)
//! and (35)); the trigger weight Upsilon-hat is the matrix of blocks (3,3),
//! (3,4), (4,4) and Y-hat the looped-functional weight of Omega_1/Omega_2;
//! Omega_2 by a Schur complement; h in {h_min, h_max}; the threshold is the
//! spec's nu. The Arino-Sala relaxation (37)-(39) is replaced by its special
//! case Lambda_ijr(h) < 0 for every (i, j) (sufficient for sum_i sum_j
//! zeta_i zeta_jk Lambda_ijr < 0 whatever the mismatch): with 7 rules and
//! blocks of size 30-36, (39) alone is a 420 x 420 LMI per r with ~1e5 slack
//! unknowns in P_ijr, G_ijr, K_ijr, beyond what Clarabel solves here.

use crate::model::TsModel;
use crate::synth::blocks::{region_block, var_row};
use crate::synth::design::{Settings, SynthError};
use crate::synth::relaxation::Family;
use crate::synth::relaxations::Relaxer;
use crate::synth::sampled::{lambda, Block12, Terms, Vertex};
use nalgebra::DMatrix;
use tsf_lang::spec::{Trigger, TriggerSynthesis};
use tsf_lmi::{Expr, LmiError, Problem, Relation, SolveStatus, Var};

/// The numbers of one Theorem 2 problem.
#[derive(Debug, Clone, PartialEq)]
pub struct Theorem2Plan {
    /// OCR reading 1, 2 or 3.
    pub reading: u8,
    /// eps_1..eps_3.
    pub eps: [f64; 3],
    /// xi (given).
    pub xi: f64,
    /// phi.
    pub phi: f64,
    /// Threshold nu.
    pub nu: f64,
    /// [h_min, h_max].
    pub sampling: (f64, f64),
    /// u_bar_s.
    pub levels: Vec<f64>,
    /// tau_bar.
    pub tau_bar: f64,
    /// L-inf disturbance index and output index.
    pub channel: (usize, usize),
}

/// What solving one reading gave.
#[derive(Debug, Clone)]
pub struct Theorem2Outcome {
    /// The plan solved.
    pub plan: Theorem2Plan,
    /// Solver status.
    pub status: SolveStatus,
    /// Interior-point iterations.
    pub iterations: u32,
    /// gamma of the returned iterate (meaningful when solved).
    pub gamma: f64,
    /// LMIs and scalar unknowns of the problem.
    pub size: (usize, usize),
    /// Seconds in Clarabel.
    pub solve_time: f64,
    /// When minimizing gamma gave no verdict: the feasibility problem with gamma
    /// fixed slightly above the last iterate, and its status.
    pub fixed_gamma: Option<(f64, SolveStatus)>,
}

impl Theorem2Outcome {
    /// One line for diagnostics and reports.
    pub fn describe(&self) -> String {
        let p = &self.plan;
        format!(
            "Theorem 2 reading {} (xi = {}, phi = {}, nu = {}, eps = {:?}, h in {{{}, {}}}): solver status {:?} after {} iterations ({} LMIs, {} unknowns, {:.1} s){}{}",
            p.reading, p.xi, p.phi, p.nu, p.eps, p.sampling.0, p.sampling.1, self.status,
            self.iterations, self.size.0, self.size.1, self.solve_time,
            if self.status == SolveStatus::Solved { format!(", gamma = {:.6}", self.gamma) } else { String::new() },
            self.fixed_gamma.map_or(String::new(), |(g, s)| format!("; feasibility with gamma fixed at {g:.4}: {s:?}"))
        )
    }
}

/// The Theorem 2 plan of a spec, if it selects `weight = synthesize theorem2(...)`.
pub fn plan_of(model: &TsModel) -> Result<Option<Theorem2Plan>, SynthError> {
    let Some(TriggerSynthesis::Theorem2 { eps, xi, reading }) = &model.spec.trigger_synthesis
    else {
        return Ok(None);
    };
    let unsupported = |m: &str| SynthError::Unsupported(format!("Theorem 2: {m}"));
    let Some(Trigger::Aperiodic {
        sampling,
        threshold,
        ..
    }) = model.spec.trigger.as_ref().map(|t| &t.node)
    else {
        return Err(unsupported("needs an aperiodic trigger"));
    };
    let (plan, _) = super::super::plan::initial_plan(&model.spec, 0.1);
    let Some(linf) = plan.linf().cloned() else {
        return Err(unsupported("needs an L-inf objective"));
    };
    let Some(sat) = plan.saturation().cloned() else {
        return Err(unsupported("needs `objective saturation region`"));
    };
    let Some(xi) = xi.or(linf.xi) else {
        return Err(unsupported(
            "needs xi: `theorem2(xi = ...)` or `objective linf(...) with xi = ...`",
        ));
    };
    Ok(Some(Theorem2Plan {
        reading: *reading,
        eps: *eps,
        xi,
        phi: linf.phi,
        nu: threshold.as_ref().map_or(0.0, |t| t.ceiling()),
        sampling: *sampling,
        levels: sat.levels,
        tau_bar: sat.disturbance_bound.unwrap_or(0.0),
        channel: (linf.from, linf.to),
    }))
}

/// Builds LMIs (37)-(41) (with (37)-(39) as described in the module docs).
pub fn build(model: &TsModel, p: &Theorem2Plan, eps: f64) -> Result<(Problem, Var), LmiError> {
    let (n, m, r) = (model.n, model.m, model.r());
    let sig = &model.spec.disturbances[p.channel.0];
    let out = &model.spec.outputs[p.channel.1];
    let q = sig.len;
    let mut problem = Problem::new();
    let qh = problem.full("Qhat", n, n)?;
    let uh = problem.symmetric("Uhat", n)?;
    let yh = problem.symmetric("Yhat", n)?;
    let wh = problem.symmetric("Upsilonhat", n)?;
    let l = [problem.full("Lhat1", n, n)?, problem.full("Lhat2", n, n)?];
    let f = (0..r)
        .map(|j| problem.full(&format!("Fhat{}", j + 1), m, n))
        .collect::<Result<Vec<_>, _>>()?;
    let nh = (0..r)
        .map(|j| problem.full(&format!("Nhat{}", j + 1), m, n))
        .collect::<Result<Vec<_>, _>>()?;
    let s = if p.reading == 3 {
        Some(problem.diagonal("S", m)?)
    } else {
        None
    };
    let gamma = problem.scalar("gamma")?;
    for (name, v) in [("Uhat > 0", uh), ("Yhat > 0", yh), ("Upsilonhat > 0", wh)] {
        problem.psd(name, Expr::var(v), eps)?;
    }
    if let Some(s) = s {
        problem.psd("S = M^-1 > 0", Expr::var(s), eps)?;
    }
    let id_n = DMatrix::identity(n, n);
    let id_m = DMatrix::identity(m, m);
    let block12 = if p.reading == 1 {
        Block12::Printed
    } else {
        Block12::Derived
    };
    let terms = |i: usize, j: usize| -> Result<Terms, LmiError> {
        let a = &model.rules[i].a;
        let b = &model.rules[i].b;
        let d = model.rules[i].d.columns(sig.offset, sig.len).into_owned();
        let by = |k: usize, e: Expr| e.scale(p.eps[k]);
        let three = |g: &dyn Fn(usize) -> Result<Expr, LmiError>| -> Result<[Expr; 3], LmiError> {
            Ok([g(0)?, g(1)?, g(2)?])
        };
        let bs = match s {
            Some(s) => Expr::product(b, s, &id_m)?,
            None => Expr::constant(b)?,
        };
        Ok(Terms {
            q: three(&|k| by(k, Expr::var(qh).transpose()))?,
            qa: three(&|k| by(k, Expr::product_t(a, qh, &id_n)?))?,
            qbf: three(&|k| by(k, Expr::product(b, f[j], &id_n)?))?,
            qb: three(&|k| by(k, bs.clone()))?,
            qd: three(&|k| by(k, Expr::constant(&d)?))?,
            u: Expr::var(uh),
            y: Expr::var(yh),
            l: [Expr::var(l[0]), Expr::var(l[1])],
            w: Expr::var(wh),
            s35: Expr::var(nh[j]).transpose(),
            s45: None,
            s55: match s {
                Some(s) => Expr::var(s).scale(-2.0)?,
                None => Expr::constant(&(DMatrix::identity(m, m) * -2.0))?,
            },
            xi: Expr::constant(&(DMatrix::identity(q, q) * p.xi))?,
        })
    };
    let mut relaxer = Relaxer::every_pair(model, eps);
    for h in [p.sampling.0, p.sampling.1] {
        for rr in [1u8, 2] {
            let vertex = Vertex {
                phi: p.phi,
                nu: p.nu,
                h,
                h_max: p.sampling.1,
                r: rr,
                block12,
            };
            let fam = Family {
                name: format!("(38) r={rr} h={h}"),
                q: Box::new(move |i, j| lambda(terms(i, j)?, vertex)),
            };
            relaxer.impose(&mut problem, &fam)?;
        }
    }
    // (40).
    let level = 1.0 + p.xi * p.tau_bar * p.tau_bar / p.phi;
    for j in 0..r {
        for (k, ub) in p.levels.iter().enumerate() {
            let row = var_row(f[j], k, m, n)?.sub(var_row(nh[j], k, m, n)?)?;
            let e = region_block(
                Expr::var(uh).scale(ub * ub / level)?,
                row,
                Expr::identity(1),
            )?;
            problem.psd(&format!("(40) [{},{}]", j + 1, k + 1), e, eps)?;
        }
    }
    // (41) with (gamma - xi).
    let pdim = out.c.nrows();
    let e = Expr::sym_blocks(vec![
        vec![
            Some(Expr::var(uh).scale(p.phi)?),
            None,
            Some(Expr::product(&id_n, qh, &out.c.transpose())?),
        ],
        vec![
            None,
            Some(
                Expr::scaled(gamma, &DMatrix::identity(q, q))?
                    .add_constant(&(DMatrix::identity(q, q) * -p.xi))?,
            ),
            None,
        ],
        vec![
            None,
            None,
            Some(Expr::scaled(gamma, &DMatrix::identity(pdim, pdim))?),
        ],
    ])?;
    problem.psd("(41)", e, eps)?;
    problem.minimize(Expr::var(gamma))?;
    Ok((problem, gamma))
}

/// Solves one reading.
pub fn solve(
    model: &TsModel,
    plan: &Theorem2Plan,
    settings: &Settings,
) -> Result<Theorem2Outcome, SynthError> {
    let (problem, gamma) = build(model, plan, settings.eps)
        .map_err(|e| SynthError::Internal(format!("internal LMI construction error: {e}")))?;
    let stats = problem.stats();
    let sol = problem
        .solve(&settings.solver)
        .map_err(|e| SynthError::Internal(format!("solver refused the problem: {e}")))?;
    let verdict = |s: SolveStatus| s == SolveStatus::Solved || s.is_primal_infeasible();
    let gamma_iterate = sol
        .assignment_any_status()
        .value(gamma)
        .map_or(f64::NAN, |g| g[(0, 0)]);
    let mut fixed_gamma = None;
    if !verdict(sol.status) {
        // Minimizing gamma drives (41) to a degenerate face (gamma -> xi+ when Uhat
        // allows it); the feasibility problem at a fixed gamma is better posed.
        let g = if gamma_iterate.is_finite() {
            1.05 * gamma_iterate.max(plan.xi)
        } else {
            2.0 * plan.xi
        };
        let (mut fixed, gv) = build(model, plan, settings.eps)
            .map_err(|e| SynthError::Internal(format!("internal LMI construction error: {e}")))?;
        let pin = fixed
            .add_scalar("gamma fixed", Expr::var(gv), Relation::Eq, g)
            .and_then(|_| fixed.minimize(Expr::zeros(1, 1)));
        pin.map_err(|e| SynthError::Internal(format!("internal LMI construction error: {e}")))?;
        let status = fixed
            .solve(&settings.solver)
            .map_err(|e| SynthError::Internal(format!("solver refused the problem: {e}")))?
            .status;
        fixed_gamma = Some((g, status));
    }
    Ok(Theorem2Outcome {
        fixed_gamma,
        plan: plan.clone(),
        status: sol.status,
        iterations: sol.iterations,
        gamma: sol
            .assignment_any_status()
            .value(gamma)
            .map_or(f64::NAN, |g| g[(0, 0)]),
        size: (stats.lmis, stats.scalar_unknowns),
        solve_time: sol.solve_time,
    })
}

/// Xu & Huang's Theorem 2 (`weight = synthesize theorem2(..)`), as an experiment.
#[derive(Debug, Clone, Copy)]
pub struct Theorem2;

impl super::Experiment for Theorem2 {
    fn claims(&self, model: &TsModel) -> bool {
        matches!(
            model.spec.trigger_synthesis,
            Some(TriggerSynthesis::Theorem2 { .. })
        )
    }

    fn run(&self, model: &TsModel, settings: &Settings) -> SynthError {
        synthesize(model, settings).unwrap_or_else(|| {
            SynthError::Internal("internal error: Theorem 2 was not selected".into())
        })
    }
}

/// Runs Theorem 2 for a spec that selects it: a solved problem is reported but
/// not emitted (its gains are not certified by tsfc), any other status is a
/// diagnosis (exit 3).
pub fn synthesize(model: &TsModel, settings: &Settings) -> Option<SynthError> {
    let plan = match plan_of(model) {
        Ok(Some(p)) => p,
        Ok(None) => return None,
        Err(e) => return Some(e),
    };
    let out = match solve(model, &plan, settings) {
        Ok(o) => o,
        Err(e) => return Some(e),
    };
    let line = out.describe();
    let achievable = vec![
        "the two-step method (`weight = synthesize;`) certifies an event trigger for the gains of the continuous design".to_string(),
    ];
    Some(match out.status {
        s if s.is_primal_infeasible() => SynthError::Infeasible {
            message: format!("infeasible: {line}"),
            achievable,
        },
        SolveStatus::Solved => SynthError::Unsupported(format!(
            "{line}; tsfc does not certify Theorem 2 designs: use `weight = synthesize;`"
        )),
        status => SynthError::Solver {
            status,
            message: format!("no verdict: {line}"),
            achievable,
        },
    })
}
