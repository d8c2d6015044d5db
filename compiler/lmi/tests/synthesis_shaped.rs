//! A problem shaped like the T-S PDC H-inf synthesis the layer is built for
//! (random local models, basic double-sum relaxation): it must solve, every
//! LMI must be certified from the returned values, and the recovered gains
//! must stabilise every vertex.

mod common;

use common::{pseudo_random, solve_ok};
use nalgebra::DMatrix;
use tsf_lmi::{Expr, LmiError, Problem, Var};

struct Model {
    a: DMatrix<f64>,
    b: DMatrix<f64>,
    d: DMatrix<f64>,
    c: DMatrix<f64>,
}

/// Q_ij = [He(A_i X + B_i M_j) + 2 alpha X, D_i, X C_i'; *, -g I, 0; *, *, -I].
fn q_block(m: &Model, x: Var, mj: Var, g: Var, alpha: f64) -> Result<Expr, LmiError> {
    let n = m.a.nrows();
    let ups = Expr::var(x)
        .left_mul(&m.a)?
        .add(Expr::product(&m.b, mj, &DMatrix::identity(n, n))?)?
        .he()?
        .add(Expr::var(x).scale(2.0 * alpha)?)?;
    Expr::sym_blocks(vec![
        vec![
            Some(ups),
            Some(Expr::constant(&m.d)?),
            Some(Expr::var(x).right_mul(&m.c.transpose())?),
        ],
        vec![
            None,
            Some(Expr::scaled(
                g,
                &-DMatrix::identity(m.d.ncols(), m.d.ncols()),
            )?),
            None,
        ],
        vec![None, None, Some(Expr::identity(m.c.nrows()).scale(-1.0)?)],
    ])
}

#[test]
fn pdc_hinf_synthesis_shaped_problem() -> Result<(), LmiError> {
    let rules: usize = std::env::var("R")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(6);
    let n: usize = std::env::var("N")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(6);
    let pert: f64 = std::env::var("PERT")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(0.05);
    let (nu, nw, ny) = (2, 2, 2);
    let a0 = pseudo_random(n, n, 100) - DMatrix::identity(n, n) * 0.5;
    let b0 = pseudo_random(n, nu, 101);
    let models: Vec<Model> = (0..rules as u64)
        .map(|i| Model {
            a: &a0 + pseudo_random(n, n, 200 + i) * pert,
            b: &b0 + pseudo_random(n, nu, 300 + i) * pert,
            d: pseudo_random(n, nw, 400 + i),
            c: pseudo_random(ny, n, 500 + i),
        })
        .collect();

    let eps = 1e-6;
    let mut pr = Problem::new();
    let x = pr.symmetric("X", n)?;
    let ms: Vec<Var> = (0..rules)
        .map(|j| pr.full(&format!("M{j}"), nu, n))
        .collect::<Result<_, _>>()?;
    let g = pr.scalar("g")?;
    pr.psd("X > 0", Expr::var(x), eps)?;
    for i in 0..rules {
        for j in i..rules {
            let q = if i == j {
                q_block(&models[i], x, ms[i], g, 0.0)?
            } else {
                q_block(&models[i], x, ms[j], g, 0.0)?
                    .add(q_block(&models[j], x, ms[i], g, 0.0)?)?
            };
            pr.nsd(&format!("Q[{i},{j}] hinf"), q, eps)?;
        }
    }
    pr.minimize(Expr::var(g))?;
    for chordal in [false, true] {
        let settings = tsf_lmi::SolveSettings {
            chordal_decomposition: chordal,
            verbose: std::env::var("VERB").is_ok(),
            ..Default::default()
        };
        let s = pr.solve(&settings)?;
        println!(
            "chordal {chordal}: {:?} {} it {:.1} ms obj {}",
            s.status,
            s.iterations,
            s.solve_time * 1e3,
            s.objective
        );
    }
    let sol = solve_ok(&pr, "PDC H-inf r=6 n=6")?;
    let values = sol.assignment()?;

    let margins = pr.margins(values)?;
    let worst = margins
        .iter()
        .min_by(|p, q| p.slack.total_cmp(&q.slack))
        .map(|m| (m.name.clone(), m.slack, m.error_bound));
    println!(
        "gamma = {:.6}, worst margin {worst:?}",
        sol.objective.sqrt()
    );
    assert!(margins.iter().all(|m| m.certified()), "{worst:?}");

    let xv = values.value(x)?;
    let Some(x_inv) = xv.clone().try_inverse() else {
        panic!("X singular");
    };
    for (i, model) in models.iter().enumerate() {
        let f = values.value(ms[i])? * &x_inv;
        let closed = &model.a + &model.b * f;
        let worst_re = closed
            .complex_eigenvalues()
            .iter()
            .map(|l| l.re)
            .fold(f64::NEG_INFINITY, f64::max);
        assert!(worst_re < 0.0, "vertex {i}: max Re {worst_re}");
    }
    Ok(())
}
