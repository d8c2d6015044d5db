//! Co-design of the PDC gains and the event-trigger weight
//! (`weight = synthesize codesign(rounds = N);`, docs/event_trigger.md).
//!
//! The sampled-loop conditions of [`super::trigger`] are bilinear in the
//! gains (F_j, G_j) and the functional's matrices (P, Y, T), and linear in
//! each when the other is known. Starting from the two-step design, rounds
//! alternate
//!
//! - a gain step: P, Y, T (and, while the threshold is still below the
//!   spec's, Upsilon) known from the last trigger step; F_j, G_j, L1, L2, xi,
//!   gamma and either nu (maximized up to the spec's threshold: continuation)
//!   or Upsilon (xi minimized with gamma at most the last one) unknown;
//! - a trigger step: the existing problem of [`super::trigger::build`] for the
//!   new gains at the threshold the gain step reached, minimizing gamma.
//!
//! Under every plant/controller pair (the held memberships of an event-
//! triggered loop) the gain step's optimum needs only one F and one G (see
//! [`gain_step_problem`]), so the co-designed controller has the same gain in
//! every rule: fuzzy scheduling buys nothing under these conditions.
//!
//! Each step's solution is feasible for the next (with the same threshold),
//! so gamma does not increase once the threshold is reached. Only a trigger
//! step's design is ever kept: it is certified by the unchanged trigger
//! certificate, with the gains as constants.

use super::design::{Design, SynthError, TriggerDesign};
use super::plan::{Goal, Plan};
use super::search::Runner;
use super::solved::{names, Solved};
use super::trigger::{self, certified_threshold, Factor, LoopVars, TriggerPlan};
use crate::model::TsModel;
use nalgebra::DMatrix;
use std::borrow::Cow;
use std::time::Instant;
use tsf_lmi::{Expr, LmiError, Problem, Relation, SolveStatus, Var};

/// Co-design stops when gamma (at the spec's threshold) changes by less than
/// this fraction in a round, or the threshold grows by less in a round.
pub const CODESIGN_REL_TOL: f64 = 0.02;

/// A threshold reached by a gain step is used this much lower in the trigger
/// step (the gain step's point then has room against solver tolerances).
const NU_BACKOFF: f64 = 1e-3;

/// One round of the co-design, for the report and the tests.
#[derive(Debug, Clone, PartialEq)]
pub struct Round {
    /// 1-based round number (0: the two-step start).
    pub round: u32,
    /// The threshold the round's trigger step certified.
    pub nu: f64,
    /// Its L-inf gamma.
    pub gamma: f64,
    /// Its xi.
    pub xi: f64,
    /// Seconds of the gain step's solve (0 for the start).
    pub gain_step_s: f64,
    /// Seconds of the trigger step's solve.
    pub trigger_step_s: f64,
}

/// What the gain step optimizes.
#[derive(Debug, Clone, Copy)]
pub(super) enum GainGoal {
    /// Upsilon known, nu unknown: maximize nu up to the target.
    RaiseNu { target: f64 },
    /// Upsilon unknown, nu the plan's: minimize xi with gamma <= the bound.
    LowerXi { gamma_cap: f64 },
    /// Upsilon unknown, nu the plan's: minimize the stiffness bound kappa,
    /// ||B_i F||_2 <= kappa for every plant rule, with gamma <= the cap
    /// (`weight = synthesize transmissions;`, [`super::transmissions`]).
    Soften { gamma_cap: f64 },
}

/// The gains of a solved gain step.
pub(super) struct GainStep {
    /// F_j (one gain in every rule).
    pub gains: Vec<DMatrix<f64>>,
    /// G_j.
    pub sector: Vec<DMatrix<f64>>,
    /// The threshold reached (the plan's unless raised).
    pub nu: f64,
    /// xi.
    pub xi: f64,
}

