//! The certificate of the SAMPLED observer-based loop: the continuous T-S
//! plant, and the discrete observer and controller the generated code runs
//! every period T (zero-order hold on u).
//!
//! What runs (`tsf_runtime::Observer::step`, premises measured): at t_k,
//! y_k = C x(t_k), memberships h_j(t_k) from y_k (the plant's own, the
//! premises read measured states), u_k = sum_l h_l(t_k) F_l xhat_k, and
//!
//! ```text
//! xhat_{k+1} = sum_j h_j(t_k) (Phi_j xhat_k + Gu_j u_k + Gy_j y_k)
//! ```
//!
//! with the tables Phi_j, Gu_j, Gy_j of every rule ([`discretize`]: the
//! exact zero-order-hold discretization of the rule's continuous observer,
//! but nothing below depends on how they were computed). The plant
//! x'(t) = sum_i h_i(x(t)) (A_i x(t) + B_i u_k) between samples.
//!
//! The estimate is read only at the samples, so any continuous curve through
//! the xhat_k describes the loop; take the straight line
//! xhat(t) = xhat_k + (t - t_k) (xhat_{k+1} - xhat_k) / T. On (t_k, t_{k+1})
//! its derivative is constant, and with sum_j h_j = 1:
//!
//! ```text
//! xhat'(t) = sum_j sum_l h_j h_l [Gy_j C / T, (Phi_j - I) / T + Gu_j F_l / T] xi(t_k)
//! x'(t)    = sum_i h_i(t) A_i x(t) + sum_i sum_l h_i(t) h_l(t_k) B_i F_l xhat(t_k)
//! ```
//!
//! so xi = (x, xhat) (2n states, absolutely continuous) follows EXACTLY
//!
//! ```text
//! xi'(t) = sum_{i,j,l} h_i(t) h_j(t_k) h_l(t_k) (Abar_i xi(t) + Bbar_i K_jl xi(t_k)),
//! Abar_i = diag(A_i, 0),  Bbar_i = diag(B_i, I_n),
//! K_jl = [0, F_l; Gy_j C / T, (Phi_j - I) / T + Gu_j F_l / T],
//! ```
//!
//! a sampled-data T-S loop with plant rules (Abar_i, Bbar_i) and
//! "controller gains" K_jl, one per pair (observer rule j, controller rule
//! l), both blended at t_k (the observer's B_j u_k makes the double sum).
//! The weights h_i(t) h_j(t_k) h_l(t_k) are >= 0 and sum to 1, so the
//! looped-functional conditions of [`crate::synth::trigger`] (Seuret 2012;
//! Xu & Huang 2020), imposed at every vertex (i, (j, l)) with every sample
//! transmitted, cover the loop with h_i varying within the period: they are
//! affine in (Abar_i, Bbar_i K_jl) but for h Phi' Y Phi, which is convex.
//! With V' + phi V < 0 between samples and the looped term zero at them,
//! V(t) <= e^{-phi (t - t_0)} x_0' P x_0: with phi = 2 alpha the loop decays
//! at rate alpha (else phi = 0: asymptotic stability). The measurement noise
//! enters as Gy_j v_k / T, an input the certificate does not bound.
//!
//! The certificate rebuilds the conditions from the shipped F_l and tables
//! (and from their stored rounding: [`crate::synth::loops::observer`]).

use super::drift::Drift;
use super::sampled_bounds::{SampledBounds, MU2_SAMPLED};
use super::ObserverDesign;
use crate::model::region::drift::{drift_bound, largest_input, state_box};
use crate::model::TsModel;
use crate::synth::advice::{about, round_down};
use crate::synth::design::{SynthError, TriggerPlan};
use crate::synth::l2_channel::L2Channel;
use crate::synth::objectives::discrete::zoh;
use crate::synth::reduction::Reduction;
use crate::synth::sampling::{longest_scale, plan_for};
use crate::synth::search::Runner;
use crate::synth::solved::{names, Solved as _};
use crate::synth::trigger_scale::LoopedSolve;
use crate::synth::Design;
use nalgebra::DMatrix;

