//! The scaling of the trigger step's Lyapunov unknowns (the SDP is solved
//! for P = sigma P~ and the values mapped back; [`super::trigger`]).

use super::design::TriggerPlan;
use super::solved::names;
use super::trigger::joint_level;
use nalgebra::DMatrix;

/// How [`super::search::Runner::solve_looped`] runs the solver on a looped-functional SDP.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct LoopedSolve {
    /// Floor of the duality-gap tolerances (relative and absolute), if any.
    pub gap_tol: Option<f64>,
    /// The problem was rescaled by tsfc ([`lyapunov_scale`] > 1,
    /// [`scaled_plan`]): Clarabel's equilibration (Ruiz scaling) is turned
    /// off, as it only costs iterations on top of that scaling (Xu & Huang
    /// two-step: 32 -> 21); when that run does not solve, the SDP is solved
    /// again with it (a saturated arm spec of tests/tests/event_trigger.rs
    /// certifies nu = 0.0125 only so). Unscaled problems (premise regions, where the
    /// level is xi's own; plain sampled loops; the sampled observer loop)
    /// keep it, with the solver's unscaled retry: without it the same
    /// regional trigger SDP stopped "Solved" up to 19 % above a gamma the
    /// equilibrated run certified (docs/limits.md, "solver scaling").
    pub rescaled: bool,
}

/// Largest scale [`lyapunov_scale`] returns.
const MAX_LYAPUNOV_SCALE: f64 = 1e12;

/// The scale sigma >= 1 of the trigger step's Lyapunov unknowns: the linear
/// region forces P >= (c / u_bar_s^2) r' r for every row r = (F_j - G_j)_s
/// (c the region level), so with large gains P, Y, L1, L2, Upsilon, T are of
/// that size while xi and gamma stay near 1; the SDP is then badly scaled and
/// the solver crawls. 1 without a linear region or with initial sets.
pub fn lyapunov_scale(plan: &TriggerPlan) -> f64 {
    if !plan.contain.is_empty() || joint_level(plan).is_some() {
        return 1.0;
    }
    let level = plan.region_level();
    let mut sigma = 1.0f64;
    for (f, g) in plan.gains.iter().zip(&plan.sector) {
        for (s, ub) in plan.levels.iter().enumerate() {
            let row = (f - g).row(s).norm_squared();
            sigma = sigma.max(level * row / (ub * ub));
        }
    }
    if sigma.is_finite() {
        sigma.min(MAX_LYAPUNOV_SCALE)
    } else {
        1.0
    }
}

/// The trigger problem for P = sigma P~ (and Y, L1, L2, Upsilon, T alike; xi
/// and gamma unchanged), exact: Lambda_{ij r}(h) of `plan` equals, by the
/// congruence diag(sqrt(sigma) I, I_tau, sqrt(sigma) I), sigma times that of
/// the returned plan with the disturbance columns D_i scaled by sqrt(sigma);
/// the region LMI [P, r'; r, u_bar^2 / c] is [P~, r'; r, sigma u_bar^2 / c]
/// by diag(sigma^-1/2, sigma^1/2), so u_bar is scaled by sqrt(sigma); the peak
/// LMI [phi P, 0, C'; *, (gamma - xi) I, G'; *, *, gamma I] takes C / sqrt(sigma)
/// by diag(sigma^-1/2 I, I, I). Each congruence maps a margin eps of the scaled
/// problem to a margin of at least eps (sigma >= 1), and the certificate
/// re-checks the unscaled values against `plan` anyway. Initial sets are not
/// scaled ([`lyapunov_scale`] is 1 with them).
pub fn scaled_plan(plan: &TriggerPlan, sigma: f64) -> TriggerPlan {
    if sigma == 1.0 {
        return plan.clone();
    }
    let root = sigma.sqrt();
    TriggerPlan {
        d: plan.d.iter().map(|d| d * root).collect(),
        model_error: super::loop_error::LoopError {
            d: plan.model_error.d * root,
            ..plan.model_error
        },
        levels: plan.levels.iter().map(|u| u * root).collect(),
        c: &plan.c / root,
        region: plan.region.as_ref().map(|r| {
            let mut r = r.clone();
            r.faces.iter_mut().for_each(|f| f.bound *= root);
            r
        }),
        ..plan.clone()
    }
}

/// The values of a problem solved for [`scaled_plan`] in the units of the
/// original plan: every unknown but gamma and xi times sigma.
pub(super) fn unscale_values(values: &mut [(String, DMatrix<f64>)], sigma: f64) {
    for (name, v) in values.iter_mut() {
        if name != names::LOOP_GAMMA && name != names::LOOP_XI {
            *v *= sigma;
        }
    }
}
