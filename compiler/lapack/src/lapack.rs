//! LAPACK routines (`dpotrf_`, `dpotrs_`, `dsyevr_`, `dgesdd_`, `dgesvd_`)
//! with the `lapack-sys` 0.14 argument lists.
//!
//! Illegal arguments give `info = -position` (nothing else is written);
//! numerical failures inside faer give `info > 0`.
//!
//! Workspace: faer allocates its own scratch, so the `work`/`iwork` buffers
//! are only used to answer queries. A query (`lwork = -1`, and for `dsyevr_`
//! also `liwork = -1`) returns LAPACK's documented minimum sizes (always
//! `>= 1`); otherwise any `lwork >= 1` (`liwork >= 1`) is accepted, which is
//! more lenient than LAPACK but never rejects a conforming caller.

use core::ffi::{c_char, c_int};

use faer::linalg::triangular_solve::{
    solve_lower_triangular_in_place, solve_upper_triangular_in_place,
};
use faer::prelude::{Reborrow, ReborrowMut};
use faer::{Mat, MatMut, MatRef, Par, Side};

use crate::ffi::{
    copy_region, dim, first_bad, guarded, ld_min, mat_mut, mat_ref, opt, set_work_size, Region,
    Uplo,
};

/// `info` reported when faer fails to converge or panics.
const INTERNAL: c_int = 1;

/// `true` when `lwork` is neither a query (`-1`) nor a usable size.
fn bad_lwork(lwork: c_int) -> bool {
    lwork < 1 && lwork != -1
}

