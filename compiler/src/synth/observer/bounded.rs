//! Input bounds and the saturation region of an observer-based loop,
//! certified on the augmented state xi = (x, e), e = x - x_hat, with the
//! shipped gains F_j and L_i as data.
//!
//! The command is u = sum_j h_j F_j x_hat = sum_j h_j K_j xi with
//! K_j = [F_j, -F_j]. With a saturating actuator the plant receives
//! sat(v), v = sum_j h_j K_j xi, and so does the observer (the runtime feeds
//! its update the command it returns, the saturated one); with the dead zone
//! psi(v) = v - sat(v) the plant is x' = sum h_i (A_i x + B_i v - B_i psi)
//! and the observer x_hat' = sum h_i (A_i x_hat + B_i (v - psi) +
//! L_i (y - C x_hat)), so e' = sum_i h_i (A_i - L_i C) e does not see psi:
//!
//! ```text
//! xi' = sum_ij h_i h_j (G_ij xi - Bbar_i psi),   Bbar_i = [B_i; 0]
//! ```
//!
//! The analysis SDP is written in X = P_aug^-1 (2n x 2n, full: with
//! diag(P1, Pe) the input bound of the textbook pendulum is 5.7 times
//! larger, docs/limits.md), so that every condition is linear:
//!
//! - decay: He(G_ij X) + 2 alpha X < 0 under the spec's relaxation, with the
//!   saturation region the dead-zone column of the generalized sector
//!   condition (Tarbouriech, Garcia, Gomes da Silva & Queinnec 2011,
//!   "Stability and Stabilization of Linear Systems with Saturating
//!   Actuators", Lemma 1.6): [He(G_ij X) + 2 alpha X, -Bbar_i S + Z_j'; *, -2S] < 0,
//!   S = T^-1 diagonal, Z_j = H_j X; the congruence diag(P, T) gives the
//!   P-form [He(P G_ij) + 2 alpha P, -P Bbar_i + H_j' T; *, -2T] < 0, so V =
//!   xi'P xi decays while psi' T (psi - H xi) <= 0, which holds on the
//!   linear region below;
//! - linear region: [X, X K_js' - Z_js'; *, u_s^2] >= 0 for every rule j and
//!   channel s, i.e. |(K_j - H_j)_s xi| <= u_s on E(P, 1);
//! - input bound: [X, X K_j'; K_j X, mu^2 I] >= 0 for every rule j, i.e.
//!   ||K_j xi|| <= mu on E(P, 1), hence ||u|| <= mu there (the blend is a
//!   convex combination);
//! - output bound: [X, X Cbar_j'; Cbar_j X, lambda^2 I] >= 0,
//!   Cbar_j = [C_z + E_z F_j, -E_z F_j], i.e. ||z|| <= lambda on E(P, 1)
//!   (with z = theta it keeps the certified set inside the rules' range);
//! - the initial set: the observer starts from x_hat(0) = 0 (the generated
//!   code's `INIT`), so xi(0) = (x0, x0) = E x0 with E = [I; I]: for a point
//!   [1, xi0'; xi0, X] >= 0, for an ellipsoid {x0' R x0 <= 1}
//!   [R, E'; E, X] >= 0.
//!
//! E(P, 1) is then invariant: from the initial set the loop stays in it and
//! the bounds hold for all t >= 0.

use super::augmented::closed_loop;
use crate::model::TsModel;
use crate::synth::blocks::{nonstrict_psd, region_block, row_selector, scalar_times_identity};
use crate::synth::relaxation::Family;
use crate::synth::relaxations::Relaxer;
use nalgebra::DMatrix;
use tsf_lang::spec::{InitialSet, Objective, Spec, Target};
use tsf_lmi::{Expr, LmiError, Problem, Relation, Var};

/// X = P_aug^-1 of the bounded certificate (2n x 2n, full).
pub const X_AUG: &str = "X_aug";
/// S = T^-1 of the generalized sector condition (m x m, diagonal).
pub const S_AUG: &str = "S_aug";
/// nu = mu^2 / sigma^2 of the input bound when minimized ([`mu_scale`]).
pub const MU2_AUG: &str = "mu2_aug";

