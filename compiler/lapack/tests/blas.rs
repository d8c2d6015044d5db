//! BLAS routines against naive triple loops: transposes, padded leading
//! dimensions, strided vectors, alpha/beta combinations, untouched triangles.

mod common;

use common::{ch, Dense, Padded, Rng, Worst};
use tsf_lapack::{dgemm_, dgemv_, dsymv_, dsyr2k_, dsyrk_};

/// (alpha, beta) pairs covering the special cases 0 and 1.
const ALPHA_BETA: [(f64, f64); 5] = [(1.0, 0.0), (-0.7, 1.0), (0.0, 0.3), (1.3, -0.4), (0.0, 0.0)];

/// `op(X)`.
fn op(x: &Dense, trans: u8) -> Dense {
    if trans.eq_ignore_ascii_case(&b'N') {
        x.clone()
    } else {
        x.t()
    }
}

/// Random `rows x cols` matrix stored as `op` expects (`cols x rows` when
/// transposed), NaN everywhere when `poison` (it must then not be read).
fn operand(rows: usize, cols: usize, trans: u8, poison: bool, rng: &mut Rng) -> Dense {
    let (r, c) = if trans.eq_ignore_ascii_case(&b'N') {
        (rows, cols)
    } else {
        (cols, rows)
    };
    let d = Dense::random(r, c, rng);
    if poison {
        Dense::from_fn(r, c, |_, _| f64::NAN)
    } else {
        d
    }
}

/// `alpha * prod + beta * c0`, omitting terms with a zero coefficient (BLAS
/// does not read them).
fn combine(alpha: f64, prod: &Dense, beta: f64, c0: &Dense) -> Dense {
    Dense::from_fn(c0.rows, c0.cols, |i, j| {
        let p = if alpha == 0.0 {
            0.0
        } else {
            alpha * prod.at(i, j)
        };
        let c = if beta == 0.0 { 0.0 } else { beta * c0.at(i, j) };
        p + c
    })
}

/// Initial output: random, or NaN when `beta == 0` (it must not be read).
fn initial_output(rows: usize, cols: usize, beta: f64, rng: &mut Rng) -> Dense {
    let d = Dense::random(rows, cols, rng);
    if beta == 0.0 {
        Dense::from_fn(rows, cols, |_, _| f64::NAN)
    } else {
        d
    }
}

#[test]
fn dgemm_matches_naive_loops() {
    let mut rng = Rng::new(11);
    let mut worst = Worst::new("dgemm", 1e-13);
    for (m, n, k) in [
        (1, 1, 1),
        (3, 5, 4),
        (7, 2, 6),
        (5, 5, 0),
        (9, 8, 10),
        (20, 17, 33),
    ] {
        for ta in [b'N', b'T', b'c'] {
            for tb in [b'n', b'T', b'C'] {
                for (alpha, beta) in ALPHA_BETA {
                    let a = operand(m, k, ta, alpha == 0.0, &mut rng);
                    let b = operand(k, n, tb, alpha == 0.0, &mut rng);
                    let c0 = initial_output(m, n, beta, &mut rng);
                    let expected = combine(alpha, &op(&a, ta).mul(&op(&b, tb)), beta, &c0);
                    let (pa, pb) = (Padded::from_dense(&a, 2), Padded::from_dense(&b, 3));
                    let mut c = Padded::from_dense(&c0, 1);
                    let (mi, ni, ki) = (m as i32, n as i32, k as i32);
                    unsafe {
                        dgemm_(
                            &ch(ta),
                            &ch(tb),
                            &mi,
                            &ni,
                            &ki,
                            &alpha,
                            pa.ptr(),
                            &pa.ld(),
                            pb.ptr(),
                            &pb.ld(),
                            &beta,
                            c.mut_ptr(),
                            &c.ld(),
                        );
                    }
                    let ctx = format!("{m}x{n}x{k} {ta}{tb} alpha={alpha} beta={beta}");
                    assert!(c.padding_intact(), "{ctx}: padding written");
                    worst.check(c.dense().max_diff(&expected), &ctx);
                }
            }
        }
    }
}

