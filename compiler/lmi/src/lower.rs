//! Lowering to the [`ConeProgram`] `A x + s = b, s ∈ K`.
//!
//! Every constraint is lowered once, when it is added, into a [`ConeBlock`]
//! of rows `s = b - A x` in one cone:
//! - an LMI `sign · E(x) ⪰ margin · I` of size `n > 1` becomes a
//!   [`Cone::PsdTriangle`] whose slack is the packed upper triangle of
//!   `sign · E(x) - margin · I` (see [`crate::cone`]);
//!   a `1 x 1` LMI becomes a non-negative row;
//! - scalar inequalities become non-negative rows, equalities zero rows.
//!
//! Coefficients come straight from the non-zeros of the term factors: the
//! coefficient of `V[p, q]` in entry `(a, b)` of `L V R` is `L[a, p] R[q, b]`,
//! and entries of a symmetric variable that share an unknown are merged.
//! [`assemble`] stacks the blocks: equalities, inequalities, then PSD cones.

use crate::cone::{Cone, ConeBlock, ConeProgram, CscMatrix};
use crate::constraint::{LmiSense, Relation};
use crate::error::{LmiError, Result};
use crate::expr::{Expr, TermKind};
use crate::objective::LinearForm;

/// Relative tolerance for the coefficient-wise symmetry check of LMIs.
const SYMMETRY_TOL: f64 = 1e-10;

/// Position of entry `(i, j)`, `i <= j`, in the column-major packed upper triangle.
fn svec_index(i: usize, j: usize) -> usize {
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

/// The key `(col, row, unknown)` as one integer of the same order (`col`
/// and `row` below 2^32).
fn pack(col: usize, row: usize, unknown: usize) -> u128 {
    ((col as u128) << 96) | ((row as u128) << 64) | unknown as u128
}

/// The key [`pack`] packed.
fn unpack(k: u128) -> (usize, usize, usize) {
    (
        (k >> 96) as usize,
        ((k >> 64) & 0xffff_ffff) as usize,
        (k & u128::from(u64::MAX)) as usize,
    )
}

/// Lowers `sign · expr ⪰ margin · I`, checking symmetry coefficient by coefficient.
pub(crate) fn lower_lmi(
    name: &str,
    expr: &Expr,
    sense: LmiSense,
    margin: f64,
) -> Result<ConeBlock> {
    let n = expr.shape().0;
    let sign = sense.sign();
    // Key (col, row, unknown) of the upper triangle; value: (sum from the upper
    // entry, sum from the mirrored lower entry). Diagonal entries feed both.
    let mut items = Vec::new();
    for_each_coefficient(expr, |i, j, u, c| {
        let halves = [if i <= j { c } else { 0.0 }, if i >= j { c } else { 0.0 }];
        items.push(((i.max(j), i.min(j), u), halves));
    });
    let add = |x: [f64; 2], y: [f64; 2]| [x[0] + y[0], x[1] + y[1]];
    let merged = if u32::try_from(n).is_ok() {
        // The same order, keys and sums with the key packed into one
        // integer (cheaper to compare and move while sorting).
        let packed = items
            .into_iter()
            .map(|((j, i, u), h)| (pack(j, i, u), h))
            .collect();
        merge(packed, add)
            .into_iter()
            .map(|(k, h)| (unpack(k), h))
            .collect()
    } else {
        merge(items, add)
    };

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
        Cone::Nonnegative(1)
    } else {
        Cone::PsdTriangle(n)
    };
    Ok(ConeBlock { cone, b, a })
}