/// A minimized input bound is certified this much (relative) above the
/// least one the solver finds.
pub const MU_SLACK: f64 = 1e-3;

/// Z_j = H_j X of controller rule `j` (0-based).
pub fn sector_product(j: usize) -> String {
    format!("Z{}_aug", j + 1)
}

/// The input bound: mu fixed (`Some`) or minimized (`None`), and the initial set.
#[derive(Debug, Clone, PartialEq)]
pub struct InputBound {
    /// The spec's mu, or `None` when minimized.
    pub mu: Option<f64>,
    /// The initial states (with x_hat(0) = 0).
    pub initial: InitialSet,
}

/// The saturation region: the levels and the initial set it must contain.
#[derive(Debug, Clone, PartialEq)]
pub struct SectorRegion {
    /// u_bar_s per channel.
    pub levels: Vec<f64>,
    /// The initial states (with x_hat(0) = 0), if any.
    pub contain: Option<InitialSet>,
}

/// An output bound ||C_z x|| <= lambda on E(P, 1) (fixed lambda): it keeps
/// the certified set inside a region of the state, e.g. the rules' range.
#[derive(Debug, Clone, PartialEq)]
pub struct OutputBound {
    /// C_z of the output (rows x n).
    pub c: DMatrix<f64>,
    /// E_z of the output (rows x m): z = C_z x + E_z u.
    pub e: DMatrix<f64>,
    /// The spec's lambda.
    pub lambda: f64,
    /// The initial states (with x_hat(0) = 0).
    pub initial: InitialSet,
}

/// What the bounded certificate imposes beyond the decay rate.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Bounds {
    /// `objective input_norm`.
    pub input: Option<InputBound>,
    /// `objective output_norm(z) <= lambda` (the checker refuses a
    /// minimized one with `control observer_based`).
    pub output: Option<OutputBound>,
    /// `objective saturation region` (asked for, or implied by `saturate`
    /// levels without an input bound).
    pub saturation: Option<SectorRegion>,
}

impl Bounds {
    /// The bounds of `spec` (`None` without an input bound or saturation
    /// levels): the saturation region when asked for, or when `saturate`
    /// levels are declared without an input bound (as the core design
    /// implies it, synth/plan.rs).
    pub fn of(spec: &Spec) -> Option<Bounds> {
        let mut b = Bounds::default();
        let mut asked = false;
        for o in &spec.objectives {
            match &o.node {
                Objective::InputNorm { target, initial } => {
                    b.input = Some(InputBound {
                        mu: match target {
                            Target::Fixed(mu) => Some(*mu),
                            Target::Optimize => None,
                        },
                        initial: initial.clone(),
                    });
                }
                Objective::OutputNorm {
                    output,
                    target: Target::Fixed(lambda),
                    initial,
                } => {
                    b.output = Some(OutputBound {
                        c: spec.outputs[*output].c.clone(),
                        e: spec.outputs[*output].e.clone(),
                        lambda: *lambda,
                        initial: initial.clone(),
                    });
                }
                Objective::SaturationRegion { contain } => {
                    asked = true;
                    b.saturation = spec.saturation.clone().map(|levels| SectorRegion {
                        levels,
                        contain: contain.clone(),
                    });
                }
                _ => {}
            }
        }
        if let (Some(levels), false, None) = (&spec.saturation, asked, &b.input) {
            b.saturation = Some(SectorRegion {
                levels: levels.clone(),
                contain: None,
            });
        }
        (b.input.is_some() || b.output.is_some() || b.saturation.is_some()).then_some(b)
    }

    /// The initial sets the region E(P, 1) must contain.
    fn initial_sets(&self) -> Vec<&InitialSet> {
        let mut sets: Vec<&InitialSet> = Vec::new();
        let asked = [
            self.input.as_ref().map(|i| &i.initial),
            self.output.as_ref().map(|o| &o.initial),
            self.saturation.as_ref().and_then(|s| s.contain.as_ref()),
        ];
        for set in asked.into_iter().flatten() {
            if !sets.contains(&set) {
                sets.push(set);
            }
        }
        sets
    }
}

