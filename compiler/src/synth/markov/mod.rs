//! Markov-switching modes (`modes { ... }`): mode-dependent or
//! mode-independent PDC gains for a T-S model whose input matrix jumps with
//! a continuous-time Markov chain r(t) with generator Pi = [pi_ab].
//!
//! With V(x, a) = x' P_a x, the weak infinitesimal generator along mode a is
//! x' (He(P_a A_cl,a) + sum_b pi_ab P_b) x, so mean-square exponential
//! stability with rate alpha (E V decays at least as e^{-2 alpha t}) holds if,
//! for every mode a and every blend of the rules,
//!
//! G_a = He(P_a (A_i + B_ai F_aj)) + sum_b pi_ab P_b + 2 alpha P_a < 0,   (P)
//!
//! relaxed over rule pairs as the relaxation seam lists them
//! ([`super::relaxation::DoubleSum::conditions`]). Change of variables: X_a =
//! P_a^{-1}, M_aj = F_aj X_a. Congruence with X_a gives
//! He(A_i X_a + B_ai M_aj) + (pi_aa + 2 alpha) X_a + sum_{b != a} pi_ab X_a X_b^{-1} X_a,
//! and the last sum is R_a S_a^{-1} R_a' with R_a = [X_a, ..., X_a] and
//! S_a = diag(X_b / pi_ab) over the modes b != a with pi_ab > 0 (pi_ab = 0
//! contributes nothing). By Schur's complement (S_a > 0), (P) is equivalent to
//!
//! [[Phi_aij, R_a], [R_a', -S_a]] < 0,  Phi_aij = He(A_i X_a + B_ai M_aj) + (pi_aa + 2 alpha) X_a.   (X)
//!
//! A relaxation condition sum_k w_k Q_{i_k j_k} (+ c Y_a) < 0 sums the top-left
//! blocks and scales R_a and S_a by k = sum_k w_k, whose Schur complement is
//! again k R_a S_a^{-1} R_a': the coupling enters each condition k times, as
//! in the P form. The slack of `tanaka` is an n x n Y_a on the top-left
//! block; in P variables it is P_a Y_a P_a.
//!
//! Mode-independent (fault-blind) design: one X and one gain set M_j for
//! every mode (P_a = P). Then sum_b pi_ab P_b = 0 (rows of Pi sum to 0), and
//! (P) is He(P (A_i + B_ai F_j)) + 2 alpha P < 0 for every mode a: a common
//! quadratic Lyapunov function for every mode, so the gains hold under any
//! switching, not only under this chain (sound, and conservative).
//!
//! H-inf (bounded-real lemma per mode and rule pair): with D_i, and the
//! output y = C x + E u + G w,
//!
//! [[G_aij, P_a D_i, (C + E F_aj)'], [*, -gamma^2 I, G'], [*, *, -I]] < 0,
//!
//! which gives E int |y|^2 < gamma^2 int |w|^2 from x(0) = 0 (mean square).
//! Congruence with diag(X_a, I, I) gives the X form with D_i and C X_a + E M_aj.
//!
//! Finite-time boundedness (Amato, Ariola & Dorato 2001; for Markov jump
//! systems as in Xue, Jin & Tian 2024): with (P) shifted by -alpha P_a
//! instead of 2 alpha P_a and all disturbances,
//!
//! [[G_aij, P_a D_i], [*, -lambda3 I]] < 0 gives E LV < alpha E V + lambda3 w'w,
//!
//! so e^{-alpha t} E V(t) < V(0) + lambda3 w2, and with lambda1 R <= P_a <=
//! lambda2 R: E x(t)' R x(t) < e^{alpha T} (lambda2 c1 + lambda3 w2) / lambda1
//! for t in [0, T]. (A matrix Q_d < lambda3 I in place of lambda3 I gives
//! nothing more: replacing Q_d by lambda3 I keeps the LMI.) The LMIs are
//! homogeneous in (P, lambda3), so lambda1 = 1: X_a <= R^{-1}, X_a >= nu
//! R^{-1} (lambda2 = 1 / nu), and [[c2 - e^{alpha T} lambda3 w2,
//! sqrt(e^{alpha T} c1)], [*, nu]] > 0, all linear; c2 is minimized for each
//! alpha of a fixed grid ([`FTB_ALPHA_T`]) refined by golden section, or
//! alpha is given. Mode-independent: V does not depend on the mode, so the
//! bound holds along every switching path, not only in the mean.
//!
//! The certificate (`certify/markov.rs`) re-checks (P) itself, with P_a =
//! X_a^{-1} and the design's F_aj, never (X), and recomputes lambda1,
//! lambda2 from the P_a and c2 from them.

