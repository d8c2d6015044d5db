//! Lowering to Clarabel's conic form `A x + s = b, s ∈ K`.
//!
//! Every constraint is lowered once, when it is added, into rows
//! `s = b - A x` of one cone:
//! - an LMI `sign · E(x) ⪰ margin · I` of size `n > 1` becomes a
//!   `PSDTriangleConeT(n)` whose slack is the upper triangle of
//!   `sign · E(x) - margin · I`, column by column, off-diagonals times `√2`;
//!   a `1 x 1` LMI becomes a non-negative row;
//! - scalar inequalities become non-negative rows, equalities zero rows.
//!
//! Coefficients come straight from the non-zeros of the term factors: the
//! coefficient of `V[p, q]` in entry `(a, b)` of `L V R` is `L[a, p] R[q, b]`,
//! and entries of a symmetric variable that share an unknown are merged.

use clarabel::algebra::CscMatrix;
use clarabel::solver::SupportedConeT;

use crate::constraint::{LmiSense, Relation};
use crate::error::{LmiError, Result};
use crate::expr::{Expr, TermKind};
use crate::problem::{ObjectiveSense, Problem};

/// Relative tolerance for the coefficient-wise symmetry check of LMIs.
const SYMMETRY_TOL: f64 = 1e-10;

/// The cone a lowered constraint lives in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum ConeKind {
    Zero,
    Nonneg,
    Psd(usize),
}

/// Rows `s = b - A x` of one constraint: `a` holds merged `(local row, unknown, value)`.
#[derive(Clone, Debug)]
pub(crate) struct Lowered {
    pub(crate) cone: ConeKind,
    pub(crate) b: Vec<f64>,
    pub(crate) a: Vec<(usize, usize, f64)>,
}

/// A linear form `constant + sum coeff · x[unknown]` with merged, sorted coefficients.
#[derive(Clone, Debug, Default)]
pub(crate) struct LinearForm {
    pub(crate) coeffs: Vec<(usize, f64)>,
    pub(crate) constant: f64,
}

/// Position of entry `(i, j)`, `i <= j`, in the column-major packed upper triangle.
pub(crate) fn svec_index(i: usize, j: usize) -> usize {
    j * (j + 1) / 2 + i
}

/// Calls `f(row, col, unknown, coefficient)` for every structural coefficient
/// of the expression's terms (unmerged; the constant is not visited).
pub(crate) fn for_each_coefficient(expr: &Expr, mut f: impl FnMut(usize, usize, usize, f64)) {
    for t in expr.terms() {
        match &t.kind {
            TermKind::Product {
                left,
                var,
                transposed,
                right,
            } => {
                let lnz: Vec<Vec<(usize, f64)>> = (0..left.ncols())
                    .map(|p| nonzeros(left.column(p).iter()))
                    .collect();
                let rnz: Vec<Vec<(usize, f64)>> = (0..right.nrows())
                    .map(|q| nonzeros(right.row(q).iter()))
                    .collect();
                for (i, j, u) in var.kind.entries() {
                    let (p, q) = if *transposed { (j, i) } else { (i, j) };
                    for &(a, l) in &lnz[p] {
                        for &(b, r) in &rnz[q] {
                            f(t.row + a, t.col + b, var.offset + u, l * r);
                        }
                    }
                }
            }
            TermKind::Scaled { var, coeff } => {
                for (b, column) in coeff.column_iter().enumerate() {
                    for (a, c) in nonzeros(column.iter()) {
                        f(t.row + a, t.col + b, var.offset, c);
                    }
                }
            }
        }
    }
}

/// `(index, value)` of the non-zero values.
fn nonzeros<'a>(values: impl Iterator<Item = &'a f64>) -> Vec<(usize, f64)> {
    values
        .enumerate()
        .filter(|(_, v)| **v != 0.0)
        .map(|(k, v)| (k, *v))
        .collect()
}

