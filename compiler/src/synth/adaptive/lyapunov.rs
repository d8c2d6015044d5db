//! The continuous Lyapunov equation `A' P + P A = -Q` by the Kronecker form
//! `(I (x) A' + A' (x) I) vec P = -vec Q` (LU; m <= 8 so at most 64 x 64),
//! with the checks the adaptive design needs: A Hurwitz (eigenvalues), P
//! symmetric positive definite, and the residual of the solution.

use nalgebra::DMatrix;

/// The solved equation and what was checked.
#[derive(Debug, Clone)]
pub struct Lyapunov {
    /// P (symmetrized).
    pub p: DMatrix<f64>,
    /// Real parts of the eigenvalues of A, ascending.
    pub a_eig_re: Vec<f64>,
    /// Eigenvalues of P, ascending.
    pub p_eig: Vec<f64>,
    /// ||A'P + PA + Q||_F / ||Q||_F.
    pub residual: f64,
}

/// Why the reference model is refused.
#[derive(Debug, Clone, PartialEq)]
pub enum Refusal {
    /// A has an eigenvalue with real part >= 0 (the largest real part).
    NotHurwitz(f64),
    /// Q is not positive definite (its smallest eigenvalue).
    QNotDefinite(f64),
    /// The Kronecker system is singular or P is not positive definite.
    NoPositiveP(String),
    /// The Schur iteration for the eigenvalues of A did not converge.
    NoEigenvalues,
}

impl std::fmt::Display for Refusal {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Refusal::NotHurwitz(re) => write!(f, "the reference model A_m is not Hurwitz (largest real part of an eigenvalue {re:.6e})"),
            Refusal::QNotDefinite(l) => write!(f, "Q is not positive definite (smallest eigenvalue {l:.6e})"),
            Refusal::NoPositiveP(why) => write!(f, "no positive definite P: {why}"),
            Refusal::NoEigenvalues => write!(f, "the eigenvalues of the reference model A_m did not converge in {SCHUR_ITERATIONS} Schur iterations"),
        }
    }
}

fn sorted(mut v: Vec<f64>) -> Vec<f64> {
    v.sort_by(f64::total_cmp);
    v
}

/// Iteration cap of the Schur decomposition behind the eigenvalues of A.
/// nalgebra's `complex_eigenvalues` iterates without a cap to machine
/// precision and does not return on some matrices with repeated
/// eigenvalues (a critically damped 6-state loop, in the tests).
pub const SCHUR_ITERATIONS: usize = 100_000;

/// Convergence tolerance of that Schur decomposition.
const SCHUR_EPS: f64 = 1e-13;

/// Real parts of the eigenvalues of `a`, ascending, by a Schur decomposition
/// with a bounded number of iterations; `None` if it does not converge.
pub fn eigenvalue_real_parts(a: &DMatrix<f64>) -> Option<Vec<f64>> {
    let schur = a.clone().try_schur(SCHUR_EPS, SCHUR_ITERATIONS)?;
    Some(sorted(
        schur.complex_eigenvalues().iter().map(|z| z.re).collect(),
    ))
}