pub mod problem;
pub mod sampled;

use super::achieved::{Achieved, Quantity};
use super::design::{Design, SolverLog, SynthError};
use super::plan::{initial_plan, Plan};
use super::relaxation::Conditions;
use super::relaxations;
use super::search::Runner;
use super::solved::Solved as _;
use nalgebra::DMatrix;
use problem::{diagonal_shift, names, FtbParams, Performance};
use std::cell::Cell;
use std::time::{Duration, Instant};
use tsf_lang::modes::{ModeDesign, Modes};
use tsf_lang::spec::{Objective, Spec, Target};
use tsf_lmi::{Solution, SolveStatus};

/// alpha * T of the finite-time grid when alpha is not given; the best grid
/// point is then refined by golden section between its neighbours.
pub const FTB_ALPHA_T: [f64; 11] = [0.0, 0.05, 0.1, 0.2, 0.35, 0.5, 0.75, 1.0, 1.5, 2.0, 3.0];

/// Golden-section steps of the alpha refinement.
const FTB_GOLDEN_STEPS: usize = 12;

/// The solved mode design: what the certificate re-checks and the report shows.
#[derive(Debug, Clone)]
pub struct ModesDesign {
    /// Mode-dependent or mode-independent gains.
    pub design: ModeDesign,
    /// The decay rate imposed (0: stability, and with finite time).
    pub alpha: f64,
    /// The performance condition with the solved numbers fixed (gamma, c2, alpha).
    pub performance: Performance,
    /// lambda3 of finite time (0 otherwise, or without disturbances).
    pub lambda3: f64,
    /// P_a = X_a^{-1}, per mode.
    pub p: Vec<DMatrix<f64>>,
    /// F_aj, per mode then rule (the same gains in every mode when mode-independent).
    pub gains: Vec<Vec<DMatrix<f64>>>,
    /// The relaxation's slack in P variables, P_a Y_a P_a, per mode (tanaka).
    pub slack: Vec<Option<DMatrix<f64>>>,
}

/// The finite-time numbers of a design, from its P_a: lambda1, lambda2 the
/// extreme generalized eigenvalues of (P_a, R) over the modes, and the c2
/// they prove, e^{alpha T} (lambda2 c1 + lambda3 w2) / lambda1.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FtbNumbers {
    /// min_a lambda_min(R^{-1/2} P_a R^{-1/2}).
    pub lambda1: f64,
    /// max_a lambda_max(R^{-1/2} P_a R^{-1/2}).
    pub lambda2: f64,
    /// The disturbance weight.
    pub lambda3: f64,
    /// The bound proven: E x(t)' R x(t) < c2 on [0, T].
    pub c2: f64,
}

