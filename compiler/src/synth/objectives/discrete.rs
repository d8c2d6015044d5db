//! The discrete-time design route of a periodic loop
//! (`trigger periodic { every = h; design = discrete; }`): the stability and
//! decay-rate conditions are written for the exact zero-order-hold
//! discretization of each local model,
//!
//!   [A_di, B_di; 0, I] = exp([A_i, B_i; 0, 0] h)   (Van Loan),
//!
//! and the discrete PDC loop x_{k+1} = sum_ij h_i h_j (A_di + B_di F_j) x_k.
//! V = x' P x contracts by rho^2 = e^{-2 alpha h} per period when
//! G(h)' P G(h) - rho^2 P < 0, G(h) = sum_ij h_i h_j G_ij; with X = P^{-1},
//! M_j = F_j X and a Schur complement this is
//!
//!   sum_ij h_i h_j [[rho^2 X, (A_di X + B_di M_j)'], [*, X]] > 0,
//!
//! a double sum of affine blocks (the diagonal blocks carry sum_ij h_i h_j = 1),
//! so every relaxation of the spec applies to Q_ij = -[[rho^2 X, ..]] < 0
//! (Tanaka, Ikeda and Wang, "Fuzzy regulators and fuzzy observers: relaxed
//! stability conditions and LMI-based designs", IEEE TFS 1998).
//!
//! What this certifies is the discretized T-S model, a design model: the
//! shipped loop (continuous plant, command held for h) is certified
//! separately by the sampled-loop certificate (`synth/sampling.rs`), which
//! every periodic design must pass. Pair conditions are never dropped for a
//! common B: B_di = int_0^h e^{A_i s} ds B differs between rules.

use crate::model::TsModel;
use crate::synth::objective::Ctx;
use crate::synth::relaxation::Family;
use nalgebra::DMatrix;
use tsf_lang::spec::{PeriodicDesign, Trigger};
use tsf_lmi::Expr;

/// The period when the spec asks for the discrete-time design route.
pub fn period(model: &TsModel) -> Option<f64> {
    let spec = &model.spec;
    match (spec.periodic_design.as_ref().map(|d| d.node), spec.trigger.as_ref().map(|t| &t.node)) {
        (Some(PeriodicDesign::Discrete), Some(Trigger::Periodic { every })) => Some(*every),
        _ => None,
    }
}

/// The exact zero-order-hold discretization (A_d, B_d) of (A, B) over `h`.
pub fn zoh(a: &DMatrix<f64>, b: &DMatrix<f64>, h: f64) -> (DMatrix<f64>, DMatrix<f64>) {
    let (n, m) = (a.nrows(), b.ncols());
    let mut big = DMatrix::zeros(n + m, n + m);
    big.view_mut((0, 0), (n, n)).copy_from(&(a * h));
    big.view_mut((0, n), (n, m)).copy_from(&(b * h));
    let e = big.exp();
    (e.view((0, 0), (n, n)).into_owned(), e.view((0, n), (n, m)).into_owned())
}

/// The family Q_ij = -[[rho^2 X, (A_di X + B_di M_j)'], [*, X]] (< 0) with
/// rho = e^{-alpha h}.
pub fn family<'a>(ctx: &'a Ctx<'a>, h: f64, alpha: f64, name: &str) -> Family<'a> {
    let n = ctx.model.n;
    let discrete: Vec<(DMatrix<f64>, DMatrix<f64>)> =
        ctx.model.rules.iter().map(|r| zoh(&r.a, &r.b, h)).collect();
    let rho2 = (-2.0 * alpha * h).exp();
    Family {
        name: format!("{name} (discrete, h = {h})"),
        q: Box::new(move |i, j| {
            let (ad, bd) = &discrete[i];
            let g = Expr::product(ad, ctx.x, &DMatrix::identity(n, n))?
                .add(ctx.m[j].times(bd, ctx.x, n)?)?;
            Expr::sym_blocks(vec![
                vec![Some(Expr::var(ctx.x).scale(rho2)?), Some(g.transpose())],
                vec![None, Some(Expr::var(ctx.x))],
            ])?
            .scale(-1.0)
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Closed forms: a double integrator, and a scalar x' = a x + b u.
    #[test]
    fn zoh_matches_closed_forms() {
        let (h, a, b) = (0.3, -2.0, 1.5);
        let (ad, bd) = zoh(&DMatrix::from_element(1, 1, a), &DMatrix::from_element(1, 1, b), h);
        assert!((ad[(0, 0)] - (a * h).exp()).abs() < 1e-14);
        assert!((bd[(0, 0)] - b * ((a * h).exp() - 1.0) / a).abs() < 1e-14);
        let a2 = DMatrix::from_row_slice(2, 2, &[0.0, 1.0, 0.0, 0.0]);
        let b2 = DMatrix::from_row_slice(2, 1, &[0.0, 1.0]);
        let (ad, bd) = zoh(&a2, &b2, h);
        assert!((ad - DMatrix::from_row_slice(2, 2, &[1.0, h, 0.0, 1.0])).amax() < 1e-14);
        assert!((bd - DMatrix::from_row_slice(2, 1, &[h * h / 2.0, h])).amax() < 1e-14);
    }
}
