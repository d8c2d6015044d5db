//! How a solve terminated, independent of the solver that ran it.

use std::fmt;

/// How the solver terminated (the statuses of an interior-point conic solver).
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

    /// Whether the solver reached a verdict: solved, or a certificate of
    /// infeasibility, each possibly to reduced accuracy.
    pub fn is_verdict(self) -> bool {
        matches!(
            self,
            SolveStatus::Solved
                | SolveStatus::AlmostSolved
                | SolveStatus::PrimalInfeasible
                | SolveStatus::DualInfeasible
                | SolveStatus::AlmostPrimalInfeasible
                | SolveStatus::AlmostDualInfeasible
        )
    }

    /// A short lower-case description for people (e.g. `"primal infeasible"`).
    pub fn describe(self) -> &'static str {
        match self {
            SolveStatus::Unsolved => "not solved",
            SolveStatus::Solved => "solved",
            SolveStatus::AlmostSolved => "solved to reduced accuracy",
            SolveStatus::PrimalInfeasible => "primal infeasible",
            SolveStatus::DualInfeasible => "dual infeasible (unbounded objective)",
            SolveStatus::AlmostPrimalInfeasible => "primal infeasible to reduced accuracy",
            SolveStatus::AlmostDualInfeasible => "dual infeasible to reduced accuracy",
            SolveStatus::MaxIterations => "iteration limit reached",
            SolveStatus::MaxTime => "time limit reached",
            SolveStatus::NumericalError => "numerical error",
            SolveStatus::InsufficientProgress => "insufficient progress",
            SolveStatus::CallbackTerminated => "stopped by a callback",
        }
    }
}

impl fmt::Display for SolveStatus {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.describe())
    }
}