impl ModesDesign {
    /// The finite-time numbers (`None` without a finite-time objective, or
    /// when R is not positive definite).
    pub fn finite_time(&self) -> Option<(FtbParams, FtbNumbers)> {
        let Performance::FiniteTime(f) = &self.performance else {
            return None;
        };
        let l = f.r.clone().cholesky()?.l();
        let linv = l.try_inverse()?;
        let (mut lo, mut hi) = (f64::INFINITY, 0.0_f64);
        for p in &self.p {
            let s = &linv * p * linv.transpose();
            let e = ((&s + s.transpose()) * 0.5).symmetric_eigenvalues();
            lo = lo.min(e.min());
            hi = hi.max(e.max());
        }
        // Padded by a bound on the eigenvalues' rounding error, so that the
        // certificate's P_a - lambda1 R >= 0 and lambda2 R - P_a >= 0 hold.
        let pad = 64.0 * (self.p.len().max(1) * f.r.nrows()) as f64 * f64::EPSILON * hi;
        let (lo, hi) = (lo - pad, hi + pad);
        if lo.is_nan() || lo <= 0.0 {
            return None;
        }
        let c2 = (f.alpha * f.horizon).exp() * (hi * f.c1 + self.lambda3 * f.w2) / lo;
        Some((
            f.clone(),
            FtbNumbers {
                lambda1: lo,
                lambda2: hi,
                lambda3: self.lambda3,
                c2,
            },
        ))
    }
}

/// What one SDP gave: the mode design and the values of its variables.
struct Solved {
    modes: ModesDesign,
    values: Vec<(String, DMatrix<f64>)>,
    /// The minimized quantity (gamma^2 or c2), when there is one.
    objective: Option<f64>,
    /// Whether the solver reached only reduced accuracy.
    almost: bool,
}

/// How the spec's objectives set alpha: fixed, or maximized.
fn decay_target(objectives: &[tsf_lang::spec::SpannedObjective]) -> Target {
    objectives
        .iter()
        .find_map(|o| match o.node {
            Objective::DecayRate(t) => Some(t),
            _ => None,
        })
        .unwrap_or(Target::Fixed(0.0))
}

/// The performance condition the spec asks for, with alpha of finite time
/// still to be chosen (`alpha` = 0 here) and its fixed alpha, if given.
fn performance(spec: &Spec) -> (Performance, Option<f64>) {
    for o in &spec.objectives {
        match &o.node {
            Objective::Hinf { from, to, target } => {
                let gamma = match target {
                    Target::Fixed(g) => Some(*g),
                    Target::Optimize => None,
                };
                return (
                    Performance::Hinf {
                        from: *from,
                        to: *to,
                        gamma,
                    },
                    None,
                );
            }
            Objective::FiniteTime(f) => {
                return (
                    Performance::FiniteTime(FtbParams {
                        alpha: 0.0,
                        c1: f.c1,
                        horizon: f.horizon,
                        r: f.r.clone(),
                        w2: spec.disturbance_energy.unwrap_or(0.0),
                        c2: match f.target {
                            Target::Fixed(c2) => Some(c2),
                            Target::Optimize => None,
                        },
                    }),
                    f.alpha,
                )
            }
            _ => {}
        }
    }
    (Performance::None, None)
}

/// `perf` at finite-time growth rate `alpha` (others unchanged).
fn at_alpha(perf: &Performance, alpha: f64) -> Performance {
    match perf {
        Performance::FiniteTime(f) => Performance::FiniteTime(FtbParams { alpha, ..f.clone() }),
        p => p.clone(),
    }
}

