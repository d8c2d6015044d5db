//! Constraints: named LMIs with recorded margins and named scalar relations.

use crate::cone::ConeBlock;
use crate::expr::Expr;

/// Direction of a linear matrix inequality.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum LmiSense {
    /// `E ⪰ margin · I` (positive semidefinite; definite when the margin is positive).
    Psd,
    /// `E ⪯ -margin · I` (negative semidefinite; definite when the margin is positive).
    Nsd,
}

impl LmiSense {
    /// `+1` for [`LmiSense::Psd`], `-1` for [`LmiSense::Nsd`]: the constraint is `sign · E ⪰ margin · I`.
    pub fn sign(self) -> f64 {
        match self {
            LmiSense::Psd => 1.0,
            LmiSense::Nsd => -1.0,
        }
    }
}

/// Relation of a scalar constraint `e (relation) rhs`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Relation {
    /// `e ≥ rhs`.
    Ge,
    /// `e ≤ rhs`.
    Le,
    /// `e = rhs`.
    Eq,
}

/// What a constraint says, as recorded for reports.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ConstraintKind {
    /// `E ⪰ margin I` or `E ⪯ -margin I` for a symmetric `size x size` expression.
    Lmi {
        /// Direction.
        sense: LmiSense,
        /// The margin that turns a strict LMI into a solvable non-strict one (0: non-strict).
        margin: f64,
        /// Size of the (square) matrix.
        size: usize,
    },
    /// `e (relation) rhs` for a `1 x 1` expression.
    Scalar {
        /// The relation.
        relation: Relation,
        /// The right-hand side.
        rhs: f64,
    },
}

/// Handle to a constraint of one [`crate::Problem`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct ConstraintId {
    pub(crate) problem: u64,
    pub(crate) index: usize,
}

impl ConstraintId {
    /// Position of the constraint in its problem (creation order).
    pub fn index(self) -> usize {
        self.index
    }
}

/// A constraint as stored by the problem: the expression is kept for evaluation,
/// its lowered rows for assembly into the cone program.
#[derive(Clone, Debug)]
pub(crate) struct Constraint {
    pub(crate) name: String,
    pub(crate) expr: Expr,
    pub(crate) kind: ConstraintKind,
    pub(crate) lowered: ConeBlock,
}
