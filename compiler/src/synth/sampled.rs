//! The block layout shared by the sampled-data / event-triggered LMIs (Xu &
//! Huang 2020, Theorem 1 (18) and its congruent form Theorem 2 (38)).
//!
//! Augmented vector psi = [x(t); x'(t); x(s); e(s); dz(u); tau(t)] with
//! s = t_k^l the latest sampling instant, e(s) = x(s) - x(t_k) the sampled
//! error and dz(u) = u - sat(u) the dead zone. The blocks come from
//! - V1 = x' U x: `2 x' U x'` and `phi x' U x`,
//! - the descriptor identity 2 [x' Q1 + x'' Q2 + x(s)' Q3] (A x + B F (x(s) - e) - B dz + D tau - x') = 0,
//! - the free-matrix bound of the looped term: 2 [x; x(s)]' L (x - x(s)) with L = [L1; L2],
//! - the event condition nu (x(s) - e)' W (x(s) - e) - e' W e >= 0 (S-procedure),
//! - the sector condition -2 dz' T dz + 2 dz' T G x(t_k) >= 0,
//! - -xi tau' tau,
//!
//! then Lambda_1(h) = Xi + h R1' Y R1 and Lambda_2(h) = Xi + h R2' L e^{phi h_max} Y^{-1} L' R2,
//! the latter by a Schur complement (one more block row and column:
//! [Xi, sqrt(h) R2' L; *, -e^{-phi h_max} Y]).
//!
//! The layout serves the congruent form of Theorem 2 (variables Q-hat, F-hat_j;
//! the caller supplies the products "Q_k times a model matrix" as expressions).
//! The two-step trigger design (`trigger.rs`) has constant gains and substitutes
//! x' instead (smaller LMIs, no Q_k).

use tsf_lmi::{Expr, LmiError};

/// The products entering the descriptor blocks for one pair (i, j), in the
/// primal naming: `q[k] = Q_k`, `qa[k] = Q_k A_i`, `qbf[k] = Q_k B_i F_j`,
/// `qb[k] = Q_k B_i`, `qd[k] = Q_k D_i` (k = 0, 1, 2 for Q1, Q2, Q3).
pub(super) struct Terms {
    /// Q_k (n x n).
    pub q: [Expr; 3],
    /// Q_k A_i (n x n).
    pub qa: [Expr; 3],
    /// Q_k B_i F_j (n x n).
    pub qbf: [Expr; 3],
    /// Q_k B_i (n x m) (times the sector scaling in a congruent form).
    pub qb: [Expr; 3],
    /// Q_k D_i (n x q).
    pub qd: [Expr; 3],
    /// U of V1 = x' U x (n x n).
    pub u: Expr,
    /// Y of the looped functional (n x n).
    pub y: Expr,
    /// L1, L2 (n x n each).
    pub l: [Expr; 2],
    /// Trigger weight W (n x n).
    pub w: Expr,
    /// Sector cross term added to block (3,5) (n x m), e.g. (T G_j)'.
    pub s35: Expr,
    /// Sector cross term of block (4,5) (n x m), if any.
    pub s45: Option<Expr>,
    /// Block (5,5) (m x m), e.g. -2 T.
    pub s55: Expr,
    /// xi I (q x q).
    pub xi: Expr,
}

/// Reading of the (1,2) block: the derivation gives U - Q1 + A' Q2'; the
/// paper prints -Q1 + A' Q2' - L1 + L2' (no U, the L-terms of block (1,3)
/// repeated).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Block12 {
    /// From the derivation: U - Q1 + A' Q2'.
    Derived,
    /// As printed in (18) and (38).
    Printed,
}

/// Parameters of one vertex of the sampled-data condition.
#[derive(Debug, Clone, Copy)]
pub(super) struct Vertex {
    /// phi of V' + phi V - xi tau' tau < 0.
    pub phi: f64,
    /// Threshold nu of the event condition.
    pub nu: f64,
    /// Sampling interval h of this vertex.
    pub h: f64,
    /// h_max (in e^{phi h_max}).
    pub h_max: f64,
    /// r = 1 (Lambda_1) or r = 2 (Lambda_2, with the Schur complement).
    pub r: u8,
    /// Reading of block (1,2).
    pub block12: Block12,
}

fn neg(e: Expr) -> Result<Expr, LmiError> {
    e.scale(-1.0)
}

/// Lambda_{ij r}(h) of the layout above, as one symmetric block expression
/// (size 4n + m + q, plus n for r = 2).
pub(super) fn lambda(t: Terms, v: Vertex) -> Result<Expr, LmiError> {
    let Terms {
        q: [q1, q2, q3],
        qa: [qa1, qa2, qa3],
        qbf: [qbf1, qbf2, qbf3],
        qb: [qb1, qb2, qb3],
        qd: [qd1, qd2, qd3],
        u,
        y,
        l: [l1, l2],
        w,
        s35,
        s45,
        s55,
        xi,
    } = t;
    let l_cross = neg(l1.clone())?.add(l2.clone().transpose())?;
    let b11 = qa1
        .he()?
        .add(u.clone().scale(v.phi)?)?
        .add(l1.clone().he()?)?;
    let b12 = neg(q1)?.add(qa2.transpose())?;
    let b12 = match v.block12 {
        Block12::Derived => b12.add(u)?,
        Block12::Printed => b12.add(l_cross.clone())?,
    };
    let b13 = qbf1.clone().add(qa3.transpose())?.add(l_cross)?;
    let mut b22 = neg(q2.he()?)?;
    if v.r == 1 {
        b22 = b22.add(y.clone().scale(v.h)?)?;
    }
    let b23 = qbf2.clone().sub(q3.transpose())?;
    let b33 = qbf3
        .clone()
        .he()?
        .sub(l2.clone().he()?)?
        .add(w.clone().scale(v.nu)?)?;
    let b34 = neg(qbf3)?.sub(w.clone().scale(v.nu)?)?;
    let b35 = neg(qb3)?.add(s35)?;
    let b44 = w.scale(v.nu - 1.0)?;
    let mut grid = vec![
        vec![
            Some(b11),
            Some(b12),
            Some(b13),
            Some(neg(qbf1)?),
            Some(neg(qb1)?),
            Some(qd1),
        ],
        vec![
            None,
            Some(b22),
            Some(b23),
            Some(neg(qbf2)?),
            Some(neg(qb2)?),
            Some(qd2),
        ],
        vec![None, None, Some(b33), Some(b34), Some(b35), Some(qd3)],
        vec![None, None, None, Some(b44), s45, None],
        vec![None, None, None, None, Some(s55), None],
        vec![None, None, None, None, None, Some(neg(xi)?)],
    ];
    if v.r == 2 {
        // Schur complement of h R2' L e^{phi h_max} Y^{-1} L' R2.
        let root = v.h.sqrt();
        let col = [
            Some(l1.scale(root)?),
            None,
            Some(l2.scale(root)?),
            None,
            None,
            None,
        ];
        for (row, c) in grid.iter_mut().zip(col) {
            row.push(c);
        }
        let mut last = vec![None; 6];
        last.push(Some(neg(y)?.scale((-v.phi * v.h_max).exp())?));
        grid.push(last);
    }
    Expr::sym_blocks(grid)
}
