//! The mode conditions in X variables, the SDP synthesis solves (see the
//! module documentation of [`super`] for the derivation).

use crate::model::TsModel;
use crate::synth::blocks::Channel;
use crate::synth::objective::BuildError;
use crate::synth::relaxation::PairCondition;
use nalgebra::DMatrix;
use tsf_lang::modes::{ModeDesign, Modes};
use tsf_lmi::{Expr, Problem, Relation, Var};

/// The variables of one mode (shared by every mode when the design is
/// mode-independent).
#[derive(Debug, Clone)]
pub struct ModeVars {
    /// X_a = P_a^{-1}.
    pub x: Var,
    /// M_aj = F_aj X_a, one per rule.
    pub m: Vec<Var>,
    /// The relaxation's slack Y_a (tanaka), in X variables.
    pub y: Option<Var>,
}

/// The built problem.
#[derive(Debug)]
pub struct XProblem {
    /// The SDP.
    pub problem: Problem,
    /// Variables per mode, in mode order.
    pub modes: Vec<ModeVars>,
}

/// The input matrices B_ai of mode `a`, one per rule.
pub fn input_matrices(model: &TsModel, modes: &Modes, a: usize) -> Vec<DMatrix<f64>> {
    model
        .rules
        .iter()
        .map(|rule| modes.modes[a].actuator.input_matrix(&rule.b))
        .collect()
}

/// The condition's name for mode `name`.
pub fn condition_name(mode: &str, c: &PairCondition) -> String {
    format!("mode {mode} {}", c.label)
}

/// Finite-time boundedness numbers of one SDP (alpha fixed).
#[derive(Debug, Clone, PartialEq)]
pub struct FtbParams {
    /// Growth rate alpha >= 0 of E V.
    pub alpha: f64,
    /// c1: x(0)' R x(0) <= c1.
    pub c1: f64,
    /// Horizon T.
    pub horizon: f64,
    /// The weight R (n x n, positive definite).
    pub r: DMatrix<f64>,
    /// Energy bound w2 of the disturbance (0 without disturbances).
    pub w2: f64,
    /// c2 when bounded (`None`: minimized).
    pub c2: Option<f64>,
}

/// What the mode conditions certify besides mean-square stability.
#[derive(Debug, Clone, PartialEq)]
pub enum Performance {
    /// Stability or decay rate only.
    None,
    /// H-inf gain from disturbance `from` to output `to`: gamma fixed, or
    /// minimized (`None`).
    Hinf {
        /// Disturbance index.
        from: usize,
        /// Output index.
        to: usize,
        /// Fixed gamma.
        gamma: Option<f64>,
    },
    /// Finite-time boundedness.
    FiniteTime(FtbParams),
}

/// The constant matrices of a performance condition: the disturbance
/// columns D_i per rule, and C, E, G of the H-inf output (empty otherwise).
#[derive(Debug, Clone)]
pub struct PerfMatrices {
    /// Disturbance columns of D_i, per rule (n x q', q' = 0 when none).
    pub d: Vec<DMatrix<f64>>,
    /// H-inf output: C (p x n), E (p x m), G (p x q'); `None` for finite time.
    pub output: Option<(DMatrix<f64>, DMatrix<f64>, DMatrix<f64>)>,
}

impl PerfMatrices {
    /// The matrices of `perf` on `model` (`None` for [`Performance::None`]).
    pub fn of(model: &TsModel, perf: &Performance) -> Option<PerfMatrices> {
        match perf {
            Performance::None => None,
            Performance::Hinf { from, to, .. } => {
                let ch = Channel::new(model, *from, *to);
                Some(PerfMatrices {
                    d: ch.d,
                    output: Some((ch.c, ch.e, ch.g)),
                })
            }
            Performance::FiniteTime(_) => Some(PerfMatrices {
                d: model.rules.iter().map(|r| r.d.clone()).collect(),
                output: None,
            }),
        }
    }

    /// Number of disturbance components in the condition.
    pub fn q(&self) -> usize {
        self.d.first().map_or(0, |d| d.ncols())
    }

