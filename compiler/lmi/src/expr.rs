//! Affine matrix expressions in the decision variables.
//!
//! An [`Expr`] is a constant matrix plus a sum of terms, each placed at a block
//! offset: `L * op(V) * R` (with `op` the identity or the transpose) or
//! `v * C` for a scalar variable `v`. Every operation checks shapes and returns
//! [`LmiError::Shape`] on a mismatch.

use nalgebra::DMatrix;

use crate::error::{check_finite, check_shape, LmiError, Result};
use crate::var::{Var, VarKind};

/// One term of an [`Expr`], occupying the block whose top-left corner is `(row, col)`.
#[derive(Clone, Debug)]
pub(crate) struct Term {
    pub(crate) row: usize,
    pub(crate) col: usize,
    pub(crate) kind: TermKind,
}

/// The two term shapes.
#[derive(Clone, Debug)]
pub(crate) enum TermKind {
    /// `left * op(var) * right`, `op` the transpose when `transposed`.
    Product {
        left: DMatrix<f64>,
        var: Var,
        transposed: bool,
        right: DMatrix<f64>,
    },
    /// `var * coeff` for a scalar `var`.
    Scaled { var: Var, coeff: DMatrix<f64> },
}

impl Term {
    /// Shape of the block the term occupies.
    pub(crate) fn shape(&self) -> (usize, usize) {
        match &self.kind {
            TermKind::Product { left, right, .. } => (left.nrows(), right.ncols()),
            TermKind::Scaled { coeff, .. } => coeff.shape(),
        }
    }

    /// The variable the term is linear in.
    pub(crate) fn var(&self) -> Var {
        match &self.kind {
            TermKind::Product { var, .. } | TermKind::Scaled { var, .. } => *var,
        }
    }

    /// Whether every coefficient of the term is zero.
    fn is_zero(&self) -> bool {
        let all_zero = |m: &DMatrix<f64>| m.iter().all(|&x| x == 0.0);
        match &self.kind {
            TermKind::Product { left, right, .. } => all_zero(left) || all_zero(right),
            TermKind::Scaled { coeff, .. } => all_zero(coeff),
        }
    }

    /// Multiplies the term's coefficients by `factor`.
    fn scale(&mut self, factor: f64) {
        match &mut self.kind {
            TermKind::Product { left, .. } => *left *= factor,
            TermKind::Scaled { coeff, .. } => *coeff *= factor,
        }
    }

    /// The term of the transposed expression.
    fn transpose(self) -> Term {
        let kind = match self.kind {
            TermKind::Product {
                left,
                var,
                transposed,
                right,
            } => TermKind::Product {
                left: right.transpose(),
                var,
                transposed: !transposed,
                right: left.transpose(),
            },
            TermKind::Scaled { var, coeff } => TermKind::Scaled {
                var,
                coeff: coeff.transpose(),
            },
        };
        Term {
            row: self.col,
            col: self.row,
            kind,
        }
    }
}

/// Affine matrix expression `C + sum of terms` in the decision variables.
#[derive(Clone, Debug)]
pub struct Expr {
    constant: DMatrix<f64>,
    terms: Vec<Term>,
}

/// A grid of optional blocks for [`Expr::blocks`] and [`Expr::sym_blocks`]; `None` is a zero block.
pub type BlockGrid = Vec<Vec<Option<Expr>>>;

impl Expr {
    /// The zero `rows x cols` expression.
    pub fn zeros(rows: usize, cols: usize) -> Expr {
        Expr {
            constant: DMatrix::zeros(rows, cols),
            terms: Vec::new(),
        }
    }

    /// The constant identity `n x n`.
    pub fn identity(n: usize) -> Expr {
        Expr {
            constant: DMatrix::identity(n, n),
            terms: Vec::new(),
        }
    }

    /// A constant expression; errors on NaN or infinite entries.
    pub fn constant(m: &DMatrix<f64>) -> Result<Expr> {
        check_finite(|| "constant matrix".into(), m.iter())?;
        Ok(Expr {
            constant: m.clone(),
            terms: Vec::new(),
        })
    }

