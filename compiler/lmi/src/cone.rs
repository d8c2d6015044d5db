//! The solver-neutral cone program every problem lowers to.
//!
//! ```text
//! minimise    ½ xᵀ P x + qᵀ x
//! subject to  A x + s = b,   s ∈ K = K₁ × K₂ × …
//! ```
//!
//! `x` holds the problem's scalar unknowns (see [`crate::VarKind::unknown_of`]
//! for their numbering), the cones `Kᵢ` take consecutive rows of `A` and `b`
//! in the order of [`ConeProgram::cones`], and both matrices are stored in
//! compressed sparse column form.
//!
//! Packing of a [`Cone::PsdTriangle`] of order `n`: its `n (n + 1) / 2` rows hold
//! the upper triangle of the symmetric slack matrix `S`, column by column
//! (`S₀₀, S₀₁, S₁₁, S₀₂, …`), off-diagonal entries multiplied by `√2` so that
//! the Euclidean inner product of two packed vectors equals the trace inner
//! product of the matrices. This is Clarabel's convention; a solver that packs
//! another triangle or order needs only a row permutation.

/// A sparse matrix in compressed sparse column form, as plain vectors.
///
/// Column `j` holds the entries `rowval[k], nzval[k]` for
/// `k in colptr[j]..colptr[j + 1]`, rows strictly increasing.
#[derive(Clone, Debug, PartialEq)]
pub struct CscMatrix {
    /// Number of rows.
    pub nrows: usize,
    /// Number of columns.
    pub ncols: usize,
    /// Column start offsets into `rowval` and `nzval` (`ncols + 1` entries).
    pub colptr: Vec<usize>,
    /// Row index of every stored entry.
    pub rowval: Vec<usize>,
    /// Value of every stored entry.
    pub nzval: Vec<f64>,
}

impl CscMatrix {
    /// The `nrows x ncols` matrix without stored entries.
    pub fn zeros(nrows: usize, ncols: usize) -> CscMatrix {
        CscMatrix {
            nrows,
            ncols,
            colptr: vec![0; ncols + 1],
            rowval: Vec::new(),
            nzval: Vec::new(),
        }
    }

    /// Number of stored entries.
    pub fn nnz(&self) -> usize {
        self.nzval.len()
    }

    /// Every stored entry as `(row, column, value)`, column by column.
    pub fn triplets(&self) -> impl Iterator<Item = (usize, usize, f64)> + '_ {
        self.colptr
            .windows(2)
            .enumerate()
            .flat_map(move |(j, w)| (w[0]..w[1]).map(move |k| (self.rowval[k], j, self.nzval[k])))
    }
}

/// One cone of the product `K`, with its size.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Cone {
    /// `{0}ⁿ`: `n` equality rows.
    Zero(usize),
    /// `ℝⁿ₊`: `n` inequality rows.
    Nonnegative(usize),
    /// Positive semidefinite `n x n` matrices, packed as described in the module docs.
    PsdTriangle(usize),
}

impl Cone {
    /// Number of rows the cone takes.
    pub fn dim(self) -> usize {
        match self {
            Cone::Zero(n) | Cone::Nonnegative(n) => n,
            Cone::PsdTriangle(n) => n * (n + 1) / 2,
        }
    }
}

/// A conic program in the standard form of the module docs.
#[derive(Clone, Debug, PartialEq)]
pub struct ConeProgram {
    /// Number of scalar unknowns (columns of `A`, order of `P`).
    pub n_vars: usize,
    /// Quadratic cost, upper triangle only (no entries for LMI problems).
    pub p: CscMatrix,
    /// Linear cost.
    pub q: Vec<f64>,
    /// Constraint matrix, `b.len() x n_vars`.
    pub a: CscMatrix,
    /// Constraint right-hand side.
    pub b: Vec<f64>,
    /// The cones, taking consecutive rows; their dimensions add up to `b.len()`.
    pub cones: Vec<Cone>,
}

/// Rows `s = b - A x` of one lowered constraint, all in one cone:
/// `a` holds merged `(local row, unknown, value)` triplets.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct ConeBlock {
    pub(crate) cone: Cone,
    pub(crate) b: Vec<f64>,
    pub(crate) a: Vec<(usize, usize, f64)>,
}
