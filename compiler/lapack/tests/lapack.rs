//! LAPACK routines against independent reconstructions (L L^T, V diag(w)
//! V^T, U S V^T), nalgebra reference spectra, workspace queries and
//! argument checks.

mod common;

use common::{ch, Dense, Padded, Rng, Worst};
use nalgebra::DMatrix;
use tsf_lapack::{dgesdd_, dgesvd_, dpotrf_, dpotrs_, dsyevr_};

fn to_nalgebra(d: &Dense) -> DMatrix<f64> {
    DMatrix::from_column_slice(d.rows, d.cols, &d.v)
}

/// The triangle opposite to `uplo`.
fn other(uplo: u8) -> u8 {
    if uplo == b'U' {
        b'L'
    } else {
        b'U'
    }
}

/// Padded symmetric matrix whose strict triangle opposite to `uplo` is NaN.
fn half_stored(a: &Dense, uplo: u8, pad: usize) -> Padded {
    let mut p = Padded::from_dense(a, pad);
    p.fill_strict_triangle(other(uplo), f64::NAN);
    p
}

/// Triangular factor read from the `uplo` triangle (zeros elsewhere).
fn triangle(p: &Padded, uplo: u8) -> Dense {
    Dense::from_fn(p.rows, p.cols, |i, j| {
        if (uplo == b'U' && i <= j) || (uplo == b'L' && i >= j) {
            p.at(i, j)
        } else {
            0.0
        }
    })
}

/// Runs dpotrf on a half-stored copy of `a`; returns (info, factor buffer).
fn potrf(a: &Dense, uplo: u8, pad: usize) -> (i32, Padded) {
    let mut p = half_stored(a, uplo, pad);
    let (n, mut info) = (a.rows as i32, 99);
    unsafe { dpotrf_(&ch(uplo), &n, p.mut_ptr(), &p.ld(), &mut info) };
    (info, p)
}

#[test]
fn dpotrf_reconstructs_and_keeps_other_triangle() {
    let mut rng = Rng::new(21);
    let mut worst = Worst::new("dpotrf |A - LL'|/|A|", 1e-14);
    for n in [1, 4, 7, 12, 30] {
        for uplo in [b'U', b'L'] {
            let a = Dense::random_spd(n, &mut rng);
            let (info, p) = potrf(&a, uplo, 3);
            assert_eq!(info, 0);
            assert!(
                p.strict_triangle_is(other(uplo), f64::NAN),
                "other triangle written"
            );
            assert!(p.padding_intact());
            let f = triangle(&p, uplo);
            let rebuilt = if uplo == b'U' {
                f.t().mul(&f)
            } else {
                f.mul(&f.t())
            };
            worst.check(rebuilt.max_diff(&a) / a.max_abs(), &format!("n={n} {uplo}"));
        }
    }
}

#[test]
fn dpotrf_reports_first_non_positive_minor() {
    let diag = [1.0, 2.0, 3.0, -1.0, 5.0, 6.0];
    let a = Dense::from_fn(6, 6, |i, j| if i == j { diag[i] } else { 0.01 });
    for uplo in [b'U', b'l'] {
        assert_eq!(potrf(&a, uplo.to_ascii_uppercase(), 0).0, 4);
    }
    let zero_first = Dense::from_fn(5, 5, |i, j| if i == j && i > 0 { 1.0 } else { 0.0 });
    assert_eq!(potrf(&zero_first, b'L', 0).0, 1);
}

#[test]
fn dpotrs_solves() {
    let mut rng = Rng::new(22);
    let mut worst = Worst::new("dpotrs |X - X*|", 1e-12);
    for (n, nrhs) in [(1, 1), (4, 3), (9, 1), (20, 6)] {
        for uplo in [b'U', b'L'] {
            let a = Dense::random_spd(n, &mut rng);
            let x = Dense::random(n, nrhs, &mut rng);
            let (info, factor) = potrf(&a, uplo, 2);
            assert_eq!(info, 0);
            let mut b = Padded::from_dense(&a.mul(&x), 1);
            let (ni, ri, mut info) = (n as i32, nrhs as i32, 99);
            unsafe {
                dpotrs_(
                    &ch(uplo),
                    &ni,
                    &ri,
                    factor.ptr(),
                    &factor.ld(),
                    b.mut_ptr(),
                    &b.ld(),
                    &mut info,
                );
            }
            assert_eq!(info, 0);
            assert!(b.padding_intact());
            worst.check(b.dense().max_diff(&x), &format!("n={n} nrhs={nrhs} {uplo}"));
        }
    }
}

