//! Errors of the LMI layer: every fallible operation returns [`LmiError`].

use std::fmt;

use crate::status::SolveStatus;

/// Everything that can go wrong when building, lowering, solving or evaluating a problem.
#[derive(Clone, Debug, PartialEq)]
pub enum LmiError {
    /// Two operands have incompatible shapes.
    Shape {
        /// The operation that was attempted (e.g. `"add"`, `"block (1, 2)"`).
        op: String,
        /// The expected shape, as `(rows, cols)`.
        expected: (usize, usize),
        /// The shape that was found.
        found: (usize, usize),
    },
    /// A dimension was zero or otherwise unusable.
    Dimension {
        /// What the dimension was for.
        what: String,
    },
    /// A constant (matrix entry, scale, margin, bound) was NaN or infinite.
    NonFinite {
        /// Where the value was found.
        what: String,
    },
    /// An expression meant to be symmetric (an LMI) is not, coefficient by coefficient.
    NotSymmetric {
        /// The constraint's name.
        constraint: String,
        /// Largest coefficient mismatch between entries (i, j) and (j, i).
        mismatch: f64,
    },
    /// A variable was used with a problem (or assignment) that did not create it,
    /// or with the wrong kind (e.g. a matrix where a scalar is needed).
    Variable {
        /// What was wrong.
        what: String,
    },
    /// A name is empty or used twice.
    Name {
        /// The offending name.
        name: String,
        /// What was wrong with it.
        what: String,
    },
    /// A value matrix does not have the structure of its variable.
    Value {
        /// The variable's name.
        var: String,
        /// What was wrong with the value.
        what: String,
    },
    /// A constraint handle does not belong to the problem.
    UnknownConstraint,
    /// The solver rejected the problem data or settings.
    Solver(String),
    /// The solver did not return `Solved`; the caller asked for a solved iterate.
    NotSolved(SolveStatus),
    /// The dense eigen-solver did not converge.
    Eigen {
        /// The constraint's name.
        constraint: String,
    },
}

impl fmt::Display for LmiError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LmiError::Shape {
                op,
                expected,
                found,
            } => write!(
                f,
                "shape mismatch in {op}: expected {}x{}, found {}x{}",
                expected.0, expected.1, found.0, found.1
            ),
            LmiError::Dimension { what } => write!(f, "invalid dimension: {what}"),
            LmiError::NonFinite { what } => write!(f, "non-finite value in {what}"),
            LmiError::NotSymmetric {
                constraint,
                mismatch,
            } => write!(
                f,
                "LMI '{constraint}' is not symmetric (coefficient mismatch {mismatch:.3e})"
            ),
            LmiError::Variable { what } => write!(f, "variable misuse: {what}"),
            LmiError::Name { name, what } => write!(f, "name '{name}': {what}"),
            LmiError::Value { var, what } => write!(f, "value of '{var}': {what}"),
            LmiError::UnknownConstraint => write!(f, "constraint does not belong to this problem"),
            LmiError::Solver(msg) => write!(f, "solver rejected the problem: {msg}"),
            LmiError::NotSolved(status) => write!(f, "solver status is {status:?}, not Solved"),
            LmiError::Eigen { constraint } => {
                write!(f, "eigenvalues of '{constraint}' did not converge")
            }
        }
    }
}

impl std::error::Error for LmiError {}

/// Shorthand for results of this crate.
pub type Result<T> = std::result::Result<T, LmiError>;

/// Returns a shape error unless `found == expected`.
pub(crate) fn check_shape(
    op: impl FnOnce() -> String,
    expected: (usize, usize),
    found: (usize, usize),
) -> Result<()> {
    if expected == found {
        Ok(())
    } else {
        Err(LmiError::Shape {
            op: op(),
            expected,
            found,
        })
    }
}

/// Returns a non-finite error if any entry of `values` is NaN or infinite.
pub(crate) fn check_finite<'a>(
    what: impl FnOnce() -> String,
    values: impl IntoIterator<Item = &'a f64>,
) -> Result<()> {
    if values.into_iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(LmiError::NonFinite { what: what() })
    }
}
