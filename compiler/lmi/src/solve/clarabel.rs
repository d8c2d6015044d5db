//! The Clarabel implementation of [`ConeSolver`]: the only code of the crate
//! that knows Clarabel's types.

use clarabel::algebra::CscMatrix as ClarabelCsc;
use clarabel::solver::{DefaultSettings, DefaultSolver, IPSolver, SolverStatus, SupportedConeT};

use crate::cone::{Cone, ConeProgram, CscMatrix};
use crate::error::{LmiError, Result};
use crate::status::SolveStatus;

use super::guard;
use super::settings::{LinearSolver, SolveSettings};
use super::solver::{ConeSolution, ConeSolver};

/// Clarabel's interior-point solver (the default of [`crate::Problem::solve`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ClarabelSolver;

/// The copies of the KKT data Clarabel keeps (matrix, factor, workspaces).
const COPIES: u64 = 5;

impl ClarabelSolver {
    /// A lower bound of [`ConeSolver::memory_estimate`] for a program with
    /// PSD cones of these matrix sizes (only their dense scaling blocks):
    /// cheap enough to refuse an oversized problem before building it.
    pub fn memory_floor(psd_sizes: impl IntoIterator<Item = usize>) -> u64 {
        psd_sizes
            .into_iter()
            .map(|s| {
                let d = (s * (s + 1) / 2) as u64;
                COPIES * 8 * d * d
            })
            .sum()
    }
}

impl ConeSolver for ClarabelSolver {
    fn name(&self) -> &'static str {
        "clarabel"
    }

    /// Clarabel's KKT system holds, per PSD cone of d = s(s+1)/2 rows, a dense
    /// d x d scaling block; the factorization adds the couplings of each cone
    /// with the unknowns it touches (d x u_i) and the dense Schur complement on
    /// the shared unknowns (u x u). The sum of those entries times 8 bytes,
    /// times 5 for the copies the solver keeps (matrix, factor, workspaces),
    /// matched the measured peak within a factor of 1.3 on PDC problems of
    /// 21 to 81 states (38 MB to 4.1 GB).
    fn memory_estimate(&self, program: &ConeProgram) -> u64 {
        let a = &program.a;
        // The unknowns each row touches, gathered per cone.
        let mut row_cone = vec![usize::MAX; a.nrows];
        let mut start = 0;
        let mut psd = Vec::new();
        for cone in &program.cones {
            let d = cone.dim();
            if matches!(cone, crate::cone::Cone::PsdTriangle(_)) {
                row_cone[start..start + d].fill(psd.len());
                psd.push((d as u64, 0u64));
            }
            start += d;
        }
        let mut touched = vec![u32::MAX; psd.len()];
        let mut shared = 0u64;
        for col in 0..a.ncols {
            let mut any = false;
            for &row in &a.rowval[a.colptr[col]..a.colptr[col + 1]] {
                let c = row_cone.get(row).copied().unwrap_or(usize::MAX);
                if c != usize::MAX && touched[c] != col as u32 {
                    touched[c] = col as u32;
                    psd[c].1 += 1;
                    any = true;
                }
            }
            shared += u64::from(any);
        }
        let entries: u64 =
            psd.iter().map(|&(d, u)| d * d + d * u).sum::<u64>() + shared * shared + a.nnz() as u64;
        COPIES * 8 * entries
    }

    /// Solves once; when that run stops on a numerical failure within its
    /// first [`EARLY_FAILURE`] iterations and equilibration was on, solves
    /// again without it and keeps the second run if it reached a verdict
    /// (solved or infeasible, exactly or almost). Both runs' time is counted.
    fn solve(&self, program: &ConeProgram, settings: &SolveSettings) -> Result<ConeSolution> {
        let first = solve_once(program, settings)?;
        if !(settings.equilibrate && failed_early(&first)) {
            return Ok(first);
        }
        let plain = SolveSettings {
            equilibrate: false,
            ..settings.clone()
        };
        let mut second = solve_once(program, &plain)?;
        second.solve_time += first.solve_time;
        if second.status.is_verdict() {
            second.unscaled_retry = true;
            Ok(second)
        } else {
            Ok(ConeSolution {
                solve_time: second.solve_time,
                ..first
            })
        }
    }
}

/// Iterations within which a numerical failure is taken for a scaling
/// failure. Clarabel's equilibration (Ruiz scaling of the data, entries kept
/// in [1e-4, 1e4]) makes some feasible event-trigger SDPs stop at iteration 1
/// with a zero step; the same data unscaled solve (docs/limits.md, "solver scaling").
pub const EARLY_FAILURE: u32 = 3;

/// Whether `s` stopped on a numerical failure within [`EARLY_FAILURE`] iterations.
fn failed_early(s: &ConeSolution) -> bool {
    matches!(
        s.status,
        SolveStatus::NumericalError | SolveStatus::InsufficientProgress
    ) && s.iterations <= EARLY_FAILURE
}