/// Lowers the scalar relation `expr (relation) rhs` of a `1 x 1` expression.
pub(crate) fn lower_scalar(expr: &Expr, relation: Relation, rhs: f64) -> ConeBlock {
    let sign = if relation == Relation::Le { -1.0 } else { 1.0 };
    let form = lower_linear_form(expr);
    ConeBlock {
        cone: if relation == Relation::Eq {
            Cone::Zero(1)
        } else {
            Cone::Nonnegative(1)
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

/// Position of a block's cone in the stacking order: equalities, inequalities, PSD cones.
fn stacking_group(cone: Cone) -> u8 {
    match cone {
        Cone::Zero(_) => 0,
        Cone::Nonnegative(_) => 1,
        Cone::PsdTriangle(_) => 2,
    }
}

/// Stacks the blocks into one program over `unknowns` unknowns with cost `q`:
/// equality rows first (one [`Cone::Zero`]), then inequality rows (one
/// [`Cone::Nonnegative`]), then one [`Cone::PsdTriangle`] per LMI, each group
/// in the blocks' order.
pub(crate) fn assemble<'a>(
    unknowns: usize,
    blocks: impl IntoIterator<Item = &'a ConeBlock>,
    q: Vec<f64>,
) -> ConeProgram {
    let mut blocks: Vec<&ConeBlock> = blocks.into_iter().collect();
    blocks.sort_by_key(|block| stacking_group(block.cone));

    let mut b = Vec::new();
    let mut entries = Vec::new();
    let mut cones: Vec<Cone> = Vec::new();
    for block in blocks {
        let offset = b.len();
        b.extend_from_slice(&block.b);
        entries.extend(block.a.iter().map(|&(r, u, v)| ((u, offset + r), v)));
        match (cones.last_mut(), block.cone) {
            (Some(Cone::Zero(n)), Cone::Zero(m))
            | (Some(Cone::Nonnegative(n)), Cone::Nonnegative(m)) => *n += m,
            (_, cone) => cones.push(cone),
        }
    }

    // Row blocks are disjoint and merged per constraint, so keys are unique.
    let entries = merge(entries, |x, y| x + y);
    let mut colptr = vec![0usize; unknowns + 1];
    for &((u, _), _) in &entries {
        colptr[u + 1] += 1;
    }
    for u in 0..unknowns {
        colptr[u + 1] += colptr[u];
    }
    let (rowval, nzval) = entries.into_iter().map(|((_, r), v)| (r, v)).unzip();
    let a = CscMatrix {
        nrows: b.len(),
        ncols: unknowns,
        colptr,
        rowval,
        nzval,
    };
    ConeProgram {
        n_vars: unknowns,
        p: CscMatrix::zeros(unknowns, unknowns),
        q,
        a,
        b,
        cones,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn block(cone: Cone, b: &[f64], a: &[(usize, usize, f64)]) -> ConeBlock {
        ConeBlock {
            cone,
            b: b.to_vec(),
            a: a.to_vec(),
        }
    }

    #[test]
    fn blocks_are_stacked_by_cone_and_scalar_rows_share_a_cone() {
        let psd = block(Cone::PsdTriangle(2), &[1.0, 2.0, 3.0], &[(1, 0, -1.0)]);
        let ge = block(Cone::Nonnegative(1), &[4.0], &[(0, 1, 2.0)]);
        let eq = block(Cone::Zero(1), &[5.0], &[(0, 0, 3.0)]);
        let le = block(Cone::Nonnegative(1), &[6.0], &[]);
        let program = assemble(2, [&psd, &ge, &eq, &le], vec![1.0, 0.0]);
        assert_eq!(
            program.cones,
            vec![Cone::Zero(1), Cone::Nonnegative(2), Cone::PsdTriangle(2)]
        );
        assert_eq!(program.b, vec![5.0, 4.0, 6.0, 1.0, 2.0, 3.0]);
        // Column 0: the equality (row 0) and the PSD off-diagonal (row 4).
        let triplets: Vec<_> = program.a.triplets().collect();
        assert_eq!(triplets, vec![(0, 0, 3.0), (4, 0, -1.0), (1, 1, 2.0)]);
        assert_eq!(program.a.nrows, 6);
        assert_eq!(program.p.nnz(), 0);
        let rows: usize = program.cones.iter().map(|c| c.dim()).sum();
        assert_eq!(rows, program.b.len());
    }

    #[test]
    fn packed_keys_keep_the_order_and_the_keys() {
        let keys = [
            (0, 0, 0),
            (0, 0, 7),
            (1, 0, 3),
            (1, 1, 0),
            (5, 2, 1 << 40),
            (5, 3, 0),
        ];
        for w in keys.windows(2) {
            assert!(super::pack(w[0].0, w[0].1, w[0].2) < super::pack(w[1].0, w[1].1, w[1].2));
        }
        for k in keys {
            assert_eq!(super::unpack(super::pack(k.0, k.1, k.2)), k);
        }
    }

    #[test]
    fn merge_sums_equal_keys_in_order() {
        let merged = merge(vec![(2, 1.0), (0, 0.5), (2, 2.0), (1, 0.0)], |x, y| x + y);
        assert_eq!(merged, vec![(0, 0.5), (1, 0.0), (2, 3.0)]);
    }
}
