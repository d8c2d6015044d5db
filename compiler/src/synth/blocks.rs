//! LMI building blocks shared by the objective families: Upsilon_ij, the
//! dead-zone (sector) column, output maps, initial-set and linear-region
//! conditions.
//!
//! Conventions (Tanaka & Wang, *Fuzzy Control Systems Design and Analysis*,
//! 2001): X = P^{-1}, M_j = F_j X, Upsilon_ij = He(A_i X + B_i M_j); strict
//! LMIs carry an explicit margin `eps`.

use super::objective::GainTerm;
use crate::model::TsModel;
use nalgebra::DMatrix;
use tsf_lang::spec::InitialSet;
use tsf_lmi::{Expr, LmiError, Problem, Var};

/// Row `k` of `v` as an expression (`v` has `m` rows and `n` columns).
pub(super) fn var_row(v: Var, k: usize, m: usize, n: usize) -> Result<Expr, LmiError> {
    Expr::product(&row_selector(k, m), v, &DMatrix::identity(n, n))
}

/// The 1 x m matrix that selects row `k`.
pub(super) fn row_selector(k: usize, m: usize) -> DMatrix<f64> {
    let mut sel = DMatrix::zeros(1, m);
    sel[(0, k)] = 1.0;
    sel
}

/// The linear-region block `[W, row'; *, rhs]` (>= 0 puts the ellipsoid of
/// `W` inside `|row x| <= sqrt(rhs)`, by a Schur complement).
pub(super) fn region_block(w: Expr, row: Expr, rhs: Expr) -> Result<Expr, LmiError> {
    Expr::sym_blocks(vec![
        vec![Some(w), Some(row.transpose())],
        vec![None, Some(rhs)],
    ])
}

/// Adds `E >= 0` (non-strict in the theory), solved as `E >= eps I`.
pub(super) fn nonstrict_psd(
    problem: &mut Problem,
    nonstrict: &mut Vec<String>,
    name: &str,
    e: Expr,
    eps: f64,
) -> Result<(), LmiError> {
    problem.psd(name, e, eps)?;
    nonstrict.push(name.to_string());
    Ok(())
}

/// Whether every rule has the same B (then the pair LMIs of the symmetric
/// relaxations are implied by the vertex LMIs: Q_ij + Q_ji = Q_ii + Q_jj).
pub fn common_b(model: &TsModel) -> bool {
    model.rules.windows(2).all(|w| w[0].b == w[1].b)
}

/// `s * I_k` for a scalar variable or constant.
pub(super) fn scalar_times_identity(
    var: Option<Var>,
    fixed: f64,
    k: usize,
) -> Result<Expr, LmiError> {
    match var {
        Some(v) => Expr::scaled(v, &DMatrix::identity(k, k)),
        None => Expr::constant(&(DMatrix::identity(k, k) * fixed)),
    }
}

/// The H-inf / L-inf signal blocks: disturbance columns of D_i, and C, E, G of the output.
pub(super) struct Channel {
    /// Disturbance columns of D_i, per rule.
    pub d: Vec<DMatrix<f64>>,
    /// C of the output.
    pub c: DMatrix<f64>,
    /// E of the output (input feedthrough).
    pub e: DMatrix<f64>,
    /// Disturbance columns of G of the output.
    pub g: DMatrix<f64>,
}

impl Channel {
    /// The channel from disturbance `from` to output `to`.
    pub fn new(model: &TsModel, from: usize, to: usize) -> Channel {
        let sig = &model.spec.disturbances[from];
        let out = &model.spec.outputs[to];
        let cols = |m: &DMatrix<f64>| m.columns(sig.offset, sig.len).into_owned();
        Channel {
            d: model.rules.iter().map(|r| cols(&r.d)).collect(),
            c: out.c.clone(),
            e: out.e.clone(),
            g: cols(&out.g),
        }
    }

    /// Number of disturbance components.
    pub fn q(&self) -> usize {
        self.d.first().map_or(0, |d| d.ncols())
    }

    /// C X + E M_j (p x n).
    pub fn output_map(&self, x: Var, mj: &GainTerm, n: usize) -> Result<Expr, LmiError> {
        let id = DMatrix::identity(n, n);
        let cx = Expr::product(&self.c, x, &id)?;
        if self.e.iter().all(|v| *v == 0.0) {
            Ok(cx)
        } else {
            cx.add(mj.times(&self.e, x, n)?)
        }
    }
}

/// The condition that puts an initial set inside E(P, 1):
/// [1, x0'; x0, X] >= 0, or X - R^{-1} >= 0 for the ellipsoid x' R x <= 1.
pub(super) fn initial_set_block(x: Var, init: &InitialSet) -> Result<(String, Expr), LmiError> {
    match init {
        InitialSet::Point(x0) => {
            let x0 = DMatrix::from_column_slice(x0.len(), 1, x0);
            let e = Expr::sym_blocks(vec![
                vec![
                    Some(Expr::identity(1)),
                    Some(Expr::constant(&x0.transpose())?),
                ],
                vec![None, Some(Expr::var(x))],
            ])?;
            Ok(("x0 in E(P,1)".into(), e))
        }
        InitialSet::Ellipsoid(r) => {
            // The checker proves R positive definite; a singular R cannot reach here.
            let rinv = r
                .clone()
                .try_inverse()
                .unwrap_or_else(|| DMatrix::zeros(r.nrows(), r.ncols()));
            Ok((
                "ellipsoid in E(P,1)".into(),
                Expr::var(x).add_constant(&(-rinv))?,
            ))
        }
    }
}