/// Result of one dsyevr call.
struct Eig {
    info: i32,
    m: usize,
    w: Vec<f64>,
    z: Padded,
    isuppz: Vec<i32>,
}

/// Calls dsyevr after a workspace query (answers checked), on a half-stored
/// copy of `a`. `z` is a 1-element placeholder (value 42) for jobz N.
fn syevr(
    a: &Dense,
    jobz: u8,
    range: u8,
    uplo: u8,
    (vl, vu): (f64, f64),
    (il, iu): (i32, i32),
) -> Eig {
    let n = a.rows;
    let mut p = half_stored(a, uplo, 2);
    let mut z = if jobz == b'V' {
        Padded::filled(n, n, 1, f64::NAN)
    } else {
        Padded::from_dense(&Dense::from_fn(1, 1, |_, _| 42.0), 0)
    };
    let ldz = n.max(1) as i32 + i32::from(jobz == b'V');
    let (ni, abstol, mut m) = (n as i32, -1.0, -1);
    let mut w = vec![f64::NAN; n.max(1)];
    let mut isuppz = vec![-7; 2 * n.max(1)];
    let (mut work, mut iwork) = (vec![0.0], vec![0]);
    let mut call = |work: &mut Vec<f64>, lwork: i32, iwork: &mut Vec<i32>, liwork: i32| {
        let mut info = 99;
        unsafe {
            dsyevr_(
                &ch(jobz),
                &ch(range),
                &ch(uplo),
                &ni,
                p.mut_ptr(),
                &p.ld(),
                &vl,
                &vu,
                &il,
                &iu,
                &abstol,
                &mut m,
                w.as_mut_ptr(),
                z.mut_ptr(),
                &ldz,
                isuppz.as_mut_ptr(),
                work.as_mut_ptr(),
                &lwork,
                iwork.as_mut_ptr(),
                &liwork,
                &mut info,
            )
        };
        info
    };
    assert_eq!(call(&mut work, -1, &mut iwork, -1), 0, "query");
    let (lwork, liwork) = (work[0] as i32, iwork[0]);
    assert!(lwork >= (26 * n as i32).max(1) && liwork >= (10 * n as i32).max(1));
    work.resize(lwork as usize, 0.0);
    iwork.resize(liwork as usize, 0);
    let info = call(&mut work, lwork, &mut iwork, liwork);
    let m = usize::try_from(m).unwrap_or(usize::MAX);
    Eig {
        info,
        m,
        w,
        z,
        isuppz,
    }
}

/// Reference eigenvalues (ascending) from nalgebra.
fn reference_eigenvalues(a: &Dense) -> Vec<f64> {
    let mut ev: Vec<f64> = to_nalgebra(a)
        .symmetric_eigen()
        .eigenvalues
        .iter()
        .copied()
        .collect();
    ev.sort_by(f64::total_cmp);
    ev
}

