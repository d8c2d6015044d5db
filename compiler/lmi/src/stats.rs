//! Size statistics of a problem as lowered for the solver, for reports.

use std::fmt;

use crate::cone::Cone;
use crate::constraint::ConstraintKind;
use crate::problem::Problem;

/// Size statistics of a problem, as lowered for the solver.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ProblemStats {
    /// Number of matrix/scalar decision variables.
    pub variables: usize,
    /// Number of scalar unknowns (columns of `A`).
    pub scalar_unknowns: usize,
    /// Number of LMI constraints.
    pub lmis: usize,
    /// Number of scalar constraints.
    pub scalar_constraints: usize,
    /// Sizes of the PSD cones, in solver order.
    pub psd_cones: Vec<usize>,
    /// Rows of the zero cone (equalities).
    pub zero_rows: usize,
    /// Rows of the non-negative cone (inequalities and `1 x 1` LMIs).
    pub nonneg_rows: usize,
    /// Total rows of `A`.
    pub rows: usize,
    /// Stored non-zeros of `A`.
    pub nnz: usize,
}

impl fmt::Display for ProblemStats {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let largest = self.psd_cones.iter().max().copied().unwrap_or(0);
        write!(
            f,
            "{} variables ({} unknowns), {} LMIs (PSD cones: {}, largest {}), {} scalar constraints, A: {} rows, {} non-zeros",
            self.variables,
            self.scalar_unknowns,
            self.lmis,
            self.psd_cones.len(),
            largest,
            self.scalar_constraints,
            self.rows,
            self.nnz
        )
    }
}

impl Problem {
    /// Size statistics for reports, counted from the lowered constraints
    /// (the same numbers [`Problem::cone_program`] would show, without assembling it).
    pub fn stats(&self) -> ProblemStats {
        let mut stats = ProblemStats {
            variables: self.vars.len(),
            scalar_unknowns: self.unknowns,
            ..ProblemStats::default()
        };
        // PSD cones keep the constraints' order when stacked, so creation order is solver order.
        for c in &self.constraints {
            match c.kind {
                ConstraintKind::Lmi { .. } => stats.lmis += 1,
                ConstraintKind::Scalar { .. } => stats.scalar_constraints += 1,
            }
            match c.lowered.cone {
                Cone::Zero(n) => stats.zero_rows += n,
                Cone::Nonnegative(n) => stats.nonneg_rows += n,
                Cone::PsdTriangle(n) => stats.psd_cones.push(n),
            }
            stats.rows += c.lowered.b.len();
            stats.nnz += c.lowered.a.len();
        }
        stats
    }
}