/// Synthesizes the gains of every mode (the spec has `modes`).
pub(super) fn synthesize(runner: &mut Runner<'_>, modes: &Modes) -> Result<Design, SynthError> {
    let model = runner.model;
    let Some(Conditions { list: conds, slack }) =
        relaxations::conditions(model, model.spec.relaxation.node)
    else {
        return Err(SynthError::Unsupported(
            "this relaxation is not supported with `modes`".into(),
        ));
    };
    let settings = runner.settings;
    let (perf, ftb_alpha) = performance(&model.spec);
    // Fault-blind gains of a sampled loop: co-designed with it at h_max
    // (a cell: the refusal's advice re-solves at shorter intervals).
    let codesign = sampled::wanted(&model.spec).filter(|_| modes.design == ModeDesign::Independent);
    let codesign_h = Cell::new(codesign.map(|s| s.1));
    // The descriptor ratio of the last solved co-design (for the note).
    let codesign_delta = Cell::new(None);
    let mut attempt = |alpha: f64, perf: &Performance| -> Result<Option<Solved>, SynthError> {
        let t0 = Instant::now();
        let shift = diagonal_shift(alpha, perf);
        // Fault-blind gains of a sampled loop are co-designed with it (one
        // SDP per descriptor ratio delta until one is solved); other designs
        // solve the continuous conditions once.
        let deltas: Vec<Option<f64>> = match codesign_h.get() {
            Some(_) => sampled::CODESIGN_DELTAS.iter().copied().map(Some).collect(),
            None => vec![None],
        };
        let mut t0 = t0;
        let mut tried = None;
        for delta in deltas {
            let mut built = problem::build(model, modes, &conds, slack, shift, perf, settings.eps)?;
            if let (Some(h), Some(delta), Some(v)) = (codesign_h.get(), delta, built.modes.first())
            {
                let (x, m) = (v.x, v.m.clone());
                sampled::add_codesign(
                    &mut built.problem,
                    model,
                    modes,
                    x,
                    &m,
                    h,
                    delta,
                    settings.eps,
                )
                .map_err(|e| SynthError::Internal(format!("internal error: {e}")))?;
            }
            runner.log.build_time += t0.elapsed();
            let sol = runner.solve(&built.problem, "mode gain problem")?;
            let done = matches!(sol.status, SolveStatus::Solved | SolveStatus::AlmostSolved);
            if done {
                codesign_delta.set(delta);
            }
            tried = Some((built, sol));
            if done {
                break;
            }
            t0 = Instant::now();
        }
        let Some((built, sol)) = tried else {
            return Ok(None);
        };
        match sol.status {
            // A reduced-accuracy iterate is kept: the certificate re-checks
            // every condition and decides.
            SolveStatus::Solved | SolveStatus::AlmostSolved => {}
            s if s.is_primal_infeasible() => return Ok(None),
            // The co-design at a long interval may end in a numerical
            // failure rather than an infeasibility certificate: not found.
            _ if codesign.is_some() => return Ok(None),
            s => {
                return Err(SynthError::Solver {
                    status: s,
                    message: format!(
                        "the solver stopped ({s}) on the mode conditions ({})",
                        at_what(alpha, perf)
                    ),
                    achievable: Vec::new(),
                })
            }
        }
        runner.log.status = Some(sol.status);
        runner.log.iterations = sol.iterations;
        runner.log.stats = Some(built.problem.stats());
        mode_solution(modes, &built, &sol, alpha, perf).map(Some)
    };
    let searched = search(
        &mut attempt,
        &perf,
        ftb_alpha,
        settings.bisection_rel_tol,
        &model.spec.objectives,
    );
    let (solved, bracket) = match (searched, codesign) {
        (Ok(s), _) => s,
        (Err(SynthError::Infeasible { message, .. }), Some(sampling)) => {
            // Advice: halve h_max until the co-design is solved, then check
            // that the analysis certifies the gains it found.
            let alpha = match decay_target(&model.spec.objectives) {
                Target::Fixed(a) => a,
                Target::Optimize => 0.0,
            };
            let fixed = at_alpha(&perf, ftb_alpha.unwrap_or(0.0));
            let mut found = None;
            for k in 1..=sampled::CODESIGN_HALVINGS {
                let h = sampling.1 / f64::from(1u32 << k);
                codesign_h.set(Some(h));
                if let Ok(Some(s)) = attempt(alpha, &fixed) {
                    found = Some((h, s));
                    break;
                }
            }
            return Err(sampled::codesign_refusal(
                runner, modes, sampling, &message, found,
            ));
        }
        (Err(e), _) => return Err(e),
    };
    let (plan, _) = initial_plan(&model.spec, settings.default_phi);
    let achieved = achieved_of(&solved.modes, bracket);
    let mut notes = vec![conditions_note(modes, &solved.modes.performance)];
    if let (Some((_, h)), Some(delta)) = (codesign, codesign_delta.get()) {
        notes.push(format!(
            "fault-blind gains co-designed with the sampled loop at h_max = {h} s: the continuous conditions and the sampled-loop conditions in descriptor form (one X = P2^-1 for every mode, descriptor ratio delta = {delta}) in one SDP; the sampled loop then re-certified by the analysis below"
        ));
    }
    if solved.almost {
        notes.push("the solver reached only reduced accuracy on the chosen SDP; the certificate re-checks every condition".into());
    }
    notes.extend(finite_time_note(&solved.modes, ftb_alpha, &perf));
    Ok(design_of(plan, solved, achieved, notes, settings.eps))
}

