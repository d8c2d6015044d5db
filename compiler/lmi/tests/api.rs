//! Builder errors (never panics), evaluation and margins on hand-set values.

mod common;

use nalgebra::DMatrix;
use tsf_lmi::{ConstraintKind, Expr, LmiError, LmiSense, Problem, Relation, VarKind};

type TestResult = Result<(), LmiError>;

fn is_shape(r: Result<impl std::fmt::Debug, LmiError>) -> bool {
    matches!(r, Err(LmiError::Shape { .. }))
}

#[test]
fn shape_mismatches_are_errors() -> TestResult {
    let mut pr = Problem::new();
    let x = pr.symmetric("X", 3)?;
    let m = pr.full("M", 2, 3)?;
    let g = pr.scalar("g")?;
    let i2 = DMatrix::<f64>::identity(2, 2);
    let i3 = DMatrix::<f64>::identity(3, 3);
    assert!(is_shape(Expr::var(x).add(Expr::identity(2))));
    assert!(is_shape(Expr::product(&i2, x, &i3)));
    assert!(is_shape(Expr::product(&i2, m, &i2)));
    assert!(is_shape(Expr::product_t(&i2, m, &i2)));
    assert!(Expr::product_t(&i3, m, &i2).is_ok());
    assert!(is_shape(Expr::var(m).he()));
    assert!(is_shape(Expr::var(m).trace()));
    assert!(is_shape(Expr::var(x).left_mul(&i2)));
    assert!(is_shape(Expr::var(x).right_mul(&i2)));
    assert!(is_shape(Expr::sum(3, 3, [Expr::var(x), Expr::var(m)])));
    // Blocks: inconsistent heights in a block row, ragged rows.
    assert!(is_shape(Expr::blocks(vec![vec![
        Some(Expr::var(x)),
        Some(Expr::var(m)),
    ]])));
    assert!(is_shape(Expr::blocks(vec![
        vec![Some(Expr::var(x)), None],
        vec![None],
    ])));
    // Symmetric blocks: E12 must have as many columns as E22.
    assert!(is_shape(Expr::sym_blocks(vec![
        vec![Some(Expr::var(x)), Some(Expr::var(m).transpose())],
        vec![None, Some(Expr::identity(3))],
    ])));
    // Lower blocks are implied; giving one is an error, as is an unsizable row.
    assert!(matches!(
        Expr::sym_blocks(vec![
            vec![Some(Expr::var(x)), None],
            vec![Some(Expr::var(m)), Some(Expr::identity(2))],
        ]),
        Err(LmiError::Dimension { .. })
    ));
    assert!(matches!(
        Expr::sym_blocks(vec![vec![Some(Expr::var(x)), None], vec![None, None]]),
        Err(LmiError::Dimension { .. })
    ));
    // Non-square LMIs, non-scalar scalar constraints and objectives.
    assert!(is_shape(pr.psd("M", Expr::var(m), 0.0)));
    assert!(is_shape(pr.add_scalar(
        "X",
        Expr::var(x),
        Relation::Ge,
        0.0
    )));
    assert!(is_shape(pr.minimize(Expr::var(x))));
    assert!(matches!(
        Expr::scaled(x, &i2),
        Err(LmiError::Variable { .. })
    ));
    assert!(Expr::scaled(g, &i2).is_ok());
    Ok(())
}

#[test]
fn bad_inputs_are_errors() -> TestResult {
    let mut pr = Problem::new();
    let x = pr.symmetric("X", 2)?;
    let mut other = Problem::new();
    let y = other.symmetric("Y", 2)?;
    assert!(matches!(
        pr.psd("foreign", Expr::var(y), 0.0),
        Err(LmiError::Variable { .. })
    ));
    let nan = DMatrix::from_element(2, 2, f64::NAN);
    assert!(matches!(
        Expr::constant(&nan),
        Err(LmiError::NonFinite { .. })
    ));
    assert!(matches!(
        Expr::var(x).scale(f64::INFINITY),
        Err(LmiError::NonFinite { .. })
    ));
    assert!(matches!(
        pr.psd("negative margin", Expr::var(x), -1.0),
        Err(LmiError::NonFinite { .. })
    ));
    assert!(matches!(pr.symmetric("X", 3), Err(LmiError::Name { .. })));
    assert!(matches!(pr.scalar(""), Err(LmiError::Name { .. })));
    assert!(matches!(
        pr.full("Z", 0, 3),
        Err(LmiError::Dimension { .. })
    ));
    pr.psd("c", Expr::var(x), 0.0)?;
    assert!(matches!(
        pr.nsd("c", Expr::var(x), 0.0),
        Err(LmiError::Name { .. })
    ));
    let foreign_id = other.psd("d", Expr::var(y), 0.0)?;
    assert_eq!(
        pr.evaluate(foreign_id, &pr.assignment()),
        Err(LmiError::UnknownConstraint)
    );
    assert!(pr.evaluate(foreign_id, &other.assignment()).is_err());
    // Structure of hand-set values.
    let mut values = pr.assignment();
    let asym = DMatrix::from_row_slice(2, 2, &[1.0, 2.0, 0.0, 1.0]);
    assert!(matches!(values.set(x, asym), Err(LmiError::Value { .. })));
    assert!(is_shape(values.set(x, DMatrix::identity(3, 3))));
    assert!(matches!(
        values.set(y, DMatrix::identity(2, 2)),
        Err(LmiError::Variable { .. })
    ));
    Ok(())
}