/// The exact discretization of one rule's observer
/// `xhat' = (A - L C) xhat + B u + L y` over `period` with u and y held:
/// `(Phi, Gu, Gy)` (C. F. Van Loan, "Computing integrals involving the
/// matrix exponential", IEEE TAC 23(3), 1978, through [`zoh`]).
pub fn discretize(
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
    c: &DMatrix<f64>,
    l: &DMatrix<f64>,
    period: f64,
) -> (DMatrix<f64>, DMatrix<f64>, DMatrix<f64>) {
    let (n, m, q) = (a.nrows(), b.ncols(), c.nrows());
    let ao = a - l * c;
    let mut inputs = DMatrix::zeros(n, m + q);
    inputs.view_mut((0, 0), (n, m)).copy_from(b);
    inputs.view_mut((0, m), (n, q)).copy_from(l);
    let (phi, g) = zoh(&ao, &inputs, period);
    let gu = g.view((0, 0), (n, m)).into_owned();
    let gy = g.view((0, m), (n, q)).into_owned();
    (phi, gu, gy)
}

/// Every rule's discrete observer step: the tables generated code stores.
#[derive(Debug, Clone, PartialEq)]
pub struct ObserverSteps {
    /// Phi_j (n x n).
    pub phi: Vec<DMatrix<f64>>,
    /// Gu_j (n x m).
    pub gu: Vec<DMatrix<f64>>,
    /// Gy_j (n x p).
    pub gy: Vec<DMatrix<f64>>,
}

impl ObserverSteps {
    /// The steps of every rule of `model` with gains `l`, at `period`.
    pub fn of(model: &TsModel, c: &DMatrix<f64>, l: &[DMatrix<f64>], period: f64) -> Self {
        let (mut phi, mut gu, mut gy) = (Vec::new(), Vec::new(), Vec::new());
        for (rule, li) in model.rules.iter().zip(l) {
            let (p, u, y) = discretize(&rule.a, &rule.b, c, li, period);
            phi.push(p);
            gu.push(u);
            gy.push(y);
        }
        ObserverSteps { phi, gu, gy }
    }

    /// Every entry passed through `round` (the stored precision).
    pub fn rounded(&self, round: &dyn Fn(f64) -> f64) -> Self {
        let r = |v: &Vec<DMatrix<f64>>| v.iter().map(|m| m.map(round)).collect();
        ObserverSteps {
            phi: r(&self.phi),
            gu: r(&self.gu),
            gy: r(&self.gy),
        }
    }

    /// Every matrix, for the stored-rounding report.
    pub fn matrices(&self) -> Vec<&DMatrix<f64>> {
        self.phi.iter().chain(&self.gu).chain(&self.gy).collect()
    }

    /// Whether every entry is finite.
    pub fn finite(&self) -> bool {
        self.matrices()
            .iter()
            .all(|m| m.iter().all(|v| v.is_finite()))
    }
}

/// The augmented loop as a T-S model of the sampled-data form: 2n states
/// xi = (x, xhat), inputs v = (u, xhat') (m + n), rules
/// Abar_i = diag(A_i, 0), Bbar_i = diag(B_i, I_n), no disturbance.
pub fn augmented_model(model: &TsModel) -> TsModel {
    let (n, m) = (model.n, model.m);
    let mut aug = model.clone();
    aug.n = 2 * n;
    aug.m = m + n;
    aug.q = 0;
    aug.plant_error = None;
    for rule in &mut aug.rules {
        let mut a = DMatrix::zeros(2 * n, 2 * n);
        a.view_mut((0, 0), (n, n)).copy_from(&rule.a);
        let mut b = DMatrix::zeros(2 * n, m + n);
        b.view_mut((0, 0), (n, m)).copy_from(&rule.b);
        b.view_mut((n, m), (n, n))
            .copy_from(&DMatrix::identity(n, n));
        rule.a = a;
        rule.b = b;
        rule.d = DMatrix::zeros(2 * n, 0);
    }
    aug
}