/// The design of the solved modes: mode 0's gains and P stand for the
/// design's (every mode's are in `modes`).
fn design_of(
    plan: Plan,
    solved: Solved,
    achieved: Achieved,
    notes: Vec<String>,
    eps: f64,
) -> Design {
    Design {
        plan,
        gains: solved.modes.gains[0].clone(),
        x: solved.modes.p[0].clone().try_inverse().unwrap_or_default(),
        p: solved.modes.p[0].clone(),
        values: solved.values,
        achieved,
        eps,
        reductions: Vec::new(),
        notes,
        log: SolverLog::default(),
        certify_time: Duration::ZERO,
        approximate: false,
        loop_design: Default::default(),
        verdicts: Vec::new(),
        fuzzy: None,
        output: None,
        modes: Some(solved.modes),
    }
}

/// The values of a solved mode problem `built` (at decay rate `alpha`, for
/// `perf`): each mode's P_a, gains and slack, and the achieved performance.
fn mode_solution(
    modes: &Modes,
    built: &problem::XProblem,
    sol: &Solution,
    alpha: f64,
    perf: &Performance,
) -> Result<Solved, SynthError> {
    let iterate = sol.assignment_any_status();
    let value = |v| {
        iterate
            .value(v)
            .cloned()
            .map_err(|e| SynthError::Internal(format!("{e}")))
    };
    let values = built
        .problem
        .vars()
        .map(|(name, v)| value(v).map(|m| (name.to_string(), m)))
        .collect::<Result<Vec<_>, _>>()?;
    let scalar = |name: &str| values.value(name).map(|m| m[(0, 0)]);
    let (performance, objective) = match perf {
        Performance::None => (Performance::None, None),
        Performance::Hinf { from, to, gamma } => {
            let g = scalar(names::G);
            (
                Performance::Hinf {
                    from: *from,
                    to: *to,
                    gamma: gamma.or(g.map(|g| g.max(0.0).sqrt())),
                },
                g,
            )
        }
        Performance::FiniteTime(f) => {
            let c2 = scalar(names::C2);
            (
                Performance::FiniteTime(FtbParams {
                    c2: f.c2.or(c2),
                    ..f.clone()
                }),
                c2,
            )
        }
    };
    let mut md = ModesDesign {
        design: modes.design,
        alpha: if matches!(perf, Performance::FiniteTime(_)) {
            0.0
        } else {
            alpha
        },
        lambda3: scalar(names::LAMBDA3).unwrap_or(0.0).max(0.0),
        performance,
        p: Vec::new(),
        gains: Vec::new(),
        slack: Vec::new(),
    };
    for v in &built.modes {
        let x = value(v.x)?;
        let Some(chol) = x.clone().cholesky() else {
            return Err(SynthError::Solver {
                status: SolveStatus::NumericalError,
                message: "a solved X_a is not positive definite".into(),
                achievable: Vec::new(),
            });
        };
        let p = chol.inverse();
        let p = (&p + p.transpose()) * 0.5;
        md.gains.push(
            v.m.iter()
                .map(|mv| value(*mv).map(|m| chol.solve(&m.transpose()).transpose()))
                .collect::<Result<_, _>>()?,
        );
        md.slack.push(match v.y {
            Some(y) => {
                let pyp = &p * value(y)? * &p;
                Some((&pyp + pyp.transpose()) * 0.5)
            }
            None => None,
        });
        md.p.push(p);
    }
    Ok(Solved {
        modes: md,
        values,
        objective,
        almost: sol.status == SolveStatus::AlmostSolved,
    })
}

