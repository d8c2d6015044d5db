//! Solving: a problem's [`crate::ConeProgram`] goes through a [`ConeSolver`]
//! (Clarabel by default) and comes back as a [`Solution`] over the problem's
//! variables.

mod clarabel;
mod guard;
mod settings;
mod solver;

use std::time::Instant;

use nalgebra::DMatrix;

use crate::assignment::Assignment;
use crate::error::{LmiError, Result};
use crate::problem::Problem;
use crate::status::SolveStatus;
use crate::var::Var;

pub use self::clarabel::ClarabelSolver;
pub use self::settings::{LinearSolver, SolveSettings};
pub use self::solver::{ConeSolution, ConeSolver};

/// What the solver returned. The iterate is only handed out as a solution
/// when the status is [`SolveStatus::Solved`]; anything else must be asked
/// for explicitly with [`Solution::assignment_any_status`].
#[derive(Clone, Debug)]
pub struct Solution {
    /// The solver that ran ([`ConeSolver::name`]).
    pub solver: &'static str,
    /// Termination status.
    pub status: SolveStatus,
    /// Interior-point iterations.
    pub iterations: u32,
    /// Solver time in seconds, as reported by the solver.
    pub solve_time: f64,
    /// Wall-clock seconds for lowering, setup and solve.
    pub total_time: f64,
    /// Primal objective value in the problem's own sense (0 for feasibility problems).
    pub objective: f64,
    /// Dual objective value in the problem's own sense.
    pub dual_objective: f64,
    /// Primal residual reported by the solver.
    pub primal_residual: f64,
    /// Dual residual reported by the solver.
    pub dual_residual: f64,
    /// Whether the solver ran a second time without its data scaling
    /// ([`ConeSolution::unscaled_retry`]); this is that run.
    pub unscaled_retry: bool,
    iterate: Assignment,
}

impl Solution {
    /// The solution's variable values; an error unless the status is `Solved`.
    pub fn assignment(&self) -> Result<&Assignment> {
        if self.status.is_solved() {
            Ok(&self.iterate)
        } else {
            Err(LmiError::NotSolved(self.status))
        }
    }

    /// The value of `v`; an error unless the status is `Solved`.
    pub fn value(&self, v: Var) -> Result<&DMatrix<f64>> {
        self.assignment()?.value(v)
    }

    /// The solver's last iterate whatever the status (for infeasible problems
    /// it is not a solution); the caller takes responsibility for using it.
    pub fn assignment_any_status(&self) -> &Assignment {
        &self.iterate
    }
}

impl Problem {
    /// Lowers the problem and runs Clarabel. `Err` only when the solver refuses
    /// the data or settings; every termination status is returned in the
    /// [`Solution`] for the caller to judge.
    pub fn solve(&self, settings: &SolveSettings) -> Result<Solution> {
        self.solve_with(&ClarabelSolver, settings)
    }

    /// The estimated peak memory, in bytes, of [`Problem::solve`] on this
    /// problem (see [`ConeSolver::memory_estimate`]).
    pub fn memory_estimate(&self) -> u64 {
        ClarabelSolver.memory_estimate(&self.cone_program())
    }

    /// Lowers the problem to its [`crate::ConeProgram`] and runs `solver` on
    /// it; like [`Problem::solve`] otherwise. A solver that returns the wrong
    /// number of values is reported as [`LmiError::Solver`].
    pub fn solve_with(
        &self,
        solver: &(impl ConeSolver + ?Sized),
        settings: &SolveSettings,
    ) -> Result<Solution> {
        if self.unknowns == 0 {
            return Err(LmiError::Dimension {
                what: "the problem has no variables".into(),
            });
        }
        let started = Instant::now();
        let raw = solver.solve(&self.cone_program(), settings)?;
        if raw.x.len() != self.unknowns {
            return Err(LmiError::Solver(format!(
                "{} returned {} values for {} unknowns",
                solver.name(),
                raw.x.len(),
                self.unknowns
            )));
        }
        Ok(Solution {
            solver: solver.name(),
            status: raw.status,
            iterations: raw.iterations,
            solve_time: raw.solve_time,
            total_time: started.elapsed().as_secs_f64(),
            objective: self.objective.in_own_sense(raw.objective),
            dual_objective: self.objective.in_own_sense(raw.dual_objective),
            primal_residual: raw.primal_residual,
            dual_residual: raw.dual_residual,
            unscaled_retry: raw.unscaled_retry,
            iterate: Assignment::from_unknowns(self, &raw.x),
        })
    }
}
