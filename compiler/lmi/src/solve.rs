//! Solving with Clarabel: settings, status and solution.

use std::time::Instant;

use clarabel::algebra::CscMatrix;
use clarabel::solver::{DefaultSettings, DefaultSolver, IPSolver, SolverStatus};
use nalgebra::DMatrix;

use crate::assignment::Assignment;
use crate::error::{LmiError, Result};
use crate::problem::{ObjectiveSense, Problem};
use crate::var::Var;

/// Solver settings (a plain struct; start from `SolveSettings::default()`).
#[derive(Clone, Debug, PartialEq)]
pub struct SolveSettings {
    /// Maximum number of interior-point iterations.
    pub max_iter: u32,
    /// Wall-clock limit in seconds (`None`: no limit).
    pub time_limit: Option<f64>,
    /// Print the solver's progress.
    pub verbose: bool,
    /// Absolute duality-gap tolerance.
    pub tol_gap_abs: f64,
    /// Relative duality-gap tolerance.
    pub tol_gap_rel: f64,
    /// Feasibility tolerance.
    pub tol_feas: f64,
    /// Absolute infeasibility tolerance.
    pub tol_infeas_abs: f64,
    /// Relative infeasibility tolerance.
    pub tol_infeas_rel: f64,
    /// Let the solver split PSD cones with a chordal sparsity pattern.
    pub chordal_decomposition: bool,
    /// Let the solver rescale the data.
    pub equilibrate: bool,
    /// Sparse LDL factorization used for the KKT systems.
    pub linear_solver: LinearSolver,
}

/// The sparse LDL factorization of the interior-point KKT systems.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LinearSolver {
    /// faer's supernodal LDL (fast on the dense blocks PSD cones create).
    Faer,
    /// Clarabel's QDLDL (scalar, simplicial).
    Qdldl,
}

impl Default for SolveSettings {
    fn default() -> Self {
        SolveSettings {
            max_iter: 200,
            time_limit: None,
            verbose: false,
            tol_gap_abs: 1e-8,
            tol_gap_rel: 1e-8,
            tol_feas: 1e-8,
            tol_infeas_abs: 1e-8,
            tol_infeas_rel: 1e-8,
            chordal_decomposition: true,
            equilibrate: true,
            linear_solver: LinearSolver::Faer,
        }
    }
}

impl SolveSettings {
    fn to_clarabel(&self) -> DefaultSettings<f64> {
        DefaultSettings {
            max_iter: self.max_iter,
            time_limit: self.time_limit.unwrap_or(f64::INFINITY),
            verbose: self.verbose,
            tol_gap_abs: self.tol_gap_abs,
            tol_gap_rel: self.tol_gap_rel,
            tol_feas: self.tol_feas,
            tol_infeas_abs: self.tol_infeas_abs,
            tol_infeas_rel: self.tol_infeas_rel,
            chordal_decomposition_enable: self.chordal_decomposition,
            equilibrate_enable: self.equilibrate,
            direct_solve_method: match self.linear_solver {
                LinearSolver::Faer => "faer".to_string(),
                LinearSolver::Qdldl => "qdldl".to_string(),
            },
            ..DefaultSettings::default()
        }
    }
}

/// How the solver terminated (mirrors Clarabel's status).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SolveStatus {
    /// The solver has not run.
    Unsolved,
    /// Solved to the requested accuracy.
    Solved,
    /// Solved to reduced accuracy.
    AlmostSolved,
    /// Certificate of primal infeasibility: the constraints cannot all hold.
    PrimalInfeasible,
    /// Certificate of dual infeasibility: the objective is unbounded.
    DualInfeasible,
    /// Primal infeasibility to reduced accuracy.
    AlmostPrimalInfeasible,
    /// Dual infeasibility to reduced accuracy.
    AlmostDualInfeasible,
    /// Iteration limit reached.
    MaxIterations,
    /// Time limit reached.
    MaxTime,
    /// Numerical error.
    NumericalError,
    /// Stopped for lack of progress.
    InsufficientProgress,
    /// Stopped by a user callback.
    CallbackTerminated,
}