/// What a mode design achieved: its decay rate (and the bracket of the
/// search), H-inf gamma, finite-time c2.
fn achieved_of(modes: &ModesDesign, bracket: Option<(f64, f64)>) -> Achieved {
    let mut achieved = Achieved::default();
    achieved.set(Quantity::DecayRate, modes.alpha);
    achieved.decay_bracket = bracket;
    if let Performance::Hinf { gamma: Some(g), .. } = modes.performance {
        achieved.set(Quantity::HinfGamma, g);
    }
    if let Some((_, numbers)) = modes.finite_time() {
        achieved.set(Quantity::FiniteTimeC2, numbers.c2);
    }
    achieved
}

/// The note naming the mode conditions of `modes` for `performance`.
fn conditions_note(modes: &Modes, performance: &Performance) -> String {
    format!(
        "Markov modes ({}): {} modes, conditions {} < 0 per mode and rule pair{}",
        modes.design.keyword(),
        modes.len(),
        match performance {
            Performance::None => "G_aij = He(P_a (A_i + B_ai F_aj)) + sum_b pi_ab P_b + 2 alpha P_a",
            Performance::Hinf { .. } => "[[G_aij, P_a D_i, (C + E F_aj)'], [*, -gamma^2 I, G'], [*, *, -I]] (G_aij = He(P_a (A_i + B_ai F_aj)) + sum_b pi_ab P_b + 2 alpha P_a)",
            Performance::FiniteTime(_) => "[[G_aij, P_a D_i], [*, -lambda3 I]] (G_aij = He(P_a (A_i + B_ai F_aj)) + sum_b pi_ab P_b - alpha P_a)",
        },
        if modes.design == ModeDesign::Independent {
            "; one P and one gain set for every mode (a common quadratic Lyapunov function: the gains hold under any switching)"
        } else {
            ""
        }
    )
}

/// The finite-time note (alpha, lambdas, c2) of a finite-time design; how
/// alpha was chosen: given (`ftb_alpha`), or searched for `perf`.
fn finite_time_note(
    modes: &ModesDesign,
    ftb_alpha: Option<f64>,
    perf: &Performance,
) -> Option<String> {
    let (f, numbers) = modes.finite_time()?;
    Some(format!(
        "finite time: alpha = {:.6} (alpha T = {:.4}{}), lambda1 = {:.6e}, lambda2 = {:.6e}, lambda3 = {:.6e}: E x(t)' R x(t) < c2 = {:.6} on [0, {}]",
        f.alpha,
        f.alpha * f.horizon,
        match (ftb_alpha, perf) {
            (Some(_), _) => ", given",
            (None, Performance::FiniteTime(FtbParams { c2: Some(_), .. })) => {
                ", the first grid point that meets the bound"
            }
            _ => ", grid and golden section",
        },
        numbers.lambda1,
        numbers.lambda2,
        numbers.lambda3,
        numbers.c2,
        f.horizon
    ))
}

