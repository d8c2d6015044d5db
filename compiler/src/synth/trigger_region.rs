//! The regions of the sampled-loop certificate ([`super::trigger`]): E(P, c)
//! inside the linear region of each controller vertex (with saturation
//! levels), inside the premise box and the drift route's faces, and around
//! each initial set; every one a nonstrict condition.

use super::blocks::{nonstrict_psd, region_block};
use super::design::TriggerPlan;
use super::observer::drift;
use super::trigger::{pick, Factor, LoopVars};
use crate::model::TsModel;
use nalgebra::DMatrix;
use tsf_lang::spec::InitialSet;
use tsf_lmi::{Expr, LmiError, Problem};

/// Imposes E(P, c) inside the linear region of each controller vertex of
/// `ctrl` (with saturation levels) and inside the premise box, and around
/// each initial set; every one a nonstrict condition, named in `nonstrict`.
pub(super) fn impose_regions(
    problem: &mut Problem,
    nonstrict: &mut Vec<String>,
    model: &TsModel,
    plan: &TriggerPlan,
    vars: &LoopVars<'_>,
    ctrl: &[(Factor<'_>, Factor<'_>)],
    eps: f64,
) -> Result<(), LmiError> {
    let n = model.n;
    let sector = !plan.levels.is_empty();
    let xi = vars.xi;
    // E(P, c) inside the linear region |(F_j - G_j)_s x| <= u_bar_s, c = plan.region_level():
    // [P, r'; r, u_bar_s^2 / c] >= 0, solved as [P, k r'; k r, 1] >= 0 with k = sqrt(c) / u_bar_s
    // (the congruence diag(I, k); entries of one size when the gains are large).
    // With a premise region and known gains the level is xi's own,
    // c = xi tau_bar^2 / phi (xi an unknown): P - xi (tau_bar^2 / (phi b^2)) r' r >= 0
    // is [P, r'; r, b^2 / c] >= 0 by a Schur complement, linear in (P, xi).
    let level = plan.region_level();
    let joint = joint_level(plan).zip(xi);
    let one = || Expr::constant(&DMatrix::identity(1, 1));
    let contain = |row: &DMatrix<f64>, bound: f64| -> Result<Expr, LmiError> {
        match joint {
            Some((per_xi, xi)) => vars.p.expr()?.sub(Expr::scaled(
                xi,
                &(row.transpose() * row * (per_xi / (bound * bound))),
            )?),
            None => region_block(
                vars.p.expr()?,
                Expr::constant(&(row * (level.sqrt() / bound)))?,
                one()?,
            ),
        }
    };
    for (j, (f, g)) in ctrl.iter().enumerate().filter(|_| sector) {
        for (s, ub) in plan.levels.iter().enumerate() {
            // Row s of the command (F's first rows) and of the sector gain.
            let (pick_f, pick_g) = (pick(1, s, model.m), pick(1, s, plan.levels.len()));
            let e = match (f, g, joint) {
                (Factor::Val(f), Factor::Val(g), Some(_)) => {
                    contain(&(&pick_f * *f - &pick_g * *g), *ub)?
                }
                _ => {
                    let row = f
                        .between(&pick_f, &DMatrix::identity(n, n))?
                        .sub(g.between(&pick_g, &DMatrix::identity(n, n))?)?
                        .scale(level.sqrt() / ub)?;
                    region_block(vars.p.expr()?, row, one()?)?
                }
            };
            nonstrict_psd(
                problem,
                nonstrict,
                &format!("trigger linear region [{},{}]", j + 1, s + 1),
                e,
                eps,
            )?;
        }
    }
    // E(P, c) inside the premise box |c_k x| <= b_k, the same block.
    for face in plan.region.iter().flat_map(|r| &r.faces) {
        let e = contain(&face.row, face.bound)?;
        nonstrict_psd(
            problem,
            nonstrict,
            &format!("trigger premise region {}", face.name),
            e,
            eps,
        )?;
    }
    drift::impose_faces(problem, nonstrict, plan, vars.p, eps)?;
    for (name, e) in &plan.contain {
        nonstrict_psd(
            problem,
            nonstrict,
            &format!("sampled region of attraction: {name}"),
            contain_block(vars.p, e)?,
            eps,
        )?;
    }
    Ok(())
}

/// With a premise region, the L-inf channel and no initial set, the level of
/// E(P, c) is xi's own, c = xi tau_bar^2 / phi: `Some(tau_bar^2 / phi)`, the
/// level per unit xi; `None`: the level is [`TriggerPlan::region_level`].
pub fn joint_level(plan: &TriggerPlan) -> Option<f64> {
    (plan.region.is_some() && plan.linf && plan.contain.is_empty())
        .then(|| crate::synth::objectives::reach_level(1.0, plan.tau_bar, plan.phi))
}

/// `E(P, 1)` contains the initial set: `1 - x0' P x0 >= 0` for a point,
/// `R - P >= 0` for the ellipsoid `x' R x <= 1`.
fn contain_block(p: Factor<'_>, set: &InitialSet) -> Result<Expr, LmiError> {
    match set {
        InitialSet::Point(x0) => {
            let x = DMatrix::from_column_slice(x0.len(), 1, x0);
            Expr::constant(&DMatrix::identity(1, 1))?.sub(p.between(&x.transpose(), &x)?)
        }
        InitialSet::Ellipsoid(r) => Expr::constant(r)?.sub(p.expr()?),
    }
}
