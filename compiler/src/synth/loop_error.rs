//! The model error in the sampled and event-triggered loops' blocks: the
//! looped functional of [`super::trigger`] made robust to ||A(x) - A_h(x)||
//! <= a, ||B(x) - B_h(x)|| <= b, ||D(x) - D_h(x)|| <= d on the region of the
//! plant claim (Petersen, "A stabilization algorithm for a class of uncertain
//! linear systems", 1987; the layout of Xu & Huang 2020 in
//! [`super::sampled`]).
//!
//! Derivation. The gains F_j (and sector gains G_j) are constants here (the
//! every-sample certificate and the trigger step of the two-step design), so
//! the loop's LMIs substitute the derivative: x' = Phi psi with
//! psi = [x(t); x(s); e; dz; tau] and, for the plant vertex i and controller
//! rule j, Phi = A_i E_x + B_i (F_j x(t_k) - E_dz) + D_i E_tau, x(t_k) = E_s - E_e
//! the state the controller holds. The plant the spec declares is
//! x' = A(x) x + B(x) sat(u) + D(x) tau, i.e. Phi + dA N_a + dB N_b + dD N_d with
//!
//!   N_a = E_x (x(t)),  N_b = F_j (E_s - E_e) - E_dz (the held, saturated input
//!   sat(u) = u - dz),  N_d = E_tau,
//!
//! and ||dA|| <= a, ||dB|| <= b, ||dD|| <= d wherever x(t) is in the region.
//! Phi enters Lambda_{ij r}(h) linearly once the r = 1 term h Phi' Y Phi is
//! written as its Schur complement [Xi, sqrt(h) Phi' Y; *, -Y] (Y > 0): in
//! He(E_x' P Phi) of Xi and in the (2,1) block sqrt(h) Y Phi. So the block is
//! M + sum_t He(G' Delta_t Ñ_t) with the left factor G' = [E_x' P; sqrt(h) Y]
//! (r = 1) or [E_x' P; 0] (r = 2, whose last block row is the Schur
//! complement of L e^{phi h_max} Y^-1 L') and Ñ_t = [N_t, 0] (zero on the
//! Schur rows). For every ||Delta_t|| <= a_t and eps_t > 0,
//! He(G' Delta_t Ñ_t) <= eps_t^-1 G' G + eps_t a_t^2 Ñ_t' Ñ_t, so the block is
//! negative definite for every admissible error when, by a Schur complement,
//!
//!   [ M + sum_t eps_t a_t^2 Ñ_t' Ñ_t   G'        G'       .. ]
//!   [ *                                -eps_a I  0        .. ]  < 0,
//!   [ *                                *         -eps_b I .. ]
//!
//! linear in (P, Y, L, Upsilon, T, eps_t) because G' is linear in P, Y and
//! Ñ_t is data (F_j known). One column per nonzero term, one multiplier per
//! term and per r, shared by every pair and interval (so the reductions of the
//! nominal problem stay valid: for fixed multipliers the block is affine in
//! (A_i, B_i, D_i), and after the congruence diag(I, h^-1/2 I, I) it depends
//! on h only through -Y / h, so h_max implies h_min). With a = b = d = 0 no
//! column is added and the nominal block is built, bit for bit.
//!
//! The premise vertices of a regional certificate enclose the blend A_h(x)
//! at every state of the premise box; the true A(x) = A_h(x) + dA(x) then
//! lies in the vertices' hull plus the ball the multipliers cover, wherever
//! the bound holds (the plant claim keeps E(P, c) inside its region).

use super::trigger::{LoopVars, TriggerPlan};
use nalgebra::DMatrix;
use tsf_lmi::{Expr, LmiError, Problem, Var};

/// The bounds of the model error the loop's blocks carry (all 0: the nominal
/// blocks).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct LoopError {
    /// Bound of ||A(x) - A_h(x)||.
    pub a: f64,
    /// Bound of ||B(x) - B_h(x)||.
    pub b: f64,
    /// Bound of ||D(x) - D_h(x)|| (0 when D is not state-dependent).
    pub d: f64,
}

/// The multipliers of one r (Lambda_1 or Lambda_2): of dA, dB, dD.
pub type LoopMultipliers = [Option<Var>; 3];

impl LoopError {
    /// The model's error bound (zero without one).
    pub fn of(model: &crate::model::TsModel) -> Self {
        model
            .plant_error
            .as_ref()
            .map_or_else(Self::default, |e| LoopError {
                a: e.a,
                b: e.b,
                d: e.d.unwrap_or(0.0),
            })
    }

    /// Whether every bound is 0 (the nominal blocks).
    pub fn is_zero(&self) -> bool {
        self.a == 0.0 && self.b == 0.0 && self.d == 0.0
    }