/// The search the spec's objectives ask for (fixed or maximized decay rate,
/// least gamma, least c2): the chosen solve and the decay bracket, if any.
fn search<F>(
    attempt: &mut F,
    perf: &Performance,
    ftb_alpha: Option<f64>,
    tol: f64,
    objectives: &[tsf_lang::spec::SpannedObjective],
) -> Result<(Solved, Option<(f64, f64)>), SynthError>
where
    F: FnMut(f64, &Performance) -> Result<Option<Solved>, SynthError>,
{
    let infeasible = |what: String| SynthError::Infeasible {
        message: format!("the mode conditions are infeasible {what}"),
        achievable: Vec::new(),
    };
    let searched = if let Performance::FiniteTime(f) = &perf {
        let alphas: Vec<f64> = match ftb_alpha {
            Some(a) => vec![a],
            None => FTB_ALPHA_T.iter().map(|k| k / f.horizon).collect(),
        };
        let s = finite_time_search(attempt, perf, &alphas, ftb_alpha.is_none())?
            .ok_or_else(|| {
                infeasible(match (ftb_alpha, f.c2) {
                    (Some(a), Some(c2)) => format!("(finite time: c2 = {c2} at alpha = {a})"),
                    (Some(a), None) => format!("(finite time at alpha = {a})"),
                    (None, Some(c2)) => format!(
                        "(finite time: c2 = {c2} at every alpha of the grid alpha T in {FTB_ALPHA_T:?})"
                    ),
                    (None, None) => format!(
                        "(finite time at every alpha of the grid alpha T in {FTB_ALPHA_T:?})"
                    ),
                })
            })?;
        (s, None)
    } else {
        match decay_target(objectives) {
            Target::Fixed(alpha) if matches!(perf, Performance::Hinf { gamma: None, .. }) => {
                let s = hinf_minimum(attempt, perf, alpha, tol)?.ok_or_else(|| {
                    infeasible(format!(
                        "(no gains found{}{})",
                        if alpha > 0.0 {
                            format!(" at decay rate {alpha}")
                        } else {
                            String::new()
                        },
                        perf_note(perf)
                    ))
                })?;
                (s, None)
            }
            Target::Fixed(alpha) => {
                let s = attempt(alpha, perf)?.ok_or_else(|| {
                    infeasible(if alpha > 0.0 {
                        format!("at decay rate {alpha}{}", perf_note(perf))
                    } else {
                        format!(
                            "(no mean-square stabilizing gains found{})",
                            perf_note(perf)
                        )
                    })
                })?;
                (s, None)
            }
            Target::Optimize => {
                let mut best = attempt(0.0, perf)?.ok_or_else(|| {
                    infeasible(format!(
                        "(no mean-square stabilizing gains found{})",
                        perf_note(perf)
                    ))
                })?;
                let (mut lo, mut hi) = (0.0, 0.5);
                // Grow the bracket until infeasible (or the solver stalls).
                while let Ok(Some(s)) = attempt(hi, perf) {
                    best = s;
                    lo = hi;
                    hi *= 2.0;
                    if hi > 1e6 {
                        hi = f64::INFINITY;
                        break;
                    }
                }
                while hi.is_finite() && hi - lo > tol * hi.max(1e-9) {
                    let mid = 0.5 * (lo + hi);
                    match attempt(mid, perf) {
                        Ok(Some(s)) => {
                            best = s;
                            lo = mid;
                        }
                        // Near the supremum the solver may stall: not achieved.
                        _ => hi = mid,
                    }
                }
                (best, Some((lo, hi)))
            }
        }
    };
    Ok(searched)
}

/// The least H-inf bound: the SDP that minimizes gamma^2; when the solver
/// reaches only reduced accuracy or stops there, a bisection on a fixed gamma
/// with feasibility SDPs (relative tolerance `tol`), which are better posed
/// when the infimum is approached only by growing gains.
fn hinf_minimum<F>(
    attempt: &mut F,
    perf: &Performance,
    alpha: f64,
    tol: f64,
) -> Result<Option<Solved>, SynthError>
where
    F: FnMut(f64, &Performance) -> Result<Option<Solved>, SynthError>,
{
    let first = attempt(alpha, perf);
    let guess = match &first {
        Ok(Some(s)) if !s.almost => return first,
        Ok(None) => return Ok(None),
        Ok(Some(s)) => match s.modes.performance {
            Performance::Hinf { gamma: Some(g), .. } if g.is_finite() && g > 0.0 => g,
            _ => 1.0,
        },
        Err(_) => 1.0,
    };
    let Performance::Hinf { from, to, .. } = *perf else {
        return first;
    };
    let mut at = |g: f64| {
        attempt(
            alpha,
            &Performance::Hinf {
                from,
                to,
                gamma: Some(g),
            },
        )
        .ok()
        .flatten()
        .filter(|s| !s.almost)
    };
    // Bracket: grow from the guess until a clean solve, then bisect.
    let (mut lo, mut hi) = (0.0, guess);
    let mut best = None;
    for _ in 0..40 {
        if let Some(s) = at(hi) {
            best = Some(s);
            break;
        }
        lo = hi;
        hi *= 2.0;
    }
    let Some(mut best) = best else {
        return first.map(|_| None);
    };
    while hi - lo > tol * hi {
        let mid = 0.5 * (lo + hi);
        match at(mid) {
            Some(s) => {
                best = s;
                hi = mid;
            }
            None => lo = mid,
        }
    }
    Ok(Some(best))
}

