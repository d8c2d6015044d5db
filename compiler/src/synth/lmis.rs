//! The LMIs of PDC synthesis for one fixed [`Plan`]: decision variables
//! X = P^{-1}, M_j = F_j X, the objective blocks Q_ij of each family, fed to
//! the relaxation, and the per-rule norm constraints.
//!
//! Conventions (docs/lmi-reference in the design notes): Upsilon_ij =
//! He(A_i X + B_i M_j); strict LMIs carry an explicit margin `eps`.

use super::plan::{Bound, LinfPlan, Plan};
use super::relaxation::{Family, Relaxer};
use crate::model::TsModel;
use nalgebra::DMatrix;
use tsf_lang::spec::{InitialSet, Relaxation};
use tsf_lmi::{Expr, LmiError, Problem, Relation, Var};

/// The variables of a built problem (same creation order in every build of a plan).
#[derive(Debug, Clone)]
pub struct Vars {
    /// X = P^{-1}, n x n.
    pub x: Var,
    /// M_j = F_j X, m x n, one per rule.
    pub m: Vec<Var>,
    /// gamma^2 of the H-inf objective, when minimized.
    pub hinf_g: Option<Var>,
    /// mu^2 of the input-norm objective, when minimized.
    pub input_s: Option<Var>,
    /// lambda^2 of the output-norm objective, when minimized.
    pub output_s: Option<Var>,
    /// gamma of the L-inf objective, when minimized.
    pub linf_gamma: Option<Var>,
    /// xi of the L-inf objective, when not fixed.
    pub linf_xi: Option<Var>,
    /// Saturation: S = T^{-1} (diagonal, m x m) and Z_j = G_j X (m x n).
    pub saturation: Option<(Var, Vec<Var>)>,
}

/// A problem built for one plan.
#[derive(Debug)]
pub struct Built {
    /// The LMI problem.
    pub problem: Problem,
    /// Its variables.
    pub vars: Vars,
    /// Human-readable notes on reductions applied (empty for the full build).
    pub reductions: Vec<String>,
    /// Names of the constraints that are non-strict in the theory (`>= 0`).
    /// They are solved with the margin too, so that the numeric solution
    /// satisfies them with room, and certified as non-strict.
    pub nonstrict: Vec<String>,
}