/// K_jl for every observer rule j (outer) and controller rule l (inner):
/// `[0, F_l; Gy_j C / T, (Phi_j - I) / T + Gu_j F_l / T]`.
pub fn pair_gains(
    f: &[DMatrix<f64>],
    c: &DMatrix<f64>,
    steps: &ObserverSteps,
    period: f64,
) -> Vec<DMatrix<f64>> {
    let Some(n) = steps.phi.first().map(DMatrix::nrows) else {
        return Vec::new();
    };
    let m = f.first().map_or(0, DMatrix::nrows);
    let id = DMatrix::<f64>::identity(n, n);
    let mut out = Vec::new();
    for j in 0..steps.phi.len() {
        let gyc = &steps.gy[j] * c / period;
        let drift = (&steps.phi[j] - &id) / period;
        for fl in f {
            let mut k = DMatrix::zeros(m + n, 2 * n);
            k.view_mut((0, n), (m, n)).copy_from(fl);
            k.view_mut((m, 0), (n, n)).copy_from(&gyc);
            k.view_mut((m, n), (n, n))
                .copy_from(&(&drift + &steps.gu[j] * fl / period));
            out.push(k);
        }
    }
    out
}

/// Sets the saturation terms of `plan` from its observer bounds
/// ([`super::sampled_bounds`]): with the saturation certified ACTIVE
/// (multiplier scale tau) the levels, the known multiplier
/// T = diag(tau / u_s^2) (the sector gains G_jl are then unknowns of the
/// problem) and per pair (observer rule j outer, controller rule l inner)
/// the dead-zone map M_jl = [I_m; Gu_j / T] ((m + n) x m: the plant gets
/// -B_i dz_k, the observer, fed the saturated command, -Gu_j dz_k / T);
/// otherwise none.
fn saturation_terms(plan: &mut TriggerPlan, steps: &ObserverSteps, period: f64) {
    plan.levels = Vec::new();
    plan.sector = Vec::new();
    plan.dz_input = Vec::new();
    plan.sector_multiplier = None;
    let Some((levels, tau)) = plan
        .observer_bounds
        .as_ref()
        .and_then(|b| b.active.map(|tau| (b.levels.clone(), tau)))
    else {
        return;
    };
    let (m, n) = (levels.len(), steps.phi.first().map_or(0, DMatrix::nrows));
    let per_rule = plan.gains.len() / steps.gu.len().max(1);
    for gu in &steps.gu {
        let mut map = DMatrix::zeros(m + n, m);
        map.view_mut((0, 0), (m, m)).fill_with_identity();
        map.view_mut((m, 0), (n, m)).copy_from(&(gu / period));
        plan.dz_input.extend(std::iter::repeat_n(map, per_rule));
    }
    plan.sector_multiplier = Some(DMatrix::from_fn(m, m, |r, c| {
        if r == c {
            tau / (levels[r] * levels[r])
        } else {
            0.0
        }
    }));
    plan.levels = levels;
}

/// The certificate of the sampled observer loop.
#[derive(Debug, Clone)]
pub struct SampledObserver {
    /// The period T (s).
    pub period: f64,
    /// The decay rate certified (0: asymptotic stability).
    pub alpha: f64,
    /// The measured output map C.
    pub c: DMatrix<f64>,
    /// The discrete observer every rule runs (what the tables store).
    pub steps: ObserverSteps,
    /// The looped-functional problem data (augmented model, gains K_jl).
    pub plan: TriggerPlan,
    /// P of the functional (2n x 2n).
    pub p: DMatrix<f64>,
    /// Values of every variable of the solved problem.
    pub values: Vec<(String, DMatrix<f64>)>,
    /// Reductions applied to the solved problem.
    pub reductions: Vec<Reduction>,
}

impl SampledObserver {
    /// The looped-functional plan for the controller gains `f` and the
    /// observer `steps` (rounded as stored by the caller, if so).
    /// With the saturation active, the plan's sector gains and dead-zone
    /// maps are rebuilt from `f` and `steps` too.
    pub fn plan_with(&self, f: &[DMatrix<f64>], steps: &ObserverSteps) -> TriggerPlan {
        let mut plan = TriggerPlan {
            gains: pair_gains(f, &self.c, steps, self.period),
            ..self.plan.clone()
        };
        saturation_terms(&mut plan, steps, self.period);
        plan
    }

    /// Whether the saturation is certified ACTIVE (the generalized sector
    /// condition; else the linear-region certificate, or no saturation).
    pub fn saturation_active(&self) -> bool {
        let levels = self.saturation_levels();
        !levels.is_empty()
            && self
                .plan
                .observer_bounds
                .as_ref()
                .is_some_and(|b| b.active.is_some())
    }