impl SolveStatus {
    /// Only [`SolveStatus::Solved`] counts as solved.
    pub fn is_solved(self) -> bool {
        self == SolveStatus::Solved
    }

    /// Whether the solver claims (possibly with reduced accuracy) that the constraints cannot hold.
    pub fn is_primal_infeasible(self) -> bool {
        matches!(
            self,
            SolveStatus::PrimalInfeasible | SolveStatus::AlmostPrimalInfeasible
        )
    }
}

impl From<SolverStatus> for SolveStatus {
    fn from(s: SolverStatus) -> Self {
        match s {
            SolverStatus::Unsolved => SolveStatus::Unsolved,
            SolverStatus::Solved => SolveStatus::Solved,
            SolverStatus::AlmostSolved => SolveStatus::AlmostSolved,
            SolverStatus::PrimalInfeasible => SolveStatus::PrimalInfeasible,
            SolverStatus::DualInfeasible => SolveStatus::DualInfeasible,
            SolverStatus::AlmostPrimalInfeasible => SolveStatus::AlmostPrimalInfeasible,
            SolverStatus::AlmostDualInfeasible => SolveStatus::AlmostDualInfeasible,
            SolverStatus::MaxIterations => SolveStatus::MaxIterations,
            SolverStatus::MaxTime => SolveStatus::MaxTime,
            SolverStatus::NumericalError => SolveStatus::NumericalError,
            SolverStatus::InsufficientProgress => SolveStatus::InsufficientProgress,
            SolverStatus::CallbackTerminated => SolveStatus::CallbackTerminated,
        }
    }
}

/// What the solver returned. The iterate is only handed out as a solution
/// when the status is [`SolveStatus::Solved`]; anything else must be asked
/// for explicitly with [`Solution::assignment_any_status`].
#[derive(Clone, Debug)]
pub struct Solution {
    /// Termination status.
    pub status: SolveStatus,
    /// Interior-point iterations.
    pub iterations: u32,
    /// Solver time in seconds, as reported by Clarabel.
    pub solve_time: f64,
    /// Wall-clock seconds for assembly, setup and solve.
    pub total_time: f64,
    /// Primal objective value in the problem's own sense (0 for feasibility problems).
    pub objective: f64,
    /// Dual objective value in the problem's own sense.
    pub dual_objective: f64,
    /// Primal residual reported by the solver.
    pub primal_residual: f64,
    /// Dual residual reported by the solver.
    pub dual_residual: f64,
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
        if self.unknowns == 0 {
            return Err(LmiError::Dimension {
                what: "the problem has no variables".into(),
            });
        }
        let started = Instant::now();
        let data = self.assemble();
        let p = CscMatrix::zeros((self.unknowns, self.unknowns));
        let mut solver = DefaultSolver::new(
            &p,
            &data.q,
            &data.a,
            &data.b,
            &data.cones,
            settings.to_clarabel(),
        )
        .map_err(|e| LmiError::Solver(e.to_string()))?;
        solver.solve();
        let raw = &solver.solution;
        let (sign, constant) = match self.sense {
            ObjectiveSense::Feasibility => (1.0, 0.0),
            ObjectiveSense::Minimize => (1.0, self.objective.constant),
            ObjectiveSense::Maximize => (-1.0, self.objective.constant),
        };
        Ok(Solution {
            status: raw.status.into(),
            iterations: raw.iterations,
            solve_time: raw.solve_time,
            total_time: started.elapsed().as_secs_f64(),
            objective: sign * raw.obj_val + constant,
            dual_objective: sign * raw.obj_val_dual + constant,
            primal_residual: raw.r_prim,
            dual_residual: raw.r_dual,
            iterate: Assignment::from_unknowns(self, &raw.x),
        })
    }
}
