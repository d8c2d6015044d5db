//! Bounded-real lemma: the LMI optimum of g = γ² matches the H-inf norm found
//! independently by bisection on the Hamiltonian's imaginary-axis eigenvalues.

mod common;

use common::{pseudo_random, solve_ok};
use nalgebra::DMatrix;
use tsf_lmi::{Expr, LmiError, Problem, SolveSettings, SolveStatus};

/// Whether `[[A, BB'/γ²], [-C'C, -A']]` has an eigenvalue on the imaginary
/// axis, which for stable A (and D = 0) holds exactly when γ ≤ ||G||∞.
fn hamiltonian_has_imaginary_eigenvalue(
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
    c: &DMatrix<f64>,
    gamma: f64,
) -> bool {
    let n = a.nrows();
    let mut h = DMatrix::zeros(2 * n, 2 * n);
    h.view_mut((0, 0), (n, n)).copy_from(a);
    h.view_mut((0, n), (n, n))
        .copy_from(&(b * b.transpose() / (gamma * gamma)));
    h.view_mut((n, 0), (n, n)).copy_from(&-(c.transpose() * c));
    h.view_mut((n, n), (n, n)).copy_from(&-a.transpose());
    let tol = 1e-8 * h.norm();
    h.complex_eigenvalues().iter().any(|l| l.re.abs() < tol)
}

/// ||G||∞ by bisection to 1e-12 relative.
fn hinf_norm_by_bisection(a: &DMatrix<f64>, b: &DMatrix<f64>, c: &DMatrix<f64>) -> f64 {
    let mut hi = 1.0;
    while hamiltonian_has_imaginary_eigenvalue(a, b, c, hi) {
        hi *= 2.0;
    }
    let mut lo = 0.0;
    while hi - lo > 1e-12 * hi {
        let mid = 0.5 * (lo + hi);
        if hamiltonian_has_imaginary_eigenvalue(a, b, c, mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    hi
}

/// min g s.t. [[He(AX), B, XC'], [B', -gI, 0], [CX, 0, -I]] ⪯ 0, X ⪰ 0.
fn hinf_norm_by_lmi(
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
    c: &DMatrix<f64>,
) -> Result<[(f64, f64); 2], LmiError> {
    let (n, m, p) = (a.nrows(), b.ncols(), c.nrows());
    let mut pr = Problem::new();
    let x = pr.symmetric("X", n)?;
    let g = pr.scalar("g")?;
    let lmi = Expr::sym_blocks(vec![
        vec![
            Some(Expr::var(x).left_mul(a)?.he()?),
            Some(Expr::constant(b)?),
            Some(Expr::var(x).right_mul(&c.transpose())?),
        ],
        vec![
            None,
            Some(Expr::scaled(g, &-DMatrix::identity(m, m))?),
            None,
        ],
        vec![None, None, Some(Expr::identity(p).scale(-1.0)?)],
    ])?;
    pr.nsd("bounded real", lmi, 0.0)?;
    pr.psd("X psd", Expr::var(x), 0.0)?;
    pr.minimize(Expr::var(g))?;
    let sol = solve_ok(&pr, &format!("H-inf BRL n={n}"))?;
    // Clarabel may split the PSD cone along its sparsity pattern (the zero
    // block); the caller compares both answers with the reference.
    let settings = SolveSettings {
        chordal_decomposition: false,
        ..SolveSettings::default()
    };
    let dense = pr.solve(&settings)?;
    assert_eq!(dense.status, SolveStatus::Solved);
    Ok([
        (sol.objective.sqrt(), sol.solve_time),
        (dense.objective.sqrt(), dense.solve_time),
    ])
}

#[test]
fn bounded_real_lemma_matches_hamiltonian_bisection() -> Result<(), LmiError> {
    let systems = [
        // Lightly damped oscillator plus a real pole: the peak is at a resonance.
        (
            DMatrix::from_row_slice(3, 3, &[-0.2, 2.0, 0.0, -2.0, -0.2, 1.0, 0.0, 0.0, -1.0]),
            pseudo_random(3, 2, 31),
            pseudo_random(2, 3, 32),
        ),
        (
            pseudo_random(4, 4, 41) - DMatrix::identity(4, 4) * 2.0,
            pseudo_random(4, 2, 42),
            pseudo_random(2, 4, 43),
        ),
        (
            DMatrix::from_row_slice(2, 2, &[0.0, 1.0, -3.0, -0.5]),
            DMatrix::from_column_slice(2, 2, &[0.0, 1.0, 1.0, 0.5]),
            DMatrix::from_row_slice(2, 2, &[1.0, 0.0, 0.3, 1.0]),
        ),
    ];
    for (a, b, c) in &systems {
        assert!(a.complex_eigenvalues().iter().all(|l| l.re < 0.0));
        let reference = hinf_norm_by_bisection(a, b, c);
        for ((gamma, time), how) in hinf_norm_by_lmi(a, b, c)?
            .into_iter()
            .zip(["", " (no chordal)"])
        {
            let err = (gamma - reference).abs() / reference;
            println!(
                "H-inf n={}{how}: LMI gamma {gamma:.10}, Hamiltonian {reference:.10}, rel error {err:.2e}, solve {:.2} ms",
                a.nrows(),
                time * 1e3
            );
            assert!(err < 1e-5, "relative error {err:e}");
        }
    }
    Ok(())
}
