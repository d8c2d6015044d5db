//! The sampled observer certificate on a region: the membership drift
//! bounded instead of free plant/observer vertices (issue 36).
//!
//! Free vertices ([`super::sampled`]) let the plant's rule i (memberships at
//! t) differ from the observer's rule j (memberships at t_k) for the whole
//! period, so every frozen loop (i, j, l) must be stable; with the textbook
//! pendulum's rules at 88 deg the loops i != j are not, at any period. With
//! measured premises the plant's and the observer's memberships differ only
//! by their drift within the period. Write h_i(t) = h_i(t_k) + delta_i(t),
//! sum_i delta_i = 0. The loop of [`super::sampled`] becomes
//!
//! ```text
//! xi'(t) = sum_{j,l} h_j(t_k) h_l(t_k) (Abar_j xi(t) + Bbar_j K_jl xi(t_k))
//!        + sum_i delta_i(t) (Abar_i xi(t) + Bbar_i v_k),
//! ```
//!
//! v_k = (u_k, xhat') the held input of the augmented loop (only u_k meets
//! B_i: Bbar_i = diag(B_i, I) and sum_i delta_i I = 0), because
//! sum_i h_i(t_k) A_i = sum_{j,l} h_j(t_k) h_l(t_k) A_j and likewise for
//! B_i u_k, u_k = sum_l h_l(t_k) F_l xhat_k (the controller's memberships
//! are those of t_k, as in the free design). With sum_i delta_i = 0 the
//! drift term is the sum over t >= 2 of delta_t ((Abar_t - Abar_1) xi(t) +
//! (Bbar_t - Bbar_1) v_k): one scalar uncertainty per rule t >= 2,
//! |delta_t| <= delta_t^max, with fixed directions ([`ScalarTerm`]). So the
//! vertices are (plant j, (observer j, controller l)) only (plant and
//! observer on the same rule, as in the continuous design), with the plant
//! moved by the drift: each condition is affine in the plant data (the r = 1
//! term h Phi' Y Phi convex), so imposing it at the 2^(r-1) corners of the
//! drift box covers every delta in it exactly (a polytope, not a norm bound:
//! no Petersen multiplier, no conservatism from it), and the basic relaxation
//! of the double sum over (j, l) covers every blend h_j(t_k) h_l(t_k)
//! ([`impose_pairs`]).
//!
//! The bound delta_t^max holds while x stays in the region R
//! ([`crate::model::region::drift`]): x(t_k) in the sample box R' and
//! |u_k| <= U keep x(t) in R for the period (u_k the command the PLANT
//! gets; the observer's flow does not move the memberships, which read the
//! measured x; with the saturation certified active U is the actuator's
//! level, which the applied sat(u_k) never exceeds, and the face below is
//! not needed: [`Drift::by_actuator`]). The certificate imposes
//! E(P, 1) inside R' (x part of xi) and inside |F_l xhat| <= U (every l), and
//! the looped functional gives xi(t_k)' P xi(t_k) = V(t_k) <= V(t_0) (the
//! looped terms vanish at the samples). By induction over k, from xi(0) in
//! E(P, 1): xi(t_k) in E(P, 1), so x(t_k) in R', |u_k| <= U, x(t) in R on
//! the period, |delta_t| <= delta_t^max, the robust LMIs hold along the
//! period, V decreases, xi(t_{k+1}) in E(P, 1). The claim is regional: for
//! (x(0), xhat(0)) in E(P, 1).

use crate::model::region::drift::DriftBound;
use crate::model::region::Face;
use crate::model::TsModel;
use crate::synth::blocks::{nonstrict_psd, region_block};
use crate::synth::design::TriggerPlan;
use crate::synth::trigger::Factor;
use crate::synth::vertices::PlantVertex;
use nalgebra::DMatrix;
use tsf_lmi::{Expr, LmiError, Problem};

/// One drift term: delta (A_t x(t) + B_t v_k) with |delta| <= `bound`, v_k
/// the held input (u_k, xhat') of the augmented loop.
#[derive(Debug, Clone, PartialEq)]
pub struct ScalarTerm {
    /// The bound of |delta|: delta_t^max.
    pub bound: f64,
    /// diag(A_t - A_1, 0) (2n x 2n).
    pub a: DMatrix<f64>,
    /// [B_t - B_1, 0; 0, 0] (2n x (m + n)).
    pub b: DMatrix<f64>,
}

/// The drift data of a sampled observer plan.
#[derive(Debug, Clone, PartialEq)]
pub struct Drift {
    /// Controller vertices per observer rule: vertex q (pair_gains order,
    /// observer rule outer) is blended by observer rule q / per_rule and
    /// imposed only with plant vertex q / per_rule ([`impose_pairs`]).
    pub per_rule: usize,
    /// The drift terms, one per rule t >= 2.
    pub terms: Vec<ScalarTerm>,
    /// E(P, 1) inside these faces of xi (the sample box R').
    pub faces: Vec<Face>,
    /// |(K_q xi)_s| <= input_bound for the first `inputs` rows of the gains
    /// of observer rule 1 (K_1l's rows u = F_l xhat, every l).
    pub inputs: usize,
    /// U.
    pub input_bound: f64,
    /// U is the actuator's saturation level (the largest): the command the
    /// plant gets is clipped to it, so |sat(u_k)_s| <= U holds without
    /// keeping E(P, 1) inside |F_l xhat| <= U (no `observer drift input`
    /// faces; the active-saturation certificate of
    /// [`super::sampled_bounds`]).
    pub by_actuator: bool,
    /// The bound the terms come from (for the report).
    pub bound: DriftBound,
}