/// K_j = [F_j, -F_j]: u = K_j xi on the augmented state.
pub fn command_map(f: &DMatrix<f64>) -> DMatrix<f64> {
    let (m, n) = f.shape();
    let mut k = DMatrix::zeros(m, 2 * n);
    k.view_mut((0, 0), (m, n)).copy_from(f);
    k.view_mut((0, n), (m, n)).copy_from(&(-f));
    k
}

/// The augmented initial state of `x0` with x_hat(0) = 0: E = [I; I] (2n x n).
pub fn initial_map(n: usize) -> DMatrix<f64> {
    let mut e = DMatrix::zeros(2 * n, n);
    e.view_mut((0, 0), (n, n)).fill_with_identity();
    e.view_mut((n, 0), (n, n)).fill_with_identity();
    e
}

/// The scale sigma of a minimized input bound (mu^2 = sigma^2 nu): the
/// command max_j ||F_j|| reaches at the largest initial point (1 without
/// points), at least 1e-6.
pub fn mu_scale(bounds: &Bounds, f: &[DMatrix<f64>], n: usize) -> f64 {
    initial_scale(bounds.initial_sets().into_iter(), f, n)
}

/// max_j ||F_j|| times the largest radius of the `initial` sets (1 without
/// one), at least 1e-6: the scale of a minimized input bound (also of the
/// sampled loop's, [`super::sampled_bounds`]).
pub fn initial_scale<'a>(
    initial: impl Iterator<Item = &'a InitialSet>,
    f: &[DMatrix<f64>],
    n: usize,
) -> f64 {
    let radius = initial
        .map(|set| match set {
            InitialSet::Point(x0) => DMatrix::from_column_slice(n, 1, x0).norm(),
            InitialSet::Ellipsoid(r) => r
                .clone()
                .symmetric_eigen()
                .eigenvalues
                .min()
                .max(f64::MIN_POSITIVE)
                .recip()
                .sqrt(),
        })
        .fold(0.0, f64::max);
    let gain = f.iter().map(|fj| fj.norm()).fold(0.0, f64::max);
    let scale = gain * if radius > 0.0 { radius } else { 1.0 };
    scale.max(1e-6)
}

/// The bounded analysis problem and what the certificate needs of it.
pub struct BoundedProblem {
    /// The problem.
    pub problem: Problem,
    /// X = P_aug^-1.
    pub x: Var,
    /// The minimized mu^2, if any.
    pub mu2: Option<Var>,
    /// Reductions the relaxation applied.
    pub reductions: Vec<crate::synth::Reduction>,
    /// Constraints non-strict in the theory.
    pub nonstrict: Vec<String>,
}

/// The containment block of `init` (with x_hat(0) = 0) in E(X^-1, 1).
fn initial_block(x: Var, init: &InitialSet, n: usize) -> Result<(String, Expr), LmiError> {
    let e = initial_map(n);
    Ok(match init {
        InitialSet::Point(x0) => {
            let xi0 = &e * DMatrix::from_column_slice(n, 1, x0);
            let block = Expr::sym_blocks(vec![
                vec![
                    Some(Expr::identity(1)),
                    Some(Expr::constant(&xi0.transpose())?),
                ],
                vec![None, Some(Expr::var(x))],
            ])?;
            ("augmented (x0, x0) in E(P,1)".into(), block)
        }
        InitialSet::Ellipsoid(r) => {
            let block = Expr::sym_blocks(vec![
                vec![
                    Some(Expr::constant(r)?),
                    Some(Expr::constant(&e.transpose())?),
                ],
                vec![None, Some(Expr::var(x))],
            ])?;
            ("augmented ellipsoid (x0, x0) in E(P,1)".into(), block)
        }
    })
}