/// Solves `A' P + P A = -Q` and checks A Hurwitz, Q > 0 and P > 0.
pub fn solve(a: &DMatrix<f64>, q: &DMatrix<f64>) -> Result<Lyapunov, Refusal> {
    let m = a.nrows();
    let a_eig_re = eigenvalue_real_parts(a).ok_or(Refusal::NoEigenvalues)?;
    let worst = a_eig_re.last().copied().unwrap_or(f64::NAN);
    // NaN (an empty or non-finite A_m) is refused too.
    if worst.is_nan() || worst >= 0.0 {
        return Err(Refusal::NotHurwitz(worst));
    }
    let q_min = q.clone().symmetric_eigen().eigenvalues.min();
    if q_min.is_nan() || q_min <= 0.0 {
        return Err(Refusal::QNotDefinite(q_min));
    }
    let eye = DMatrix::<f64>::identity(m, m);
    let at = a.transpose();
    let k = eye.kronecker(&at) + at.kronecker(&eye);
    let rhs = DMatrix::from_column_slice(m * m, 1, (-q).as_slice());
    let x = k
        .lu()
        .solve(&rhs)
        .ok_or_else(|| Refusal::NoPositiveP("the Kronecker system is singular".into()))?;
    let p = DMatrix::from_column_slice(m, m, x.as_slice());
    let p = (&p + p.transpose()) * 0.5;
    let residual = (a.transpose() * &p + &p * a + q).norm() / q.norm();
    let p_eig = sorted(
        p.clone()
            .symmetric_eigen()
            .eigenvalues
            .iter()
            .copied()
            .collect(),
    );
    let p_min = p_eig.first().copied().unwrap_or(f64::NAN);
    if p_min.is_nan() || p_min <= 0.0 || residual.is_nan() || residual >= 1e-8 {
        return Err(Refusal::NoPositiveP(format!(
            "smallest eigenvalue {p_min:.6e}, relative residual {residual:.3e}"
        )));
    }
    Ok(Lyapunov {
        p,
        a_eig_re,
        p_eig,
        residual,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A critically damped 6-state loop (Xu & Huang's spacecraft near the
    /// origin, u = -J (0.44 w + 0.0968 q)) on which nalgebra's uncapped
    /// `complex_eigenvalues` does not return: the capped Schur form does.
    #[test]
    fn repeated_eigenvalues_get_an_answer() {
        let s = 0.5 * (1.0f64 - 3.0 * 0.056 * 0.056).sqrt();
        let j = nalgebra::Matrix3::new(350.0, 3.0, 4.0, 3.0, 270.0, 10.0, 4.0, 10.0, 190.0);
        let j_inv = j.try_inverse().expect("J invertible"); // ok: unit test
        let f = DMatrix::from_row_slice(
            3,
            6,
            &[
                -154.0, -1.32, -1.76, -33.88, -0.2904, -0.3872, -1.32, -118.8, -4.4, -0.2904,
                -26.136, -0.968, -1.76, -4.4, -83.6, -0.3872, -0.968, -18.392,
            ],
        );
        let mut a = DMatrix::<f64>::zeros(6, 6);
        let mut b = DMatrix::<f64>::zeros(6, 3);
        for i in 0..3 {
            a[(3 + i, i)] = s;
            for k in 0..3 {
                b[(i, k)] = j_inv[(i, k)];
            }
        }
        let acl = &a + &b * &f;
        // Each axis about s^2 + 0.44 s + 0.0484 * 2 s (s = sqrt(1 - |q|^2) /
        // 2 = 0.497), J coupling them: six poles with real parts near -0.22.
        let re = eigenvalue_real_parts(&acl).expect("converges"); // ok: unit test
        assert_eq!(re.len(), 6);
        assert!(re.iter().all(|&r| (-0.35..-0.1).contains(&r)), "{re:?}");
        let l = solve(&acl, &DMatrix::identity(6, 6)).expect("Hurwitz"); // ok: unit test
        assert!(l.residual < 1e-9, "{}", l.residual);
    }

    #[test]
    fn scalar_and_diagonal_closed_forms() {
        // a p + p a = -q  =>  p = -q / (2 a).
        let l = solve(
            &DMatrix::from_element(1, 1, -2.0),
            &DMatrix::from_element(1, 1, 2.0),
        )
        .unwrap(); // ok: unit test
        assert!((l.p[(0, 0)] - 0.5).abs() < 1e-14);
        let a = DMatrix::from_diagonal(&nalgebra::DVector::from_vec(vec![-0.5, -1.0, -4.0]));
        let l = solve(&a, &DMatrix::identity(3, 3)).unwrap(); // ok: unit test
        for (k, ak) in [-0.5, -1.0, -4.0].iter().enumerate() {
            assert!((l.p[(k, k)] + 1.0 / (2.0 * ak)).abs() < 1e-13);
        }
    }

    #[test]
    fn a_full_matrix_satisfies_the_equation_and_p_is_positive() {
        let a = DMatrix::from_row_slice(2, 2, &[0.0, 1.0, -2.0, -3.0]);
        let q = DMatrix::from_row_slice(2, 2, &[2.0, 0.5, 0.5, 1.0]);
        let l = solve(&a, &q).unwrap(); // ok: unit test
        let r = a.transpose() * &l.p + &l.p * &a + &q;
        assert!(r.norm() < 1e-12);
        assert!(l.p_eig[0] > 0.0);
        assert!((l.a_eig_re[0] + 2.0).abs() < 1e-12 && (l.a_eig_re[1] + 1.0).abs() < 1e-12);
    }

    #[test]
    fn unstable_or_marginal_models_are_refused() {
        let a = DMatrix::from_row_slice(2, 2, &[0.0, 1.0, -1.0, 0.0]);
        assert!(matches!(
            solve(&a, &DMatrix::identity(2, 2)),
            Err(Refusal::NotHurwitz(_))
        ));
        let a = DMatrix::from_element(1, 1, 0.3);
        assert!(matches!(
            solve(&a, &DMatrix::identity(1, 1)),
            Err(Refusal::NotHurwitz(_))
        ));
    }
}