/// Margins of hand-set values against eigenvalues known exactly.
#[test]
fn margins_of_hand_set_values() -> TestResult {
    let mut pr = Problem::new();
    let x = pr.symmetric("X", 3)?;
    let d = pr.diagonal("D", 2)?;
    let g = pr.scalar("g")?;
    let pos = pr.psd("X > 0.5 I", Expr::var(x), 0.5)?;
    let neg = pr.nsd(
        "-X - D < 0",
        {
            let top = Expr::var(x).scale(-1.0)?;
            Expr::sym_blocks(vec![
                vec![Some(top), None],
                vec![None, Some(Expr::var(d).scale(-1.0)?)],
            ])?
        },
        0.0,
    )?;
    let le = pr.add_scalar("g <= 2", Expr::var(g), Relation::Le, 2.0)?;
    let eq = pr.add_scalar("g = 1.5", Expr::var(g), Relation::Eq, 1.5)?;

    let mut values = pr.assignment();
    let xv = DMatrix::from_row_slice(3, 3, &[2.0, 1.0, 0.0, 1.0, 2.0, 0.0, 0.0, 0.0, 4.0]);
    values.set(x, xv.clone())?;
    values.set(
        d,
        DMatrix::from_diagonal(&nalgebra::DVector::from_vec(vec![0.25, 3.0])),
    )?;
    values.set(g, DMatrix::from_element(1, 1, 1.5))?;

    assert_eq!(pr.evaluate(pos, &values)?, xv);
    let m = pr.margin(pos, &values)?;
    // eig(X) = {1, 3, 4}.
    assert!((m.slack - 1.0).abs() < 1e-14 && (m.excess - 0.5).abs() < 1e-14);
    assert!(
        m.error_bound > 0.0 && m.error_bound < 1e-13,
        "{}",
        m.error_bound
    );
    assert!(m.certified() && m.meets_margin());
    assert_eq!(
        m.kind,
        ConstraintKind::Lmi {
            sense: LmiSense::Psd,
            margin: 0.5,
            size: 3
        }
    );
    let m = pr.margin(neg, &values)?;
    assert!((m.slack - 0.25).abs() < 1e-14, "{m:?}");
    let m = pr.margin(le, &values)?;
    assert_eq!((m.slack, m.certified()), (0.5, true));
    let m = pr.margin(eq, &values)?;
    assert_eq!((m.slack, m.certified()), (0.0, true));

    // A value on the boundary is not certified, a violated one fails the margin.
    values.set(
        x,
        DMatrix::from_diagonal(&nalgebra::DVector::from_vec(vec![0.0, 1.0, 1.0])),
    )?;
    let m = pr.margin(pos, &values)?;
    assert!(!m.certified() && !m.meets_margin());
    assert_eq!(pr.margins(&values)?.len(), 4);
    assert_eq!(pr.var_name(d)?, "D");
    assert_eq!(d.kind(), VarKind::Diagonal(2));
    Ok(())
}

/// The error bound grows with the magnitude of what was summed, so a
/// cancellation-prone evaluation is not certified on a tiny eigenvalue.
#[test]
fn error_bound_tracks_cancellation() -> TestResult {
    let mut pr = Problem::new();
    let x = pr.symmetric("X", 2)?;
    let big = 1e8;
    let e = Expr::var(x).add_constant(&(DMatrix::identity(2, 2) * -big))?;
    let id = pr.psd("X - 1e8 I", e, 0.0)?;
    let mut values = pr.assignment();
    values.set(x, DMatrix::identity(2, 2) * (big + 1e-9))?;
    let m = pr.margin(id, &values)?;
    assert!(m.error_bound > 1e-9, "bound {:e}", m.error_bound);
    assert!(!m.certified());
    Ok(())
}

#[test]
fn stats_count_unknowns_cones_and_nonzeros() -> TestResult {
    let mut pr = Problem::new();
    let x = pr.symmetric("X", 20)?;
    let m = pr.full("M", 3, 20)?;
    let g = pr.scalar("g")?;
    let a = common::pseudo_random(20, 20, 7);
    let b = common::pseudo_random(20, 3, 8);
    let ups = Expr::var(x)
        .left_mul(&a)?
        .add(Expr::product(&b, m, &DMatrix::identity(20, 20))?)?
        .he()?;
    pr.nsd("Q", ups, 1e-6)?;
    pr.add_scalar("g >= 0", Expr::var(g), Relation::Ge, 0.0)?;
    let s = pr.stats();
    assert_eq!((s.variables, s.scalar_unknowns), (3, 210 + 60 + 1));
    assert_eq!((s.lmis, s.scalar_constraints), (1, 1));
    assert_eq!(s.psd_cones, vec![20]);
    assert_eq!((s.rows, s.nonneg_rows, s.zero_rows), (211, 1, 0));
    // Row (a, b) of He(AX) depends on X[p, q] with p or q in {a, b}: a dense
    // block, but never more than rows x unknowns.
    assert!(s.nnz > 0 && s.nnz <= 210 * 271);
    println!("{s}");
    Ok(())
}

/// Degenerate problems are answered with a status or an error, never a panic.
#[test]
fn degenerate_problems() -> TestResult {
    let empty = Problem::new();
    assert!(matches!(
        empty.solve(&tsf_lmi::SolveSettings::default()),
        Err(LmiError::Dimension { .. })
    ));
    let mut free = Problem::new();
    let t = free.scalar("t")?;
    let sol = free.solve(&tsf_lmi::SolveSettings::default())?;
    assert_eq!(sol.status, tsf_lmi::SolveStatus::Solved);
    free.minimize(Expr::var(t))?;
    let sol = free.solve(&tsf_lmi::SolveSettings::default())?;
    assert_eq!(sol.status, tsf_lmi::SolveStatus::DualInfeasible);
    Ok(())
}