    /// The variable itself, as an expression of its shape (scalars give `1 x 1`).
    pub fn var(v: Var) -> Expr {
        let (r, c) = v.shape();
        Expr::single(
            (r, c),
            TermKind::Product {
                left: DMatrix::identity(r, r),
                var: v,
                transposed: false,
                right: DMatrix::identity(c, c),
            },
        )
    }

    /// `left * v * right`.
    pub fn product(left: &DMatrix<f64>, v: Var, right: &DMatrix<f64>) -> Result<Expr> {
        Expr::product_op(left, v, false, right)
    }

    /// `left * v' * right`.
    pub fn product_t(left: &DMatrix<f64>, v: Var, right: &DMatrix<f64>) -> Result<Expr> {
        Expr::product_op(left, v, true, right)
    }

    /// `v * coeff` for a scalar variable `v` (e.g. `-g I`).
    pub fn scaled(v: Var, coeff: &DMatrix<f64>) -> Result<Expr> {
        if v.kind() != VarKind::Scalar {
            return Err(LmiError::Variable {
                what: format!("scaled() needs a scalar variable, got {:?}", v.kind()),
            });
        }
        check_finite(|| "scaled() coefficient".into(), coeff.iter())?;
        Ok(Expr::single(
            coeff.shape(),
            TermKind::Scaled {
                var: v,
                coeff: coeff.clone(),
            },
        ))
    }

    /// Sum of expressions that all have shape `rows x cols` (the zero matrix if empty).
    pub fn sum(rows: usize, cols: usize, items: impl IntoIterator<Item = Expr>) -> Result<Expr> {
        items
            .into_iter()
            .try_fold(Expr::zeros(rows, cols), |acc, e| acc.add(e))
    }

    /// Block matrix from a rectangular grid; `None` blocks are zero and take
    /// their size from the other blocks of their block row and column.
    pub fn blocks(grid: BlockGrid) -> Result<Expr> {
        let n_rows = grid.len();
        let n_cols = grid.first().map_or(0, Vec::len);
        let mut heights = vec![None; n_rows];
        let mut widths = vec![None; n_cols];
        for (i, row) in grid.iter().enumerate() {
            check_shape(
                || format!("block grid row {i}"),
                (1, n_cols),
                (1, row.len()),
            )?;
            for (j, block) in row.iter().enumerate() {
                if let Some(b) = block {
                    let (h, w) = b.shape();
                    let op = || format!("block ({i}, {j})");
                    settle(&mut heights[i], h, |m| shape_error(op(), (m, w), (h, w)))?;
                    settle(&mut widths[j], w, |m| shape_error(op(), (h, m), (h, w)))?;
                }
            }
        }
        let heights = resolve(heights, "block row")?;
        let widths = resolve(widths, "block column")?;
        let mut out = Expr::zeros(heights.iter().sum(), widths.iter().sum());
        let mut r0 = 0;
        for (row, h) in grid.into_iter().zip(&heights) {
            let mut c0 = 0;
            for (block, w) in row.into_iter().zip(&widths) {
                if let Some(b) = block {
                    out.embed(b, r0, c0);
                }
                c0 += w;
            }
            r0 += h;
        }
        Ok(out)
    }

    /// Symmetric block matrix `[[E11, E12, ..], [*, E22, ..], ..]` from its upper
    /// block triangle: blocks below the diagonal must be `None` and are implied as
    /// transposes; `None` blocks on or above the diagonal are zero.
    pub fn sym_blocks(upper: BlockGrid) -> Result<Expr> {
        let k = upper.len();
        let mut sizes = vec![None; k];
        for (i, row) in upper.iter().enumerate() {
            check_shape(
                || format!("symmetric block grid row {i}"),
                (1, k),
                (1, row.len()),
            )?;
            for (j, block) in row.iter().enumerate() {
                let Some(b) = block else { continue };
                if j < i {
                    return Err(LmiError::Dimension {
                        what: format!(
                            "sym_blocks takes the upper triangle: block ({i}, {j}) must be None"
                        ),
                    });
                }
                let (h, w) = b.shape();
                let op = || format!("symmetric block ({i}, {j})");
                settle(&mut sizes[i], h, |m| shape_error(op(), (m, w), (h, w)))?;
                settle(&mut sizes[j], w, |m| shape_error(op(), (h, m), (h, w)))?;
            }
        }
        let sizes = resolve(sizes, "diagonal block")?;
        let mut full: BlockGrid = (0..k).map(|_| vec![None; k]).collect();
        for (i, row) in upper.into_iter().enumerate() {
            for (j, block) in row.into_iter().enumerate() {
                let Some(b) = block else { continue };
                if j > i {
                    full[j][i] = Some(b.clone().transpose());
                }
                full[i][j] = Some(b);
            }
        }
        for (i, &n) in sizes.iter().enumerate() {
            full[i][i].get_or_insert_with(|| Expr::zeros(n, n));
        }
        Expr::blocks(full)
    }