/// Builds the bounded analysis problem for the gains `f`, `l` at decay rate
/// `alpha`; `levels` replaces the saturation levels (the stored-precision
/// check passes them rounded).
pub fn problem(
    model: &TsModel,
    (f, l): (&[DMatrix<f64>], &[DMatrix<f64>]),
    c: &DMatrix<f64>,
    alpha: f64,
    bounds: &Bounds,
    eps: f64,
) -> Result<BoundedProblem, LmiError> {
    let (n, m) = (model.n, model.m);
    let mut problem = Problem::new();
    let x = problem.symmetric(X_AUG, 2 * n)?;
    let sector = match &bounds.saturation {
        Some(_) => {
            let s = problem.diagonal(S_AUG, m)?;
            let z = (0..model.r())
                .map(|j| problem.full(&sector_product(j), m, 2 * n))
                .collect::<Result<Vec<_>, _>>()?;
            Some((s, z))
        }
        None => None,
    };
    let mu2 = match &bounds.input {
        Some(InputBound { mu: None, .. }) => Some(problem.scalar(MU2_AUG)?),
        _ => None,
    };
    let mut nonstrict = Vec::new();
    problem.psd("augmented X > 0", Expr::var(x), eps)?;
    let mut relaxer = Relaxer::new(model, model.spec.relaxation.node, eps, false);
    let fam = Family {
        name: "augmented bounded".into(),
        q: Box::new(|i, j| {
            let g = closed_loop(model, f, l, c, i, j);
            let decay = Expr::var(x)
                .left_mul(&g)?
                .he()?
                .add(Expr::var(x).scale(2.0 * alpha)?)?;
            let Some((s, z)) = &sector else {
                return Ok(decay);
            };
            let mut bbar = DMatrix::zeros(2 * n, m);
            bbar.view_mut((0, 0), (n, m)).copy_from(&model.rules[i].b);
            let column = Expr::var(*s)
                .left_mul(&(-bbar))?
                .add(Expr::var(z[j]).transpose())?;
            Expr::sym_blocks(vec![
                vec![Some(decay), Some(column)],
                vec![None, Some(Expr::var(*s).scale(-2.0)?)],
            ])
        }),
    };
    relaxer.impose(&mut problem, &fam)?;
    for init in bounds.initial_sets() {
        let (name, block) = initial_block(x, init, n)?;
        nonstrict_psd(&mut problem, &mut nonstrict, &name, block, eps)?;
    }
    if let (Some(sat), Some((s, z))) = (&bounds.saturation, &sector) {
        problem.psd("augmented S > 0", Expr::var(*s), eps)?;
        for (j, fj) in f.iter().enumerate() {
            let k = command_map(fj);
            for (ch, level) in sat.levels.iter().enumerate() {
                let sel = row_selector(ch, m);
                // Row s of K_j X - Z_j (1 x 2n), divided by u_s: the block
                // [X, row'/u_s; *, 1] >= 0 is the condition's congruence by
                // diag(I, 1/u_s), scaled for the solver.
                let row = Expr::var(x)
                    .left_mul(&(&sel * &k))?
                    .sub(Expr::product(&sel, z[j], &DMatrix::identity(2 * n, 2 * n))?)?
                    .scale(1.0 / level)?;
                let rhs = Expr::identity(1);
                let name = format!("augmented linear region [{},{}]", j + 1, ch + 1);
                nonstrict_psd(
                    &mut problem,
                    &mut nonstrict,
                    &name,
                    region_block(Expr::var(x), row, rhs)?,
                    eps,
                )?;
            }
        }
    }
    if let Some(input) = &bounds.input {
        // A fixed bound as [X, X K_j'/mu; *, I] >= 0 (scaled as the region).
        let (fixed, by) = input.mu.map_or((0.0, 1.0), |mu| (1.0, mu));
        for (j, fj) in f.iter().enumerate() {
            // A minimized one as [X, X K_j'/sigma; *, nu I] >= 0 with
            // mu^2 = sigma^2 nu (sigma from [`mu_scale`], nu of order 1).
            let by = if mu2.is_some() {
                mu_scale(bounds, f, n)
            } else {
                by
            };
            let kx = Expr::var(x).left_mul(&(command_map(fj) / by))?;
            let block = Expr::sym_blocks(vec![
                vec![Some(Expr::var(x)), Some(kx.transpose())],
                vec![None, Some(scalar_times_identity(mu2, fixed, m)?)],
            ])?;
            let name = format!("augmented input norm [{}]", j + 1);
            nonstrict_psd(&mut problem, &mut nonstrict, &name, block, eps)?;
        }
    }
    if let Some(out) = &bounds.output {
        let rows = out.c.nrows();
        let level = DMatrix::identity(rows, rows);
        for (j, fj) in f.iter().enumerate() {
            // z = C_z x + E_z u = [C_z + E_z F_j, -E_z F_j] xi under rule j.
            let mut cbar = &out.e * command_map(fj);
            let mut cx_part = cbar.view_mut((0, 0), (rows, n));
            cx_part += &out.c;
            let cx = Expr::var(x).left_mul(&(cbar / out.lambda))?;
            let block = Expr::sym_blocks(vec![
                vec![Some(Expr::var(x)), Some(cx.transpose())],
                vec![None, Some(Expr::constant(&level)?)],
            ])?;
            let name = format!("augmented output norm [{}]", j + 1);
            nonstrict_psd(&mut problem, &mut nonstrict, &name, block, eps)?;
        }
    }
    if let Some(mu2) = mu2 {
        problem.add_scalar("mu2_aug >= 0", Expr::var(mu2), Relation::Ge, 0.0)?;
        problem.minimize(Expr::var(mu2))?;
    }
    nonstrict.extend(relaxer.nonstrict);
    Ok(BoundedProblem {
        problem,
        x,
        mu2,
        reductions: relaxer.reductions,
        nonstrict,
    })
}