    /// Declares the multipliers of the nonzero terms for Lambda_r, named
    /// `trigger robust r={r} eps_a` (`_b`, `_d`).
    pub fn declare(&self, problem: &mut Problem, r: u8) -> Result<LoopMultipliers, LmiError> {
        let mut one = |bound: f64, tag: &str| -> Result<Option<Var>, LmiError> {
            match bound > 0.0 {
                true => problem
                    .scalar(&format!("trigger robust r={r} eps_{tag}"))
                    .map(Some),
                false => Ok(None),
            }
        };
        Ok([one(self.a, "a")?, one(self.b, "b")?, one(self.d, "d")?])
    }
}

/// `block` (K x K) made robust to the terms He(G' Delta_t Ñ_t) with
/// `left` = G' (K x n) and `right[t]` = Ñ_t (w_t x K, `None` when the loop has
/// no such signal): [[block + sum eps_t a_t^2 Ñ_t' Ñ_t, G', ..], [*, -eps_t I]]
/// for each term with a nonzero bound and a multiplier.
pub fn robust_block(
    block: Expr,
    left: Expr,
    right: [Option<DMatrix<f64>>; 3],
    eps: &LoopMultipliers,
    err: &LoopError,
) -> Result<Expr, LmiError> {
    let n = left.shape().1;
    let bounds = [err.a, err.b, err.d];
    let mut top = block;
    let mut columns = 0;
    for ((nt, e), bound) in right.iter().zip(eps).zip(bounds) {
        if let (Some(nt), Some(e), true) = (nt, e, bound > 0.0) {
            top = top.add(Expr::scaled(*e, &(nt.transpose() * nt * (bound * bound)))?)?;
            columns += 1;
        }
    }
    if columns == 0 {
        return Ok(top);
    }
    let size = columns + 1;
    let mut grid: Vec<Vec<Option<Expr>>> = vec![vec![None; size]];
    grid[0][0] = Some(top);
    let mut c = 0;
    for ((nt, e), bound) in right.iter().zip(eps).zip(bounds) {
        if let (Some(_), Some(e), true) = (nt, e, bound > 0.0) {
            c += 1;
            grid[0][c] = Some(left.clone());
            let mut row = vec![None; size];
            row[c] = Some(Expr::scaled(*e, &(-DMatrix::identity(n, n)))?);
            grid.push(row);
        }
    }
    Expr::sym_blocks(grid)
}

/// What the model-error terms of one pair read ([`robust_lambda`]).
pub(super) struct Selectors<'m> {
    /// E_x: x(t) in psi.
    pub(super) ex: &'m DMatrix<f64>,
    /// Phi of the pair (x' = Phi psi for the blend).
    pub(super) phi: DMatrix<f64>,
    /// N_b = F_j x(t_k) - E_dz: the held, saturated input sat(u).
    pub(super) sat_u: DMatrix<f64>,
    /// N_d = E_tau, with the L-inf channel.
    pub(super) tau: Option<DMatrix<f64>>,
}

/// Lambda_{ij r}(h) with the model error ([`super::loop_error`]): `top` is
/// the block with the r = 1 term as its Schur complement [Xi, sqrt(h) Phi' Y;
/// *, -Y] (r = 2: as in the nominal Lambda_2), both of size k + n; one column G' per
/// uncertain term with G' = [E_x' P; sqrt(h) Y] (r = 1) or [E_x' P; 0]
/// (r = 2) and Ñ_t = [N_t, 0]: N_a = E_x, N_b = F_j x(t_k) - E_dz, N_d = E_tau.
pub(super) fn robust_lambda(
    plan: &TriggerPlan,
    v: &LoopVars<'_>,
    top: Expr,
    sel: &Selectors<'_>,
    h: f64,
    r: u8,
) -> Result<Expr, LmiError> {
    let (n, k) = sel.ex.shape();
    let id_n = DMatrix::identity(n, n);
    let lower = match r {
        1 => v.y.expr()?.scale(h.sqrt())?,
        _ => Expr::zeros(n, n),
    };
    let left = Expr::blocks(vec![
        vec![Some(v.p.between(&sel.ex.transpose(), &id_n)?)],
        vec![Some(lower)],
    ])?;
    let pad = |nt: &DMatrix<f64>| -> DMatrix<f64> {
        let mut full = DMatrix::zeros(nt.nrows(), k + n);
        full.columns_mut(0, k).copy_from(nt);
        full
    };
    let right = [
        Some(pad(sel.ex)),
        Some(pad(&sel.sat_u)),
        sel.tau.as_ref().map(pad),
    ];
    robust_block(
        top,
        left,
        right,
        &v.robust[usize::from(r - 1)],
        &plan.model_error,
    )
}
