//! tsf-lmi: a small modelling layer for linear matrix inequalities. It knows
//! nothing about fuzzy systems. Problems lower to a solver-neutral
//! [`ConeProgram`] (zero, non-negative and PSD cones); only the `solve` module
//! knows a solver, Clarabel, behind the [`ConeSolver`] seam, and it is the
//! only code of tsfc that knows Clarabel exists.
//!
//! Flow: create variables on a [`Problem`], build affine [`Expr`]essions
//! (`L V R` terms, `he`, block matrices), add named constraints
//! (`E ⪰ margin I`, `E ⪯ -margin I`, scalar relations), set an objective,
//! [`Problem::solve`], then rebuild every constraint from the returned values
//! with [`Problem::margins`] to certify it. [`Problem::cone_program`] shows the
//! lowered data; [`Problem::solve_with`] runs any other [`ConeSolver`] on it.
//!
//! Conventions:
//! - LMIs must be symmetric coefficient by coefficient (checked when the
//!   constraint is added, relative tolerance 1e-10); give symmetric block
//!   matrices with [`Expr::sym_blocks`] (upper blocks only).
//! - Strict LMIs are written with an explicit margin (`E ⪯ -eps I`), recorded
//!   in [`ConstraintKind`] and reported with every [`Margin`].
//! - Only [`SolveStatus::Solved`] yields values through [`Solution::assignment`];
//!   other statuses must be handled (or explicitly overridden) by the caller.
//! - Output is deterministic: no hash-ordered iteration reaches the solver.
//!
//! Cost: Clarabel factors the full KKT system with a sparse LDL, so one iteration
//! costs roughly `Σ_cones svec(n)·(svec(n) + unknowns)²` flops and depends on
//! the fill AMD finds; a T-S H-inf problem with 22 LMIs of size 10 and 94
//! unknowns takes ~0.3 s, 37 LMIs of size 12 and 165 unknowns ~6 s.
//!
//! ```
//! use nalgebra::DMatrix;
//! use tsf_lmi::{Expr, Problem, SolveSettings, SolveStatus};
//!
//! # fn main() -> Result<(), tsf_lmi::LmiError> {
//! // Lyapunov: find P ⪰ I with A'P + PA ⪯ -I, minimising trace P.
//! let a = DMatrix::from_row_slice(2, 2, &[-1.0, 2.0, 0.0, -3.0]);
//! let mut lp = Problem::new();
//! let p = lp.symmetric("P", 2)?;
//! lp.psd("P > 0", Expr::var(p), 1.0)?;
//! lp.nsd("A'P + PA < 0", Expr::var(p).right_mul(&a)?.he()?, 1.0)?;
//! lp.minimize(Expr::var(p).trace()?)?;
//! let solution = lp.solve(&SolveSettings::default())?;
//! assert_eq!(solution.status, SolveStatus::Solved);
//! let values = solution.assignment()?;
//! assert!(lp.margins(values)?.iter().all(|m| m.certified()));
//! # Ok(())
//! # }
//! ```

use tsf_lapack as _;

mod assignment;
mod cone;
mod constraint;
mod error;
mod expr;
mod lower;
mod margin;
mod objective;
mod problem;
mod solve;
mod stats;
mod status;
mod var;

pub use assignment::Assignment;
pub use cone::{Cone, ConeProgram, CscMatrix};
pub use constraint::{ConstraintId, ConstraintKind, LmiSense, Relation};
pub use error::{LmiError, Result};
pub use expr::{BlockGrid, Expr};
pub use margin::Margin;
pub use objective::ObjectiveSense;
pub use problem::Problem;
pub use solve::{ClarabelSolver, ConeSolution, ConeSolver, LinearSolver, Solution, SolveSettings};
pub use stats::ProblemStats;
pub use status::SolveStatus;
pub use var::{Var, VarKind};