    /// The active certificate's sector gains G_jl (m x 2n, on xi = (x,
    /// xhat)), one per pair (observer rule j outer, controller rule l
    /// inner), as solved; empty otherwise.
    pub fn sector_gains(&self) -> Vec<DMatrix<f64>> {
        if !self.saturation_active() {
            return Vec::new();
        }
        (1..=self.plan.gains.len())
            .filter_map(|q| {
                self.values
                    .value(&format!("{}{q}", names::LOOP_SECTOR_GAIN))
                    .cloned()
            })
            .collect()
    }

    /// The H-inf gain certified from w to z (the spec's `objective hinf`).
    pub fn hinf_gamma(&self) -> Option<f64> {
        self.plan.l2.as_ref()?;
        let g = self.values.value(names::LOOP_HINF)?;
        Some(g[(0, 0)].max(0.0).sqrt())
    }

    /// What it certifies, in words.
    pub fn covers(&self) -> String {
        let rate = if self.alpha > 0.0 {
            format!(
                "decays at rate {} (V(t) <= e^(-{} t) V(0))",
                self.alpha,
                2.0 * self.alpha
            )
        } else {
            "is asymptotically stable (the decay rate of the spec is not certified for the sampled loop)".into()
        };
        let start = match &self.plan.drift {
            Some(d) => format!(
                " from every (x(0), xhat(0)) in E(P, 1), which lies in the sample box and where {} <= {:.6}; the plant's memberships drift by at most {:?} within a period (paired plant/observer vertices)",
                if d.by_actuator { "the applied command (by the actuator) |sat(u)|" } else { "|u|" },
                d.input_bound, d.bound.delta
            ),
            None => String::new(),
        };
        let bounds = match &self.plan.observer_bounds {
            Some(b) => {
                let mut parts = Vec::new();
                if let Some(mu) = b.mu() {
                    parts.push(format!(
                        "||u(t)|| <= {mu:.6} for t >= 0 (the command held between samples)"
                    ));
                }
                match b.active {
                    _ if b.levels.is_empty() => {}
                    Some(_) => parts.push(format!("the actuator saturates at the levels {:?} and the saturation may be ACTIVE on E(P, 1): the loop with the saturated command (plant and observer) is certified by the generalized sector condition dz_k' T (dz_k - G_jl xi_k) <= 0 (T known, the sector gains G_jl solved), which holds on E(P, 1) where |((Kbar_l - G_jl) xi)_s| <= u_s", b.levels)),
                    None => parts.push(format!("|u_s| <= u_s on E(P, 1) for the levels {:?}: the saturation is inactive on the certified set (linear-region certificate), so the saturated loop is the certified linear one there", b.levels)),
                }
                if !b.initial.is_empty() {
                    parts.push("E(P, 1) contains the initial set with x_hat(0) = 0".to_string());
                }
                format!("; {}", parts.join("; "))
            }
            None => String::new(),
        };
        let gain = match self.hinf_gamma() {
            Some(g) => format!("; from rest (x(0) = xhat(0) = 0) its H-inf gain from the disturbance to the output is at most {g:.6}: ||z||_2 <= {g:.6} ||w||_2"),
            None => String::new(),
        };
        format!(
            "the sampled observer-based loop (continuous T-S plant, the discrete observer and controller every {} s, zero-order hold) {rate}{start}{bounds}{gain}; the measurement noise is not bounded by it",
            self.period
        )
    }

    /// The certified input bound mu (||u(t)|| <= mu), if one was imposed.
    pub fn input_bound(&self) -> Option<f64> {
        self.plan
            .observer_bounds
            .as_ref()
            .and_then(SampledBounds::mu)
    }

    /// The saturation levels the certified set keeps the command within
    /// (empty: no actuator limit).
    pub fn saturation_levels(&self) -> &[f64] {
        self.plan
            .observer_bounds
            .as_ref()
            .map_or(&[], |b| b.levels.as_slice())
    }
}

/// The input bounds U tried by the drift route, as fractions of the largest
/// one that leaves a sample box, in order.
pub const INPUT_FRACTIONS: [f64; 4] = [0.5, 0.25, 0.75, 0.125];