/// Sorts by key (stably, so summation order is deterministic) and merges equal keys.
fn merge<K: Ord + Copy, V: Copy>(mut items: Vec<(K, V)>, add: impl Fn(V, V) -> V) -> Vec<(K, V)> {
    items.sort_by_key(|x| x.0);
    let mut out: Vec<(K, V)> = Vec::with_capacity(items.len());
    for (k, v) in items {
        match out.last_mut() {
            Some((last, acc)) if *last == k => *acc = add(*acc, v),
            _ => out.push((k, v)),
        }
    }
    out
}

/// Lowers `sign · expr ⪰ margin · I`, checking symmetry coefficient by coefficient.
pub(crate) fn lower_lmi(name: &str, expr: &Expr, sense: LmiSense, margin: f64) -> Result<Lowered> {
    let n = expr.shape().0;
    let sign = sense.sign();
    // Key (col, row, unknown) of the upper triangle; value: (sum from the upper
    // entry, sum from the mirrored lower entry). Diagonal entries feed both.
    let mut items = Vec::new();
    for_each_coefficient(expr, |i, j, u, c| {
        let halves = [if i <= j { c } else { 0.0 }, if i >= j { c } else { 0.0 }];
        items.push(((i.max(j), i.min(j), u), halves));
    });
    let merged = merge(items, |x, y| [x[0] + y[0], x[1] + y[1]]);

    let c0 = expr.constant_part();
    let upper_pairs = (0..n).flat_map(|j| (0..=j).map(move |i| (i, j)));
    let constant_pairs = upper_pairs.clone().map(|(i, j)| [c0[(i, j)], c0[(j, i)]]);
    let (scale, mismatch) = merged
        .iter()
        .map(|(_, h)| *h)
        .chain(constant_pairs)
        .fold((0.0f64, 0.0f64), |(s, m), [up, lo]| {
            (s.max(up.abs()).max(lo.abs()), m.max((up - lo).abs()))
        });
    if mismatch > SYMMETRY_TOL * scale {
        return Err(LmiError::NotSymmetric {
            constraint: name.to_owned(),
            mismatch,
        });
    }

    let weight = |i: usize, j: usize| {
        if i == j {
            1.0
        } else {
            std::f64::consts::SQRT_2
        }
    };
    let a = merged
        .into_iter()
        .map(|((j, i, u), [up, lo])| (svec_index(i, j), u, -sign * weight(i, j) * 0.5 * (up + lo)))
        .filter(|&(_, _, v)| v != 0.0)
        .collect();
    let b = upper_pairs
        .map(|(i, j)| {
            let sym = sign * 0.5 * (c0[(i, j)] + c0[(j, i)]);
            if i == j {
                sym - margin
            } else {
                weight(i, j) * sym
            }
        })
        .collect();
    let cone = if n == 1 {
        ConeKind::Nonneg
    } else {
        ConeKind::Psd(n)
    };
    Ok(Lowered { cone, b, a })
}

/// Lowers the scalar relation `expr (relation) rhs` of a `1 x 1` expression.
pub(crate) fn lower_scalar(expr: &Expr, relation: Relation, rhs: f64) -> Lowered {
    let sign = if relation == Relation::Le { -1.0 } else { 1.0 };
    let form = lower_linear_form(expr);
    Lowered {
        cone: if relation == Relation::Eq {
            ConeKind::Zero
        } else {
            ConeKind::Nonneg
        },
        b: vec![sign * (form.constant - rhs)],
        a: form
            .coeffs
            .into_iter()
            .map(|(u, c)| (0, u, -sign * c))
            .collect(),
    }
}

/// The linear form of a `1 x 1` expression.
pub(crate) fn lower_linear_form(expr: &Expr) -> LinearForm {
    let mut items = Vec::new();
    for_each_coefficient(expr, |_, _, u, c| items.push((u, c)));
    let mut coeffs = merge(items, |x, y| x + y);
    coeffs.retain(|&(_, c)| c != 0.0);
    LinearForm {
        coeffs,
        constant: expr.constant_part()[(0, 0)],
    }
}

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