/// " with the hinf bound" etc., for the infeasibility message.
fn perf_note(perf: &Performance) -> String {
    match perf {
        Performance::Hinf { gamma: Some(g), .. } => format!(", with H-inf gamma <= {g}"),
        Performance::Hinf { gamma: None, .. } => ", with an H-inf bound".into(),
        _ => String::new(),
    }
}

/// Where an attempt was made, for messages.
fn at_what(alpha: f64, perf: &Performance) -> String {
    match perf {
        Performance::FiniteTime(f) => format!("finite time at alpha = {}", f.alpha),
        _ => format!("decay rate {alpha}{}", perf_note(perf)),
    }
}

/// The finite-time design over `alphas`: with c2 minimized, the least c2 over
/// the grid, refined by golden section between the best point's neighbours
/// when `refine`; with c2 fixed, the first feasible alpha.
fn finite_time_search<F>(
    attempt: &mut F,
    perf: &Performance,
    alphas: &[f64],
    refine: bool,
) -> Result<Option<Solved>, SynthError>
where
    F: FnMut(f64, &Performance) -> Result<Option<Solved>, SynthError>,
{
    let minimize = matches!(perf, Performance::FiniteTime(f) if f.c2.is_none());
    let mut try_at = |a: f64| -> Result<Option<(f64, Solved)>, SynthError> {
        Ok(attempt(0.0, &at_alpha(perf, a))?.map(|s| {
            let c2 = s.objective.unwrap_or(f64::INFINITY);
            (c2, s)
        }))
    };
    let mut best: Option<(usize, f64, Solved)> = None;
    for (k, &a) in alphas.iter().enumerate() {
        // A stalled solve at one alpha is not fatal on a grid.
        let got = match try_at(a) {
            Ok(g) => g,
            Err(e) if alphas.len() == 1 => return Err(e),
            Err(_) => None,
        };
        if let Some((c2, s)) = got {
            if !minimize {
                return Ok(Some(s));
            }
            if best.as_ref().is_none_or(|b| c2 < b.1) {
                best = Some((k, c2, s));
            }
        }
    }
    let Some((k, c2, s)) = best else {
        return Ok(None);
    };
    if !refine || alphas.len() < 2 {
        return Ok(Some(s));
    }
    // Golden section on [alpha_{k-1}, alpha_{k+1}] (c2 is taken as unimodal
    // there; a point that does not improve is simply not kept).
    let (mut lo, mut hi) = (
        alphas[k.saturating_sub(1)],
        alphas[(k + 1).min(alphas.len() - 1)],
    );
    let mut best = (c2, s);
    let ratio = (5f64.sqrt() - 1.0) / 2.0;
    let mut eval = |a: f64, best: &mut (f64, Solved)| -> f64 {
        match try_at(a) {
            Ok(Some((c2, s))) => {
                if c2 < best.0 {
                    *best = (c2, s);
                }
                c2
            }
            _ => f64::INFINITY,
        }
    };
    let mut x1 = hi - ratio * (hi - lo);
    let mut x2 = lo + ratio * (hi - lo);
    let mut f1 = eval(x1, &mut best);
    let mut f2 = eval(x2, &mut best);
    for _ in 0..FTB_GOLDEN_STEPS {
        if f1 <= f2 {
            hi = x2;
            x2 = x1;
            f2 = f1;
            x1 = hi - ratio * (hi - lo);
            f1 = eval(x1, &mut best);
        } else {
            lo = x1;
            x1 = x2;
            f1 = f2;
            x2 = lo + ratio * (hi - lo);
            f2 = eval(x2, &mut best);
        }
    }
    Ok(Some(best.1))
}
