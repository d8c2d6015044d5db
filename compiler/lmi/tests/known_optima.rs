//! End-to-end problems with known optima, solved by Clarabel through the
//! pure-Rust LAPACK (every PSD cone has size >= 4 so LAPACK is exercised).

mod common;

use common::{pseudo_random, pseudo_random_sym, rel_err, solve_ok};
use nalgebra::{DMatrix, DVector};
use tsf_lmi::{Expr, LmiError, Problem, Relation, SolveSettings, SolveStatus};

type TestResult = Result<(), LmiError>;

/// min trace(C X) s.t. X ⪰ 0, trace X = 1 equals λ_min(C).
#[test]
fn min_trace_over_density_matrices_is_lambda_min() -> TestResult {
    let c = pseudo_random_sym(5, 11);
    let mut pr = Problem::new();
    let x = pr.symmetric("X", 5)?;
    pr.psd("X psd", Expr::var(x), 0.0)?;
    pr.add_scalar("trace X = 1", Expr::var(x).trace()?, Relation::Eq, 1.0)?;
    pr.minimize(Expr::var(x).left_mul(&c)?.trace()?)?;
    let sol = solve_ok(&pr, "lambda_min 5x5")?;
    let expected = c.symmetric_eigenvalues().min();
    let err = (sol.objective - expected).abs();
    println!(
        "lambda_min: got {}, expected {expected}, error {err:.2e}",
        sol.objective
    );
    assert!(err < 1e-7, "error {err:e}");
    // The optimal X is the projector on the bottom eigenvector.
    let xv = sol.value(x)?;
    assert!((xv.trace() - 1.0).abs() < 1e-7);
    assert!(((c * xv).trace() - expected).abs() < 1e-7);
    Ok(())
}

/// min t s.t. t I - A ⪰ 0 equals λ_max(A); maximize 3 - t gives 3 - λ_max.
#[test]
fn max_eigenvalue_via_epigraph() -> TestResult {
    let a = pseudo_random_sym(6, 23);
    let expected = a.symmetric_eigenvalues().max();
    for maximize in [false, true] {
        let mut pr = Problem::new();
        let t = pr.scalar("t")?;
        let lmi = Expr::scaled(t, &DMatrix::identity(6, 6))?.sub(Expr::constant(&a)?)?;
        pr.psd("tI - A", lmi, 0.0)?;
        let (got, label) = if maximize {
            let obj = Expr::var(t)
                .scale(-1.0)?
                .add_constant(&DMatrix::from_element(1, 1, 3.0))?;
            pr.maximize(obj)?;
            let sol = solve_ok(&pr, "lambda_max 6x6 (maximize)")?;
            (3.0 - sol.objective, "maximize")
        } else {
            pr.minimize(Expr::var(t))?;
            (solve_ok(&pr, "lambda_max 6x6")?.objective, "minimize")
        };
        let err = (got - expected).abs();
        println!("lambda_max ({label}): got {got}, expected {expected}, error {err:.2e}");
        assert!(err < 1e-7, "{label}: error {err:e}");
    }
    Ok(())
}

/// Full M (2x3) pinned to K by equalities, diagonal D (3x3), transposed term:
/// min trace D s.t. [[D, M'w], [w'M, 1]] ⪰ 0. With m = K'w the optimum is
/// (Σ|m_i|)², attained at d_i = |m_i| Σ|m_j| (Cauchy-Schwarz on Σ m_i²/d_i ≤ 1).
#[test]
fn full_and_diagonal_variables_with_transposed_terms() -> TestResult {
    let k = DMatrix::from_row_slice(2, 3, &[0.5, -1.0, 2.0, 1.5, 0.25, -0.75]);
    let w = DMatrix::from_column_slice(2, 1, &[0.8, -0.6]);
    let mut pr = Problem::new();
    let m = pr.full("M", 2, 3)?;
    let d = pr.diagonal("D", 3)?;
    for i in 0..2 {
        for j in 0..3 {
            let entry = Expr::product(
                &DMatrix::identity(2, 2).rows(i, 1).into_owned(),
                m,
                &DMatrix::identity(3, 3).columns(j, 1).into_owned(),
            )?;
            pr.add_scalar(&format!("M[{i},{j}]"), entry, Relation::Eq, k[(i, j)])?;
        }
    }
    let coupling = Expr::product_t(&DMatrix::identity(3, 3), m, &w)?;
    let lmi = Expr::sym_blocks(vec![
        vec![Some(Expr::var(d)), Some(coupling)],
        vec![None, Some(Expr::identity(1))],
    ])?;
    pr.psd("[D, M'w; w'M, 1]", lmi, 0.0)?;
    pr.minimize(Expr::var(d).trace()?)?;
    let sol = solve_ok(&pr, "full+diagonal closed form")?;

    let mv = k.transpose() * &w;
    let l1: f64 = mv.iter().map(|v| v.abs()).sum();
    let err = rel_err(sol.objective, l1 * l1);
    println!(
        "full+diag: got {}, expected {}, rel error {err:.2e}",
        sol.objective,
        l1 * l1
    );
    assert!(err < 1e-7, "objective error {err:e}");
    let dv = sol.value(d)?;
    for i in 0..3 {
        let expected = mv[i].abs() * l1;
        assert!(
            (dv[(i, i)] - expected).abs() < 1e-5,
            "d[{i}] = {}",
            dv[(i, i)]
        );
    }
    assert!((sol.value(m)? - &k).abs().max() < 1e-7);
    Ok(())
}

