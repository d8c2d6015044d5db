//! The solver-neutral cone program: packing, stacking and merging checked
//! without a solver, then solved through the `ConeSolver` seam.

mod common;

use std::cell::RefCell;
use std::f64::consts::SQRT_2;

use common::pseudo_random;
use nalgebra::{DMatrix, DVector};
use tsf_lmi::{
    Assignment, ClarabelSolver, Cone, ConeProgram, ConeSolution, ConeSolver, CscMatrix, Expr,
    LmiError, Problem, Relation, SolveSettings, SolveStatus, Var, VarKind,
};

type TestResult = Result<(), LmiError>;

/// The matrix as a dense one, built from its triplets.
fn dense(a: &CscMatrix) -> DMatrix<f64> {
    let mut d = DMatrix::zeros(a.nrows, a.ncols);
    for (i, j, v) in a.triplets() {
        d[(i, j)] += v;
    }
    d
}

/// Upper triangle column by column, off-diagonals times √2.
fn svec(m: &DMatrix<f64>) -> Vec<f64> {
    let n = m.nrows();
    (0..n)
        .flat_map(|j| (0..=j).map(move |i| (i, j)))
        .map(|(i, j)| {
            if i == j {
                m[(i, i)]
            } else {
                SQRT_2 * m[(i, j)]
            }
        })
        .collect()
}

/// Inverse of [`svec`] for an `n x n` symmetric matrix.
fn smat(packed: &[f64], n: usize) -> DMatrix<f64> {
    let mut m = DMatrix::zeros(n, n);
    let mut k = 0;
    for j in 0..n {
        for i in 0..=j {
            let v = if i == j {
                packed[k]
            } else {
                packed[k] / SQRT_2
            };
            m[(i, j)] = v;
            m[(j, i)] = v;
            k += 1;
        }
    }
    m
}

/// `b - A x`.
fn slack(program: &ConeProgram, x: &[f64]) -> Vec<f64> {
    let ax = dense(&program.a) * DVector::from_column_slice(x);
    program
        .b
        .iter()
        .zip(ax.iter())
        .map(|(b, a)| b - a)
        .collect()
}

/// Fills every variable with pseudo-random values of the right structure.
fn random_assignment(problem: &Problem, seed: u64) -> Result<Assignment, LmiError> {
    let mut values = problem.assignment();
    let vars: Vec<Var> = problem.vars().map(|(_, v)| v).collect();
    for (k, v) in vars.into_iter().enumerate() {
        let (r, c) = v.shape();
        let m = pseudo_random(r, c, seed + k as u64);
        let m = match v.kind() {
            VarKind::Symmetric(_) => (&m + m.transpose()) * 0.5,
            VarKind::Diagonal(_) => DMatrix::from_diagonal(&m.diagonal()),
            _ => m,
        };
        values.set(v, m)?;
    }
    Ok(values)
}

/// The H-inf-like block with every kind of variable and transposed terms.
fn mixed_problem() -> Result<Problem, LmiError> {
    let mut pr = Problem::new();
    let x = pr.symmetric("X", 3)?;
    let m = pr.full("M", 2, 3)?;
    let d = pr.diagonal("T", 2)?;
    let g = pr.scalar("g")?;
    let a = pseudo_random(3, 3, 1);
    let b = pseudo_random(3, 2, 2);
    let c = pseudo_random(2, 3, 3);
    let s = pseudo_random(2, 2, 9);
    let ups = Expr::var(x)
        .left_mul(&a)?
        .add(Expr::product(&b, m, &DMatrix::identity(3, 3))?)?
        .he()?
        .add(Expr::var(x).scale(0.7)?)?;
    let e12 = Expr::product_t(&DMatrix::identity(3, 3), m, &pseudo_random(2, 2, 5))?
        .add(Expr::constant(&b)?)?;
    let e22 = Expr::scaled(g, &(-DMatrix::identity(2, 2)))?
        .add(Expr::var(d))?
        .add(Expr::constant(&(&s + s.transpose()))?)?;
    let e13 = Expr::product(&DMatrix::identity(3, 3), x, &c.transpose())?;
    let lmi = Expr::sym_blocks(vec![
        vec![Some(ups), Some(e12), Some(e13)],
        vec![None, Some(e22), None],
        vec![None, None, Some(Expr::identity(2).scale(-1.0)?)],
    ])?;
    pr.nsd("Q", lmi.clone(), 0.25)?;
    pr.psd("Q flipped", lmi, 0.0)?;
    pr.add_scalar("g bound", Expr::var(g), Relation::Le, 5.0)?;
    pr.add_scalar("trace", Expr::var(x).trace()?, Relation::Eq, 1.0)?;
    pr.minimize(Expr::var(g))?;
    Ok(pr)
}