/// The solved bounded certificate (beyond [`super::augmented::AugmentedDesign`]'s P).
#[derive(Debug, Clone, PartialEq)]
pub struct BoundedDesign {
    /// What was imposed.
    pub bounds: Bounds,
    /// X = P_aug^-1 as solved.
    pub x: DMatrix<f64>,
    /// The certified input bound mu (the spec's, or the minimized one).
    pub mu: Option<f64>,
    /// T = S^-1 (m x m diagonal) of the sector condition.
    pub t: Option<DMatrix<f64>>,
    /// H_j = Z_j X^-1 (m x 2n), one per controller rule.
    pub h: Vec<DMatrix<f64>>,
}

/// What the spec asked for, in words (error messages).
fn asked(bounds: &Bounds) -> String {
    let mut parts = Vec::new();
    if let Some(i) = &bounds.input {
        parts.push(match i.mu {
            Some(mu) => format!("the input bound ||u|| <= {mu}"),
            None => "a minimized input bound".to_string(),
        });
    }
    if let Some(o) = &bounds.output {
        parts.push(format!("the output bound {}", o.lambda));
    }
    if bounds.saturation.is_some() {
        parts.push("the saturation region".to_string());
    }
    parts.join(" and ")
}

/// The least input bound the gains admit with the other bounds (the input
/// bound minimized), when the solver finds one (solved, or almost: the
/// certificate checks the fixed bound made of it).
fn least_input_bound(
    runner: &mut crate::synth::Runner<'_>,
    (f, l): (&[DMatrix<f64>], &[DMatrix<f64>]),
    c: &DMatrix<f64>,
    alpha: f64,
    bounds: &Bounds,
) -> Result<Option<f64>, crate::synth::SynthError> {
    use tsf_lmi::SolveStatus;
    let model = runner.model;
    let mut loose = bounds.clone();
    if let Some(input) = &mut loose.input {
        input.mu = None;
    }
    let built = problem(model, (f, l), c, alpha, &loose, runner.settings.eps).map_err(|e| {
        crate::synth::SynthError::Internal(format!(
            "internal error: bounded augmented problem: {e}"
        ))
    })?;
    let sol = runner.solve(
        &built.problem,
        "augmented observer-loop input bound (minimized)",
    )?;
    if !matches!(sol.status, SolveStatus::Solved | SolveStatus::AlmostSolved) {
        return Ok(None);
    }
    let Some(v) = built.mu2 else {
        return Ok(None);
    };
    // An almost-solved iterate only proposes the level: the fixed bound made
    // of it is solved again and certified.
    Ok(sol
        .assignment_any_status()
        .value(v)
        .ok()
        .map(|nu| mu_scale(&loose, f, model.n) * nu[(0, 0)].max(0.0).sqrt()))
}

