//! The H-inf gain of an observer-based loop, certified on the augmented
//! state (x, e), e = x - x_hat, with the shipped gains F_j and L_i as data.
//!
//! With a disturbance w (x' gains D_i w) and a measurement noise v
//! (y = C x + v), the observer x_hat' = sum_i h_i (A_i x_hat + B_i u +
//! L_i (y - C x_hat)) gives e' = sum_i h_i ((A_i - L_i C) e + D_i w - L_i v),
//! and the output z = C_z x + E u + G w with u = sum_j h_j F_j x_hat is
//! z = sum_j h_j ((C_z + E F_j) x - E F_j e + G w). So with
//! P = diag(P1, Pe) and G_ij = [A_i + B_i F_j, -B_i F_j; 0, A_i - L_i C], the
//! bounded-real block of rule pair (i, j)
//!
//! ```text
//! [ He(P1 Gxx)  P1 Gxe      P1 D_i     0          (C_z + E F_j)' ]
//! [ *           He(Pe Gee)  Pe D_i     -Pe L_i    -(E F_j)'      ]
//! [ *           *           -g I       0          G'             ]
//! [ *           *           *          -g I       0              ]
//! [ *           *           *          *          -I             ]  < 0
//! ```
//!
//! imposed under the spec's relaxation (sum_ij h_i h_j of the blocks is then
//! negative definite) gives V' + z'z - g (w'w + v'v) < 0 along the loop, hence
//! from x(0) = 0, x_hat(0) = 0: ||z||_2^2 < g (||w||_2^2 + ||v||_2^2), the
//! H-inf gain from (w, v) to z at most sqrt(g) (bounded-real lemma; Tanaka &
//! Wang 2001, ch. 5 for the augmented observer loop). g is minimized (or fixed
//! at the spec's gamma^2); P1, Pe are shared with the decay conditions of
//! [`super::augmented`].

use super::augmented::{closed_loop, Split};
use crate::model::TsModel;
use crate::synth::blocks::{scalar_times_identity, Channel};
use crate::synth::relaxation::Family;
use crate::synth::relaxations::Relaxer;
use nalgebra::DMatrix;
use tsf_lang::spec::{Objective, Target};
use tsf_lmi::{Expr, LmiError, Problem, Relation, Var};

/// The variable g = gamma^2 of the augmented H-inf block.
pub const G_AUG: &str = "g_aug";

/// The H-inf objective of a spec: (disturbance, output, fixed gamma or `None`
/// when minimized); `None` without one.
pub fn objective(model: &TsModel) -> Option<(usize, usize, Option<f64>)> {
    model.spec.objectives.iter().find_map(|o| match &o.node {
        Objective::Hinf { from, to, target } => Some((
            *from,
            *to,
            match target {
                Target::Fixed(g) => Some(*g),
                Target::Optimize => None,
            },
        )),
        _ => None,
    })
}

/// Imposes the augmented H-inf blocks on `problem` (the P1, Pe of the decay
/// conditions); returns g's variable when it is minimized.
pub fn impose(
    problem: &mut Problem,
    relaxer: &mut Relaxer,
    model: &TsModel,
    gains: (&[DMatrix<f64>], &[DMatrix<f64>]),
    c: &DMatrix<f64>,
    (p1, pe): (Var, Var),
    (from, to, fixed): (usize, usize, Option<f64>),
) -> Result<Option<Var>, LmiError> {
    let (f, l) = gains;
    let n = model.n;
    let ch = Channel::new(model, from, to);
    let (q, pm, po) = (ch.q(), c.nrows(), ch.c.nrows());
    let g = match fixed {
        Some(_) => None,
        None => Some(problem.scalar(G_AUG)?),
    };
    let g_fixed = fixed.map_or(0.0, |gamma| gamma * gamma);
    let fam = Family {
        name: "augmented hinf".into(),
        q: Box::new(|i, j| {
            let Split { xx, xe, ee } = Split::of(&closed_loop(model, f, l, c, i, j), n);
            let ef = &ch.e * &f[j];
            let zx: DMatrix<f64> = &ch.c + &ef;
            let rows = vec![
                vec![
                    Some(Expr::var(p1).right_mul(&xx)?.he()?),
                    Some(Expr::var(p1).right_mul(&xe)?),
                    Some(Expr::var(p1).right_mul(&ch.d[i])?),
                    None,
                    Some(Expr::constant(&zx.transpose())?),
                ],
                vec![
                    None,
                    Some(Expr::var(pe).right_mul(&ee)?.he()?),
                    Some(Expr::var(pe).right_mul(&ch.d[i])?),
                    Some(Expr::var(pe).right_mul(&(-&l[i]))?),
                    Some(Expr::constant(&(-ef.transpose()))?),
                ],
                vec![
                    None,
                    None,
                    Some(scalar_times_identity(g, g_fixed, q)?.scale(-1.0)?),
                    None,
                    Some(Expr::constant(&ch.g.transpose())?),
                ],
                vec![
                    None,
                    None,
                    None,
                    Some(scalar_times_identity(g, g_fixed, pm)?.scale(-1.0)?),
                    None,
                ],
                vec![
                    None,
                    None,
                    None,
                    None,
                    Some(Expr::identity(po).scale(-1.0)?),
                ],
            ];
            Expr::sym_blocks(rows)
        }),
    };
    relaxer.impose(problem, &fam)?;
    if let Some(g) = g {
        problem.add_scalar("g_aug >= 0", Expr::var(g), Relation::Ge, 0.0)?;
        problem.minimize(Expr::var(g))?;
    }
    Ok(g)
}