#[test]
fn slack_equals_svec_of_evaluated_constraint() -> TestResult {
    let pr = mixed_problem()?;
    let values = random_assignment(&pr, 42)?;
    let program = pr.cone_program();
    let slack = slack(&program, &values.unknowns());
    // Expected slacks in solver order: equality, inequality, then the two PSD cones.
    let ids: Vec<_> = pr.constraints().collect();
    let e = pr.evaluate(ids[0], &values)?;
    let eye = DMatrix::<f64>::identity(e.nrows(), e.nrows());
    let mut expected = vec![pr.evaluate(ids[3], &values)?[(0, 0)] - 1.0];
    expected.push(5.0 - pr.evaluate(ids[2], &values)?[(0, 0)]);
    expected.extend(svec(&(-&e - &eye * 0.25)));
    expected.extend(svec(&e));
    assert_eq!(slack.len(), expected.len());
    let worst = slack
        .iter()
        .zip(&expected)
        .map(|(s, e)| (s - e).abs())
        .fold(0.0, f64::max);
    assert!(worst < 1e-12, "worst slack mismatch {worst:e}");
    let expected_cones = vec![
        Cone::Zero(1),
        Cone::Nonnegative(1),
        Cone::PsdTriangle(7),
        Cone::PsdTriangle(7),
    ];
    assert_eq!(program.cones, expected_cones);
    assert_eq!(pr.stats().psd_cones, vec![7, 7]);
    assert_eq!(pr.stats().nnz, program.a.nnz());
    assert_eq!(pr.stats().rows, program.b.len());
    Ok(())
}

#[test]
fn symmetric_unknown_is_one_column_and_packing_is_sqrt2() -> TestResult {
    let mut pr = Problem::new();
    let x = pr.symmetric("X", 2)?;
    pr.psd("X", Expr::var(x), 0.0)?;
    // s = svec(X) = [x00, √2 x01, x11] = -A x.
    let a = dense(&pr.cone_program().a);
    let expected =
        DMatrix::from_row_slice(3, 3, &[-1.0, 0.0, 0.0, 0.0, -SQRT_2, 0.0, 0.0, 0.0, -1.0]);
    assert_eq!(a, expected);
    Ok(())
}

#[test]
fn asymmetric_lmi_is_rejected() -> TestResult {
    let mut pr = Problem::new();
    let x = pr.symmetric("X", 2)?;
    let a = DMatrix::from_row_slice(2, 2, &[1.0, 2.0, 0.0, 1.0]);
    let err = pr.nsd("AX", Expr::var(x).left_mul(&a)?, 0.0);
    assert!(matches!(err, Err(LmiError::NotSymmetric { .. })), "{err:?}");
    Ok(())
}

#[test]
fn duplicate_triplets_are_merged() -> TestResult {
    let mut pr = Problem::new();
    let x = pr.symmetric("X", 3)?;
    // X + X' + 2X: every unknown appears in four terms of each entry.
    let e = Expr::var(x).he()?.add(Expr::var(x).scale(2.0)?)?;
    pr.psd("4X", e, 0.0)?;
    let program = pr.cone_program();
    assert_eq!(program.a.nnz(), 6);
    let diag = -4.0;
    let off = -4.0 * SQRT_2;
    assert_eq!(program.a.nzval, [diag, off, diag, off, off, diag]);
    Ok(())
}

/// `M` with eigenvalues 3, 1 and 1: `λ_max(M) = 3`.
fn m3() -> DMatrix<f64> {
    DMatrix::from_row_slice(3, 3, &[2.0, 1.0, 0.0, 1.0, 2.0, 0.0, 0.0, 0.0, 1.0])
}

