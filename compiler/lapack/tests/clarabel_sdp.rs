//! End-to-end: Clarabel's SDP path (PSD cones of size >= 4, which always go
//! through LAPACK) linked against this crate's symbols, on problems with
//! known optimal values computed by nalgebra's eigen solver.

mod common;

use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettingsBuilder, DefaultSolver, IPSolver, SolverStatus, SupportedConeT,
};
use common::Rng;
use nalgebra::DMatrix;
use SupportedConeT::{PSDTriangleConeT, ZeroConeT};

/// Required agreement with the nalgebra reference.
const TOL: f64 = 1e-7;

/// Packs the upper triangle of a symmetric matrix column by column with
/// off-diagonals scaled by sqrt(2) (Clarabel's `PSDTriangleConeT` layout).
fn svec(m: &DMatrix<f64>) -> Vec<f64> {
    let n = m.nrows();
    (0..n)
        .flat_map(|j| (0..=j).map(move |i| (i, j)))
        .map(|(i, j)| {
            if i == j {
                m[(i, j)]
            } else {
                2f64.sqrt() * m[(i, j)]
            }
        })
        .collect()
}

fn random_sym(n: usize, seed: u64) -> DMatrix<f64> {
    let mut rng = Rng::new(seed);
    let b = DMatrix::from_fn(n, n, |_, _| rng.next());
    &b + b.transpose()
}

fn eigenvalues(a: &DMatrix<f64>) -> (f64, f64) {
    let ev = a.clone().symmetric_eigen().eigenvalues;
    (ev.min(), ev.max())
}

/// Sparse matrix from dense columns (zeros dropped).
fn csc_from_columns(rows: usize, cols: &[Vec<f64>]) -> CscMatrix<f64> {
    let (mut colptr, mut rowval, mut nzval) = (vec![0], vec![], vec![]);
    for col in cols {
        assert_eq!(col.len(), rows);
        for (i, &v) in col.iter().enumerate().filter(|(_, v)| **v != 0.0) {
            rowval.push(i);
            nzval.push(v);
        }
        colptr.push(rowval.len());
    }
    CscMatrix::new(rows, cols.len(), colptr, rowval, nzval)
}

/// Solves min c'x s.t. A x + s = b, s in cones (A given densely by columns);
/// returns the status and x.
fn solve(
    c: &[f64],
    a_cols: &[Vec<f64>],
    b: &[f64],
    cones: &[SupportedConeT<f64>],
) -> (SolverStatus, Vec<f64>) {
    tsf_lapack::link();
    let (rows, cols) = (b.len(), c.len());
    let a = csc_from_columns(rows, a_cols);
    let p = CscMatrix::zeros((cols, cols));
    let settings = DefaultSettingsBuilder::default()
        .verbose(false)
        .build()
        .unwrap();
    let mut solver = DefaultSolver::new(&p, c, &a, b, cones, settings).unwrap();
    solver.solve();
    (solver.solution.status, solver.solution.x.clone())
}

/// Checks status and |got - reference| <= TOL, printing the measurement.
fn expect(name: &str, status: SolverStatus, got: f64, reference: f64) {
    let err = (got - reference).abs();
    eprintln!("[accuracy] clarabel {name}: got {got:.12}, reference {reference:.12}, error {err:.2e} (tolerance {TOL:.0e})");
    assert_eq!(status, SolverStatus::Solved, "{name}");
    assert!(err <= TOL, "{name}: error {err:e}");
}

/// min t s.t. t I - A is PSD  ->  lambda_max(A).
fn lambda_max(a: &DMatrix<f64>) -> (SolverStatus, f64) {
    let n = a.nrows();
    let col: Vec<f64> = svec(&DMatrix::identity(n, n)).iter().map(|x| -x).collect();
    let b: Vec<f64> = svec(a).iter().map(|x| -x).collect();
    let (status, x) = solve(&[1.0], &[col], &b, &[PSDTriangleConeT(n)]);
    (status, x[0])
}

