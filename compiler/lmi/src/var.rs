//! Decision variables: matrix-shaped handles onto scalar unknowns.

/// Structure of a decision variable.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum VarKind {
    /// Symmetric `n x n` matrix: `n (n + 1) / 2` unknowns (upper triangle).
    Symmetric(usize),
    /// Unstructured `rows x cols` matrix: one unknown per entry.
    Full(usize, usize),
    /// Diagonal `n x n` matrix: `n` unknowns, zero off the diagonal.
    Diagonal(usize),
    /// A scalar (a `1 x 1` matrix).
    Scalar,
}

impl VarKind {
    /// Matrix shape `(rows, cols)` of a variable of this kind.
    pub fn shape(self) -> (usize, usize) {
        match self {
            VarKind::Symmetric(n) | VarKind::Diagonal(n) => (n, n),
            VarKind::Full(r, c) => (r, c),
            VarKind::Scalar => (1, 1),
        }
    }

    /// Number of scalar unknowns of a variable of this kind.
    pub fn unknowns(self) -> usize {
        match self {
            VarKind::Symmetric(n) => n * (n + 1) / 2,
            VarKind::Full(r, c) => r * c,
            VarKind::Diagonal(n) => n,
            VarKind::Scalar => 1,
        }
    }

    /// Local unknown index of entry `(i, j)`, or `None` for a structural zero.
    ///
    /// Symmetric entries `(i, j)` and `(j, i)` share one unknown, numbered like
    /// the column-major upper triangle.
    pub fn unknown_of(self, i: usize, j: usize) -> Option<usize> {
        match self {
            VarKind::Symmetric(_) => {
                let (lo, hi) = if i <= j { (i, j) } else { (j, i) };
                Some(hi * (hi + 1) / 2 + lo)
            }
            VarKind::Full(r, _) => Some(j * r + i),
            VarKind::Diagonal(_) => (i == j).then_some(i),
            VarKind::Scalar => Some(0),
        }
    }

    /// Every structurally non-zero entry `(i, j, local unknown)`, column by column.
    pub(crate) fn entries(self) -> impl Iterator<Item = (usize, usize, usize)> {
        let (rows, cols) = self.shape();
        (0..cols)
            .flat_map(move |j| (0..rows).map(move |i| (i, j)))
            .filter_map(move |(i, j)| self.unknown_of(i, j).map(|u| (i, j, u)))
    }
}

/// Handle to a decision variable of one [`crate::Problem`].
///
/// Cheap to copy; it remembers its problem so that misuse is reported as an error.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Var {
    pub(crate) problem: u64,
    pub(crate) index: usize,
    pub(crate) offset: usize,
    pub(crate) kind: VarKind,
}

impl Var {
    /// Structure of the variable.
    pub fn kind(self) -> VarKind {
        self.kind
    }

    /// Matrix shape `(rows, cols)`.
    pub fn shape(self) -> (usize, usize) {
        self.kind.shape()
    }

    /// Position of the variable in its problem (creation order).
    pub fn index(self) -> usize {
        self.index
    }

    /// Global index of scalar unknown for entry `(i, j)`, `None` for a structural zero.
    pub(crate) fn unknown_of(self, i: usize, j: usize) -> Option<usize> {
        self.kind.unknown_of(i, j).map(|u| self.offset + u)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unknown_counts_match_entries() {
        for kind in [
            VarKind::Symmetric(4),
            VarKind::Full(2, 3),
            VarKind::Diagonal(5),
            VarKind::Scalar,
        ] {
            let mut seen: Vec<usize> = kind.entries().map(|(_, _, u)| u).collect();
            seen.sort_unstable();
            seen.dedup();
            assert_eq!(seen, (0..kind.unknowns()).collect::<Vec<_>>(), "{kind:?}");
        }
    }

    #[test]
    fn symmetric_entries_share_unknowns() {
        let k = VarKind::Symmetric(3);
        assert_eq!(k.unknown_of(0, 2), k.unknown_of(2, 0));
        assert_eq!(k.unknown_of(2, 2), Some(5));
        assert_eq!(VarKind::Diagonal(3).unknown_of(0, 1), None);
    }
}