/// min t + u s.t. t I - M ⪰ 0, t ≤ 10, u = 0.5: optimum λ_max(M) + 0.5 = 3.5
/// at `(t, u) = (3, 0.5)`; `maximize` states it as max -(t + u) (optimum -3.5).
fn epigraph(maximize: bool) -> Result<Problem, LmiError> {
    let mut pr = Problem::new();
    let t = pr.scalar("t")?;
    let u = pr.scalar("u")?;
    let lmi = Expr::scaled(t, &DMatrix::identity(3, 3))?.sub(Expr::constant(&m3())?)?;
    pr.psd("tI - M", lmi, 0.0)?;
    pr.add_scalar("t <= 10", Expr::var(t), Relation::Le, 10.0)?;
    pr.add_scalar("u = 0.5", Expr::var(u), Relation::Eq, 0.5)?;
    let sum = Expr::var(t).add(Expr::var(u))?;
    if maximize {
        pr.maximize(sum.scale(-1.0)?)?;
    } else {
        pr.minimize(sum)?;
    }
    Ok(pr)
}

/// Known optimum of [`epigraph`].
const OPTIMUM: [f64; 2] = [3.0, 0.5];

#[test]
fn known_optimum_lowers_to_the_documented_program() -> TestResult {
    let program = epigraph(false)?.cone_program();
    assert_eq!(program.n_vars, 2);
    assert_eq!(
        program.cones,
        vec![Cone::Zero(1), Cone::Nonnegative(1), Cone::PsdTriangle(3)]
    );
    let rows: usize = program.cones.iter().map(|c| c.dim()).sum();
    assert_eq!((rows, program.a.nrows, program.a.ncols), (8, 8, 2));
    assert_eq!(program.p, CscMatrix::zeros(2, 2));
    assert_eq!(program.q, vec![1.0, 1.0]);
    // Rows: u - 0.5 = 0; 10 - t ≥ 0; svec(t I - M) with M01 = 1 packed as -√2.
    let b_psd = [-2.0, -SQRT_2, -2.0, 0.0, 0.0, -1.0];
    assert_eq!(program.b[..2], [-0.5, 10.0]);
    assert_eq!(program.b[2..], b_psd);
    let a = dense(&program.a);
    assert_eq!(
        a.column(0).as_slice(),
        [0.0, 1.0, -1.0, 0.0, -1.0, 0.0, 0.0, -1.0]
    );
    assert_eq!(
        a.column(1).as_slice(),
        [-1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
    );

    // The known optimum is feasible and on the boundary of the PSD cone;
    // slightly below it the PSD slack leaves the cone.
    let at = |t: f64| slack(&program, &[t, OPTIMUM[1]]);
    let s = at(OPTIMUM[0]);
    assert_eq!(s[0], 0.0);
    assert!(s[1] > 0.0);
    let lambda_min = |s: &[f64]| smat(&s[2..], 3).symmetric_eigenvalues().min();
    assert!(lambda_min(&s).abs() < 1e-12, "{}", lambda_min(&s));
    assert!(lambda_min(&at(OPTIMUM[0] - 1e-3)) < -1e-4);
    let cost: f64 = program.q.iter().zip(OPTIMUM).map(|(q, x)| q * x).sum();
    assert_eq!(cost, 3.5);

    // Maximising the negation is the same program.
    assert_eq!(epigraph(true)?.cone_program(), program);
    Ok(())
}

/// Hands the program to Clarabel and keeps a copy of what it saw.
#[derive(Default)]
struct Recording {
    seen: RefCell<Vec<ConeProgram>>,
}

impl ConeSolver for Recording {
    fn name(&self) -> &'static str {
        "recording clarabel"
    }

    fn solve(
        &self,
        program: &ConeProgram,
        settings: &SolveSettings,
    ) -> Result<ConeSolution, LmiError> {
        self.seen.borrow_mut().push(program.clone());
        ClarabelSolver.solve(program, settings)
    }
}

