//! An input bound and saturation levels on the SAMPLED observer-based loop
//! ([`super::sampled`]), certified on its looped functional's E(P, 1) in
//! xi = (x, xhat) (issue 36).
//!
//! The command u_k = sum_l h_l(t_k) F_l xhat_k is held between samples, so
//! ||u(t)|| <= max_l ||F_l xhat_k|| = max_l ||Kbar_l xi_k||, Kbar_l = [0, F_l]
//! (the u-rows of the pair gains K_jl). The looped functional gives
//! V(t_k) = xi_k' P xi_k <= V(t_0) (its looped terms vanish at the
//! samples), so xi_k stays in E(P, 1) once xi_0 is in it. Imposed:
//!
//! - input bound: [P, Kbar_l'/mu; Kbar_l/mu, I] >= 0 for every controller
//!   rule l, i.e. ||Kbar_l xi|| <= mu on E(P, 1) (Schur complement); the
//!   blend is a convex combination, so ||u(t)|| <= mu for all t >= 0.
//!   Minimized: [P, Kbar_l'/sigma; Kbar_l/sigma, nu I] >= 0, mu^2 = sigma^2 nu,
//!   nu minimized, then certified as a fixed bound
//!   [`super::bounded::MU_SLACK`] above (the optimum lies on the boundary);
//! - saturation levels (the LINEAR-REGION certificate):
//!   [P, row'/u_s; row/u_s, 1] >= 0 with row = (Kbar_l)_s, every rule l and
//!   channel s, i.e. |(F_l xhat_k)_s| <= u_s on E(P, 1): the actuator never
//!   saturates on the certified set, so the saturated loop IS the linear
//!   sampled loop there and its certificate covers it. Conservative: the set
//!   is kept where the actuator is linear;
//! - or the ACTIVE-saturation certificate ([`SampledBounds::active`]):
//!   the dead zone dz_k = u_k - sat(u_k) is held like u_k, the plant gets
//!   B (u_k - dz_k) and the observer is fed the saturated command
//!   (`tsf_runtime::Observer::update` takes the clipped u), so xi' gets
//!   -[B_i; Gu_j / T] dz_k: the dead-zone map M_jl of
//!   [`crate::synth::design::TriggerPlan::dz_input`]. The generalized sector
//!   condition (Tarbouriech, Garcia, Gomes da Silva & Queinnec 2011, Lemma
//!   1.6) dz_k' T (dz_k - G_jl xi_k) <= 0 holds where
//!   |((Kbar_l - G_jl) xi_k)_s| <= u_s; that region contains E(P, 1)
//!   (imposed as the looped functional's `trigger linear region`), which
//!   holds xi_k (V(t_k) <= V(t_0) <= 1). The looped functional carries the
//!   S-procedure term He(E_dz' T G_jl xi_k) - 2 E_dz' T E_dz, as the
//!   state-feedback sampled loop ([`crate::synth::trigger`]). T and G_jl
//!   cannot both be unknown (bilinear): T = diag(tau / u_s^2) is fixed (tau
//!   scanned) and the G_jl (m x 2n, one per pair) are unknowns, which keeps
//!   every term linear in (P, Y, L, G). Fixing G instead (G_jl = c Kbar_l,
//!   T unknown, c in 0.05 .. 0.9) certified nothing beyond the
//!   linear-region certificate on the pendulum; the free G_jl reach 25 deg
//!   there. The blend: G(h) = sum h_j h_l G_jl and Kbar(h) = sum h_j h_l
//!   Kbar_l, so the region holds for the blend by convexity, and every
//!   vertex condition is affine in G_jl. Tried when the linear-region
//!   certificate does not hold;
//! - the initial set with x_hat(0) = 0 (the generated code's `INIT`):
//!   xi_0 = (x0, 0) = E x0, E = [I; 0]: for a point 1 - xi_0' P xi_0 >= 0,
//!   for an ellipsoid {x0' R x0 <= 1}: R - E' P E >= 0 (P11 <= R).
//!
//! Every block is linear in P (and nu) and is built from the plan's gains,
//! so the certificate rebuilds it from the shipped F_l, also as stored.

use crate::synth::blocks::{nonstrict_psd, region_block, scalar_times_identity};
use crate::synth::design::TriggerPlan;
use crate::synth::trigger::Factor;
use nalgebra::DMatrix;
use tsf_lang::spec::{InitialSet, Objective, Spec, Target};
use tsf_lmi::{Expr, LmiError, Problem, Relation, Var};

/// The minimized nu = mu^2 / sigma^2 of the sampled loop's input bound.
pub const MU2_SAMPLED: &str = "mu2_sampled";

/// What the sampled observer loop imposes beyond its decay rate.
#[derive(Debug, Clone, PartialEq)]
pub struct SampledBounds {
    /// The controller rules r: the pair gains K_1l (l < r, observer rule 1)
    /// carry the u-rows [0, F_l].
    pub per_rule: usize,
    /// The inputs m (the first m rows of each pair gain).
    pub inputs: usize,
    /// The input bound: `Some(Some(mu))` fixed, `Some(None)` minimized.
    pub input: Option<Option<f64>>,
    /// sigma of a minimized bound (mu^2 = sigma^2 nu).
    pub scale: f64,
    /// Saturation levels u_s (empty: no actuator limit): E(P, 1) inside
    /// the linear region.
    pub levels: Vec<f64>,
    /// `Some(tau)`: the saturation certified ACTIVE with the known sector
    /// multiplier T = diag(tau / u_s^2) and unknown sector gains (the plan's
    /// `levels`, `sector_multiplier`, `dz_input`); `None`: the linear-region
    /// certificate.
    pub active: Option<f64>,
    /// The initial sets (in x, with x_hat(0) = 0) E(P, 1) must contain.
    pub initial: Vec<InitialSet>,
}

