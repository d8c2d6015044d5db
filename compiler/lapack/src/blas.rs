//! Level-2/3 BLAS routines (`dgemm_`, `dgemv_`, `dsymv_`, `dsyrk_`,
//! `dsyr2k_`) with the `blas-sys` 0.7 argument lists.
//!
//! Illegal arguments are reported on stderr and the routine returns without
//! touching its output (OpenBLAS behaviour); reference BLAS would stop.

use core::ffi::{c_char, c_int};

use faer::linalg::matmul::matmul;
use faer::linalg::matmul::triangular::{matmul as tri_matmul, BlockStructure};
use faer::prelude::ReborrowMut;
use faer::{Accum, MatMut, MatRef, Par};

use crate::ffi::{
    blas_error, dim, first_bad, ld_min, mat_mut, mat_ref, opt, parse_trans, scale, vec_mut,
    vec_ref, Region, Uplo,
};

/// `op(X)`: `X` or its transpose.
fn op(x: MatRef<'_, f64>, trans: bool) -> MatRef<'_, f64> {
    if trans {
        x.transpose()
    } else {
        x
    }
}

/// `dst := beta * dst + alpha * lhs * rhs` (general shapes).
fn gemm_core(
    mut dst: MatMut<'_, f64>,
    alpha: f64,
    lhs: MatRef<'_, f64>,
    rhs: MatRef<'_, f64>,
    beta: f64,
) {
    scale(dst.rb_mut(), beta, Region::Full);
    if alpha != 0.0 && lhs.ncols() > 0 {
        matmul(dst, Accum::Add, lhs, rhs, alpha, Par::Seq);
    }
}

/// Block structure of one triangle (diagonal included).
fn tri_structure(uplo: Uplo) -> BlockStructure {
    match uplo {
        Uplo::Upper => BlockStructure::TriangularUpper,
        Uplo::Lower => BlockStructure::TriangularLower,
    }
}

/// `tri(dst) += alpha * lhs * rhs`, writing only the `uplo` triangle of the
/// square `dst`.
fn tri_update(
    dst: MatMut<'_, f64>,
    uplo: Uplo,
    alpha: f64,
    lhs: MatRef<'_, f64>,
    rhs: MatRef<'_, f64>,
) {
    tri_matmul(
        dst,
        tri_structure(uplo),
        Accum::Add,
        lhs,
        BlockStructure::Rectangular,
        rhs,
        BlockStructure::Rectangular,
        alpha,
        Par::Seq,
    );
}

/// General matrix product `C := alpha * op(A) * op(B) + beta * C`, with
/// `op(A)` `m x k`, `op(B)` `k x n` and `C` `m x n`.
///
/// Options: `transa`, `transb` in `N`, `T`, `C` (case-insensitive). With
/// `beta == 0` the input `C` is not read; with `alpha == 0` `A`/`B` are not
/// read.
///
/// # Safety
/// All pointers must be valid as in the reference BLAS (`A`, `B`, `C` with
/// the given leading dimensions); `C` must not alias `A` or `B`.
#[no_mangle]
pub unsafe extern "C" fn dgemm_(
    transa: *const c_char,
    transb: *const c_char,
    m: *const c_int,
    n: *const c_int,
    k: *const c_int,
    alpha: *const f64,
    a: *const f64,
    lda: *const c_int,
    b: *const f64,
    ldb: *const c_int,
    beta: *const f64,
    c: *mut f64,
    ldc: *const c_int,
) {
    let (ta, tb) = (parse_trans(opt(transa)), parse_trans(opt(transb)));
    let (m, n, k) = (*m, *n, *k);
    let nrowa = if ta == Some(true) { k } else { m };
    let nrowb = if tb == Some(true) { n } else { k };
    if let Some(pos) = first_bad(&[
        (ta.is_none(), 1),
        (tb.is_none(), 2),
        (m < 0, 3),
        (n < 0, 4),
        (k < 0, 5),
        (*lda < ld_min(nrowa), 8),
        (*ldb < ld_min(nrowb), 10),
        (*ldc < ld_min(m), 13),
    ]) {
        return blas_error("DGEMM ", pos);
    }
    let (ta, tb) = (ta == Some(true), tb == Some(true));
    let (m, n, k) = (dim(m), dim(n), dim(k));
    if m == 0 || n == 0 {
        return;
    }
    let (ra, ca) = if ta { (k, m) } else { (m, k) };
    let (rb, cb) = if tb { (n, k) } else { (k, n) };
    let a = op(mat_ref(a, ra, ca, dim(*lda)), ta);
    let b = op(mat_ref(b, rb, cb, dim(*ldb)), tb);
    gemm_core(mat_mut(c, m, n, dim(*ldc)), *alpha, a, b, *beta);
}

/// Matrix-vector product `y := alpha * op(A) * x + beta * y`, `A` `m x n`.
///
/// Options: `trans` in `N`, `T`, `C`; any non-zero `incx`/`incy` (negative
/// increments walk the vectors backwards, as in BLAS). With `beta == 0` `y`
/// is not read.
///
/// # Safety
/// Pointers valid as in the reference BLAS; `y` must not alias `A` or `x`.
#[no_mangle]
pub unsafe extern "C" fn dgemv_(
    trans: *const c_char,
    m: *const c_int,
    n: *const c_int,
    alpha: *const f64,
    a: *const f64,
    lda: *const c_int,
    x: *const f64,
    incx: *const c_int,
    beta: *const f64,
    y: *mut f64,
    incy: *const c_int,
) {
    let t = parse_trans(opt(trans));
    let (m, n) = (*m, *n);
    if let Some(pos) = first_bad(&[
        (t.is_none(), 1),
        (m < 0, 2),
        (n < 0, 3),
        (*lda < ld_min(m), 6),
        (*incx == 0, 8),
        (*incy == 0, 11),
    ]) {
        return blas_error("DGEMV ", pos);
    }
    let t = t == Some(true);
    let (m, n) = (dim(m), dim(n));
    if m == 0 || n == 0 {
        return;
    }
    let (lenx, leny) = if t { (m, n) } else { (n, m) };
    let a = op(mat_ref(a, m, n, dim(*lda)), t);
    let x = vec_ref(x, lenx, *incx);
    gemm_core(vec_mut(y, leny, *incy), *alpha, a, x, *beta);
}

/// Symmetric matrix-vector product `y := alpha * A * x + beta * y`, where
/// only the `uplo` triangle of the `n x n` matrix `A` is read.
///
/// Options: `uplo` in `U`, `L`; any non-zero `incx`/`incy`. With `beta == 0`
/// `y` is not read.
///
/// # Safety
/// Pointers valid as in the reference BLAS; `y` must not alias `A` or `x`.
#[no_mangle]
pub unsafe extern "C" fn dsymv_(
    uplo: *const c_char,
    n: *const c_int,
    alpha: *const f64,
    a: *const f64,
    lda: *const c_int,
    x: *const f64,
    incx: *const c_int,
    beta: *const f64,
    y: *mut f64,
    incy: *const c_int,
) {
    let ul = Uplo::parse(opt(uplo));
    let n = *n;
    if let Some(pos) = first_bad(&[
        (ul.is_none(), 1),
        (n < 0, 2),
        (*lda < ld_min(n), 5),
        (*incx == 0, 7),
        (*incy == 0, 10),
    ]) {
        return blas_error("DSYMV ", pos);
    }
    let ul = ul.expect("validated");
    let n = dim(n);
    if n == 0 {
        return;
    }
    let a = mat_ref(a, n, n, dim(*lda));
    let x = vec_ref(x, n, *incx);
    let mut y = vec_mut(y, n, *incy);
    scale(y.rb_mut(), *beta, Region::Full);
    if *alpha == 0.0 {
        return;
    }
    // A = T + S^T, T the stored triangle (with diagonal), S its strict part.
    let (tri, strict_t) = match ul {
        Uplo::Upper => (
            BlockStructure::TriangularUpper,
            BlockStructure::StrictTriangularLower,
        ),
        Uplo::Lower => (
            BlockStructure::TriangularLower,
            BlockStructure::StrictTriangularUpper,
        ),
    };
    for (lhs, structure) in [(a, tri), (a.transpose(), strict_t)] {
        tri_matmul(
            y.rb_mut(),
            BlockStructure::Rectangular,
            Accum::Add,
            lhs,
            structure,
            x,
            BlockStructure::Rectangular,
            *alpha,
            Par::Seq,
        );
    }
}

/// Validated arguments shared by `dsyrk_` and `dsyr2k_`.
struct RankK {
    uplo: Uplo,
    trans: bool,
    n: usize,
    k: usize,
}

/// Checks the common `uplo, trans, n, k, lda[, ldb], ldc` arguments of the
/// symmetric rank-k updates; `ldb` is `None` for `dsyrk_`. Returns the
/// offending position on failure.
fn check_rank_k(
    uplo: u8,
    trans: u8,
    n: c_int,
    k: c_int,
    lda: c_int,
    ldb: Option<c_int>,
    ldc: c_int,
) -> Result<RankK, c_int> {
    let ul = Uplo::parse(uplo);
    let t = parse_trans(trans);
    let nrowa = if t == Some(true) { k } else { n };
    let ldc_pos = if ldb.is_some() { 12 } else { 10 };
    let bad_b = ldb.is_some_and(|ldb| ldb < ld_min(nrowa));
    match first_bad(&[
        (ul.is_none(), 1),
        (t.is_none(), 2),
        (n < 0, 3),
        (k < 0, 4),
        (lda < ld_min(nrowa), 7),
        (bad_b, 9),
        (ldc < ld_min(n), ldc_pos),
    ]) {
        Some(pos) => Err(pos),
        None => Ok(RankK {
            uplo: ul.expect("validated"),
            trans: t == Some(true),
            n: dim(n),
            k: dim(k),
        }),
    }
}

/// Symmetric rank-k update of one triangle of `C` (`n x n`):
/// `C := alpha * A * A^T + beta * C` (`trans = N`, `A` `n x k`) or
/// `C := alpha * A^T * A + beta * C` (`trans = T`/`C`, `A` `k x n`).
///
/// Options: `uplo` in `U`, `L` (the other triangle is never read or
/// written), `trans` in `N`, `T`, `C`. With `beta == 0` `C` is not read.
///
/// # Safety
/// Pointers valid as in the reference BLAS; `C` must not alias `A`.
#[no_mangle]
pub unsafe extern "C" fn dsyrk_(
    uplo: *const c_char,
    trans: *const c_char,
    n: *const c_int,
    k: *const c_int,
    alpha: *const f64,
    a: *const f64,
    lda: *const c_int,
    beta: *const f64,
    c: *mut f64,
    ldc: *const c_int,
) {
    let args = match check_rank_k(opt(uplo), opt(trans), *n, *k, *lda, None, *ldc) {
        Ok(args) => args,
        Err(pos) => return blas_error("DSYRK ", pos),
    };
    let RankK { uplo, trans, n, k } = args;
    if n == 0 {
        return;
    }
    let (ra, ca) = if trans { (k, n) } else { (n, k) };
    let a = op(mat_ref(a, ra, ca, dim(*lda)), trans);
    let mut c = mat_mut(c, n, n, dim(*ldc));
    scale(c.rb_mut(), *beta, Region::Triangle(uplo));
    if *alpha != 0.0 && k > 0 {
        tri_update(c, uplo, *alpha, a, a.transpose());
    }
}

/// Symmetric rank-2k update of one triangle of `C` (`n x n`):
/// `C := alpha * (A * B^T + B * A^T) + beta * C` (`trans = N`, `A`, `B`
/// `n x k`) or `C := alpha * (A^T * B + B^T * A) + beta * C` (`trans = T`/`C`,
/// `A`, `B` `k x n`).
///
/// Options: `uplo` in `U`, `L` (the other triangle is never read or
/// written), `trans` in `N`, `T`, `C`. With `beta == 0` `C` is not read.
///
/// # Safety
/// Pointers valid as in the reference BLAS; `C` must not alias `A` or `B`.
#[no_mangle]
pub unsafe extern "C" fn dsyr2k_(
    uplo: *const c_char,
    trans: *const c_char,
    n: *const c_int,
    k: *const c_int,
    alpha: *const f64,
    a: *const f64,
    lda: *const c_int,
    b: *const f64,
    ldb: *const c_int,
    beta: *const f64,
    c: *mut f64,
    ldc: *const c_int,
) {
    let args = match check_rank_k(opt(uplo), opt(trans), *n, *k, *lda, Some(*ldb), *ldc) {
        Ok(args) => args,
        Err(pos) => return blas_error("DSYR2K", pos),
    };
    let RankK { uplo, trans, n, k } = args;
    if n == 0 {
        return;
    }
    let (r, c_) = if trans { (k, n) } else { (n, k) };
    let a = op(mat_ref(a, r, c_, dim(*lda)), trans);
    let b = op(mat_ref(b, r, c_, dim(*ldb)), trans);
    let mut c = mat_mut(c, n, n, dim(*ldc));
    scale(c.rb_mut(), *beta, Region::Triangle(uplo));
    if *alpha != 0.0 && k > 0 {
        tri_update(c.rb_mut(), uplo, *alpha, a, b.transpose());
        tri_update(c, uplo, *alpha, b, a.transpose());
    }
}