#[test]
fn known_optimum_is_solved_through_the_seam() -> TestResult {
    for (maximize, expected) in [(false, 3.5), (true, -3.5)] {
        let pr = epigraph(maximize)?;
        let recording = Recording::default();
        let solution = pr.solve_with(&recording, &SolveSettings::default())?;
        assert_eq!(solution.status, SolveStatus::Solved);
        assert_eq!(solution.solver, "recording clarabel");
        assert!(
            (solution.objective - expected).abs() < 1e-7,
            "{}",
            solution.objective
        );
        assert!((solution.dual_objective - expected).abs() < 1e-6);
        let (t, u) = (pr.vars().next(), pr.vars().nth(1));
        let values = solution.assignment()?;
        for (var, want) in [t, u].into_iter().flatten().zip(OPTIMUM) {
            let got = values.value(var.1)?[(0, 0)];
            assert!((got - want).abs() < 1e-6, "{}: {got}", var.0);
        }
        assert_eq!(*recording.seen.borrow(), vec![pr.cone_program()]);
        // The default solve is the same solver on the same program.
        let direct = pr.solve(&SolveSettings::default())?;
        assert_eq!(direct.solver, "clarabel");
        assert_eq!(direct.objective, solution.objective);
    }
    Ok(())
}

/// Returns a fixed iterate without solving anything.
struct Stub {
    x: Vec<f64>,
}

impl ConeSolver for Stub {
    fn name(&self) -> &'static str {
        "stub"
    }

    fn solve(&self, program: &ConeProgram, _: &SolveSettings) -> Result<ConeSolution, LmiError> {
        let cost = program.q.iter().zip(&self.x).map(|(q, x)| q * x).sum();
        Ok(ConeSolution {
            status: SolveStatus::Solved,
            iterations: 0,
            solve_time: 0.0,
            objective: cost,
            dual_objective: cost,
            primal_residual: 0.0,
            dual_residual: 0.0,
            x: self.x.clone(),
            unscaled_retry: false,
        })
    }
}

#[test]
fn any_solver_plugs_into_the_seam() -> TestResult {
    let pr = epigraph(true)?;
    let stub = Stub {
        x: OPTIMUM.to_vec(),
    };
    let solution = pr.solve_with(&stub, &SolveSettings::default())?;
    // The cone program minimises t + u = 3.5; the problem maximises -(t + u).
    assert_eq!(solution.objective, -3.5);
    assert_eq!(solution.assignment()?.unknowns(), OPTIMUM.to_vec());
    let short = Stub { x: vec![3.0] };
    let err = pr.solve_with(&short, &SolveSettings::default());
    assert!(matches!(err, Err(LmiError::Solver(_))), "{err:?}");
    Ok(())
}

/// The memory estimate counts each PSD cone's dense block, its coupling with
/// the unknowns it touches and the shared unknowns' Schur complement: for one
/// n x n LMI on a symmetric X (d = n(n+1)/2 rows, d unknowns) that is
/// 5 copies x 8 bytes x (d^2 + d*d + d^2 + nnz(A)), and the floor counts the
/// dense block only.
#[test]
fn memory_estimate_matches_its_closed_form_and_bounds_the_floor() -> TestResult {
    for n in [4usize, 9] {
        let mut p = Problem::new();
        let x = p.symmetric("X", n)?;
        p.psd("X > 0", Expr::var(x), 1e-6)?;
        let prog = p.cone_program();
        let d = (n * (n + 1) / 2) as u64;
        let nnz = prog.a.nnz() as u64;
        assert_eq!(nnz, d, "one entry per unknown");
        let expected = 5 * 8 * (d * d + d * d + d * d + nnz);
        assert_eq!(p.memory_estimate(), expected, "n = {n}");
        let floor = ClarabelSolver::memory_floor([n]);
        assert_eq!(floor, 5 * 8 * d * d);
        assert!(floor <= p.memory_estimate());
    }
    Ok(())
}

/// Non-finite or overflowing data in b, q or A ends in a status that is not
/// `Solved`, never a panic (Clarabel's own failures inside an iteration are
/// caught by the seam's guard, unit-tested in `solve::guard`).
#[test]
fn non_finite_data_ends_in_a_status_not_a_panic() -> TestResult {
    for (at, poison) in [
        (0, f64::NAN),
        (1, f64::NAN),
        (2, f64::NAN),
        (0, f64::INFINITY),
        (2, 1e308),
    ] {
        let mut program = epigraph(false)?.cone_program();
        match at {
            0 => program.b[4] = poison,
            1 => program.q[0] = poison,
            _ => program.a.nzval[0] = poison,
        }
        let solution = ClarabelSolver.solve(&program, &SolveSettings::default());
        let Ok(solution) = solution else {
            continue; // rejected at set-up: also no panic
        };
        assert_ne!(solution.status, SolveStatus::Solved, "poison {poison}");
    }
    Ok(())
}