    /// sum_k w_k D_{i_k} over the terms of a condition.
    pub fn d_sum(&self, terms: &[(usize, usize, f64)]) -> DMatrix<f64> {
        let n = self.d.first().map_or(0, |d| d.nrows());
        terms
            .iter()
            .fold(DMatrix::zeros(n, self.q()), |acc, &(i, _, w)| {
                acc + &self.d[i] * w
            })
    }
}

/// The shift of the diagonal term of (P): 2 alpha for a decay rate, -alpha
/// for finite-time boundedness.
pub fn diagonal_shift(decay: f64, perf: &Performance) -> f64 {
    match perf {
        Performance::FiniteTime(f) => -f.alpha,
        _ => 2.0 * decay,
    }
}

/// The names of the scalar variables of the performance conditions.
pub mod names {
    /// gamma^2 (H-inf, minimized).
    pub const G: &str = "g";
    /// lambda3: the weight of the disturbance energy (finite time).
    pub const LAMBDA3: &str = "lambda3";
    /// nu = 1 / lambda2 (finite time; lambda1 = 1 by scaling).
    pub const NU: &str = "nu";
    /// c2 (finite time, minimized).
    pub const C2: &str = "c2";
}

/// The scalar variables of a performance condition.
#[derive(Debug, Clone, Copy, Default)]
struct PerfVars {
    g: Option<Var>,
    lambda3: Option<Var>,
    nu: Option<Var>,
    c2: Option<Var>,
}

/// Builds the conditions of every mode with diagonal shift `shift` (2 alpha
/// for a decay rate, -alpha for finite time) and performance `perf`, with
/// strict margin `eps`.
#[allow(clippy::too_many_arguments)]
pub fn build(
    model: &TsModel,
    modes: &Modes,
    conditions: &[PairCondition],
    slack: bool,
    shift: f64,
    perf: &Performance,
    eps: f64,
) -> Result<XProblem, BuildError> {
    let (n, m, r) = (model.n, model.m, model.r());
    let mut problem = Problem::new();
    let dependent = modes.design == ModeDesign::Dependent;
    let mut vars: Vec<ModeVars> = Vec::new();
    for mode in &modes.modes {
        let suffix = if dependent {
            format!("_{}", mode.name)
        } else {
            String::new()
        };
        let shared = vars.first().filter(|_| !dependent);
        let x = match shared {
            Some(v) => v.x,
            None => problem.symmetric(&format!("X{suffix}"), n)?,
        };
        let mv = match shared {
            Some(v) => v.m.clone(),
            None => (0..r)
                .map(|j| problem.full(&format!("M{}{suffix}", j + 1), m, n))
                .collect::<Result<_, _>>()?,
        };
        let y = if slack {
            Some(problem.symmetric(&format!("Y_{}", mode.name), n)?)
        } else {
            None
        };
        vars.push(ModeVars { x, m: mv, y });
    }
    let mats = PerfMatrices::of(model, perf);
    let pv = declare_performance(&mut problem, perf, mats.as_ref())?;
    let id = DMatrix::identity(n, n);
    for (a, mode) in modes.modes.iter().enumerate() {
        let v = &vars[a];
        if dependent || a == 0 {
            let name = if dependent {
                format!("mode {}: X > 0", mode.name)
            } else {
                "X > 0".to_string()
            };
            problem.psd(&name, Expr::var(v.x), eps)?;
            if let Performance::FiniteTime(f) = perf {
                ftb_bounds(&mut problem, v.x, &f.r, pv, &name, eps)?;
            }
        }
        if let Some(y) = v.y {
            let name = format!("mode {} Y >= 0", mode.name);
            problem.psd(&name, Expr::var(y), eps)?;
        }
        let b = input_matrices(model, modes, a);
        // Coupling: the modes b != a reachable from a, with pi_ab > 0.
        let coupled: Vec<(usize, f64)> = if dependent {
            (0..modes.len())
                .filter(|&c| c != a && modes.rates[(a, c)] > 0.0)
                .map(|c| (c, modes.rates[(a, c)]))
                .collect()
        } else {
            Vec::new()
        };
        let diagonal = shift + if dependent { modes.rates[(a, a)] } else { 0.0 };
        let phi = |i: usize, j: usize| -> Result<Expr, BuildError> {
            let ax = Expr::product(&model.rules[i].a, v.x, &id)?;
            let bm = Expr::product(&b[i], v.m[j], &id)?;
            Ok(ax.add(bm)?.he()?.add(Expr::var(v.x).scale(diagonal)?)?)
        };
        for c in conditions {
            let mut top = Expr::zeros(n, n);
            for &(i, j, w) in &c.terms {
                top = top.add(phi(i, j)?.scale(w)?)?;
            }
            if let (Some(y), true) = (v.y, c.slack != 0.0) {
                top = top.add(Expr::var(y).scale(c.slack)?)?;
            }
            let k = c.multiplicity();
            let mut grid: Vec<Vec<Option<Expr>>> = vec![vec![Some(top)]];
            if let Some(mats) = &mats {
                performance_blocks(&mut grid, mats, perf, pv, v, &c.terms, k, n)?;
            }
            let lead = grid.len();
            let len = lead + coupled.len();
            for row in &mut grid {
                row.resize(len, None);
            }
            grid.resize(len, vec![None; len]);
            for (s, &(bm, pi)) in coupled.iter().enumerate() {
                grid[0][lead + s] = Some(Expr::var(v.x).scale(k)?);
                grid[lead + s][lead + s] = Some(Expr::var(vars[bm].x).scale(-k / pi)?);
            }
            let e = if len == 1 {
                grid.swap_remove(0)
                    .swap_remove(0)
                    .unwrap_or_else(|| Expr::zeros(n, n))
            } else {
                Expr::sym_blocks(grid)?
            };
            // Non-strict conditions are solved with the margin too.
            problem.nsd(&condition_name(&mode.name, c), e, eps)?;
        }
    }
    if let Performance::FiniteTime(f) = perf {
        ftb_final(&mut problem, f, pv, eps)?;
    }
    Ok(XProblem {
        problem,
        modes: vars,
    })
}