/// View of the `uplo` triangle of a square matrix as a lower triangle
/// (the transpose of the upper one).
fn as_lower(a: MatRef<'_, f64>, uplo: Uplo) -> MatRef<'_, f64> {
    match uplo {
        Uplo::Lower => a,
        Uplo::Upper => a.transpose(),
    }
}

/// Mutable counterpart of [`as_lower`].
fn as_lower_mut(a: MatMut<'_, f64>, uplo: Uplo) -> MatMut<'_, f64> {
    match uplo {
        Uplo::Lower => a,
        Uplo::Upper => a.transpose_mut(),
    }
}

fn side(uplo: Uplo) -> Side {
    match uplo {
        Uplo::Lower => Side::Lower,
        Uplo::Upper => Side::Upper,
    }
}

/// Cholesky factorisation of a symmetric positive definite `n x n` matrix:
/// `A = U^T U` (`uplo = U`) or `A = L L^T` (`uplo = L`), written over the
/// referenced triangle.
///
/// The other triangle is neither read nor written. `info = k > 0` when the
/// leading minor of order `k` is not positive definite; `A` is then left
/// unchanged (LAPACK leaves a partial factor there).
///
/// # Safety
/// Pointers valid as in LAPACK: `a` holds `lda * n` elements.
#[no_mangle]
pub unsafe extern "C" fn dpotrf_(
    uplo: *const c_char,
    n: *const c_int,
    a: *mut f64,
    lda: *const c_int,
    info: *mut c_int,
) {
    let ul = Uplo::parse(opt(uplo));
    let n = *n;
    if let Some(pos) = first_bad(&[(ul.is_none(), 1), (n < 0, 2), (*lda < ld_min(n), 4)]) {
        *info = -pos;
        return;
    }
    let (ul, n) = (ul.expect("validated"), dim(n));
    let lda = dim(*lda);
    *info = guarded(INTERNAL, || {
        if n == 0 {
            return 0;
        }
        let view = mat_mut(a, n, n, lda);
        match view.rb().llt(side(ul)) {
            Ok(llt) => {
                let lower = Region::Triangle(Uplo::Lower);
                copy_region(as_lower_mut(view, ul), llt.L(), lower);
                0
            }
            Err(faer::linalg::cholesky::llt::factor::LltError::NonPositivePivot { index }) => {
                c_int::try_from(index + 1).unwrap_or(c_int::MAX)
            }
        }
    });
}

/// Solves `A X = B` with the Cholesky factor from [`dpotrf_`] (same `uplo`);
/// `B` (`n x nrhs`) is overwritten by `X`. Only the `uplo` triangle of `A` is
/// read.
///
/// # Safety
/// Pointers valid as in LAPACK; `B` must not alias `A`.
#[no_mangle]
pub unsafe extern "C" fn dpotrs_(
    uplo: *const c_char,
    n: *const c_int,
    nrhs: *const c_int,
    a: *const f64,
    lda: *const c_int,
    b: *mut f64,
    ldb: *const c_int,
    info: *mut c_int,
) {
    let ul = Uplo::parse(opt(uplo));
    let (n, nrhs) = (*n, *nrhs);
    if let Some(pos) = first_bad(&[
        (ul.is_none(), 1),
        (n < 0, 2),
        (nrhs < 0, 3),
        (*lda < ld_min(n), 5),
        (*ldb < ld_min(n), 7),
    ]) {
        *info = -pos;
        return;
    }
    let ul = ul.expect("validated");
    let (n, nrhs, lda, ldb) = (dim(n), dim(nrhs), dim(*lda), dim(*ldb));
    *info = guarded(INTERNAL, || {
        if n == 0 || nrhs == 0 {
            return 0;
        }
        let l = as_lower(mat_ref(a, n, n, lda), ul);
        let mut x = mat_mut(b, n, nrhs, ldb);
        solve_lower_triangular_in_place(l, x.rb_mut(), Par::Seq);
        solve_upper_triangular_in_place(l.transpose(), x, Par::Seq);
        0
    });
}

/// Symmetric eigenproblem driver: eigenvalues (ascending) and optionally
/// eigenvectors of the `n x n` matrix whose `uplo` triangle is stored in `A`.
///
/// Options: `jobz` `N` (values only; `Z` is not touched) or `V`; `range` `A`
/// (all), `V` (values in `(vl, vu]`) or `I` (the `il`-th to `iu`-th, 1-based);
/// `uplo` `U` or `L`. `abstol` is ignored (faer works to full precision).
/// `A` is not modified (LAPACK destroys it). `isuppz` is written, as in
/// LAPACK, only for `jobz = V` with all eigenvalues selected; it gives the
/// first and last non-zero row (1-based) of each eigenvector.
///
/// # Safety
/// Pointers valid as in LAPACK: `w` holds `n` values, `Z` (`jobz = V`) is
/// `ldz x m`, `isuppz` `2 * m`, `work`/`iwork` at least one element each.
#[no_mangle]
pub unsafe extern "C" fn dsyevr_(
    jobz: *const c_char,
    range: *const c_char,
    uplo: *const c_char,
    n: *const c_int,
    a: *mut f64,
    lda: *const c_int,
    vl: *const f64,
    vu: *const f64,
    il: *const c_int,
    iu: *const c_int,
    _abstol: *const f64,
    m: *mut c_int,
    w: *mut f64,
    z: *mut f64,
    ldz: *const c_int,
    isuppz: *mut c_int,
    work: *mut f64,
    lwork: *const c_int,
    iwork: *mut c_int,
    liwork: *const c_int,
    info: *mut c_int,
) {
    let (jobz, range, ul) = (opt(jobz), opt(range), Uplo::parse(opt(uplo)));
    let wantz = jobz == b'V';
    let (n, il, iu, vl, vu) = (*n, *il, *iu, *vl, *vu);
    let (lwork, liwork) = (*lwork, *liwork);
    if let Some(pos) = first_bad(&[
        (!wantz && jobz != b'N', 1),
        (!matches!(range, b'A' | b'V' | b'I'), 2),
        (ul.is_none(), 3),
        (n < 0, 4),
        (*lda < ld_min(n), 6),
        (range == b'V' && n > 0 && vu <= vl, 8),
        (range == b'I' && (il < 1 || il > ld_min(n)), 9),
        (range == b'I' && (iu < n.min(il) || iu > n), 10),
        (*ldz < 1 || (wantz && *ldz < n), 15),
        (bad_lwork(lwork), 18),
        (bad_lwork(liwork), 20),
    ]) {
        *info = -pos;
        return;
    }
    let (ul, n_us) = (ul.expect("validated"), dim(n));
    set_work_size(work, 26 * n_us);
    *iwork = c_int::try_from((10 * n_us).max(1)).unwrap_or(c_int::MAX);
    if lwork == -1 || liwork == -1 {
        *info = 0;
        return;
    }
    let (lda, ldz) = (dim(*lda), dim(*ldz));
    *info = guarded(INTERNAL, || {
        *m = 0;
        if n_us == 0 {
            return 0;
        }
        let a = mat_ref(a, n_us, n_us, lda);
        let (values, vectors) = if wantz {
            match a.self_adjoint_eigen(side(ul)) {
                Ok(e) => {
                    let values: Vec<f64> = e.S().column_vector().iter().copied().collect();
                    (values, Some(e))
                }
                Err(_) => return INTERNAL,
            }
        } else {
            match a.self_adjoint_eigenvalues(side(ul)) {
                Ok(values) => (values, None),
                Err(_) => return INTERNAL,
            }
        };
        let selected = match range {
            b'A' => 0..n_us,
            b'I' => dim(il - 1)..dim(iu),
            _ => values.partition_point(|&x| x <= vl)..values.partition_point(|&x| x <= vu),
        };
        let count = selected.len();
        *m = c_int::try_from(count).expect("count <= n");
        if count == 0 {
            return 0;
        }
        core::slice::from_raw_parts_mut(w, count).copy_from_slice(&values[selected.clone()]);
        if let Some(e) = vectors {
            let src = e.U().subcols(selected.start, count);
            mat_mut(z, n_us, count, ldz).copy_from(src);
            if count == n_us {
                let supp = core::slice::from_raw_parts_mut(isuppz, 2 * count);
                for (j, pair) in supp.chunks_exact_mut(2).enumerate() {
                    let col = src.col(j);
                    let nz: Vec<usize> = (0..n_us).filter(|&i| col[i] != 0.0).collect();
                    let first = nz.first().copied().unwrap_or(0);
                    let last = nz.last().copied().unwrap_or(n_us - 1);
                    pair[0] = c_int::try_from(first + 1).expect("row <= n");
                    pair[1] = c_int::try_from(last + 1).expect("row <= n");
                }
            }
        }
        0
    });
}

/// What to do with one SVD factor (`U` or `V^T`).
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Factor {
    /// Not computed, its argument is not touched.
    Skip,
    /// The `min(m, n)` leading singular vectors, into their own argument.
    Thin,
    /// All singular vectors (`m` for `U`, `n` for `V^T`), into their own
    /// argument.
    Full,
    /// The `min(m, n)` leading singular vectors, written over `A`.
    OverA,
}

impl Factor {
    /// Number of singular vectors written, given the full count.
    fn count(self, full: usize, k: usize) -> usize {
        match self {
            Factor::Skip => 0,
            Factor::Full => full,
            Factor::Thin | Factor::OverA => k,
        }
    }
}

/// Output arguments of an SVD driver.
struct SvdOut {
    s: *mut f64,
    u: (Factor, *mut f64, usize),
    vt: (Factor, *mut f64, usize),
}

/// Computes the SVD of the `m x n` matrix at `a` and stores the requested
/// factors; returns `info` (0, or [`INTERNAL`] if faer fails).
///
/// # Safety
/// Arguments validated as in `dgesvd_`/`dgesdd_`.
unsafe fn svd_driver(m: usize, n: usize, a: *mut f64, lda: usize, out: SvdOut) -> c_int {
    let k = m.min(n);
    if k == 0 {
        return 0;
    }
    let mut copy = Mat::<f64>::zeros(m, n);
    copy.as_mut().copy_from(mat_ref(a, m, n, lda));
    let (uf, vf) = (out.u.0, out.vt.0);
    let s = core::slice::from_raw_parts_mut(out.s, k);
    if uf == Factor::Skip && vf == Factor::Skip {
        return match copy.as_ref().singular_values() {
            Ok(values) => {
                s.copy_from_slice(&values[..k]);
                0
            }
            Err(_) => INTERNAL,
        };
    }
    let svd = if uf == Factor::Full || vf == Factor::Full {
        copy.as_ref().svd()
    } else {
        copy.as_ref().thin_svd()
    };
    let Ok(svd) = svd else { return INTERNAL };
    for (dst, src) in s.iter_mut().zip(svd.S().column_vector().iter()) {
        *dst = *src;
    }
    let (ucols, vrows) = (uf.count(m, k), vf.count(n, k));
    let target = |f: Factor, (ptr, ld): (*mut f64, usize), rows, cols| match f {
        Factor::OverA => mat_mut(a, rows, cols, lda),
        _ => mat_mut(ptr, rows, cols, ld),
    };
    if uf != Factor::Skip {
        target(uf, (out.u.1, out.u.2), m, ucols).copy_from(svd.U().subcols(0, ucols));
    }
    if vf != Factor::Skip {
        let vt = svd.V().subcols(0, vrows).transpose();
        target(vf, (out.vt.1, out.vt.2), vrows, n).copy_from(vt);
    }
    0
}

/// Parses an SVD job letter `A`/`S`/`O`/`N`.
fn parse_job(c: u8) -> Option<Factor> {
    match c {
        b'A' => Some(Factor::Full),
        b'S' => Some(Factor::Thin),
        b'O' => Some(Factor::OverA),
        b'N' => Some(Factor::Skip),
        _ => None,
    }
}

/// Singular value decomposition `A = U * diag(S) * V^T` of an `m x n` matrix
/// (divide-and-conquer driver interface); singular values descending.
///
/// Options (`k = min(m, n)`): `jobz = A` (all `m` columns of `U`, all `n`
/// rows of `V^T`), `S` (`k` of each), `O` (if `m >= n`, `U`'s `k` columns
/// over `A` and `V^T` in `vt`; otherwise `U` in `u` and `V^T`'s `k` rows over
/// `A`), `N` (values only). `A` is otherwise left unchanged.
///
/// # Safety
/// Pointers valid as in LAPACK; `work` holds at least one element.
#[no_mangle]
pub unsafe extern "C" fn dgesdd_(
    jobz: *const c_char,
    m: *const c_int,
    n: *const c_int,
    a: *mut f64,
    lda: *const c_int,
    s: *mut f64,
    u: *mut f64,
    ldu: *const c_int,
    vt: *mut f64,
    ldvt: *const c_int,
    work: *mut f64,
    lwork: *const c_int,
    _iwork: *mut c_int,
    info: *mut c_int,
) {
    let job = opt(jobz);
    let (m, n, ldu, ldvt) = (*m, *n, *ldu, *ldvt);
    let k = m.min(n);
    let (wa, ws, wo) = (job == b'A', job == b'S', job == b'O');
    if let Some(pos) = first_bad(&[
        (parse_job(job).is_none(), 1),
        (m < 0, 2),
        (n < 0, 3),
        (*lda < ld_min(m), 5),
        (ldu < 1 || ((wa || ws || (wo && m < n)) && ldu < m), 8),
        (
            ldvt < 1 || (wa && ldvt < n) || (ws && ldvt < k) || (wo && m >= n && ldvt < n),
            10,
        ),
        (bad_lwork(*lwork), 12),
    ]) {
        *info = -pos;
        return;
    }
    let (m, n) = (dim(m), dim(n));
    let (k, mx) = (m.min(n), m.max(n));
    let size = if k == 0 {
        1
    } else {
        3 * k
            + match job {
                b'N' => mx.max(7 * k),
                b'O' => mx.max(5 * k * k + 4 * k),
                _ => mx.max(4 * k * k + 4 * k),
            }
    };
    set_work_size(work, size);
    if *lwork == -1 {
        *info = 0;
        return;
    }
    let (uf, vf) = match job {
        b'O' if m >= n => (Factor::OverA, Factor::Full),
        b'O' => (Factor::Full, Factor::OverA),
        _ => {
            let f = parse_job(job).expect("validated");
            (f, f)
        }
    };
    let out = SvdOut {
        s,
        u: (uf, u, dim(ldu)),
        vt: (vf, vt, dim(ldvt)),
    };
    let lda = dim(*lda);
    *info = guarded(INTERNAL, || svd_driver(m, n, a, lda, out));
}

/// Singular value decomposition `A = U * diag(S) * V^T` of an `m x n` matrix
/// (QR-iteration driver interface); singular values descending.
///
/// Options (`k = min(m, n)`): `jobu`/`jobvt` each `A` (all `m` columns of
/// `U` / all `n` rows of `V^T`), `S` (the first `k`), `O` (the first `k`
/// written over `A`; not both), `N` (not computed). `A` is otherwise left
/// unchanged. `work[1..]` (LAPACK's unconverged superdiagonal) is not set.
///
/// # Safety
/// Pointers valid as in LAPACK; `work` holds at least one element.
#[no_mangle]
pub unsafe extern "C" fn dgesvd_(
    jobu: *const c_char,
    jobvt: *const c_char,
    m: *const c_int,
    n: *const c_int,
    a: *mut f64,
    lda: *const c_int,
    s: *mut f64,
    u: *mut f64,
    ldu: *const c_int,
    vt: *mut f64,
    ldvt: *const c_int,
    work: *mut f64,
    lwork: *const c_int,
    info: *mut c_int,
) {
    let (uf, vf) = (parse_job(opt(jobu)), parse_job(opt(jobvt)));
    let (m, n, ldu, ldvt) = (*m, *n, *ldu, *ldvt);
    let k = m.min(n);
    let u_in_arg = matches!(uf, Some(Factor::Full | Factor::Thin));
    if let Some(pos) = first_bad(&[
        (uf.is_none(), 1),
        (
            vf.is_none() || (vf == Some(Factor::OverA) && uf == Some(Factor::OverA)),
            2,
        ),
        (m < 0, 3),
        (n < 0, 4),
        (*lda < ld_min(m), 6),
        (ldu < 1 || (u_in_arg && ldu < m), 9),
        (
            ldvt < 1
                || (vf == Some(Factor::Full) && ldvt < n)
                || (vf == Some(Factor::Thin) && ldvt < k),
            11,
        ),
        (bad_lwork(*lwork), 13),
    ]) {
        *info = -pos;
        return;
    }
    let (m, n) = (dim(m), dim(n));
    let (k, mx) = (m.min(n), m.max(n));
    set_work_size(work, (3 * k + mx).max(5 * k));
    if *lwork == -1 {
        *info = 0;
        return;
    }
    let out = SvdOut {
        s,
        u: (uf.expect("validated"), u, dim(ldu)),
        vt: (vf.expect("validated"), vt, dim(ldvt)),
    };
    let lda = dim(*lda);
    *info = guarded(INTERNAL, || svd_driver(m, n, a, lda, out));
}
