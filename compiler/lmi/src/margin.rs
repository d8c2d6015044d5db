//! Certificates: constraints rebuilt from numeric variable values (never from
//! solver slacks), their eigenvalue margins, and a floating-point error bound.
//!
//! # Error bound
//! A constraint matrix is evaluated as `Ê = C + Σ L op(V) R` in floating point.
//! With `B = |C| + Σ |L| |op(V)| |R|` (entrywise absolute values) and
//! `K = max over terms (inner dimensions of L and R) + number of terms + 1`,
//! the standard product and summation bounds give `|Ê - E| ≤ γ_K B` entrywise,
//! `γ_K = K ε / (1 - K ε)`. Eigenvalues move by at most the 2-norm (≤ Frobenius
//! norm) of a symmetric perturbation (Weyl), and the backward-stable dense
//! symmetric eigen-solver adds about `c n ε ‖Ê‖` (we take `c = 8`, a heuristic
//! constant). Hence the reported bound
//!
//! `error_bound = γ_K ‖(B + Bᵀ)/2‖_F + 8 n ε ‖(Ê + Êᵀ)/2‖_F + ε (|λ| + margin)`.
//!
//! The bound is with respect to the matrix defined by the exact values held in
//! the [`Assignment`]; a constraint is certified when its eigenvalue margin
//! exceeds it.

use nalgebra::{DMatrix, SymmetricEigen};

use crate::assignment::Assignment;
use crate::constraint::{ConstraintId, ConstraintKind, Relation};
use crate::error::{LmiError, Result};
use crate::expr::{Expr, TermKind};
use crate::problem::Problem;

/// The heuristic constant `c` of the eigen-solver term of the error bound.
const EIGEN_ERROR_FACTOR: f64 = 8.0;

/// Numeric margin of one constraint at an [`Assignment`].
#[derive(Clone, Debug, PartialEq)]
pub struct Margin {
    /// The constraint's name.
    pub name: String,
    /// What the constraint says (sense, recorded margin, size / relation, rhs).
    pub kind: ConstraintKind,
    /// Strict-feasibility measure: `λ_min(E)` for `E ⪰ ..`, `-λ_max(E)` for
    /// `E ⪯ ..`, `e - rhs` for `≥`, `rhs - e` for `≤`, `-|e - rhs|` for `=`.
    /// Positive means the strict inequality holds.
    pub slack: f64,
    /// `slack` minus the recorded margin (≥ 0: the solver's constraint holds).
    pub excess: f64,
    /// Rounding-error bound on `slack` and `excess` (see the module docs).
    pub error_bound: f64,
}

impl Margin {
    /// Whether the strict constraint (`≻`, `≺`, `>`, `<`) holds beyond rounding:
    /// `slack > error_bound`; for equalities, `|e - rhs| ≤ error_bound`.
    pub fn certified(&self) -> bool {
        match self.kind {
            ConstraintKind::Scalar {
                relation: Relation::Eq,
                ..
            } => -self.slack <= self.error_bound,
            _ => self.slack > self.error_bound,
        }
    }

    /// Whether the constraint with its recorded margin holds up to rounding:
    /// `excess ≥ -error_bound`.
    pub fn meets_margin(&self) -> bool {
        self.excess >= -self.error_bound
    }
}

/// `E` evaluated at the values together with the entrywise bound matrix `B`
/// and the operation count `K` of the module docs.
struct Evaluated {
    value: DMatrix<f64>,
    abs_bound: DMatrix<f64>,
    depth: usize,
}

fn evaluate_expr(expr: &Expr, values: &Assignment) -> Result<Evaluated> {
    let c = expr.constant_part();
    let mut value = c.clone();
    let mut abs_bound = c.abs();
    let mut inner = 0;
    for t in expr.terms() {
        let (h, w) = t.shape();
        let v = values.value(t.var())?;
        let (product, bound, k) = match &t.kind {
            TermKind::Product {
                left,
                transposed,
                right,
                ..
            } => {
                let op = if *transposed {
                    v.transpose()
                } else {
                    v.clone()
                };
                (
                    left * &op * right,
                    left.abs() * op.abs() * right.abs(),
                    left.ncols() + right.nrows(),
                )
            }
            TermKind::Scaled { coeff, .. } => {
                let s = v[(0, 0)];
                (coeff * s, coeff.abs() * s.abs(), 1)
            }
        };
        inner = inner.max(k);
        let mut block = value.view_mut((t.row, t.col), (h, w));
        block += product;
        let mut block = abs_bound.view_mut((t.row, t.col), (h, w));
        block += bound;
    }
    Ok(Evaluated {
        value,
        abs_bound,
        depth: inner + expr.terms().len() + 1,
    })
}

/// `γ_k = k ε / (1 - k ε)` (infinite when `k ε ≥ 1`).
fn gamma(k: usize) -> f64 {
    let ke = k as f64 * f64::EPSILON;
    if ke < 1.0 {
        ke / (1.0 - ke)
    } else {
        f64::INFINITY
    }
}

fn symmetric_part(m: &DMatrix<f64>) -> DMatrix<f64> {
    (m + m.transpose()) * 0.5
}

impl Problem {
    /// The constraint's matrix (`1 x 1` for scalar constraints) rebuilt from
    /// the values, exactly as the expression was written.
    pub fn evaluate(&self, id: ConstraintId, values: &Assignment) -> Result<DMatrix<f64>> {
        values.check_problem(self)?;
        Ok(evaluate_expr(&self.constraint(id)?.expr, values)?.value)
    }

    /// Eigenvalue margin of one constraint at the values, with its error bound.
    pub fn margin(&self, id: ConstraintId, values: &Assignment) -> Result<Margin> {
        values.check_problem(self)?;
        let c = self.constraint(id)?;
        let ev = evaluate_expr(&c.expr, values)?;
        let eps = f64::EPSILON;
        let rounding = gamma(ev.depth) * symmetric_part(&ev.abs_bound).norm();
        let (slack, recorded, solver_term) = match c.kind {
            ConstraintKind::Lmi {
                sense,
                margin,
                size,
            } => {
                let sym = symmetric_part(&ev.value) * sense.sign();
                let norm = sym.norm();
                let eig =
                    SymmetricEigen::try_new(sym, eps, 1000 * size.max(1)).ok_or_else(|| {
                        LmiError::Eigen {
                            constraint: c.name.clone(),
                        }
                    })?;
                let lambda = eig
                    .eigenvalues
                    .iter()
                    .copied()
                    .fold(f64::INFINITY, f64::min);
                (
                    lambda,
                    margin,
                    EIGEN_ERROR_FACTOR * size as f64 * eps * norm,
                )
            }
            ConstraintKind::Scalar { relation, rhs } => {
                let r = ev.value[(0, 0)] - rhs;
                let slack = match relation {
                    Relation::Ge => r,
                    Relation::Le => -r,
                    Relation::Eq => -r.abs(),
                };
                (slack, 0.0, eps * rhs.abs())
            }
        };
        Ok(Margin {
            name: c.name.clone(),
            kind: c.kind,
            slack,
            excess: slack - recorded,
            error_bound: rounding + solver_term + eps * (slack.abs() + recorded),
        })
    }

    /// Margins of every constraint, in creation order.
    pub fn margins(&self, values: &Assignment) -> Result<Vec<Margin>> {
        self.constraints()
            .map(|id| self.margin(id, values))
            .collect()
    }
}