/// Declares the scalar variables of `perf` and their sign constraints, and
/// the objective (gamma^2 or c2 minimized).
fn declare_performance(
    problem: &mut Problem,
    perf: &Performance,
    mats: Option<&PerfMatrices>,
) -> Result<PerfVars, BuildError> {
    let mut pv = PerfVars::default();
    match perf {
        Performance::None => {}
        Performance::Hinf { gamma, .. } => {
            if gamma.is_none() {
                let g = problem.scalar(names::G)?;
                problem.add_scalar("g >= 0", Expr::var(g), Relation::Ge, 0.0)?;
                problem.minimize(Expr::var(g))?;
                pv.g = Some(g);
            }
        }
        Performance::FiniteTime(f) => {
            if mats.is_some_and(|m| m.q() > 0) {
                let l3 = problem.scalar(names::LAMBDA3)?;
                problem.add_scalar("lambda3 >= 0", Expr::var(l3), Relation::Ge, 0.0)?;
                pv.lambda3 = Some(l3);
            }
            pv.nu = Some(problem.scalar(names::NU)?);
            if f.c2.is_none() {
                let c2 = problem.scalar(names::C2)?;
                problem.minimize(Expr::var(c2))?;
                pv.c2 = Some(c2);
            }
        }
    }
    Ok(pv)
}