/// Buffer holding `vals` with increment `inc` (gaps are NaN).
fn strided(vals: &[f64], inc: i32) -> Vec<f64> {
    let step = inc.unsigned_abs() as usize;
    let mut buf = vec![f64::NAN; 1 + vals.len().saturating_sub(1) * step];
    for (i, v) in vals.iter().enumerate() {
        buf[position(i, vals.len(), inc)] = *v;
    }
    buf
}

/// Buffer position of logical element `i` of a BLAS vector.
fn position(i: usize, len: usize, inc: i32) -> usize {
    let step = inc.unsigned_abs() as usize;
    if inc > 0 {
        i * step
    } else {
        (len - 1 - i) * step
    }
}

/// Logical elements of a strided buffer; panics if a gap was written.
fn unstrided(buf: &[f64], len: usize, inc: i32) -> Vec<f64> {
    let used: Vec<usize> = (0..len).map(|i| position(i, len, inc)).collect();
    for (p, x) in buf.iter().enumerate() {
        assert!(used.contains(&p) || x.is_nan(), "gap {p} written");
    }
    used.iter().map(|&p| buf[p]).collect()
}

/// Column vector as a `len x 1` matrix.
fn column(v: &[f64]) -> Dense {
    Dense::from_fn(v.len(), 1, |i, _| v[i])
}

/// Runs one strided matrix-vector case and compares with the reference;
/// `call(x_buf, y_buf)` invokes the routine.
fn check_mv(
    worst: &mut Worst,
    op_a: &Dense,
    (alpha, beta): (f64, f64),
    (incx, incy): (i32, i32),
    rng: &mut Rng,
    ctx: &str,
    call: impl FnOnce(&[f64], &mut [f64]),
) {
    let x: Vec<f64> = (0..op_a.cols).map(|_| rng.next()).collect();
    let y0 = initial_output(op_a.rows, 1, beta, rng).v;
    let expected = combine(alpha, &op_a.mul(&column(&x)), beta, &column(&y0));
    let xb = strided(&x, incx);
    let mut yb = strided(&y0, incy);
    call(&xb, &mut yb);
    let y = unstrided(&yb, op_a.rows, incy);
    worst.check(column(&y).max_diff(&expected), ctx);
}

const INCS: [(i32, i32); 4] = [(1, 1), (2, -1), (-3, 2), (-1, -2)];

#[test]
fn dgemv_matches_naive_loops() {
    let mut rng = Rng::new(12);
    let mut worst = Worst::new("dgemv", 1e-13);
    for (m, n) in [(1, 1), (4, 7), (9, 3), (16, 16)] {
        for trans in [b'N', b't', b'C'] {
            for (alpha, beta) in ALPHA_BETA {
                for (incx, incy) in INCS {
                    let a = Dense::random(m, n, &mut rng);
                    let pa = Padded::from_dense(&a, 3);
                    let ctx = format!("{m}x{n} {trans} a={alpha} b={beta} inc={incx},{incy}");
                    let (mi, ni) = (m as i32, n as i32);
                    let call = |x: &[f64], y: &mut [f64]| unsafe {
                        dgemv_(
                            &ch(trans),
                            &mi,
                            &ni,
                            &alpha,
                            pa.ptr(),
                            &pa.ld(),
                            x.as_ptr(),
                            &incx,
                            &beta,
                            y.as_mut_ptr(),
                            &incy,
                        );
                    };
                    let op_a = op(&a, trans);
                    check_mv(
                        &mut worst,
                        &op_a,
                        (alpha, beta),
                        (incx, incy),
                        &mut rng,
                        &ctx,
                        call,
                    );
                }
            }
        }
    }
}

/// Padded symmetric matrix whose strict triangle opposite to `uplo` is NaN.
fn half_stored(a: &Dense, uplo: u8, pad: usize) -> Padded {
    let mut p = Padded::from_dense(a, pad);
    p.fill_strict_triangle(if uplo == b'U' { b'L' } else { b'U' }, f64::NAN);
    p
}