/// A built gain step: the problem and the unknowns read back.
struct GainStepProblem {
    problem: Problem,
    /// The one F of every controller rule.
    f: Var,
    /// The one G of every controller rule.
    g: Var,
    /// The threshold, when unknown.
    nu: Option<Var>,
    /// xi.
    xi: Var,
}

/// Builds the gain step for the plan's data with P, Y, T and (for
/// [`GainGoal::RaiseNu`]) Upsilon known from `last`.
fn gain_step_problem(
    model: &TsModel,
    plan: &TriggerPlan,
    last: &TriggerDesign,
    goal: GainGoal,
    eps: f64,
) -> Result<GainStepProblem, SynthError> {
    let internal = |e: LmiError| SynthError::Internal(format!("co-design gain step: {e}"));
    let (n, m, r) = (model.n, model.m, model.r());
    let p = last.values.required(names::LOOP_P)?;
    let y = last.values.required(names::LOOP_Y)?;
    let t = (!plan.levels.is_empty())
        .then(|| last.values.required(names::LOOP_SECTOR))
        .transpose()?;
    let w_known = last.values.required(names::TRIGGER_WEIGHT)?;
    let mut problem = Problem::new();
    // One F and one G for every controller rule, without loss: every pair
    // (i, j) is imposed, so the conditions on (F_j, G_j) are the same for
    // each j and the shared unknowns (L, Upsilon, xi, nu) enter them alike;
    // they are convex, so the average of feasible (F_j, G_j) is feasible for
    // every j. The solved problem keeps one controller rule.
    let f1 = problem.full("Fcd", m, n).map_err(internal)?;
    let g1 = problem.full("Gcd", m, n).map_err(internal)?;

    let l = [
        problem.full(names::LOOP_L1, n, n).map_err(internal)?,
        problem.full(names::LOOP_L2, n, n).map_err(internal)?,
    ];
    let (w, nu) = match goal {
        GainGoal::RaiseNu { .. } => (
            Factor::Val(&w_known),
            Some(problem.scalar("nu_cd").map_err(internal)?),
        ),
        GainGoal::LowerXi { .. } | GainGoal::Soften { .. } => (
            Factor::Var(
                problem
                    .symmetric(names::TRIGGER_WEIGHT, n)
                    .map_err(internal)?,
            ),
            None,
        ),
    };
    let vars = LoopVars {
        p: Factor::Val(&p),
        y: Factor::Val(&y),
        l,
        w: plan.event.then_some(w),
        nu,
        t: t.as_ref().map(Factor::Val),
        xi: None,
        gains: vec![Factor::Var(f1); r],
        sector: vec![Factor::Var(g1); r],
        robust: Default::default(),
    };
    let built = trigger::impose(problem, model, plan, vars, eps, true).map_err(internal)?;
    let mut problem = built.problem;
    let (Some(gamma), Some(xi)) = (built.vars.gamma, built.vars.xi) else {
        return Err(SynthError::Internal(
            "co-design needs the L-inf channel".into(),
        ));
    };
    match goal {
        GainGoal::RaiseNu { target } => {
            let Some(nu) = nu else {
                return Err(SynthError::Internal(
                    "co-design: the nu unknown of a RaiseNu step is missing".into(),
                ));
            };
            problem
                .add_scalar("co-design nu >= 0", Expr::var(nu), Relation::Ge, 0.0)
                .and_then(|_| {
                    problem.add_scalar(
                        "co-design nu <= target",
                        Expr::var(nu),
                        Relation::Le,
                        target,
                    )
                })
                .and_then(|_| problem.maximize(Expr::var(nu)))
                .map_err(internal)?;
        }
        GainGoal::LowerXi { gamma_cap } => {
            problem
                .add_scalar(
                    "co-design gamma <= last",
                    Expr::var(gamma),
                    Relation::Le,
                    gamma_cap,
                )
                .and_then(|_| problem.minimize(Expr::var(xi)))
                .map_err(internal)?;
        }
        GainGoal::Soften { gamma_cap } => {
            problem
                .add_scalar(
                    "co-design gamma <= bound",
                    Expr::var(gamma),
                    Relation::Le,
                    gamma_cap,
                )
                .map_err(internal)?;
            let kappa = stiffness_bound(&mut problem, model, f1).map_err(internal)?;
            problem.minimize(Expr::var(kappa)).map_err(internal)?;
        }
    }
    Ok(GainStepProblem {
        problem,
        f: f1,
        g: g1,
        nu,
        xi,
    })
}