/// Solves the bounded analysis SDP; refused (not certified) when infeasible,
/// with the input bound these gains achieve when a fixed one fails.
pub fn solve(
    runner: &mut crate::synth::Runner<'_>,
    (f, l): (&[DMatrix<f64>], &[DMatrix<f64>]),
    c: &DMatrix<f64>,
    alpha: f64,
    bounds: &Bounds,
) -> Result<super::augmented::AugmentedDesign, crate::synth::SynthError> {
    use crate::synth::SynthError;
    use tsf_lmi::SolveStatus;
    let model = runner.model;
    let internal = |e: LmiError| {
        SynthError::Internal(format!("internal error: bounded augmented problem: {e}"))
    };
    // A minimized bound is found first, then certified as a fixed one
    // MU_SLACK above the least: the optimum lies on the boundary, where the
    // solver's residuals (about 1e-7 at mu^2 ~ 1e5) break the certificate.
    let mut bounds = bounds.clone();
    if let Some(input) = &bounds.input {
        if input.mu.is_none() {
            let least = least_input_bound(runner, (f, l), c, alpha, &bounds)?;
            if let (Some(mu), Some(input)) = (least, &mut bounds.input) {
                input.mu = Some(mu * (1.0 + MU_SLACK));
            }
        }
    }
    let bounds = &bounds;
    let built = problem(model, (f, l), c, alpha, bounds, runner.settings.eps).map_err(internal)?;
    let sol = runner.solve(&built.problem, "augmented observer-loop bounds problem")?;
    if sol.status != SolveStatus::Solved {
        let mut achievable = vec![
            "lower the observer's decay rate (`control observer_based(decay = ..)`: a fast observer peaks from x_hat(0) = 0) or the controller's `decay_rate`, or shrink the initial set".to_string(),
        ];
        if bounds.input.as_ref().is_some_and(|i| i.mu.is_some()) {
            if let Some(mu) = least_input_bound(runner, (f, l), c, alpha, bounds)? {
                achievable.insert(0, format!("these gains certify ||u|| <= {mu:.6} on the augmented loop: `objective input_norm(u) <= {:.6} ...` (or minimize)", mu * (1.0 + 10.0 * MU_SLACK)));
            }
        }
        return Err(SynthError::Infeasible {
            message: format!(
                "the observer-based loop is not certified: the augmented (x, e) conditions at decay rate {alpha} with {} (x_hat(0) = 0) are {} for the controller and observer gains",
                asked(bounds),
                sol.status.describe()
            ),
            achievable,
        });
    }
    let values = super::SolvedVars::read(&built.problem, &sol)?;
    let get = |name: &str| values.get(name);
    let x = get(X_AUG)?;
    let Some(p) = x.clone().cholesky().map(|ch| ch.inverse()) else {
        return Err(SynthError::Internal(
            "internal error: the augmented X is not positive definite".into(),
        ));
    };
    let mu = match &bounds.input {
        Some(InputBound { mu: Some(mu), .. }) => Some(*mu),
        Some(InputBound { mu: None, .. }) => {
            Some(mu_scale(bounds, f, model.n) * get(MU2_AUG)?[(0, 0)].max(0.0).sqrt())
        }
        None => None,
    };
    let (t, h) = match &bounds.saturation {
        Some(_) => {
            let s = get(S_AUG)?;
            let t = DMatrix::from_diagonal(&s.diagonal().map(|v| 1.0 / v));
            let h = (0..model.r())
                .map(|j| get(&sector_product(j)).map(|z| z * &p))
                .collect::<Result<Vec<_>, _>>()?;
            (Some(t), h)
        }
        None => (None, Vec::new()),
    };
    Ok(super::augmented::AugmentedDesign {
        alpha,
        p,
        values: values.0,
        reductions: built.reductions,
        hinf_gamma: None,
        bounded: Some(Box::new(BoundedDesign {
            bounds: bounds.clone(),
            x,
            mu,
            t,
            h,
        })),
    })
}
