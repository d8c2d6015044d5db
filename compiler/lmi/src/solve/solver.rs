//! The seam between the LMI layer and a conic solver.

use crate::cone::ConeProgram;
use crate::error::Result;
use crate::status::SolveStatus;

use super::settings::SolveSettings;

/// A conic solver: takes a [`ConeProgram`] and returns its raw result.
///
/// [`crate::Problem::solve_with`] lowers a problem, calls the solver and maps
/// the result back to the problem's variables and objective sense, so an
/// implementation only ever sees the solver-neutral program.
pub trait ConeSolver {
    /// Short name for reports (e.g. the solver crate's name).
    fn name(&self) -> &'static str;

    /// Solves the program. `Err` only when the solver refuses the data or
    /// settings; every termination status is returned in the [`ConeSolution`].
    fn solve(&self, program: &ConeProgram, settings: &SolveSettings) -> Result<ConeSolution>;

    /// An estimate of the peak memory, in bytes, that solving `program`
    /// takes (callers refuse problems over their budget before solving). The
    /// default counts one dense block per PSD cone and the constraint matrix.
    fn memory_estimate(&self, program: &ConeProgram) -> u64 {
        let blocks: u64 = program
            .cones
            .iter()
            .filter(|c| matches!(c, crate::cone::Cone::PsdTriangle(_)))
            .map(|c| (c.dim() as u64).pow(2))
            .sum();
        8 * (blocks + program.a.nnz() as u64)
    }
}

/// What a [`ConeSolver`] returns, in the cone program's own terms.
#[derive(Clone, Debug, PartialEq)]
pub struct ConeSolution {
    /// Termination status.
    pub status: SolveStatus,
    /// Interior-point iterations.
    pub iterations: u32,
    /// Solver time in seconds, as the solver reports it.
    pub solve_time: f64,
    /// Primal objective `½ xᵀ P x + qᵀ x` of the cone program.
    pub objective: f64,
    /// Dual objective of the cone program.
    pub dual_objective: f64,
    /// Primal residual.
    pub primal_residual: f64,
    /// Dual residual.
    pub dual_residual: f64,
    /// The last primal iterate, one value per unknown.
    pub x: Vec<f64>,
    /// Whether this is a second run without the solver's data scaling
    /// (equilibration), made because the first stopped on a numerical failure
    /// in its first iterations.
    pub unscaled_retry: bool,
}

impl ConeSolution {
    /// The outcome of a solver that stopped abnormally (a failure inside the
    /// solver's own linear algebra): a numerical error with no usable iterate.
    pub fn failed(unknowns: usize) -> Self {
        Self {
            status: SolveStatus::NumericalError,
            iterations: 0,
            solve_time: 0.0,
            objective: f64::NAN,
            dual_objective: f64::NAN,
            primal_residual: f64::NAN,
            dual_residual: f64::NAN,
            x: vec![f64::NAN; unknowns],
            unscaled_retry: false,
        }
    }
}