#[test]
fn dsymv_reads_only_its_triangle() {
    let mut rng = Rng::new(13);
    let mut worst = Worst::new("dsymv", 1e-13);
    for n in [1, 4, 7, 15] {
        for uplo in [b'U', b'L'] {
            for (alpha, beta) in ALPHA_BETA {
                for (incx, incy) in INCS {
                    let a = Dense::random_sym(n, &mut rng);
                    let pa = half_stored(&a, uplo, 2);
                    let ctx = format!("n={n} {uplo} a={alpha} b={beta} inc={incx},{incy}");
                    let ni = n as i32;
                    let lower = uplo.to_ascii_lowercase();
                    let call = |x: &[f64], y: &mut [f64]| unsafe {
                        dsymv_(
                            &ch(lower),
                            &ni,
                            &alpha,
                            pa.ptr(),
                            &pa.ld(),
                            x.as_ptr(),
                            &incx,
                            &beta,
                            y.as_mut_ptr(),
                            &incy,
                        );
                    };
                    check_mv(
                        &mut worst,
                        &a,
                        (alpha, beta),
                        (incx, incy),
                        &mut rng,
                        &ctx,
                        call,
                    );
                }
            }
        }
    }
}

/// Runs one rank-k style case: `C` (n x n) starts symmetric with NaN in the
/// strict triangle opposite to `uplo`; checks that triangle stays NaN and
/// the `uplo` triangle equals `expected_prod` combined with `beta * C0`.
fn check_rank_update(
    worst: &mut Worst,
    uplo: u8,
    expected_prod: &Dense,
    (alpha, beta): (f64, f64),
    rng: &mut Rng,
    ctx: &str,
    call: impl FnOnce(&mut Padded),
) {
    let n = expected_prod.rows;
    let c0 = if beta == 0.0 {
        Dense::from_fn(n, n, |_, _| f64::NAN)
    } else {
        Dense::random_sym(n, rng)
    };
    let expected = combine(alpha, expected_prod, beta, &c0);
    let mut c = half_stored(&c0, uplo, 2);
    call(&mut c);
    let other = if uplo == b'U' { b'L' } else { b'U' };
    assert!(
        c.strict_triangle_is(other, f64::NAN),
        "{ctx}: other triangle written"
    );
    assert!(c.padding_intact(), "{ctx}: padding written");
    worst.check(c.sym_from(uplo).max_diff(&expected), ctx);
}

#[test]
fn dsyrk_updates_only_its_triangle() {
    let mut rng = Rng::new(14);
    let mut worst = Worst::new("dsyrk", 1e-13);
    for (n, k) in [(1, 1), (4, 6), (7, 3), (6, 0), (16, 21)] {
        for uplo in [b'U', b'L'] {
            for trans in [b'N', b'T', b'c'] {
                for (alpha, beta) in ALPHA_BETA {
                    let a = operand(n, k, trans, alpha == 0.0, &mut rng);
                    let opa = op(&a, trans);
                    let pa = Padded::from_dense(&a, 3);
                    let ctx = format!("n={n} k={k} {uplo}{trans} a={alpha} b={beta}");
                    let (ni, ki) = (n as i32, k as i32);
                    let call = |c: &mut Padded| unsafe {
                        dsyrk_(
                            &ch(uplo),
                            &ch(trans),
                            &ni,
                            &ki,
                            &alpha,
                            pa.ptr(),
                            &pa.ld(),
                            &beta,
                            c.mut_ptr(),
                            &c.ld(),
                        );
                    };
                    let prod = opa.mul(&opa.t());
                    check_rank_update(&mut worst, uplo, &prod, (alpha, beta), &mut rng, &ctx, call);
                }
            }
        }
    }
}