/// One Clarabel run with `settings`.
fn solve_once(program: &ConeProgram, settings: &SolveSettings) -> Result<ConeSolution> {
    let cones: Vec<SupportedConeT<f64>> = program.cones.iter().map(|&c| cone(c)).collect();
    let built = guard::run(|| {
        DefaultSolver::new(
            &csc(&program.p),
            &program.q,
            &csc(&program.a),
            &program.b,
            &cones,
            clarabel_settings(settings),
        )
    });
    let mut solver = match built {
        Ok(solver) => solver.map_err(|e| LmiError::Solver(e.to_string()))?,
        // Clarabel's chordal decomposition indexes the constant vector b by
        // the sparsity pattern of A alone and panics (an index left at
        // usize::MAX) when b has an entry outside it: the same data without
        // the decomposition.
        Err(_) if settings.chordal_decomposition => {
            let whole = SolveSettings {
                chordal_decomposition: false,
                ..settings.clone()
            };
            return solve_once(program, &whole);
        }
        Err(_) => return Ok(ConeSolution::failed(program.q.len())),
    };
    if guard::run(|| solver.solve()).is_err() {
        return Ok(ConeSolution::failed(program.q.len()));
    }
    let raw = &solver.solution;
    Ok(ConeSolution {
        status: status(raw.status),
        iterations: raw.iterations,
        solve_time: raw.solve_time,
        objective: raw.obj_val,
        dual_objective: raw.obj_val_dual,
        primal_residual: raw.r_prim,
        dual_residual: raw.r_dual,
        x: raw.x.clone(),
        unscaled_retry: false,
    })
}

/// The same matrix in Clarabel's type.
fn csc(m: &CscMatrix) -> ClarabelCsc<f64> {
    ClarabelCsc::new(
        m.nrows,
        m.ncols,
        m.colptr.clone(),
        m.rowval.clone(),
        m.nzval.clone(),
    )
}

/// The same cone in Clarabel's type (both pack PSD cones the same way).
fn cone(c: Cone) -> SupportedConeT<f64> {
    match c {
        Cone::Zero(n) => SupportedConeT::ZeroConeT(n),
        Cone::Nonnegative(n) => SupportedConeT::NonnegativeConeT(n),
        Cone::PsdTriangle(n) => SupportedConeT::PSDTriangleConeT(n),
    }
}

fn clarabel_settings(s: &SolveSettings) -> DefaultSettings<f64> {
    DefaultSettings {
        max_iter: s.max_iter,
        time_limit: s.time_limit.unwrap_or(f64::INFINITY),
        verbose: s.verbose,
        tol_gap_abs: s.tol_gap_abs,
        tol_gap_rel: s.tol_gap_rel,
        tol_feas: s.tol_feas,
        tol_infeas_abs: s.tol_infeas_abs,
        tol_infeas_rel: s.tol_infeas_rel,
        chordal_decomposition_enable: s.chordal_decomposition,
        equilibrate_enable: s.equilibrate,
        direct_solve_method: match s.linear_solver {
            #[cfg(target_pointer_width = "64")]
            LinearSolver::Faer => "faer".to_string(),
            // Clarabel has no faer LDL on 32-bit targets (see LinearSolver::DEFAULT).
            #[cfg(not(target_pointer_width = "64"))]
            LinearSolver::Faer => "qdldl".to_string(),
            LinearSolver::Qdldl => "qdldl".to_string(),
        },
        max_threads: s.threads,
        ..DefaultSettings::default()
    }
}

fn status(s: SolverStatus) -> SolveStatus {
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

#[cfg(test)]
mod tests {
    use super::{failed_early, EARLY_FAILURE};
    use crate::solve::solver::ConeSolution;
    use crate::status::SolveStatus;

    fn ended(status: SolveStatus, iterations: u32) -> ConeSolution {
        ConeSolution {
            status,
            iterations,
            ..ConeSolution::failed(1)
        }
    }

    #[test]
    fn only_numerical_failures_at_the_start_are_retried() {
        assert!(failed_early(&ended(SolveStatus::NumericalError, 1)));
        assert!(failed_early(&ended(SolveStatus::InsufficientProgress, 0)));
        assert!(failed_early(&ended(
            SolveStatus::NumericalError,
            EARLY_FAILURE
        )));
        assert!(!failed_early(&ended(
            SolveStatus::NumericalError,
            EARLY_FAILURE + 1
        )));
        assert!(!failed_early(&ended(SolveStatus::Solved, 1)));
        assert!(!failed_early(&ended(SolveStatus::PrimalInfeasible, 1)));
        assert!(!failed_early(&ended(SolveStatus::MaxIterations, 1)));
    }
}