impl SampledBounds {
    /// The bounds of `spec` on the sampled loop with controller gains `f`
    /// (`None` without an input bound or saturation levels).
    pub fn of(spec: &Spec, f: &[DMatrix<f64>]) -> Option<Self> {
        let mut input = None;
        let mut initial: Vec<InitialSet> = Vec::new();
        let mut add = |set: &InitialSet| {
            if !initial.contains(set) {
                initial.push(set.clone());
            }
        };
        for o in &spec.objectives {
            match &o.node {
                Objective::InputNorm {
                    target,
                    initial: set,
                } => {
                    input = Some(match target {
                        Target::Fixed(mu) => Some(*mu),
                        Target::Optimize => None,
                    });
                    add(set);
                }
                Objective::SaturationRegion { contain: Some(set) } => add(set),
                _ => {}
            }
        }
        let levels = spec.saturation.clone().unwrap_or_default();
        if input.is_none() && levels.is_empty() {
            return None;
        }
        let n = spec.n();
        Some(SampledBounds {
            per_rule: f.len(),
            inputs: f.first().map_or(0, DMatrix::nrows),
            input,
            scale: super::bounded::initial_scale(initial.iter(), f, n),
            levels,
            active: None,
            initial,
        })
    }

    /// The same bounds with the input bound fixed at `mu`.
    pub fn fixed(&self, mu: f64) -> Self {
        SampledBounds {
            input: self.input.map(|_| Some(mu)),
            ..self.clone()
        }
    }

    /// The same bounds with the saturation certified active, the sector
    /// multiplier T = diag(tau / u_s^2).
    pub fn with_active(&self, tau: f64) -> Self {
        SampledBounds {
            active: Some(tau),
            ..self.clone()
        }
    }

    /// The certified input bound, when fixed.
    pub fn mu(&self) -> Option<f64> {
        self.input.flatten()
    }

    /// What is asked, in words (notes and errors).
    pub fn asked(&self) -> String {
        let mut parts = Vec::new();
        match self.input {
            Some(Some(mu)) => parts.push(format!("the input bound ||u|| <= {mu}")),
            Some(None) => parts.push("a minimized input bound".to_string()),
            None => {}
        }
        if !self.levels.is_empty() {
            parts.push(format!(
                "the actuator's linear region (saturate {:?})",
                self.levels
            ));
        }
        if !self.initial.is_empty() {
            parts.push("the initial set with x_hat(0) = 0".to_string());
        }
        parts.join(" and ")
    }
}

/// E = [I; 0] (2n x n): xi_0 = (x0, 0).
fn initial_map(n: usize) -> DMatrix<f64> {
    let mut e = DMatrix::zeros(2 * n, n);
    e.view_mut((0, 0), (n, n)).fill_with_identity();
    e
}

/// Imposes the plan's sampled-observer bounds on `p` (nonstrict, named
/// `observer sampled input norm [l]`, `observer sampled linear region [l,s]`,
/// `observer sampled initial set [k]`); returns nu when the input bound is
/// minimized (the caller minimizes it).
pub(in crate::synth) fn impose(
    problem: &mut Problem,
    nonstrict: &mut Vec<String>,
    plan: &TriggerPlan,
    p: Factor<'_>,
    eps: f64,
) -> Result<Option<Var>, LmiError> {
    let Some(b) = &plan.observer_bounds else {
        return Ok(None);
    };
    let m = b.inputs;
    let u_rows: Vec<DMatrix<f64>> = plan
        .gains
        .iter()
        .take(b.per_rule)
        .map(|k| k.rows(0, m).into_owned())
        .collect();
    let nu = match b.input {
        Some(None) => Some(problem.scalar(MU2_SAMPLED)?),
        _ => None,
    };
    if let Some(input) = b.input {
        let by = input.unwrap_or(b.scale);
        for (l, kbar) in u_rows.iter().enumerate() {
            let rhs = scalar_times_identity(nu, 1.0, m)?;
            let e = region_block(p.expr()?, Expr::constant(&(kbar / by))?, rhs)?;
            let name = format!("observer sampled input norm [{}]", l + 1);
            nonstrict_psd(problem, nonstrict, &name, e, eps)?;
        }
    }
    // Active saturation: the sector's region is the looped functional's.
    let linear = if b.active.is_some() {
        &[][..]
    } else {
        &b.levels[..]
    };
    for (l, kbar) in u_rows.iter().enumerate() {
        for (s, level) in linear.iter().enumerate() {
            let row = kbar.rows(s, 1) / *level;
            let e = region_block(p.expr()?, Expr::constant(&row)?, Expr::identity(1))?;
            let name = format!("observer sampled linear region [{},{}]", l + 1, s + 1);
            nonstrict_psd(problem, nonstrict, &name, e, eps)?;
        }
    }
    let n = plan.gains.first().map_or(0, DMatrix::ncols) / 2;
    let e = initial_map(n);
    for (k, set) in b.initial.iter().enumerate() {
        let block = match set {
            InitialSet::Point(x0) => {
                let xi0 = &e * DMatrix::from_column_slice(n, 1, x0);
                Expr::identity(1).sub(p.between(&xi0.transpose(), &xi0)?)?
            }
            InitialSet::Ellipsoid(r) => Expr::constant(r)?.sub(p.between(&e.transpose(), &e)?)?,
        };
        let name = format!("observer sampled initial set [{}]", k + 1);
        nonstrict_psd(problem, nonstrict, &name, block, eps)?;
    }
    if let Some(nu) = nu {
        problem.add_scalar("observer sampled nu >= 0", Expr::var(nu), Relation::Ge, 0.0)?;
    }
    Ok(nu)
}
