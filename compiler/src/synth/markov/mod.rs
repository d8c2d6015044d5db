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
//! relaxed over rule pairs as [`pairs`] lists. Change of variables: X_a =
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
//! The certificate (`certify/markov.rs`) re-checks (P) itself, with P_a =
//! X_a^{-1} and the design's F_aj, never (X).

pub mod pairs;
pub mod problem;
pub mod report;

use super::achieved::{Achieved, Quantity};
use super::design::{Design, SolverLog, SynthError};
use super::plan::initial_plan;
use super::search::Runner;
use nalgebra::DMatrix;
use std::time::{Duration, Instant};
use tsf_lang::modes::{ModeDesign, Modes};
use tsf_lang::spec::{Objective, Target};
use tsf_lmi::SolveStatus;

/// The solved mode design: what the certificate re-checks and the report shows.
#[derive(Debug, Clone)]
pub struct ModesDesign {
    /// Mode-dependent or mode-independent gains.
    pub design: ModeDesign,
    /// The decay rate imposed (0: stability).
    pub alpha: f64,
    /// P_a = X_a^{-1}, per mode.
    pub p: Vec<DMatrix<f64>>,
    /// F_aj, per mode then rule (the same gains in every mode when mode-independent).
    pub gains: Vec<Vec<DMatrix<f64>>>,
    /// The relaxation's slack in P variables, P_a Y_a P_a, per mode (tanaka).
    pub slack: Vec<Option<DMatrix<f64>>>,
}

/// What one SDP gave: the mode design and the values of its variables.
struct Solved {
    modes: ModesDesign,
    values: Vec<(String, DMatrix<f64>)>,
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

/// Synthesizes the gains of every mode (the spec has `modes`).
pub(super) fn synthesize(runner: &mut Runner<'_>, modes: &Modes) -> Result<Design, SynthError> {
    let model = runner.model;
    let Some((conds, slack)) = pairs::conditions(model, model.spec.relaxation.node) else {
        return Err(SynthError::Unsupported(
            "this relaxation is not supported with `modes`".into(),
        ));
    };
    let settings = runner.settings;
    let mut attempt = |alpha: f64| -> Result<Option<Solved>, SynthError> {
        let t0 = Instant::now();
        let built = problem::build(model, modes, &conds, slack, alpha, settings.eps)?;
        runner.log.build_time += t0.elapsed();
        let sol = runner.solve(&built.problem, "mode gain problem")?;
        match sol.status {
            SolveStatus::Solved => {}
            s if s.is_primal_infeasible() => return Ok(None),
            s => {
                return Err(SynthError::Solver {
                    status: s,
                    message: format!(
                        "the solver stopped ({s}) on the mode conditions at decay rate {alpha}"
                    ),
                    achievable: Vec::new(),
                })
            }
        }
        runner.log.status = Some(sol.status);
        runner.log.iterations = sol.iterations;
        runner.log.stats = Some(built.problem.stats());
        let iterate = sol.assignment_any_status();
        let value = |v| {
            iterate
                .value(v)
                .cloned()
                .map_err(|e| SynthError::Internal(format!("{e}")))
        };
        let mut md = ModesDesign {
            design: modes.design,
            alpha,
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
        let values = built
            .problem
            .vars()
            .map(|(name, v)| value(v).map(|m| (name.to_string(), m)))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Some(Solved { modes: md, values }))
    };
    let infeasible = |what: String| SynthError::Infeasible {
        message: format!("the mode conditions are infeasible {what}"),
        achievable: Vec::new(),
    };
    let (solved, bracket) = match decay_target(&model.spec.objectives) {
        Target::Fixed(alpha) => {
            let s = attempt(alpha)?.ok_or_else(|| {
                infeasible(if alpha > 0.0 {
                    format!("at decay rate {alpha}")
                } else {
                    "(no mean-square stabilizing gains found)".into()
                })
            })?;
            (s, None)
        }
        Target::Optimize => {
            let mut best = attempt(0.0)?
                .ok_or_else(|| infeasible("(no mean-square stabilizing gains found)".into()))?;
            let (mut lo, mut hi) = (0.0, 0.5);
            // Grow the bracket until infeasible (or the solver stalls).
            while let Ok(Some(s)) = attempt(hi) {
                best = s;
                lo = hi;
                hi *= 2.0;
                if hi > 1e6 {
                    hi = f64::INFINITY;
                    break;
                }
            }
            while hi.is_finite() && hi - lo > settings.bisection_rel_tol * hi.max(1e-9) {
                let mid = 0.5 * (lo + hi);
                match attempt(mid) {
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
    };
    let (plan, _) = initial_plan(&model.spec, settings.default_phi);
    let mut achieved = Achieved::default();
    achieved.set(Quantity::DecayRate, solved.modes.alpha);
    achieved.decay_bracket = bracket;
    let notes = vec![format!(
        "Markov modes ({}): {} modes, conditions He(P_a (A_i + B_ai F_aj)) + sum_b pi_ab P_b + 2 alpha P_a < 0 per mode and rule pair{}",
        modes.design.keyword(),
        modes.len(),
        if modes.design == ModeDesign::Independent {
            "; one P and one gain set for every mode (a common quadratic Lyapunov function: the gains hold under any switching)"
        } else {
            ""
        }
    )];
    Ok(Design {
        plan,
        gains: solved.modes.gains[0].clone(),
        x: solved.modes.p[0].clone().try_inverse().unwrap_or_default(),
        p: solved.modes.p[0].clone(),
        values: solved.values,
        achieved,
        eps: settings.eps,
        reductions: Vec::new(),
        notes,
        log: SolverLog::default(),
        certify_time: Duration::ZERO,
        approximate: false,
        trigger: None,
        sampled: None,
        signal_trigger: None,
        verdicts: Vec::new(),
        modes: Some(solved.modes),
    })
}