impl std::fmt::Display for ProblemStats {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
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

/// The whole problem in Clarabel's form (`P = 0`).
pub(crate) struct Assembled {
    pub(crate) q: Vec<f64>,
    pub(crate) a: CscMatrix<f64>,
    pub(crate) b: Vec<f64>,
    pub(crate) cones: Vec<SupportedConeT<f64>>,
}

/// Order of the constraints' row blocks: equalities, inequalities, then PSD cones.
fn solver_order(problem: &Problem) -> Vec<usize> {
    let group = |cone: ConeKind| match cone {
        ConeKind::Zero => 0,
        ConeKind::Nonneg => 1,
        ConeKind::Psd(_) => 2,
    };
    let mut order: Vec<usize> = (0..problem.constraints.len()).collect();
    order.sort_by_key(|&k| group(problem.constraints[k].lowered.cone));
    order
}

impl Problem {
    /// Size statistics for reports.
    pub fn stats(&self) -> ProblemStats {
        let mut stats = ProblemStats {
            variables: self.vars.len(),
            scalar_unknowns: self.unknowns,
            ..ProblemStats::default()
        };
        for k in solver_order(self) {
            let c = &self.constraints[k];
            match c.kind {
                crate::ConstraintKind::Lmi { .. } => stats.lmis += 1,
                crate::ConstraintKind::Scalar { .. } => stats.scalar_constraints += 1,
            }
            match c.lowered.cone {
                ConeKind::Zero => stats.zero_rows += 1,
                ConeKind::Nonneg => stats.nonneg_rows += 1,
                ConeKind::Psd(n) => stats.psd_cones.push(n),
            }
            stats.rows += c.lowered.b.len();
            stats.nnz += c.lowered.a.len();
        }
        stats
    }