    /// Shape `(rows, cols)`.
    pub fn shape(&self) -> (usize, usize) {
        self.constant.shape()
    }

    /// Sum of two expressions of equal shape.
    #[allow(clippy::should_implement_trait)]
    pub fn add(mut self, other: Expr) -> Result<Expr> {
        check_shape(|| "add".into(), self.shape(), other.shape())?;
        self.constant += other.constant;
        self.terms.extend(other.terms);
        Ok(self)
    }

    /// Difference of two expressions of equal shape.
    #[allow(clippy::should_implement_trait)]
    pub fn sub(self, other: Expr) -> Result<Expr> {
        self.add(other.scale(-1.0)?)
    }

    /// Adds a constant matrix of the same shape.
    pub fn add_constant(self, m: &DMatrix<f64>) -> Result<Expr> {
        self.add(Expr::constant(m)?)
    }

    /// Multiplies by a finite scalar.
    pub fn scale(mut self, factor: f64) -> Result<Expr> {
        check_finite(|| "scale factor".into(), [factor].iter())?;
        self.constant *= factor;
        self.terms.iter_mut().for_each(|t| t.scale(factor));
        Ok(self.pruned())
    }

    /// The transposed expression.
    pub fn transpose(self) -> Expr {
        Expr {
            constant: self.constant.transpose(),
            terms: self.terms.into_iter().map(Term::transpose).collect(),
        }
    }

    /// `He(S) = S + S'` of a square expression.
    pub fn he(self) -> Result<Expr> {
        let (r, c) = self.shape();
        check_shape(|| "he (needs a square expression)".into(), (r, r), (r, c))?;
        let t = self.clone().transpose();
        self.add(t)
    }

    /// `m * self`.
    pub fn left_mul(mut self, m: &DMatrix<f64>) -> Result<Expr> {
        check_shape(
            || "left_mul: columns of the factor".into(),
            (m.nrows(), self.shape().0),
            m.shape(),
        )?;
        check_finite(|| "left_mul factor".into(), m.iter())?;
        self.constant = m * &self.constant;
        for t in &mut self.terms {
            let (h, _) = t.shape();
            let sub = m.columns(t.row, h);
            match &mut t.kind {
                TermKind::Product { left, .. } => *left = sub * &*left,
                TermKind::Scaled { coeff, .. } => *coeff = sub * &*coeff,
            }
            t.row = 0;
        }
        Ok(self.pruned())
    }

    /// `self * m`.
    pub fn right_mul(mut self, m: &DMatrix<f64>) -> Result<Expr> {
        check_shape(
            || "right_mul: rows of the factor".into(),
            (self.shape().1, m.ncols()),
            m.shape(),
        )?;
        check_finite(|| "right_mul factor".into(), m.iter())?;
        self.constant = &self.constant * m;
        for t in &mut self.terms {
            let (_, w) = t.shape();
            let sub = m.rows(t.col, w);
            match &mut t.kind {
                TermKind::Product { right, .. } => *right = &*right * sub,
                TermKind::Scaled { coeff, .. } => *coeff = &*coeff * sub,
            }
            t.col = 0;
        }
        Ok(self.pruned())
    }