/// `model` with `gains` as the rules' given gains.
fn with_gains(model: &TsModel, gains: &[DMatrix<f64>]) -> TsModel {
    let mut given = model.clone();
    for (rule, f) in given.spec.rules.iter_mut().zip(gains) {
        rule.gain = Some((f.clone(), Default::default()));
    }
    given
}

/// The model the continuous loop of `design` is certified on: the spec's,
/// or, for a few-transmissions design with a premise region (one common gain,
/// re-analyzed on the box), the spec's with that gain given in every rule.
pub fn analysis_model<'a>(model: &'a TsModel, design: &Design) -> Cow<'a, TsModel> {
    match design.loop_design.event() {
        Some(t) if t.method == "transmissions" && t.plan.region.is_some() => {
            Cow::Owned(super::region_auto::scaled(
                &with_gains(model, &design.gains),
                t.region_scale.unwrap_or(1.0),
            ))
        }
        _ => Cow::Borrowed(model),
    }
}

/// The stiffness of a common gain F: max over the plant rules of
/// ||B_i F||_2, the closed-loop effect of a state error on x' (Tabuada's
/// inter-event bound grows with ||B K||). Distinct B_i only.
pub fn stiffness(model: &TsModel, f: &DMatrix<f64>) -> f64 {
    model
        .rules
        .iter()
        .map(|rule| (&rule.b * f).singular_values().max())
        .fold(0.0, f64::max)
}

/// Declares kappa with [kappa I, B_i F; *, kappa I] >= 0 (||B_i F||_2 <= kappa)
/// for every distinct B_i of the model.
fn stiffness_bound(problem: &mut Problem, model: &TsModel, f: Var) -> Result<Var, LmiError> {
    let kappa = problem.scalar("stiffness kappa")?;
    let n = model.n;
    let mut seen: Vec<&DMatrix<f64>> = Vec::new();
    for rule in &model.rules {
        if seen.contains(&&rule.b) {
            continue;
        }
        seen.push(&rule.b);
        let eye = DMatrix::identity(n, n);
        let bf = Expr::product(&rule.b, f, &eye)?;
        let block = Expr::sym_blocks(vec![
            vec![Some(Expr::scaled(kappa, &eye)?), Some(bf)],
            vec![None, Some(Expr::scaled(kappa, &eye)?)],
        ])?;
        problem.psd(&format!("stiffness of rule {}", rule.name), block, 0.0)?;
    }
    Ok(kappa)
}