fn max_abs_diff(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

#[test]
fn dsyevr_all_eigenpairs() {
    let mut rng = Rng::new(23);
    let mut residual = Worst::new("dsyevr |AV - V diag(w)|/|A|", 1e-13);
    let mut orth = Worst::new("dsyevr |V'V - I|", 1e-13);
    let mut values = Worst::new("dsyevr |w - w_nalgebra|/|A|", 1e-13);
    for n in [1, 4, 6, 10, 25] {
        for uplo in [b'U', b'L'] {
            let a = Dense::random_sym(n, &mut rng);
            let e = syevr(&a, b'V', b'A', uplo, (0.0, 0.0), (0, 0));
            assert_eq!((e.info, e.m), (0, n));
            assert!(e.w.windows(2).all(|p| p[0] <= p[1]), "not ascending");
            assert!(e.z.padding_intact());
            let ctx = format!("n={n} {uplo}");
            let v = e.z.dense();
            let scale = a.max_abs();
            residual.check(a.mul(&v).max_diff(&v.scale_cols(&e.w)) / scale, &ctx);
            orth.check(v.orthogonality_error(), &ctx);
            values.check(max_abs_diff(&e.w, &reference_eigenvalues(&a)) / scale, &ctx);
            for pair in e.isuppz.chunks(2) {
                assert!(
                    1 <= pair[0] && pair[0] <= pair[1] && pair[1] <= n as i32,
                    "{pair:?}"
                );
            }
        }
    }
}

#[test]
fn dsyevr_values_only_leaves_z_alone() {
    let mut rng = Rng::new(24);
    let mut worst = Worst::new("dsyevr jobz=N vs jobz=V", 1e-13);
    for n in [4, 9] {
        for uplo in [b'U', b'L'] {
            let a = Dense::random_sym(n, &mut rng);
            let e = syevr(&a, b'N', b'A', uplo, (0.0, 0.0), (0, 0));
            assert_eq!((e.info, e.m), (0, n));
            assert_eq!(e.z.data, vec![42.0], "Z written with jobz = N");
            assert_eq!(e.isuppz, vec![-7; 2 * n], "isuppz written with jobz = N");
            let full = syevr(&a, b'V', b'A', uplo, (0.0, 0.0), (0, 0));
            worst.check(max_abs_diff(&e.w, &full.w), &format!("n={n}"));
        }
    }
}

#[test]
fn dsyevr_index_and_value_ranges() {
    let mut rng = Rng::new(25);
    let mut worst = Worst::new("dsyevr subsets", 1e-13);
    let n = 8;
    let a = Dense::random_sym(n, &mut rng);
    let all = syevr(&a, b'N', b'A', b'U', (0.0, 0.0), (0, 0)).w;
    for jobz in [b'N', b'V'] {
        let by_index = syevr(&a, jobz, b'I', b'L', (0.0, 0.0), (2, 5));
        assert_eq!((by_index.info, by_index.m), (0, 4));
        worst.check(max_abs_diff(&by_index.w[..4], &all[1..5]), "range I");
        let (vl, vu) = ((all[2] + all[3]) / 2.0, (all[6] + all[7]) / 2.0);
        let by_value = syevr(&a, jobz, b'V', b'U', (vl, vu), (0, 0));
        assert_eq!((by_value.info, by_value.m), (0, 4));
        worst.check(max_abs_diff(&by_value.w[..4], &all[3..7]), "range V");
        if jobz == b'V' {
            // Only m columns are written; they are eigenvectors.
            for (e, lo) in [(&by_index, 1), (&by_value, 3)] {
                let v = e.z.dense().left(4);
                let r = a.mul(&v).max_diff(&v.scale_cols(&all[lo..lo + 4]));
                worst.check(r / a.max_abs(), "subset residual");
                assert!(
                    (0..n).all(|i| e.z.at(i, 4).is_nan()),
                    "extra column written"
                );
            }
        }
    }
    let none = syevr(&a, b'V', b'V', b'U', (all[7] + 1.0, all[7] + 2.0), (0, 0));
    assert_eq!((none.info, none.m), (0, 0));
}

#[test]
fn dsyevr_rejects_bad_arguments() {
    let a = Padded::filled(4, 4, 0, 1.0);
    let run = |jobz: u8, range: u8, uplo: u8, lda: i32, vl: f64, il: i32, ldz: i32, lwork: i32| {
        let mut a = a.clone();
        let (n, vu, iu, abstol, mut m, liwork, mut info) = (4, 1.0, 4, 0.0, 0, 40, 0);
        let (mut w, mut z, mut isuppz) = ([0.0; 4], [0.0; 16], [0; 8]);
        let (mut work, mut iwork) = ([0.0; 104], [0; 40]);
        unsafe {
            dsyevr_(
                &ch(jobz),
                &ch(range),
                &ch(uplo),
                &n,
                a.mut_ptr(),
                &lda,
                &vl,
                &vu,
                &il,
                &iu,
                &abstol,
                &mut m,
                w.as_mut_ptr(),
                z.as_mut_ptr(),
                &ldz,
                isuppz.as_mut_ptr(),
                work.as_mut_ptr(),
                &lwork,
                iwork.as_mut_ptr(),
                &liwork,
                &mut info,
            );
        }
        info
    };
    assert_eq!(run(b'V', b'A', b'U', 4, 0.0, 1, 4, 104), 0);
    assert_eq!(run(b'X', b'A', b'U', 4, 0.0, 1, 4, 104), -1);
    assert_eq!(run(b'V', b'Q', b'U', 4, 0.0, 1, 4, 104), -2);
    assert_eq!(run(b'V', b'A', b'Z', 4, 0.0, 1, 4, 104), -3);
    assert_eq!(run(b'V', b'A', b'U', 3, 0.0, 1, 4, 104), -6);
    assert_eq!(run(b'V', b'V', b'U', 4, 2.0, 1, 4, 104), -8);
    assert_eq!(run(b'V', b'I', b'U', 4, 0.0, 0, 4, 104), -9);
    assert_eq!(run(b'V', b'A', b'U', 4, 0.0, 1, 3, 104), -15);
    assert_eq!(run(b'V', b'A', b'U', 4, 0.0, 1, 4, 0), -18);
}

/// One SVD result: singular values and whichever factors were produced
/// (`U` with its columns, `V^T` with its rows).
struct SvdResult {
    s: Vec<f64>,
    u: Option<Dense>,
    vt: Option<Dense>,
}

/// Checks an SVD of `a`: values descending, non-negative and equal to
/// nalgebra's; every factor orthonormal; `U_k diag(s) VT_k == A` when both
/// factors are present.
fn check_svd(a: &Dense, r: &SvdResult, worst: &mut [Worst; 3], ctx: &str) {
    let k = a.rows.min(a.cols);
    assert!(
        r.s.windows(2).all(|p| p[0] >= p[1]),
        "{ctx}: not descending"
    );
    assert!(r.s.iter().all(|&x| x >= 0.0), "{ctx}: negative value");
    let mut reference: Vec<f64> = to_nalgebra(a).singular_values().iter().copied().collect();
    reference.sort_by(|x, y| y.total_cmp(x));
    worst[0].check(max_abs_diff(&r.s, &reference), ctx);
    if let Some(u) = &r.u {
        worst[1].check(u.orthogonality_error(), ctx);
    }
    if let Some(vt) = &r.vt {
        worst[1].check(vt.t().orthogonality_error(), ctx);
    }
    if let (Some(u), Some(vt)) = (&r.u, &r.vt) {
        let rebuilt = u.left(k).scale_cols(&r.s).mul(&vt.top(k));
        worst[2].check(rebuilt.max_diff(a), ctx);
    }
}

/// Error records for [`check_svd`]: values, orthogonality, reconstruction.
fn svd_worsts(name: &str) -> [Worst; 3] {
    [
        Worst::new(format!("{name} |s - s_nalgebra|"), 1e-13),
        Worst::new(format!("{name} orthogonality"), 1e-13),
        Worst::new(format!("{name} |U S V' - A|"), 1e-13),
    ]
}

/// Number of singular vectors produced by a job letter.
fn count(job: u8, full: usize, k: usize) -> usize {
    match job {
        b'A' => full,
        b'N' => 0,
        _ => k,
    }
}

/// Extracts the factors of an SVD call from its buffers.
fn collect(
    (m, n): (usize, usize),
    (ujob, vjob): (u8, u8),
    a_after: &Padded,
    u: &Padded,
    vt: &Padded,
) -> (Option<Dense>, Option<Dense>) {
    let k = m.min(n);
    let (ucols, vrows) = (count(ujob, m, k), count(vjob, n, k));
    let u_out = match ujob {
        b'N' => None,
        b'O' => Some(a_after.dense().left(ucols)),
        _ => Some(u.dense().left(ucols)),
    };
    let vt_out = match vjob {
        b'N' => None,
        b'O' => Some(a_after.dense().top(vrows)),
        _ => Some(vt.dense().top(vrows)),
    };
    (u_out, vt_out)
}

const SHAPES: [(usize, usize); 6] = [(6, 6), (7, 4), (4, 7), (1, 5), (5, 1), (12, 9)];

#[test]
fn dgesvd_all_job_combinations() {
    let mut rng = Rng::new(26);
    let mut worst = svd_worsts("dgesvd");
    for (m, n) in SHAPES {
        let a = Dense::random(m, n, &mut rng);
        for ujob in [b'A', b'S', b'O', b'N'] {
            for vjob in [b'A', b'S', b'O', b'N'] {
                if ujob == b'O' && vjob == b'O' {
                    continue;
                }
                let mut pa = Padded::from_dense(&a, 2);
                let mut u = Padded::filled(m, m, 1, f64::NAN);
                let mut vt = Padded::filled(n, n, 2, f64::NAN);
                let k = m.min(n);
                let mut s = vec![f64::NAN; k];
                let (mi, ni) = (m as i32, n as i32);
                let mut work = vec![0.0];
                let mut call = |work: &mut Vec<f64>, lwork: i32| {
                    let mut info = 99;
                    unsafe {
                        dgesvd_(
                            &ch(ujob),
                            &ch(vjob),
                            &mi,
                            &ni,
                            pa.mut_ptr(),
                            &pa.ld(),
                            s.as_mut_ptr(),
                            u.mut_ptr(),
                            &u.ld(),
                            vt.mut_ptr(),
                            &vt.ld(),
                            work.as_mut_ptr(),
                            &lwork,
                            &mut info,
                        )
                    };
                    info
                };
                assert_eq!(call(&mut work, -1), 0);
                let lwork = work[0] as i32;
                assert!(lwork >= (3 * k + m.max(n)).max(5 * k) as i32);
                work.resize(lwork as usize, 0.0);
                let info = call(&mut work, lwork);
                let ctx = format!("{m}x{n} {}{}", ujob as char, vjob as char);
                assert_eq!(info, 0, "{ctx}");
                assert!(pa.padding_intact() && u.padding_intact() && vt.padding_intact());
                let (uf, vtf) = collect((m, n), (ujob, vjob), &pa, &u, &vt);
                check_svd(&a, &SvdResult { s, u: uf, vt: vtf }, &mut worst, &ctx);
            }
        }
    }
}

#[test]
fn dgesdd_all_jobs() {
    let mut rng = Rng::new(27);
    let mut worst = svd_worsts("dgesdd");
    for (m, n) in SHAPES {
        let a = Dense::random(m, n, &mut rng);
        for job in [b'A', b'S', b'O', b'N'] {
            let k = m.min(n);
            let mut pa = Padded::from_dense(&a, 1);
            let (ur, uc, vr) = if job == b'S' { (m, k, k) } else { (m, m, n) };
            let mut u = Padded::filled(ur, uc, 2, f64::NAN);
            let mut vt = Padded::filled(vr, n, 1, f64::NAN);
            let mut s = vec![f64::NAN; k];
            let mut iwork = vec![0; 8 * k];
            let (mi, ni) = (m as i32, n as i32);
            let mut work = vec![0.0];
            let mut call = |work: &mut Vec<f64>, lwork: i32| {
                let mut info = 99;
                unsafe {
                    dgesdd_(
                        &ch(job),
                        &mi,
                        &ni,
                        pa.mut_ptr(),
                        &pa.ld(),
                        s.as_mut_ptr(),
                        u.mut_ptr(),
                        &u.ld(),
                        vt.mut_ptr(),
                        &vt.ld(),
                        work.as_mut_ptr(),
                        &lwork,
                        iwork.as_mut_ptr(),
                        &mut info,
                    )
                };
                info
            };
            assert_eq!(call(&mut work, -1), 0);
            let lwork = work[0] as i32;
            assert!(lwork >= 1);
            work.resize(lwork as usize, 0.0);
            let info = call(&mut work, lwork);
            let ctx = format!("{m}x{n} {}", job as char);
            assert_eq!(info, 0, "{ctx}");
            assert!(pa.padding_intact() && u.padding_intact() && vt.padding_intact());
            let jobs = match job {
                b'O' if m >= n => (b'O', b'A'),
                b'O' => (b'A', b'O'),
                j => (j, j),
            };
            if job == b'N' {
                assert!(
                    u.data.iter().chain(&vt.data).all(|x| x.is_nan()),
                    "factor written"
                );
            }
            let (uf, vtf) = collect((m, n), jobs, &pa, &u, &vt);
            check_svd(&a, &SvdResult { s, u: uf, vt: vtf }, &mut worst, &ctx);
        }
    }
}

#[test]
fn svd_rejects_bad_arguments() {
    let a = Padded::filled(4, 3, 0, 1.0);
    let svd = |jobu: u8, jobvt: u8, ldu: i32, lwork: i32| {
        let mut a = a.clone();
        let (m, n, ldvt, mut info) = (4, 3, 3, 0);
        let (mut s, mut u, mut vt, mut work) = ([0.0; 3], [0.0; 16], [0.0; 9], [0.0; 64]);
        unsafe {
            dgesvd_(
                &ch(jobu),
                &ch(jobvt),
                &m,
                &n,
                a.mut_ptr(),
                &4,
                s.as_mut_ptr(),
                u.as_mut_ptr(),
                &ldu,
                vt.as_mut_ptr(),
                &ldvt,
                work.as_mut_ptr(),
                &lwork,
                &mut info,
            );
        }
        info
    };
    assert_eq!(svd(b'S', b'S', 4, 64), 0);
    assert_eq!(svd(b'O', b'O', 4, 64), -2);
    assert_eq!(svd(b'Q', b'S', 4, 64), -1);
    assert_eq!(svd(b'A', b'S', 3, 64), -9);
    assert_eq!(svd(b'S', b'S', 4, 0), -13);
    let sdd = |jobz: u8, lda: i32, ldvt: i32| {
        let mut a = a.clone();
        let (m, n, ldu, lwork, mut info) = (4, 3, 4, 64, 0);
        let (mut s, mut u, mut vt, mut work) = ([0.0; 3], [0.0; 16], [0.0; 9], [0.0; 64]);
        let mut iwork = [0; 24];
        unsafe {
            dgesdd_(
                &ch(jobz),
                &m,
                &n,
                a.mut_ptr(),
                &lda,
                s.as_mut_ptr(),
                u.as_mut_ptr(),
                &ldu,
                vt.as_mut_ptr(),
                &ldvt,
                work.as_mut_ptr(),
                &lwork,
                iwork.as_mut_ptr(),
                &mut info,
            );
        }
        info
    };
    assert_eq!(sdd(b'S', 4, 3), 0);
    assert_eq!(sdd(b'W', 4, 3), -1);
    assert_eq!(sdd(b'S', 3, 3), -5);
    assert_eq!(sdd(b'A', 4, 2), -10);
}

#[test]
fn lapack_rejects_bad_uplo_and_sizes() {
    let mut a = Padded::filled(3, 3, 0, 1.0);
    let (mut info, n, neg) = (0, 3, -1);
    unsafe {
        dpotrf_(&ch(b'X'), &n, a.mut_ptr(), &3, &mut info);
        assert_eq!(info, -1);
        dpotrf_(&ch(b'U'), &neg, a.mut_ptr(), &3, &mut info);
        assert_eq!(info, -2);
        dpotrf_(&ch(b'U'), &n, a.mut_ptr(), &2, &mut info);
        assert_eq!(info, -4);
        let mut b = [0.0; 3];
        dpotrs_(
            &ch(b'L'),
            &n,
            &neg,
            a.ptr(),
            &3,
            b.as_mut_ptr(),
            &3,
            &mut info,
        );
        assert_eq!(info, -3);
        dpotrs_(
            &ch(b'L'),
            &n,
            &1,
            a.ptr(),
            &3,
            b.as_mut_ptr(),
            &2,
            &mut info,
        );
        assert_eq!(info, -7);
    }
    assert_eq!(a.data, vec![1.0; 9]);
}