#[test]
fn lambda_max_by_sdp() {
    for (n, seed) in [(4, 1), (6, 7), (6, 8), (10, 3), (16, 4)] {
        let a = random_sym(n, seed);
        let (status, t) = lambda_max(&a);
        expect(
            &format!("lambda_max {n}x{n} seed {seed}"),
            status,
            t,
            eigenvalues(&a).1,
        );
    }
}

/// min <C, X> s.t. trace X = 1, X PSD  ->  lambda_min(C); X = svec variables.
#[test]
fn lambda_min_by_trace_constrained_sdp() {
    for (n, seed) in [(5, 11), (8, 12)] {
        let cmat = random_sym(n, seed);
        let nvec = n * (n + 1) / 2;
        let trace_row = svec(&DMatrix::identity(n, n));
        // Rows: one equality (trace), then s = x in the PSD cone (A = -I).
        let a_cols: Vec<Vec<f64>> = (0..nvec)
            .map(|j| {
                let mut col = vec![trace_row[j]];
                col.extend((0..nvec).map(|i| if i == j { -1.0 } else { 0.0 }));
                col
            })
            .collect();
        let mut b = vec![1.0];
        b.extend(vec![0.0; nvec]);
        let cones = [ZeroConeT(1), PSDTriangleConeT(n)];
        let (status, x) = solve(&svec(&cmat), &a_cols, &b, &cones);
        let value: f64 = svec(&cmat).iter().zip(&x).map(|(c, x)| c * x).sum();
        expect(
            &format!("lambda_min {n}x{n}"),
            status,
            value,
            eigenvalues(&cmat).0,
        );
    }
}

/// Two PSD cones of different sizes in one problem:
/// min t1 + 2 t2 s.t. t1 I - A1 PSD, t2 I - A2 PSD.
#[test]
fn two_psd_cones() {
    let (a1, a2) = (random_sym(4, 21), random_sym(7, 22));
    let (v1, v2) = (svec(&a1), svec(&a2));
    let (i1, i2) = (
        svec(&DMatrix::identity(4, 4)),
        svec(&DMatrix::identity(7, 7)),
    );
    let col1: Vec<f64> = i1.iter().map(|x| -x).chain(vec![0.0; i2.len()]).collect();
    let col2: Vec<f64> = vec![0.0; i1.len()]
        .into_iter()
        .chain(i2.iter().map(|x| -x))
        .collect();
    let b: Vec<f64> = v1.iter().chain(&v2).map(|x| -x).collect();
    let (status, x) = solve(
        &[1.0, 2.0],
        &[col1, col2],
        &b,
        &[PSDTriangleConeT(4), PSDTriangleConeT(7)],
    );
    let reference = eigenvalues(&a1).1 + 2.0 * eigenvalues(&a2).1;
    expect("two cones (4 and 7)", status, x[0] + 2.0 * x[1], reference);
}

/// A banded 14x14 constraint, sparse enough for Clarabel's chordal
/// decomposition: min t s.t. t I - y T PSD, y = 1  ->  lambda_max(T).
#[test]
fn banded_constraint_with_chordal_decomposition() {
    let n = 14;
    let full = random_sym(n, 31);
    let t = DMatrix::from_fn(n, n, |i, j| {
        if i.abs_diff(j) <= 4 {
            full[(i, j)]
        } else {
            0.0
        }
    });
    let identity_col: Vec<f64> = std::iter::once(0.0)
        .chain(svec(&DMatrix::identity(n, n)).iter().map(|x| -x))
        .collect();
    let t_col: Vec<f64> = std::iter::once(1.0)
        .chain(svec(&t).iter().copied())
        .collect();
    let mut b = vec![1.0];
    b.extend(vec![0.0; n * (n + 1) / 2]);
    let (status, x) = solve(
        &[1.0, 0.0],
        &[identity_col, t_col],
        &b,
        &[ZeroConeT(1), PSDTriangleConeT(n)],
    );
    expect("banded 14x14", status, x[0], eigenvalues(&t).1);
}