/// The rows and columns a performance condition adds to the top-left block
/// (`grid` holds it): H-inf [[., D, (C X + E M)'], [*, -g I, G'], [*, *, -I]],
/// finite time [[., D], [*, -lambda3 I]], each summed over the condition's
/// terms (weights w_k, total k).
#[allow(clippy::too_many_arguments)]
fn performance_blocks(
    grid: &mut Vec<Vec<Option<Expr>>>,
    mats: &PerfMatrices,
    perf: &Performance,
    pv: PerfVars,
    v: &ModeVars,
    terms: &[(usize, usize, f64)],
    k: f64,
    n: usize,
) -> Result<(), BuildError> {
    let q = mats.q();
    if q == 0 && mats.output.is_none() {
        return Ok(());
    }
    let id = DMatrix::identity(n, n);
    let d = Expr::constant(&mats.d_sum(terms))?;
    let weight = |var: Option<Var>, fixed: f64| -> Result<Expr, BuildError> {
        Ok(match var {
            Some(s) => Expr::scaled(s, &(DMatrix::identity(q, q) * -k))?,
            None => Expr::constant(&(DMatrix::identity(q, q) * (-k * fixed)))?,
        })
    };
    match (perf, &mats.output) {
        (Performance::Hinf { gamma, .. }, Some((c, e, g))) => {
            let p = c.nrows();
            let mut out = Expr::zeros(p, n);
            for &(_, j, w) in terms {
                let cx = Expr::product(c, v.x, &id)?;
                let em = Expr::product(e, v.m[j], &id)?;
                out = out.add(cx.add(em)?.scale(w)?)?;
            }
            grid[0].push(Some(d));
            grid[0].push(Some(out.transpose()));
            let g2 = gamma.map_or(0.0, |g| g * g);
            grid.push(vec![
                None,
                Some(weight(pv.g, g2)?),
                Some(Expr::constant(&(g.transpose() * k))?),
            ]);
            grid.push(vec![None, None, Some(Expr::identity(p).scale(-k)?)]);
        }
        (Performance::FiniteTime(_), _) => {
            grid[0].push(Some(d));
            grid.push(vec![None, Some(weight(pv.lambda3, 0.0)?)]);
        }
        _ => {}
    }
    Ok(())
}

/// R^{-1} - X_a >= 0 (P_a >= R: lambda1 = 1 by scaling) and
/// X_a - nu R^{-1} >= 0 (P_a <= R / nu: lambda2 = 1 / nu).
fn ftb_bounds(
    problem: &mut Problem,
    x: Var,
    r: &DMatrix<f64>,
    pv: PerfVars,
    name: &str,
    eps: f64,
) -> Result<(), BuildError> {
    let rinv = r
        .clone()
        .try_inverse()
        .ok_or_else(|| BuildError::Unsupported("the weight R is singular".into()))?;
    let rinv = (&rinv + rinv.transpose()) * 0.5;
    let upper = Expr::constant(&rinv)?.sub(Expr::var(x))?;
    problem.psd(&format!("{name}: X <= R^-1"), upper, eps)?;
    if let Some(nu) = pv.nu {
        let lower = Expr::var(x).sub(Expr::scaled(nu, &rinv)?)?;
        problem.psd(&format!("{name}: X >= nu R^-1"), lower, eps)?;
    }
    Ok(())
}

/// nu > 0 and e^{alpha T} (c1 / nu + lambda3 w2) < c2, as the 2 x 2 LMI
/// [[c2 - e^{alpha T} lambda3 w2, sqrt(e^{alpha T} c1)], [*, nu]] > 0.
fn ftb_final(
    problem: &mut Problem,
    f: &FtbParams,
    pv: PerfVars,
    eps: f64,
) -> Result<(), BuildError> {
    let Some(nu) = pv.nu else {
        return Ok(());
    };
    problem.psd("nu > 0", Expr::var(nu), eps)?;
    let growth = (f.alpha * f.horizon).exp();
    let mut corner = match (pv.c2, f.c2) {
        (Some(c2), _) => Expr::var(c2),
        (None, Some(c2)) => Expr::constant(&DMatrix::from_element(1, 1, c2))?,
        (None, None) => {
            return Err(BuildError::Unsupported(
                "c2 is neither fixed nor minimized".into(),
            ))
        }
    };
    if let Some(l3) = pv.lambda3 {
        corner = corner.add(Expr::var(l3).scale(-growth * f.w2)?)?;
    }
    let e = Expr::sym_blocks(vec![
        vec![
            Some(corner),
            Some(Expr::constant(&DMatrix::from_element(
                1,
                1,
                (growth * f.c1).sqrt(),
            ))?),
        ],
        vec![None, Some(Expr::var(nu))],
    ])?;
    problem.psd(
        "finite time: e^(alpha T) (lambda2 c1 + lambda3 w2) < c2",
        e,
        eps,
    )?;
    Ok(())
}