    /// Trace of a square expression, as a `1 x 1` expression.
    pub fn trace(self) -> Result<Expr> {
        let (r, c) = self.shape();
        check_shape(
            || "trace (needs a square expression)".into(),
            (r, r),
            (r, c),
        )?;
        let mut terms = Vec::new();
        for t in &self.terms {
            let (h, w) = t.shape();
            let first = t.row.max(t.col);
            let last = (t.row + h).min(t.col + w);
            for a in first..last {
                let (i, j) = (a - t.row, a - t.col);
                let kind = match &t.kind {
                    TermKind::Product {
                        left,
                        var,
                        transposed,
                        right,
                    } => TermKind::Product {
                        left: left.rows(i, 1).into_owned(),
                        var: *var,
                        transposed: *transposed,
                        right: right.columns(j, 1).into_owned(),
                    },
                    TermKind::Scaled { var, coeff } => TermKind::Scaled {
                        var: *var,
                        coeff: DMatrix::from_element(1, 1, coeff[(i, j)]),
                    },
                };
                terms.push(Term {
                    row: 0,
                    col: 0,
                    kind,
                });
            }
        }
        Ok(Expr {
            constant: DMatrix::from_element(1, 1, self.constant.trace()),
            terms,
        }
        .pruned())
    }

    /// The constant part.
    pub(crate) fn constant_part(&self) -> &DMatrix<f64> {
        &self.constant
    }

    /// The terms.
    pub(crate) fn terms(&self) -> &[Term] {
        &self.terms
    }

    /// Expression with one term covering the whole `shape`.
    fn single(shape: (usize, usize), kind: TermKind) -> Expr {
        Expr {
            constant: DMatrix::zeros(shape.0, shape.1),
            terms: vec![Term {
                row: 0,
                col: 0,
                kind,
            }],
        }
        .pruned()
    }

    fn product_op(
        left: &DMatrix<f64>,
        v: Var,
        transposed: bool,
        right: &DMatrix<f64>,
    ) -> Result<Expr> {
        let (vr, vc) = v.shape();
        let (r, c) = if transposed { (vc, vr) } else { (vr, vc) };
        let op = if transposed { "product_t" } else { "product" };
        check_shape(
            || format!("{op}: left factor"),
            (left.nrows(), r),
            left.shape(),
        )?;
        check_shape(
            || format!("{op}: right factor"),
            (c, right.ncols()),
            right.shape(),
        )?;
        check_finite(|| format!("{op} factors"), left.iter().chain(right.iter()))?;
        Ok(Expr::single(
            (left.nrows(), right.ncols()),
            TermKind::Product {
                left: left.clone(),
                var: v,
                transposed,
                right: right.clone(),
            },
        ))
    }

    /// Adds `block` with its top-left corner at `(r0, c0)`; the caller checked it fits.
    fn embed(&mut self, block: Expr, r0: usize, c0: usize) {
        let (h, w) = block.shape();
        self.constant
            .view_mut((r0, c0), (h, w))
            .copy_from(&block.constant);
        self.terms.extend(block.terms.into_iter().map(|mut t| {
            t.row += r0;
            t.col += c0;
            t
        }));
    }

    /// Drops terms whose coefficients are all zero.
    fn pruned(mut self) -> Expr {
        self.terms.retain(|t| !t.is_zero());
        self
    }
}

/// Records a block dimension, or checks it against the one already recorded
/// (`conflict` receives the recorded one).
fn settle(
    slot: &mut Option<usize>,
    n: usize,
    conflict: impl FnOnce(usize) -> LmiError,
) -> Result<()> {
    match *slot {
        Some(m) if m != n => Err(conflict(m)),
        _ => {
            *slot = Some(n);
            Ok(())
        }
    }
}

fn shape_error(op: String, expected: (usize, usize), found: (usize, usize)) -> LmiError {
    LmiError::Shape {
        op,
        expected,
        found,
    }
}

/// Turns inferred block dimensions into sizes, failing on one that no block fixes.
fn resolve(sizes: Vec<Option<usize>>, what: &str) -> Result<Vec<usize>> {
    sizes
        .into_iter()
        .enumerate()
        .map(|(i, s)| {
            s.ok_or_else(|| LmiError::Dimension {
                what: format!("{what} {i} has no block to take its size from"),
            })
        })
        .collect()
}