#[test]
fn dsyr2k_updates_only_its_triangle() {
    let mut rng = Rng::new(15);
    let mut worst = Worst::new("dsyr2k", 1e-13);
    for (n, k) in [(1, 1), (4, 6), (7, 3), (6, 0), (16, 21)] {
        for uplo in [b'U', b'L'] {
            for trans in [b'N', b'T', b'c'] {
                for (alpha, beta) in ALPHA_BETA {
                    let a = operand(n, k, trans, alpha == 0.0, &mut rng);
                    let b = operand(n, k, trans, alpha == 0.0, &mut rng);
                    let (opa, opb) = (op(&a, trans), op(&b, trans));
                    let (pa, pb) = (Padded::from_dense(&a, 1), Padded::from_dense(&b, 4));
                    let ctx = format!("n={n} k={k} {uplo}{trans} a={alpha} b={beta}");
                    let (ni, ki) = (n as i32, k as i32);
                    let call = |c: &mut Padded| unsafe {
                        dsyr2k_(
                            &ch(uplo),
                            &ch(trans),
                            &ni,
                            &ki,
                            &alpha,
                            pa.ptr(),
                            &pa.ld(),
                            pb.ptr(),
                            &pb.ld(),
                            &beta,
                            c.mut_ptr(),
                            &c.ld(),
                        );
                    };
                    let ab = opa.mul(&opb.t());
                    let prod = Dense::from_fn(n, n, |i, j| ab.at(i, j) + ab.at(j, i));
                    check_rank_update(&mut worst, uplo, &prod, (alpha, beta), &mut rng, &ctx, call);
                }
            }
        }
    }
}

#[test]
fn illegal_blas_arguments_leave_output_untouched() {
    let a = Padded::filled(3, 3, 0, 1.0);
    let c0 = Padded::filled(3, 3, 0, 5.0);
    let (three, two, one, zero) = (3, 2, 1.0, 0.0);
    let cases: [(u8, u8, i32); 3] = [(b'X', b'N', 3), (b'N', b'Q', 3), (b'N', b'N', 2)];
    for (ta, tb, lda) in cases {
        let mut c = c0.clone();
        unsafe {
            dgemm_(
                &ch(ta),
                &ch(tb),
                &three,
                &three,
                &three,
                &one,
                a.ptr(),
                &lda,
                a.ptr(),
                &three,
                &zero,
                c.mut_ptr(),
                &three,
            );
        }
        assert_eq!(c.data, c0.data, "dgemm {ta} {tb} lda={lda}");
    }
    let mut c = c0.clone();
    unsafe {
        dsyrk_(
            &ch(b'X'),
            &ch(b'N'),
            &three,
            &three,
            &one,
            a.ptr(),
            &three,
            &zero,
            c.mut_ptr(),
            &two,
        );
    }
    assert_eq!(c.data, c0.data, "dsyrk");
    let (x, mut y) = ([1.0; 3], [7.0; 3]);
    let zero_inc = 0;
    unsafe {
        dsymv_(
            &ch(b'U'),
            &three,
            &one,
            a.ptr(),
            &three,
            x.as_ptr(),
            &zero_inc,
            &zero,
            y.as_mut_ptr(),
            &1,
        );
    }
    assert_eq!(y, [7.0; 3], "dsymv");
}

#[test]
fn empty_dimensions_are_quick_returns() {
    let (zero_i, one_i, alpha, beta) = (0, 1, 2.0, 0.0);
    let a = [f64::NAN];
    let mut c = [3.0];
    unsafe {
        // m = 0: C must not be touched even with beta = 0.
        dgemm_(
            &ch(b'N'),
            &ch(b'N'),
            &zero_i,
            &one_i,
            &one_i,
            &alpha,
            a.as_ptr(),
            &one_i,
            a.as_ptr(),
            &one_i,
            &beta,
            c.as_mut_ptr(),
            &one_i,
        );
        assert_eq!(c, [3.0]);
        dsyrk_(
            &ch(b'L'),
            &ch(b'N'),
            &zero_i,
            &one_i,
            &alpha,
            a.as_ptr(),
            &one_i,
            &beta,
            c.as_mut_ptr(),
            &one_i,
        );
        assert_eq!(c, [3.0]);
        // k = 0 with beta = 0 zeroes C without reading A.
        dsyrk_(
            &ch(b'L'),
            &ch(b'N'),
            &one_i,
            &zero_i,
            &alpha,
            a.as_ptr(),
            &one_i,
            &beta,
            c.as_mut_ptr(),
            &one_i,
        );
        assert_eq!(c, [0.0]);
    }
}