/// The plan of the sampled observer loop at `period` with `phi`.
fn plan_at(
    model: &TsModel,
    d: &Design,
    o: &ObserverDesign,
    (period, phi): (f64, f64),
    (drift, bounds): (Option<&Drift>, Option<&SampledBounds>),
) -> (TriggerPlan, ObserverSteps) {
    let steps = ObserverSteps::of(model, &o.c, &o.gains, period);
    let mut plan = plan_for(model, d, (period, period));
    plan.phi = phi;
    plan.contain = Vec::new();
    plan.c = DMatrix::zeros(0, 2 * model.n);
    plan.gains = pair_gains(&d.gains, &o.c, &steps, period);
    plan.drift = drift.cloned();
    plan.observer_bounds = bounds.cloned();
    saturation_terms(&mut plan, &steps, period);
    if let Some((d, l2)) = hinf_channel(model) {
        plan.d = d;
        plan.l2 = Some(l2);
    }
    (plan, steps)
}

/// The spec's H-inf objective as the sampled loop's channel on xi = (x,
/// xhat): the disturbance columns [D_i; 0] per rule (the observer does not
/// see w), z = [C_z, 0] xi + E_z u_k + G w, g <= gamma^2 with the spec's
/// fixed gamma (a minimized one is refused at check time: with g unbounded
/// the feasibility problem has a recession direction and Clarabel stops with
/// NumericalError). `None` without the objective or its bound.
fn hinf_channel(model: &TsModel) -> Option<(Vec<DMatrix<f64>>, L2Channel)> {
    let (from, to, fixed) = super::hinf::objective(model)?;
    let gamma = fixed?;
    let (sig, out) = (
        model.spec.disturbances.get(from)?,
        model.spec.outputs.get(to)?,
    );
    let n = model.n;
    let d = model
        .rules
        .iter()
        .map(|r| {
            let mut d = DMatrix::zeros(2 * n, sig.len);
            d.view_mut((0, 0), (n, sig.len))
                .copy_from(&r.d.columns(sig.offset, sig.len));
            d
        })
        .collect();
    let mut c = DMatrix::zeros(out.c.nrows(), 2 * n);
    c.view_mut((0, 0), (out.c.nrows(), n)).copy_from(&out.c);
    let l2 = L2Channel {
        c,
        e: out.e.clone(),
        g: out.g.columns(sig.offset, sig.len).into_owned(),
        gamma,
        minimize: false,
    };
    Some((d, l2))
}

/// The multiplier scales tau tried, in order, by the active-saturation
/// certificate (T = diag(tau / u_s^2) known, the sector gains solved:
/// [`super::sampled_bounds`]). On the pendulum of
/// `specs/pendulum_observer_sampled_saturated.tsf` tau from 12 to 120
/// certifies 25 deg at rest (stability) and up to 120 the decay rate at
/// 17 deg; 400 loses the decay rate there, 4 the 25 deg.
pub const SECTOR_MULTIPLIERS: [f64; 3] = [40.0, 10.0, 160.0];