    /// Assembles `q, A, b` and the cones.
    pub(crate) fn assemble(&self) -> Assembled {
        let mut b = Vec::new();
        let mut entries = Vec::new();
        let (mut zero_rows, mut nonneg_rows, mut psd) = (0, 0, Vec::new());
        for k in solver_order(self) {
            let lowered = &self.constraints[k].lowered;
            let offset = b.len();
            b.extend_from_slice(&lowered.b);
            entries.extend(lowered.a.iter().map(|&(r, u, v)| ((u, offset + r), v)));
            match lowered.cone {
                ConeKind::Zero => zero_rows += 1,
                ConeKind::Nonneg => nonneg_rows += 1,
                ConeKind::Psd(n) => psd.push(SupportedConeT::PSDTriangleConeT(n)),
            }
        }
        let mut cones = Vec::with_capacity(psd.len() + 2);
        if zero_rows > 0 {
            cones.push(SupportedConeT::ZeroConeT(zero_rows));
        }
        if nonneg_rows > 0 {
            cones.push(SupportedConeT::NonnegativeConeT(nonneg_rows));
        }
        cones.extend(psd);

        // Row blocks are disjoint and merged per constraint, so keys are unique.
        let entries = merge(entries, |x, y| x + y);
        let mut colptr = vec![0usize; self.unknowns + 1];
        for &((u, _), _) in &entries {
            colptr[u + 1] += 1;
        }
        for u in 0..self.unknowns {
            colptr[u + 1] += colptr[u];
        }
        let (rowval, nzval) = entries.into_iter().map(|((_, r), v)| (r, v)).unzip();
        let a = CscMatrix::new(b.len(), self.unknowns, colptr, rowval, nzval);

        let sign = if self.sense == ObjectiveSense::Maximize {
            -1.0
        } else {
            1.0
        };
        let mut q = vec![0.0; self.unknowns];
        for &(u, c) in &self.objective.coeffs {
            q[u] = sign * c;
        }
        Assembled { q, a, b, cones }
    }
}

/// Dense `svec` of the upper triangle (off-diagonals times `√2`), for tests.
#[cfg(test)]
pub(crate) fn svec(m: &nalgebra::DMatrix<f64>) -> Vec<f64> {
    let n = m.nrows();
    (0..n)
        .flat_map(|j| (0..=j).map(move |i| (i, j)))
        .map(|(i, j)| {
            if i == j {
                m[(i, i)]
            } else {
                std::f64::consts::SQRT_2 * m[(i, j)]
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use nalgebra::DMatrix;

    use super::*;
    use crate::{Assignment, Expr, LmiError, Var};

    /// Deterministic pseudo-random matrix with entries in [-1, 1) (xorshift).
    fn pseudo_random(rows: usize, cols: usize, seed: u64) -> DMatrix<f64> {
        let mut s = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
        DMatrix::from_fn(rows, cols, |_, _| {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 11) as f64 / (1u64 << 52) as f64 - 1.0
        })
    }

    /// Fills every variable with pseudo-random values of the right structure.
    fn random_assignment(problem: &Problem, seed: u64) -> Assignment {
        let mut values = problem.assignment();
        let vars: Vec<Var> = problem.vars().map(|(_, v)| v).collect();
        for (k, v) in vars.into_iter().enumerate() {
            let (r, c) = v.shape();
            let m = pseudo_random(r, c, seed + k as u64);
            let m = match v.kind() {
                crate::VarKind::Symmetric(_) => (&m + m.transpose()) * 0.5,
                crate::VarKind::Diagonal(_) => DMatrix::from_diagonal(&m.diagonal()),
                _ => m,
            };
            values.set(v, m).expect("structured value");
        }
        values
    }

    fn dense(a: &CscMatrix<f64>) -> DMatrix<f64> {
        let mut d = DMatrix::zeros(a.m, a.n);
        for col in 0..a.n {
            for k in a.colptr[col]..a.colptr[col + 1] {
                d[(a.rowval[k], col)] += a.nzval[k];
            }
        }
        d
    }

    /// The H-inf-like block with every kind of variable and transposed terms.
    fn mixed_problem() -> Result<(Problem, Vec<f64>)> {
        let mut pr = Problem::new();
        let x = pr.symmetric("X", 3)?;
        let m = pr.full("M", 2, 3)?;
        let d = pr.diagonal("T", 2)?;
        let g = pr.scalar("g")?;
        let a = pseudo_random(3, 3, 1);
        let b = pseudo_random(3, 2, 2);
        let c = pseudo_random(2, 3, 3);
        let ups = Expr::var(x)
            .left_mul(&a)?
            .add(Expr::product(&b, m, &DMatrix::identity(3, 3))?)?
            .he()?
            .add(Expr::var(x).scale(0.7)?)?;
        let e12 = Expr::product_t(&DMatrix::identity(3, 3), m, &pseudo_random(2, 2, 5))?
            .add(Expr::constant(&b)?)?;
        let e22 = Expr::scaled(g, &(-DMatrix::identity(2, 2)))?
            .add(Expr::var(d))?
            .add(Expr::constant(&pseudo_random(2, 2, 9).he_like())?)?;
        let e13 = Expr::product(&DMatrix::identity(3, 3), x, &c.transpose())?;
        let lmi = Expr::sym_blocks(vec![
            vec![Some(ups), Some(e12), Some(e13)],
            vec![None, Some(e22), None],
            vec![None, None, Some(Expr::identity(2).scale(-1.0)?)],
        ])?;
        pr.nsd("Q", lmi.clone(), 0.25)?;
        pr.psd("Q flipped", lmi, 0.0)?;
        pr.add_scalar("g bound", Expr::var(g), crate::Relation::Le, 5.0)?;
        pr.add_scalar("trace", Expr::var(x).trace()?, crate::Relation::Eq, 1.0)?;
        pr.minimize(Expr::var(g))?;
        let x = random_assignment(&pr, 42).unknowns();
        Ok((pr, x))
    }

    trait HeLike {
        fn he_like(&self) -> DMatrix<f64>;
    }
    impl HeLike for DMatrix<f64> {
        fn he_like(&self) -> DMatrix<f64> {
            self + self.transpose()
        }
    }

    #[test]
    fn slack_equals_svec_of_evaluated_constraint() -> Result<()> {
        let (pr, x) = mixed_problem()?;
        let data = pr.assemble();
        let ax = dense(&data.a) * nalgebra::DVector::from_column_slice(&x);
        let slack: Vec<f64> = data.b.iter().zip(ax.iter()).map(|(b, a)| b - a).collect();
        let mut values = pr.assignment();
        for (_, v) in pr.vars() {
            let (r, c) = v.shape();
            let m = DMatrix::from_fn(r, c, |i, j| v.unknown_of(i, j).map_or(0.0, |u| x[u]));
            values.set(v, m)?;
        }
        // Expected slacks in solver order: equality, inequality, then the two PSD cones.
        let ids: Vec<_> = pr.constraints().collect();
        let e = pr.evaluate(ids[0], &values)?;
        let eye = DMatrix::<f64>::identity(e.nrows(), e.nrows());
        let mut expected = vec![pr.evaluate(ids[3], &values)?[(0, 0)] - 1.0];
        expected.push(5.0 - pr.evaluate(ids[2], &values)?[(0, 0)]);
        expected.extend(svec(&(-&e - &eye * 0.25)));
        expected.extend(svec(&e));
        assert_eq!(slack.len(), expected.len());
        let worst = slack
            .iter()
            .zip(&expected)
            .map(|(s, e)| (s - e).abs())
            .fold(0.0, f64::max);
        assert!(worst < 1e-12, "worst slack mismatch {worst:e}");
        assert_eq!(data.cones.len(), 4);
        assert_eq!(pr.stats().psd_cones, vec![7, 7]);
        assert_eq!(pr.stats().nnz, data.a.nzval.len());
        Ok(())
    }

    #[test]
    fn symmetric_unknown_is_one_column_and_packing_is_sqrt2() -> Result<()> {
        let mut pr = Problem::new();
        let x = pr.symmetric("X", 2)?;
        pr.psd("X", Expr::var(x), 0.0)?;
        let data = pr.assemble();
        // s = svec(X) = [x00, √2 x01, x11] = -A x.
        let a = dense(&data.a);
        let expected =
            DMatrix::from_row_slice(3, 3, &[-1.0, 0.0, 0.0, 0.0, -SQRT2, 0.0, 0.0, 0.0, -1.0]);
        assert_eq!(a, expected);
        Ok(())
    }
    const SQRT2: f64 = std::f64::consts::SQRT_2;

    #[test]
    fn asymmetric_lmi_is_rejected() -> Result<()> {
        let mut pr = Problem::new();
        let x = pr.symmetric("X", 2)?;
        let a = DMatrix::from_row_slice(2, 2, &[1.0, 2.0, 0.0, 1.0]);
        let err = pr.nsd("AX", Expr::var(x).left_mul(&a)?, 0.0);
        assert!(matches!(err, Err(LmiError::NotSymmetric { .. })), "{err:?}");
        Ok(())
    }

    #[test]
    fn duplicate_triplets_are_merged() -> Result<()> {
        let mut pr = Problem::new();
        let x = pr.symmetric("X", 3)?;
        // X + X' + 2X: every unknown appears in four terms of each entry.
        let e = Expr::var(x).he()?.add(Expr::var(x).scale(2.0)?)?;
        pr.psd("4X", e, 0.0)?;
        let data = pr.assemble();
        assert_eq!(data.a.nzval.len(), 6);
        let diag = -4.0;
        let off = -4.0 * SQRT2;
        let expected = [diag, off, diag, off, off, diag];
        assert_eq!(data.a.nzval, expected);
        Ok(())
    }
}