/// Row `k` of `L v` as an expression (`v` has `m` rows and `n` columns).
pub(super) fn var_row(v: Var, k: usize, m: usize, n: usize) -> Result<Expr, LmiError> {
    let mut sel = DMatrix::zeros(1, m);
    sel[(0, k)] = 1.0;
    Expr::product(&sel, v, &DMatrix::identity(n, n))
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

fn lmi_err(e: LmiError) -> String {
    format!("internal LMI construction error: {e}")
}

/// Columns `off..off+len` of `m`.
fn cols(m: &DMatrix<f64>, off: usize, len: usize) -> DMatrix<f64> {
    m.columns(off, len).into_owned()
}

/// The H-inf / L-inf signal blocks: disturbance columns of D_i, and C, E, G of the output.
struct Channel {
    d: Vec<DMatrix<f64>>,
    c: DMatrix<f64>,
    e: DMatrix<f64>,
    g: DMatrix<f64>,
}

fn channel(model: &TsModel, from: usize, to: usize) -> Channel {
    let sig = &model.spec.disturbances[from];
    let out = &model.spec.outputs[to];
    Channel {
        d: model
            .rules
            .iter()
            .map(|r| cols(&r.d, sig.offset, sig.len))
            .collect(),
        c: out.c.clone(),
        e: out.e.clone(),
        g: cols(&out.g, sig.offset, sig.len),
    }
}

/// Upsilon_ij = He(A_i X + B_i M_j) (+ shift * X).
fn upsilon(model: &TsModel, v: &Vars, i: usize, j: usize, shift: f64) -> Result<Expr, LmiError> {
    let n = model.n;
    let (a, b) = (&model.rules[i].a, &model.rules[i].b);
    let ax = Expr::product(a, v.x, &DMatrix::identity(n, n))?;
    let bm = Expr::product(b, v.m[j], &DMatrix::identity(n, n))?;
    let he = ax.add(bm)?.he()?;
    if shift == 0.0 {
        Ok(he)
    } else {
        he.add(Expr::var(v.x).scale(shift)?)
    }
}

/// Adds the dead-zone signal psi of the generalized sector condition to a
/// block: [[U, -B_i S + Z_j', (W)], [*, -2S, 0], [*, *, (-xi I)]], or returns
/// `[[U, W], [*, -xi I]]` / `U` unchanged without saturation.
fn with_sector(
    model: &TsModel,
    v: &Vars,
    i: usize,
    j: usize,
    ups: Expr,
    w: Option<(Expr, Expr)>,
) -> Result<Expr, LmiError> {
    let Some((s, zs)) = &v.saturation else {
        return match w {
            Some((d, xi)) => Expr::sym_blocks(vec![vec![Some(ups), Some(d)], vec![None, Some(xi)]]),
            None => Ok(ups),
        };
    };
    let m = model.m;
    let b = &model.rules[i].b;
    let cross = Expr::product(b, *s, &DMatrix::identity(m, m))?
        .scale(-1.0)?
        .add(Expr::var(zs[j]).transpose())?;
    let psi = Expr::var(*s).scale(-2.0)?;
    match w {
        Some((d, xi)) => Expr::sym_blocks(vec![
            vec![Some(ups), Some(cross), Some(d)],
            vec![None, Some(psi), None],
            vec![None, None, Some(xi)],
        ]),
        None => Expr::sym_blocks(vec![vec![Some(ups), Some(cross)], vec![None, Some(psi)]]),
    }
}

/// C X + E M_j (p x n).
fn output_map(ch: &Channel, v: &Vars, j: usize, n: usize) -> Result<Expr, LmiError> {
    let id = DMatrix::identity(n, n);
    let cx = Expr::product(&ch.c, v.x, &id)?;
    if ch.e.iter().all(|x| *x == 0.0) {
        Ok(cx)
    } else {
        cx.add(Expr::product(&ch.e, v.m[j], &id)?)
    }
}

/// `s * I_k` for a scalar variable or constant.
fn scalar_times_identity(var: Option<Var>, fixed: f64, k: usize) -> Result<Expr, LmiError> {
    match var {
        Some(v) => Expr::scaled(v, &DMatrix::identity(k, k)),
        None => Expr::constant(&(DMatrix::identity(k, k) * fixed)),
    }
}

/// [1, x0'; x0, X] >= 0, or X - R^{-1} >= 0 for an ellipsoid of initial states.
fn initial_set(
    problem: &mut Problem,
    ns: &mut Vec<String>,
    eps: f64,
    v: &Vars,
    init: &InitialSet,
    what: &str,
) -> Result<(), LmiError> {
    match init {
        InitialSet::Point(x0) => {
            let x0 = DMatrix::from_column_slice(x0.len(), 1, x0);
            let e = Expr::sym_blocks(vec![
                vec![
                    Some(Expr::identity(1)),
                    Some(Expr::constant(&x0.transpose())?),
                ],
                vec![None, Some(Expr::var(v.x))],
            ])?;
            nonstrict_psd(problem, ns, &format!("{what}: x0 in E(P,1)"), e, eps)?;
        }
        InitialSet::Ellipsoid(r) => {
            let rinv = r
                .clone()
                .try_inverse()
                .unwrap_or_else(|| DMatrix::zeros(r.nrows(), r.ncols()));
            nonstrict_psd(
                problem,
                ns,
                &format!("{what}: ellipsoid in E(P,1)"),
                Expr::var(v.x).add_constant(&(-rinv))?,
                eps,
            )?;
        }
    }
    Ok(())
}

/// Builds the problem for `plan`. With `reduce`, constraints provably implied
/// by others are left out (and listed in `reductions`).
pub fn build(
    model: &TsModel,
    plan: &Plan,
    relaxation: Relaxation,
    eps: f64,
    reduce: bool,
) -> Result<Built, String> {
    build_inner(model, plan, relaxation, eps, reduce).map_err(lmi_err)
}

fn build_inner(
    model: &TsModel,
    plan: &Plan,
    relaxation: Relaxation,
    eps: f64,
    reduce: bool,
) -> Result<Built, LmiError> {
    let (n, m, r) = (model.n, model.m, model.r());
    let mut problem = Problem::new();
    let x = problem.symmetric("X", n)?;
    let mvars = (0..r)
        .map(|j| problem.full(&format!("M{}", j + 1), m, n))
        .collect::<Result<Vec<_>, _>>()?;
    let opt_var =
        |problem: &mut Problem, name: &str, b: Option<Bound>| -> Result<Option<Var>, LmiError> {
            match b {
                Some(Bound::Minimize | Bound::Free) => Ok(Some(problem.scalar(name)?)),
                _ => Ok(None),
            }
        };
    let hinf_g = opt_var(&mut problem, "g", plan.hinf.as_ref().map(|h| h.bound))?;
    let input_s = opt_var(
        &mut problem,
        "mu2",
        plan.input_norm.as_ref().map(|h| h.bound),
    )?;
    let output_s = opt_var(
        &mut problem,
        "lambda2",
        plan.output_norm.as_ref().map(|h| h.bound),
    )?;
    let linf_gamma = opt_var(&mut problem, "gamma", plan.linf.as_ref().map(|h| h.bound))?;
    let linf_xi = match &plan.linf {
        Some(l) if l.xi.is_none() => Some(problem.scalar("xi")?),
        _ => None,
    };
    let saturation = match &plan.saturation {
        Some(_) => {
            let s = problem.diagonal("S", m)?;
            let z = (0..r)
                .map(|j| problem.full(&format!("Z{}", j + 1), m, n))
                .collect::<Result<Vec<_>, _>>()?;
            Some((s, z))
        }
        None => None,
    };
    let vars = Vars {
        saturation,
        x,
        m: mvars,
        hinf_g,
        input_s,
        output_s,
        linf_gamma,
        linf_xi,
    };
    let pair_reduce = reduce && common_b(model);
    let mut relaxer = Relaxer::new(model, relaxation, eps, pair_reduce);

    problem.psd("X > 0", Expr::var(x), eps)?;

    // Stability / decay family: He(A_i X + B_i M_j) + 2 alpha X < 0. Implied by
    // the H-inf or L-inf family (their (1,1) blocks) when there is no decay rate.
    let alpha = plan.decay.unwrap_or(0.0);
    if plan.decay.is_some() || (plan.hinf.is_none() && plan.linf.is_none()) {
        let name = if plan.decay.is_some() {
            "decay"
        } else {
            "stability"
        };
        let fam = Family {
            name: name.into(),
            q: Box::new(|i, j| {
                with_sector(
                    model,
                    &vars,
                    i,
                    j,
                    upsilon(model, &vars, i, j, 2.0 * alpha)?,
                    None,
                )
            }),
        };
        relaxer.impose(&mut problem, &fam)?;
    }

    if let Some(h) = &plan.hinf {
        let ch = channel(model, h.from, h.to);
        let q = ch.d.first().map_or(0, |d| d.ncols());
        let p = ch.c.nrows();
        let g_fixed = match h.bound {
            Bound::Fixed(gamma) => gamma * gamma,
            _ => 0.0,
        };
        let fam = Family {
            name: "hinf".into(),
            q: Box::new(|i, j| {
                Expr::sym_blocks(vec![
                    vec![
                        Some(upsilon(model, &vars, i, j, 0.0)?),
                        Some(Expr::constant(&ch.d[i])?),
                        Some(output_map(&ch, &vars, j, n)?.transpose()),
                    ],
                    vec![
                        None,
                        Some(scalar_times_identity(vars.hinf_g, g_fixed, q)?.scale(-1.0)?),
                        Some(Expr::constant(&ch.g.transpose())?),
                    ],
                    vec![None, None, Some(Expr::identity(p).scale(-1.0)?)],
                ])
            }),
        };
        relaxer.impose(&mut problem, &fam)?;
        if let Some(g) = vars.hinf_g {
            problem.add_scalar("g >= 0", Expr::var(g), Relation::Ge, 0.0)?;
            if h.bound == Bound::Minimize {
                problem.minimize(Expr::var(g))?;
            }
        }
    }

    if let Some(l) = &plan.linf {
        let ch = channel(model, l.from, l.to);
        let q = ch.d.first().map_or(0, |d| d.ncols());
        let p = ch.c.nrows();
        let xi_fixed = l.xi.unwrap_or(0.0);
        let gamma_fixed = match l.bound {
            Bound::Fixed(g) => g,
            _ => 0.0,
        };
        let phi = l.phi;
        let fam = Family {
            name: "linf".into(),
            q: Box::new(|i, j| {
                let w = (
                    Expr::constant(&ch.d[i])?,
                    scalar_times_identity(vars.linf_xi, xi_fixed, q)?.scale(-1.0)?,
                );
                with_sector(
                    model,
                    &vars,
                    i,
                    j,
                    upsilon(model, &vars, i, j, phi)?,
                    Some(w),
                )
            }),
        };
        relaxer.impose(&mut problem, &fam)?;
        // Output peak: [phi X, 0, (C X + E M_j)'; *, (gamma - xi) I, G'; *, *, gamma I] > 0 for every j.
        let gi = |k| scalar_times_identity(vars.linf_gamma, gamma_fixed, k);
        for j in 0..r {
            let e = Expr::sym_blocks(vec![
                vec![
                    Some(Expr::var(x).scale(phi)?),
                    None,
                    Some(output_map(&ch, &vars, j, n)?.transpose()),
                ],
                vec![
                    None,
                    Some(gi(q)?.sub(scalar_times_identity(vars.linf_xi, xi_fixed, q)?)?),
                    Some(Expr::constant(&ch.g.transpose())?),
                ],
                vec![None, None, Some(gi(p)?)],
            ])?;
            problem.psd(&format!("linf peak [{}]", j + 1), e, eps)?;
        }
        if let Some(xi) = vars.linf_xi {
            problem.add_scalar("xi > 0", Expr::var(xi), Relation::Ge, eps)?;
        }
        if let (Some(g), Bound::Minimize) = (vars.linf_gamma, l.bound) {
            problem.minimize(Expr::var(g))?;
        }
    }

    if let Some(u) = &plan.input_norm {
        initial_set(
            &mut problem,
            &mut relaxer.nonstrict,
            eps,
            &vars,
            &u.initial,
            "input norm",
        )?;
        let fixed = match u.bound {
            Bound::Fixed(mu) => mu * mu,
            _ => 0.0,
        };
        for j in 0..r {
            let e = Expr::sym_blocks(vec![
                vec![Some(Expr::var(x)), Some(Expr::var(vars.m[j]).transpose())],
                vec![None, Some(scalar_times_identity(vars.input_s, fixed, m)?)],
            ])?;
            nonstrict_psd(
                &mut problem,
                &mut relaxer.nonstrict,
                &format!("input norm [{}]", j + 1),
                e,
                eps,
            )?;
        }
        if let (Some(s), Bound::Minimize) = (vars.input_s, u.bound) {
            problem.minimize(Expr::var(s))?;
        }
    }

    if let Some(o) = &plan.output_norm {
        let out = &model.spec.outputs[o.output];
        if plan.input_norm.is_none() {
            initial_set(
                &mut problem,
                &mut relaxer.nonstrict,
                eps,
                &vars,
                &o.initial,
                "output norm",
            )?;
        }
        let fixed = match o.bound {
            Bound::Fixed(l) => l * l,
            _ => 0.0,
        };
        let p = out.c.nrows();
        let cx = Expr::product(&out.c, x, &DMatrix::identity(n, n))?;
        let e = Expr::sym_blocks(vec![
            vec![Some(Expr::var(x)), Some(cx.transpose())],
            vec![None, Some(scalar_times_identity(vars.output_s, fixed, p)?)],
        ])?;
        nonstrict_psd(&mut problem, &mut relaxer.nonstrict, "output norm", e, eps)?;
        if let (Some(s), Bound::Minimize) = (vars.output_s, o.bound) {
            problem.minimize(Expr::var(s))?;
        }
    }
    if let (Some(sat), Some((s, zs))) = (&plan.saturation, &vars.saturation) {
        if plan.hinf.is_some() {
            return Err(LmiError::Dimension { what: "the saturation region is supported with stability, decay rate and L-inf objectives, not with H-inf".into() });
        }
        problem.psd("S > 0", Expr::var(*s), eps)?;
        if let Some(init) = &sat.contain {
            initial_set(
                &mut problem,
                &mut relaxer.nonstrict,
                eps,
                &vars,
                init,
                "region of attraction",
            )?;
        }
        // With a disturbance bounded by tau, V stays below 1 + xi tau^2 / phi
        // only if the linear region holds on the larger level set: shrink the
        // levels by that factor (Xu & Huang (19)/(40)).
        let shrink = match (&plan.linf, sat.disturbance_bound) {
            (
                Some(LinfPlan {
                    xi: Some(xi), phi, ..
                }),
                Some(tau),
            ) => 1.0 + xi * tau * tau / phi,
            (Some(LinfPlan { xi: None, .. }), Some(_)) => {
                return Err(LmiError::Dimension { what: "the saturation region with a bounded disturbance needs a fixed xi: write `objective linf(...) ... with xi = ...`".into() });
            }
            _ => 1.0,
        };
        for (j, (&mj, &zj)) in vars.m.iter().zip(zs).enumerate() {
            for (k, level) in sat.levels.iter().enumerate() {
                let row = var_row(mj, k, m, n)?.sub(var_row(zj, k, m, n)?)?;
                let rhs = Expr::constant(&DMatrix::from_element(1, 1, level * level / shrink))?;
                let e = region_block(Expr::var(x), row, rhs)?;
                nonstrict_psd(
                    &mut problem,
                    &mut relaxer.nonstrict,
                    &format!("linear region [{},{}]", j + 1, k + 1),
                    e,
                    eps,
                )?;
            }
        }
    }
    Ok(Built {
        problem,
        vars,
        reductions: relaxer.reductions,
        nonstrict: relaxer.nonstrict,
    })
}
