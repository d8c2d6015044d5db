//! End-to-end: Clarabel's SDP path linked against this crate's symbols.

use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettingsBuilder, DefaultSolver, IPSolver, SolverStatus, SupportedConeT,
};
use nalgebra::DMatrix;

/// Packs the upper triangle of a symmetric matrix column by column with
/// off-diagonals scaled by sqrt(2) (Clarabel's `PSDTriangleConeT` layout).
fn svec(m: &DMatrix<f64>) -> Vec<f64> {
    let n = m.nrows();
    let mut v = Vec::with_capacity(n * (n + 1) / 2);
    for j in 0..n {
        for i in 0..=j {
            let scale = if i == j { 1.0 } else { 2f64.sqrt() };
            v.push(scale * m[(i, j)]);
        }
    }
    v
}

/// Deterministic symmetric test matrix.
fn sym_matrix(n: usize, seed: u64) -> DMatrix<f64> {
    let mut state = seed;
    let mut next = || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((state >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    };
    let b = DMatrix::from_fn(n, n, |_, _| next());
    (&b + b.transpose()) * 0.5
}

/// minimize t s.t. t I - A is PSD  ->  t = lambda_max(A).
fn lambda_max_sdp(a: &DMatrix<f64>) -> (SolverStatus, f64) {
    tsf_lapack::link();
    let n = a.nrows();
    let neg_identity: Vec<f64> = svec(&DMatrix::identity(n, n)).iter().map(|x| -x).collect();
    let rows = neg_identity.len();
    let amat = CscMatrix::new(rows, 1, vec![0, rows], (0..rows).collect(), neg_identity);
    let b: Vec<f64> = svec(a).iter().map(|x| -x).collect();
    let p = CscMatrix::zeros((1, 1));
    let cones = [SupportedConeT::PSDTriangleConeT(n)];
    let settings = DefaultSettingsBuilder::default()
        .verbose(false)
        .build()
        .unwrap();
    let mut solver = DefaultSolver::new(&p, &[1.0], &amat, &b, &cones, settings).unwrap();
    solver.solve();
    (solver.solution.status, solver.solution.x[0])
}

#[test]
fn lambda_max_6x6() {
    let a = sym_matrix(6, 7);
    let reference = a.clone().symmetric_eigen().eigenvalues.max();
    let (status, t) = lambda_max_sdp(&a);
    assert_eq!(status, SolverStatus::Solved);
    let err = (t - reference).abs();
    eprintln!("lambda_max 6x6: got {t}, reference {reference}, error {err:e}");
    assert!(err < 1e-7, "error {err}");
}