impl Runner<'_> {
    /// The sampled observer loop at `period` and `alpha`
    /// ([`Runner::observer_routes`]); with saturation levels the linear-region
    /// certificate first, then the ACTIVE one at each of
    /// [`SECTOR_MULTIPLIERS`] (the first that certifies is kept), so a loop
    /// the linear-region certificate covers keeps it.
    fn observer_attempt(
        &mut self,
        aug: &TsModel,
        d: &Design,
        o: &ObserverDesign,
        (period, alpha): (f64, f64),
        bounds: Option<&SampledBounds>,
    ) -> Result<Option<SampledObserver>, SynthError> {
        if let Some(s) = self.observer_routes(aug, d, o, (period, alpha), bounds)? {
            return Ok(Some(s));
        }
        let Some(b) = bounds.filter(|b| !b.levels.is_empty() && b.active.is_none()) else {
            return Ok(None);
        };
        // On a region the plant gets sat(u_k): U = the largest level, by the
        // actuator. A smaller U would keep E(P, 1) where nothing saturates
        // (the linear-region certificate, tried above).
        let drift = match state_box(self.model) {
            None => None,
            Some(_) => {
                let level = b.levels.iter().fold(0.0, |a: f64, v| a.max(*v));
                let Ok(bound) = drift_bound(self.model, period, level) else {
                    return Ok(None);
                };
                Some(Drift {
                    by_actuator: true,
                    ..Drift::of(self.model, bound)
                })
            }
        };
        for tau in SECTOR_MULTIPLIERS {
            let active = b.with_active(tau);
            let on = (drift.as_ref(), Some(&active));
            if let Some(s) = self.observer_solve(aug, d, o, (period, alpha), on)? {
                return Ok(Some(s));
            }
        }
        Ok(None)
    }

    /// The sampled observer loop at `period` and `alpha` with `bounds` as
    /// given: free vertices, or with a state box on every state the drift
    /// route ([`super::drift`]), whose input bound U is tried at
    /// [`INPUT_FRACTIONS`] of the largest that leaves a sample box (the first
    /// that certifies is kept).
    fn observer_routes(
        &mut self,
        aug: &TsModel,
        d: &Design,
        o: &ObserverDesign,
        (period, alpha): (f64, f64),
        bounds: Option<&SampledBounds>,
    ) -> Result<Option<SampledObserver>, SynthError> {
        let Some(region) = state_box(self.model) else {
            return self.observer_solve(aug, d, o, (period, alpha), (None, bounds));
        };
        let most = largest_input(self.model, &region, period);
        let fractions: &[f64] = if most.is_finite() {
            &INPUT_FRACTIONS
        } else {
            &[1.0]
        };
        for f in fractions {
            let Ok(bound) = drift_bound(self.model, period, most * f) else {
                continue;
            };
            let drift = Drift::of(self.model, bound);
            if let Some(s) =
                self.observer_solve(aug, d, o, (period, alpha), (Some(&drift), bounds))?
            {
                return Ok(Some(s));
            }
        }
        Ok(None)
    }

    /// With the H-inf channel, `s` re-solved minimizing g under the spec's
    /// bound (the first solve is a feasibility problem, whose g is an
    /// interior point): the reported gain is then the least this functional
    /// certifies. When the minimization does not solve (on the pendulum
    /// Clarabel stops with NumericalError for some bounds where the
    /// feasibility problem solves), `s` is kept.
    fn least_hinf(
        &mut self,
        aug: &TsModel,
        o: &ObserverDesign,
        s: SampledObserver,
    ) -> Result<SampledObserver, SynthError> {
        let mut plan = s.plan.clone();
        let Some(c) = plan.l2.as_mut() else {
            return Ok(s);
        };
        c.minimize = true;
        let least = self.observer_plan_solve(aug, o, plan, s.steps.clone(), (s.period, s.alpha))?;
        Ok(least.unwrap_or(s))
    }

    /// One SDP of the sampled observer loop at `period` and `alpha` (two
    /// with a minimized input bound: the least bound, then the fixed bound
    /// [`super::bounded::MU_SLACK`] above it, which is what is certified).
    fn observer_solve(
        &mut self,
        aug: &TsModel,
        d: &Design,
        o: &ObserverDesign,
        (period, alpha): (f64, f64),
        (drift, bounds): (Option<&Drift>, Option<&SampledBounds>),
    ) -> Result<Option<SampledObserver>, SynthError> {
        let fixed;
        let bounds = match bounds {
            Some(b) if b.input == Some(None) => {
                let (plan, steps) =
                    plan_at(self.model, d, o, (period, 2.0 * alpha), (drift, Some(b)));
                if !steps.finite() {
                    return Ok(None);
                }
                let what = "sampled observer-loop input bound (minimized)";
                let Some((_, all)) =
                    self.solve_looped_on(aug, &plan, what, LoopedSolve::default())?
                else {
                    return Ok(None);
                };
                let nu = all.required(MU2_SAMPLED)?[(0, 0)].max(0.0);
                fixed = b.fixed(b.scale * nu.sqrt() * (1.0 + super::bounded::MU_SLACK));
                Some(&fixed)
            }
            other => other,
        };
        let (plan, steps) = plan_at(self.model, d, o, (period, 2.0 * alpha), (drift, bounds));
        self.observer_plan_solve(aug, o, plan, steps, (period, alpha))
    }
    /// The SDP of the sampled observer loop for `plan` (its observer `steps`).
    fn observer_plan_solve(
        &mut self,
        aug: &TsModel,
        o: &ObserverDesign,
        plan: TriggerPlan,
        steps: ObserverSteps,
        (period, alpha): (f64, f64),
    ) -> Result<Option<SampledObserver>, SynthError> {
        if !steps.finite() {
            return Ok(None);
        }
        let what = "sampled observer-loop problem";
        let Some((built, all)) = self.solve_looped_on(aug, &plan, what, LoopedSolve::default())?
        else {
            return Ok(None);
        };
        Ok(Some(SampledObserver {
            period,
            alpha,
            c: o.c.clone(),
            steps,
            plan,
            p: all.required(names::LOOP_P)?,
            values: all,
            reductions: built.reductions,
        }))
    }

    /// The refusal of `bounds` on a loop that certifies without them at
    /// `period`: with the least input bound these gains admit with the other
    /// bounds (minimized), when one is found.
    fn bounds_refusal(
        &mut self,
        aug: &TsModel,
        (d, o): (&Design, &ObserverDesign),
        period: f64,
        bounds: &SampledBounds,
    ) -> Result<SynthError, SynthError> {
        let mut achievable = Vec::new();
        if let Some(Some(_)) = bounds.input {
            let loose = SampledBounds {
                input: Some(None),
                ..bounds.clone()
            };
            if let Some(s) = self.observer_attempt(aug, d, o, (period, 0.0), Some(&loose))? {
                if let Some(mu) = s.input_bound() {
                    achievable.push(format!("these gains certify ||u|| <= {mu:.6} on the sampled loop (stability): `objective input_norm(u) <= {:.6} ...` (or minimize)", mu * (1.0 + 10.0 * super::bounded::MU_SLACK)));
                }
            }
        }
        achievable.push("shrink the initial set, raise the saturation levels or the input bound, or lower the controller's gains (its decay rate, or `input_norm` on the design)".to_string());
        Ok(SynthError::Infeasible {
            message: format!(
                "the observer-based loop sampled every {period} s certifies without its bounds, but not with {} (neither the linear-region certificate, which keeps E(P, 1) where the actuator does not saturate, nor, with saturation levels, the active-saturation one at the multiplier scales {SECTOR_MULTIPLIERS:?})",
                bounds.asked()
            ),
            achievable,
        })
    }

    /// The certificate of the sampled observer loop of `d` at `period`: at
    /// the controller's decay rate `alpha` if it holds, else for stability
    /// (noted); refused with the longest period that certifies stability
    /// (bisection, [`longest_scale`]; the advice re-solved).
    pub fn sampled_observer(
        &mut self,
        d: &Design,
        o: &ObserverDesign,
        period: f64,
        alpha: f64,
    ) -> Result<SampledObserver, SynthError> {
        let aug = augmented_model(self.model);
        let bounds = SampledBounds::of(&self.model.spec, &d.gains);
        let bounds = bounds.as_ref();
        if alpha > 0.0 {
            if let Some(s) = self.observer_attempt(&aug, d, o, (period, alpha), bounds)? {
                return self.least_hinf(&aug, o, s);
            }
        }
        if let Some(s) = self.observer_attempt(&aug, d, o, (period, 0.0), bounds)? {
            return self.least_hinf(&aug, o, s);
        }
        if let Some(b) = bounds {
            if self
                .observer_attempt(&aug, d, o, (period, 0.0), None)?
                .is_some()
            {
                return Err(self.bounds_refusal(&aug, (d, o), period, b)?);
            }
        }
        let what = format!("the observer-based loop sampled every {period} s is not certified (the looped-functional conditions of the sampled loop, with the discrete observer at that period, are infeasible)");
        let Some(lo) = longest_scale(|s| {
            Ok(self
                .observer_attempt(&aug, d, o, (period * s, 0.0), bounds)?
                .is_some())
        })?
        else {
            return Err(SynthError::Infeasible {
                message: what,
                achievable: vec![format!("not even a period of {} s certifies: weaken the controller's decay rate or change the observer's (`control observer_based(decay = ..)`)", about(period / 1024.0))],
            });
        };
        let mut advice = round_down(period * lo);
        let mut checked = "not re-certified";
        for _ in 0..4 {
            if self
                .observer_attempt(&aug, d, o, (advice, 0.0), bounds)?
                .is_some()
            {
                checked = "certified";
                break;
            }
            advice = round_down(advice * 0.95);
        }
        Err(SynthError::Infeasible {
            message: what,
            achievable: vec![format!(
                "the longest certified period is about {} s: write `trigger periodic {{ every = {advice}; }}` ({checked})",
                about(period * lo)
            )],
        })
    }
}