impl Drift {
    /// The drift data of `model` (the plant's n, m, rules) with `bound`:
    /// terms (diag(A_t - A_1, 0), [B_t - B_1, 0; 0, 0]) for the augmented
    /// state (x, xhat) and input (u, xhat'), faces |x_s| <= b_s of R'.
    pub fn of(model: &TsModel, bound: DriftBound) -> Self {
        let (n, m) = (model.n, model.m);
        let first = &model.rules[0];
        let terms = model.rules[1..]
            .iter()
            .zip(&bound.delta[1..])
            .map(|(rule, delta)| {
                let mut a = DMatrix::zeros(2 * n, 2 * n);
                a.view_mut((0, 0), (n, n)).copy_from(&(&rule.a - &first.a));
                let mut b = DMatrix::zeros(2 * n, m + n);
                b.view_mut((0, 0), (n, m)).copy_from(&(&rule.b - &first.b));
                ScalarTerm {
                    bound: *delta,
                    a,
                    b,
                }
            })
            .collect();
        let names = tsf_lang::spec::Signal::names_of(&model.spec.states);
        let faces = bound
            .samples
            .iter()
            .enumerate()
            .map(|(s, (lo, hi))| Face {
                name: names
                    .get(s)
                    .cloned()
                    .unwrap_or_else(|| format!("x{}", s + 1)),
                row: DMatrix::from_fn(1, 2 * n, |_, c| if c == s { 1.0 } else { 0.0 }),
                bound: (-lo).min(*hi),
            })
            .collect();
        Drift {
            per_rule: model.r(),
            terms,
            faces,
            inputs: m,
            input_bound: bound.input_bound,
            by_actuator: false,
            bound,
        }
    }
}

/// The corners of the drift box: every sign pattern of the terms' bounds
/// (2^terms corners, each a vector of delta_t).
fn corners(terms: &[ScalarTerm]) -> Vec<Vec<f64>> {
    (0..1usize << terms.len())
        .map(|mask| {
            terms
                .iter()
                .enumerate()
                .map(|(t, term)| {
                    if mask >> t & 1 == 1 {
                        term.bound
                    } else {
                        -term.bound
                    }
                })
                .collect()
        })
        .collect()
}

/// Plant vertex `pv` moved by the drift `delta`: (A + sum delta_t A_t,
/// B + sum delta_t B_t).
fn drifted(pv: &PlantVertex, terms: &[ScalarTerm], delta: &[f64]) -> PlantVertex {
    let mut out = pv.clone();
    for (term, d) in terms.iter().zip(delta) {
        out.a += &term.a * *d;
        out.b += &term.b * *d;
    }
    out
}

/// Imposes the paired vertex conditions of one (r, h): for every corner v of
/// the drift box and with Lambda_jl(v) = `lambda(plant j drifted by v, q)`,
/// q = (j, l) the controller vertex, the basic relaxation of the double sum
/// (Tanaka & Wang 2001, Theorem 2.2): Lambda_jj(v) < 0 and
/// Lambda_jl(v) + Lambda_lj(v) < 0 (j < l), named `{prefix} D[j,l] v{v}`.
/// Sufficient: at time t the loop's block is
/// sum_{j,l} h_j(t_k) h_l(t_k) Lambda_jl(delta(t)) with the weights
/// symmetric, and each Lambda_jl is affine in the plant data (the r = 1 term
/// h Phi' Y Phi convex), so convex in delta: the corners bound the box.
pub(in crate::synth) fn impose_pairs(
    problem: &mut Problem,
    drift: &Drift,
    plant: &[PlantVertex],
    prefix: &str,
    eps: f64,
    mut lambda: impl FnMut(&PlantVertex, usize) -> Result<Expr, LmiError>,
) -> Result<(), LmiError> {
    let r = drift.per_rule;
    for (v, delta) in corners(&drift.terms).iter().enumerate() {
        let moved: Vec<PlantVertex> = plant
            .iter()
            .map(|pv| drifted(pv, &drift.terms, delta))
            .collect();
        for j in 0..r {
            for l in j..r {
                let mut e = lambda(&moved[j], j * r + l)?;
                if l != j {
                    e = e.add(lambda(&moved[l], l * r + j)?)?;
                }
                let name = format!("{prefix} D[{},{}] v{}", j + 1, l + 1, v + 1);
                problem.nsd(&name, e, eps)?;
            }
        }
    }
    Ok(())
}

/// Imposes E(P, 1) inside the drift's sample box and input bound (nonstrict,
/// named `observer drift region <state>` and `observer drift input [q,s]`).
pub(in crate::synth) fn impose_faces(
    problem: &mut Problem,
    nonstrict: &mut Vec<String>,
    plan: &TriggerPlan,
    p: Factor<'_>,
    eps: f64,
) -> Result<(), LmiError> {
    let Some(d) = &plan.drift else {
        return Ok(());
    };
    let one = || Expr::constant(&DMatrix::identity(1, 1));
    for f in &d.faces {
        let e = region_block(p.expr()?, Expr::constant(&(&f.row / f.bound))?, one()?)?;
        nonstrict_psd(
            problem,
            nonstrict,
            &format!("observer drift region {}", f.name),
            e,
            eps,
        )?;
    }
    if d.input_bound.is_finite() && !d.by_actuator {
        for (q, k) in plan.gains.iter().enumerate().take(d.per_rule) {
            for s in 0..d.inputs {
                let row = k.rows(s, 1) / d.input_bound;
                let e = region_block(p.expr()?, Expr::constant(&row)?, one()?)?;
                let name = format!("observer drift input [{},{}]", q + 1, s + 1);
                nonstrict_psd(problem, nonstrict, &name, e, eps)?;
            }
        }
    }
    Ok(())
}
