//! The checked `adaptive { ... }` block: a model-reference adaptive T-S
//! controller (Wang, Gao & He 2013, generalized to several inputs as in
//! `docs/adaptive.md`). The matched error signal `s = C x` has one component
//! per input; a reference model `s_m' = A_m s_m + B_m r` with `B_m = -A_m`
//! (unit DC gain) defines the tracking error `eps = s - s_m`, and the per-rule
//! estimates are adapted along `P eps` with `A_m' P + P A_m = -Q`.

use crate::ast::Expr;
use crate::eval::Mat;
use crate::span::Span;
use crate::spec::Convergence;

/// An adapted quantity with its adaptation rate and projection box.
#[derive(Debug, Clone, PartialEq)]
pub struct Estimate {
    /// Adaptation rate (> 0).
    pub rate: f64,
    /// Lower projection bound (every component).
    pub lo: f64,
    /// Upper projection bound (every component).
    pub hi: f64,
    /// Initial value of every component; `None`: the design model's value.
    pub init: Option<f64>,
    /// The statement.
    pub span: Span,
}

/// The robust term `w_k = d_hat sat((P eps)_k / layer)` and its bound estimate.
#[derive(Debug, Clone, PartialEq)]
pub struct Robust {
    /// The adapted disturbance bound d_hat (init defaults to `lo`).
    pub estimate: Estimate,
    /// Boundary-layer width phi (> 0): `sat` instead of `sign`.
    pub layer: f64,
}

/// The checked adaptive controller.
#[derive(Debug, Clone, PartialEq)]
pub struct Adaptive {
    /// C (m x n): the error signal `s = C x`.
    pub error: Mat,
    /// A_m (m x m): the reference model.
    pub reference: Mat,
    /// Q (m x m, symmetric) of the Lyapunov equation (default identity).
    pub q: Mat,
    /// Estimates of the state coefficients a_i (rows of C A_i), if adapted.
    pub a: Option<Estimate>,
    /// Estimates of the input gains b_i (diagonal of C B_i), if adapted.
    pub b: Option<Estimate>,
    /// The robust term, if any.
    pub robust: Option<Robust>,
    /// The reference input r(t) (m-vector expression of `t`); `None`: zero.
    pub r: Option<Expr>,
    /// The convergence claims the simulation checks.
    pub converged: Vec<Convergence>,
    /// The block.
    pub span: Span,
}