/// Solution of A'P + PA = -I through the Kronecker system.
fn lyapunov(a: &DMatrix<f64>) -> Option<DMatrix<f64>> {
    let n = a.nrows();
    let eye = DMatrix::<f64>::identity(n, n);
    let at = a.transpose();
    let k = eye.kronecker(&at) + at.kronecker(&eye);
    let rhs = -DVector::from_column_slice(eye.as_slice());
    let vec_p = k.lu().solve(&rhs)?;
    Some(DMatrix::from_column_slice(n, n, vec_p.as_slice()))
}

fn stable_4x4() -> DMatrix<f64> {
    pseudo_random(4, 4, 5) - DMatrix::identity(4, 4) * 2.5
}

/// min trace P s.t. A'P + PA ⪯ -I, P ⪰ 0: every feasible P dominates the
/// Lyapunov solution of A'P + PA = -I, so that is the optimum.
#[test]
fn lyapunov_lmi_recovers_lyapunov_equation_solution() -> TestResult {
    let a = stable_4x4();
    assert!(a.complex_eigenvalues().iter().all(|l| l.re < 0.0));
    let mut pr = Problem::new();
    let p = pr.symmetric("P", 4)?;
    pr.psd("P psd", Expr::var(p), 0.0)?;
    let lyap = pr.nsd("A'P + PA < 0", Expr::var(p).right_mul(&a)?.he()?, 1.0)?;
    pr.minimize(Expr::var(p).trace()?)?;
    let sol = solve_ok(&pr, "Lyapunov 4x4")?;
    let Some(expected) = lyapunov(&a) else {
        panic!("Kronecker system singular");
    };
    let pv = sol.value(p)?;
    let err = (pv - &expected).norm() / expected.norm();
    println!("Lyapunov: ||P - P_lyap||_F / ||P_lyap||_F = {err:.2e}");
    assert!(err < 1e-6, "relative error {err:e}");

    let margin = pr.margin(lyap, sol.assignment()?)?;
    println!("Lyapunov margin: {margin:?}");
    assert!(margin.certified());
    assert!((margin.slack - 1.0).abs() < 1e-6);
    Ok(())
}

/// An unstable A admits no P ⪰ I with A'P + PA ⪯ -I.
#[test]
fn unstable_lyapunov_is_primal_infeasible() -> TestResult {
    let a = stable_4x4() + DMatrix::identity(4, 4) * 5.0;
    let mut pr = Problem::new();
    let p = pr.symmetric("P", 4)?;
    pr.psd("P > 0", Expr::var(p), 1.0)?;
    pr.nsd("A'P + PA < 0", Expr::var(p).right_mul(&a)?.he()?, 1.0)?;
    let sol = pr.solve(&SolveSettings::default())?;
    println!(
        "infeasible: status {:?}, {} iterations, {:.2} ms",
        sol.status,
        sol.iterations,
        sol.solve_time * 1e3
    );
    assert_eq!(sol.status, SolveStatus::PrimalInfeasible);
    assert_eq!(
        sol.value(p).err(),
        Some(LmiError::NotSolved(SolveStatus::PrimalInfeasible))
    );
    assert!(sol.assignment_any_status().value(p).is_ok());
    Ok(())
}

/// An objective unbounded below is dual infeasible; an iteration cap is reported.
#[test]
fn unbounded_and_iteration_limit_statuses() -> TestResult {
    let mut pr = Problem::new();
    let x = pr.symmetric("X", 4)?;
    let t = pr.scalar("t")?;
    pr.psd("X psd", Expr::var(x), 0.0)?;
    pr.add_scalar("t <= 5", Expr::var(t), Relation::Le, 5.0)?;
    pr.minimize(Expr::var(t).add(Expr::var(x).trace()?)?)?;
    let sol = pr.solve(&SolveSettings::default())?;
    assert_eq!(sol.status, SolveStatus::DualInfeasible);

    pr.add_scalar("t >= -5", Expr::var(t), Relation::Ge, -5.0)?;
    let settings = SolveSettings {
        max_iter: 1,
        ..SolveSettings::default()
    };
    let sol = pr.solve(&settings)?;
    assert_eq!(sol.status, SolveStatus::MaxIterations);
    assert!(matches!(sol.assignment(), Err(LmiError::NotSolved(_))));
    let sol = solve_ok(&pr, "bounded")?;
    assert!((sol.objective + 5.0).abs() < 1e-7);
    Ok(())
}