impl Runner<'_> {
    /// Solves one gain step; `None` when the solver gives no solution.
    pub(super) fn gain_step(
        &mut self,
        plan: &TriggerPlan,
        last: &TriggerDesign,
        goal: GainGoal,
    ) -> Result<Option<GainStep>, SynthError> {
        let t0 = Instant::now();
        let built = gain_step_problem(self.model, plan, last, goal, self.settings.eps)?;
        self.log.build_time += t0.elapsed();
        let sol = self.solve(&built.problem, "co-design gain step")?;
        // A gain step only proposes gains: the trigger step that follows
        // re-solves with them fixed, and only its design is certified. So an
        // iterate of reduced accuracy is good enough here.
        if !matches!(sol.status, SolveStatus::Solved | SolveStatus::AlmostSolved) {
            return Ok(None);
        }
        let internal = |e: LmiError| SynthError::Internal(format!("co-design gain step: {e}"));
        let a = sol.assignment_any_status();
        let read = |v: Var| a.value(v).cloned().map_err(internal);
        let r = self.model.r();
        Ok(Some(GainStep {
            gains: vec![read(built.f)?; r],
            sector: vec![read(built.g)?; r],
            nu: match built.nu {
                Some(v) => read(v)?[(0, 0)],
                None => plan.nu,
            },
            xi: read(built.xi)?[(0, 0)],
        }))
    }

    /// Co-designs gains and trigger weight from the two-step design of
    /// `design`'s gains: the certified trigger design at the spec's threshold
    /// (its plan carries the co-designed gains), the rounds, and notes. When
    /// the threshold is not reached, the error names the best certified
    /// (nu, gamma) and the step that stopped.
    pub(super) fn codesign(
        &mut self,
        design: &Design,
        rounds: u32,
    ) -> Result<(TriggerDesign, Vec<String>), SynthError> {
        let base = trigger::plan_for(self.model, design)?;
        let target = certified_threshold(self.model);
        let with = |nu: f64| TriggerPlan { nu, ..base.clone() };
        let mut notes = Vec::new();
        // Start: the two-step design at the target, else at nu = 0.
        let t0 = Instant::now();
        let mut last = match self.trigger_attempt(&with(target))? {
            Some(d) => d,
            None => match self.trigger_attempt(&with(0.0))? {
                Some(d) => d,
                None => {
                    return Err(SynthError::Infeasible {
                        message: format!(
                            "event-trigger co-design: the gains of the continuous design are not certified for aperiodic sampling in [{}, {}] s even with nu = 0, so the co-design has no start",
                            base.sampling.0, base.sampling.1
                        ),
                        achievable: vec!["shorten h_max or weaken the objectives that set the gains".into()],
                    })
                }
            },
        };
        let mut history = vec![Round {
            round: 0,
            nu: last.plan.nu,
            gamma: last.gamma,
            xi: last.xi,
            gain_step_s: 0.0,
            trigger_step_s: t0.elapsed().as_secs_f64(),
        }];
        let mut stopped = None;
        for round in 1..=rounds {
            let at_target = last.plan.nu >= target;
            let goal = if at_target {
                GainGoal::LowerXi {
                    gamma_cap: last.gamma,
                }
            } else {
                GainGoal::RaiseNu { target }
            };
            let t1 = Instant::now();
            let Some(step) = self.gain_step(&last.plan, &last, goal)? else {
                stopped = Some(format!(
                    "round {round}: the gain step ({}) gave no solution (solver status {})",
                    if at_target { "lower xi" } else { "raise nu" },
                    self.log.last_status.map_or("-".into(), |s| s.to_string())
                ));
                break;
            };
            let gain_s = t1.elapsed().as_secs_f64();
            let nu = if at_target || step.nu >= target * (1.0 - NU_BACKOFF) {
                target
            } else {
                step.nu * (1.0 - NU_BACKOFF)
            };
            let plan = TriggerPlan {
                nu,
                gains: step.gains,
                sector: step.sector,
                ..last.plan.clone()
            };
            let t2 = Instant::now();
            let Some(next) = self.trigger_attempt(&plan)? else {
                stopped = Some(format!(
                    "round {round}: the trigger step at nu = {nu:.4} for the new gains gave no solution (solver status {}; the gain step reached nu = {:.4}, xi = {:.4})",
                    self.log.last_status.map_or("-".into(), |s| s.to_string()),
                    step.nu,
                    step.xi
                ));
                break;
            };
            let trigger_s = t2.elapsed().as_secs_f64();
            history.push(Round {
                round,
                nu: next.plan.nu,
                gamma: next.gamma,
                xi: next.xi,
                gain_step_s: gain_s,
                trigger_step_s: trigger_s,
            });
            let (before, after) = (&last, &next);
            let converged = if at_target {
                (before.gamma - after.gamma).abs() <= CODESIGN_REL_TOL * before.gamma
            } else {
                after.plan.nu < target
                    && after.plan.nu - before.plan.nu <= CODESIGN_REL_TOL * before.plan.nu.max(1e-3)
            };
            // A trigger step never loses gamma at the same threshold (the gain
            // step's point is feasible): keep the better design if the solver
            // says otherwise.
            if !(at_target && after.gamma > before.gamma) {
                last = next;
            }
            if converged {
                stopped = Some(format!(
                    "round {round}: {} changed by less than {}%",
                    if at_target { "gamma" } else { "nu" },
                    CODESIGN_REL_TOL * 100.0
                ));
                break;
            }
        }
        let table = history
            .iter()
            .map(|h| {
                format!(
                    "{}: nu {:.4}, gamma {:.4}, xi {:.4} ({:.1} s + {:.1} s)",
                    h.round, h.nu, h.gamma, h.xi, h.gain_step_s, h.trigger_step_s
                )
            })
            .collect::<Vec<_>>()
            .join("; ");
        let why = stopped.unwrap_or_else(|| format!("{rounds} rounds done"));
        if last.plan.nu < target {
            return Err(SynthError::Infeasible {
                message: format!(
                    "event-trigger co-design: threshold nu = {target} not reached; the best certified design has nu = {:.4}, gamma = {:.4} (stopped at {why})",
                    last.plan.nu, last.gamma
                ),
                achievable: vec![
                    if last.plan.nu > 0.0 {
                        let nu = super::advice::round_down(last.plan.nu);
                        format!("write `threshold nu = {nu}` (or `adaptive(.., max = {nu})`), or raise `rounds`")
                    } else {
                        "no positive threshold was certified: shorten h_max, or use `weight = synthesize two_step;`".into()
                    },
                    format!("rounds (round: nu, gamma, xi, gain step + trigger step seconds): {table}"),
                ],
            });
        }
        notes.push(format!(
            "event trigger co-designed with the gains for nu(t_k) <= {target}: L-inf gamma of the event-triggered loop = {:.6} (xi = {:.6}) after {} round(s), stopped at {why}; rounds (round: nu, gamma, xi, gain step + trigger step seconds): {table}",
            last.gamma,
            last.xi,
            history.len() - 1
        ));
        last.method = "codesign";
        last.rounds = history;
        Ok((last, notes))
    }

    /// The continuous-loop analysis of the spec's objectives for the
    /// co-designed `gains` (as if the rules gave them), so that the whole
    /// certificate speaks of the gains that are emitted. The values carry
    /// M_j = F_j X for the synthesis form the certificate rebuilds.
    pub(super) fn reanalyze(
        &mut self,
        plan: &Plan,
        goal: Goal,
        gains: &[DMatrix<f64>],
        region_scale: Option<f64>,
    ) -> Result<Design, SynthError> {
        let mut given = with_gains(self.model, gains);
        let regional = region_scale.is_some();
        if let Some(s) = region_scale {
            given = super::region_auto::scaled(&given, s);
        }
        // The certificate rebuilds the synthesis form on the spec's rules, so
        // the re-analysis of a co-design stays on the whole premise range
        // (only its trigger step is regional). A few-transmissions design
        // keeps the region: its common gain is analyzed on the box, and the
        // certificate does the same ([`analysis_model`]).
        if !regional {
            given.spec.trigger_region.clear();
        }
        let mut sub = Runner {
            model: &given,
            settings: self.settings,
            log: std::mem::take(&mut self.log),
            accept_almost: false,
        };
        let out = sub.run(plan, goal);
        self.log = sub.log;
        let Some(mut d) = out? else {
            return Err(SynthError::Infeasible {
                message: "event-trigger co-design: the co-designed gains are not certified for the continuous loop's objectives".into(),
                achievable: vec!["use `weight = synthesize two_step;`".into()],
            });
        };
        if !regional {
            let x = d.values.required(names::X)?;
            for (j, f) in gains.iter().enumerate() {
                d.values.push((names::gain_product(j), f * &x));
            }
        }
        Ok(d)
    }
}
