//! Helpers shared by the integration tests.
#![allow(dead_code)]

use nalgebra::DMatrix;
use tsf_lmi::{Problem, Solution, SolveSettings, SolveStatus};

/// Deterministic pseudo-random matrix with entries in [-1, 1) (xorshift64).
pub fn pseudo_random(rows: usize, cols: usize, seed: u64) -> DMatrix<f64> {
    let mut s = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    DMatrix::from_fn(rows, cols, |_, _| {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    })
}

/// Symmetric pseudo-random matrix.
pub fn pseudo_random_sym(n: usize, seed: u64) -> DMatrix<f64> {
    let m = pseudo_random(n, n, seed);
    (&m + m.transpose()) * 0.5
}

/// Solves with default settings, prints the timing line, and requires `Solved`.
pub fn solve_ok(problem: &Problem, label: &str) -> Result<Solution, tsf_lmi::LmiError> {
    let solution = problem.solve(&SolveSettings::default())?;
    println!(
        "{label}: status {:?}, {} iterations, solve {:.2} ms (total {:.2} ms); {}",
        solution.status,
        solution.iterations,
        solution.solve_time * 1e3,
        solution.total_time * 1e3,
        problem.stats()
    );
    assert_eq!(solution.status, SolveStatus::Solved, "{label}");
    Ok(solution)
}

/// `|a - b| / max(1, |b|)`.
pub fn rel_err(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs().max(1.0)
}
