//! Synthesis: a [`TsModel`] and its objectives become PDC gains F_j = M_j X^{-1}.
//!
//! One SDP per [`Plan`]; a maximized decay rate is found by bisection over
//! feasibility problems, an L-inf gain without a fixed phi by a line search
//! over phi. Infeasible specs are diagnosed: each fixed bound is optimized with
//! the others kept, to say what is achievable. This stage knows nothing about
//! Clarabel: it talks to `tsf_lmi`.

mod lmis;
pub mod plan;
mod relaxation;
mod sampled;
pub mod theorem2;
pub mod trigger;

pub use lmis::{build, common_b, Built, Vars};
pub use plan::{Bound, Goal, Plan};
pub use sampled::Block12;
pub use trigger::{TriggerBuilt, TriggerPlan};

use crate::model::TsModel;
use nalgebra::DMatrix;
use std::time::{Duration, Instant};
use tsf_lmi::{ProblemStats, SolveSettings, SolveStatus};

/// With `linf <= g`, the largest xi tried is g (1 - XI_CAP_REL).
const XI_CAP_REL: f64 = 1e-6;

/// Synthesis settings.
#[derive(Debug, Clone)]
pub struct Settings {
    /// Margin eps of strict LMIs (`< 0` is enforced as `<= -eps I`).
    pub eps: f64,
    /// Solver settings.
    pub solver: SolveSettings,
    /// Relative width at which the decay-rate bisection stops.
    pub bisection_rel_tol: f64,
    /// phi used first when the spec leaves it free.
    pub default_phi: f64,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            eps: 1e-7,
            solver: SolveSettings {
                // TSFC_SOLVER_VERBOSE=1 prints Clarabel's iteration log (diagnosis of slow solves).
                verbose: std::env::var_os("TSFC_SOLVER_VERBOSE").is_some_and(|v| v == "1"),
                chordal_decomposition: std::env::var_os("TSFC_SOLVER_CHORDAL")
                    .is_none_or(|v| v != "0"),
                ..SolveSettings::default()
            },
            bisection_rel_tol: 1e-3,
            default_phi: 0.1,
        }
    }
}

/// Values achieved by a design.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Achieved {
    /// Certified H-inf bound gamma.
    pub hinf_gamma: Option<f64>,
    /// Certified peak-to-peak bound gamma.
    pub linf_gamma: Option<f64>,
    /// phi used for L-inf.
    pub linf_phi: Option<f64>,
    /// xi used for L-inf.
    pub linf_xi: Option<f64>,
    /// Certified decay rate.
    pub decay_rate: Option<f64>,
    /// Bracket of the maximal decay rate (feasible, infeasible).
    pub decay_bracket: Option<(f64, f64)>,
    /// Certified bound on ||u(t)||.
    pub input_norm_bound: Option<f64>,
    /// Certified bound on ||y(t)||.
    pub output_norm_bound: Option<f64>,
}

/// Solver bookkeeping over all SDPs of a synthesis.
#[derive(Debug, Clone, Default)]
pub struct SolverLog {
    /// Number of SDPs solved.
    pub solves: usize,
    /// Status of the SDP whose solution was kept.
    pub status: Option<SolveStatus>,
    /// Iterations of that SDP.
    pub iterations: u32,
    /// Clarabel time summed over all SDPs.
    pub solve_time: Duration,
    /// Time spent building problems.
    pub build_time: Duration,
    /// Sizes of the kept SDP.
    pub stats: Option<ProblemStats>,
}

/// A synthesized (not yet certified) design.
#[derive(Debug, Clone)]
pub struct Design {
    /// The plan that was solved.
    pub plan: Plan,
    /// PDC gains F_j (m x n), in rule order.
    pub gains: Vec<DMatrix<f64>>,
    /// X = P^{-1}.
    pub x: DMatrix<f64>,
    /// Lyapunov matrix P.
    pub p: DMatrix<f64>,
    /// Values of every variable of the solved problem, by name (for the certificate).
    pub values: Vec<(String, DMatrix<f64>)>,
    /// Achieved objectives.
    pub achieved: Achieved,
    /// Strict-LMI margin used.
    pub eps: f64,
    /// Problem reductions applied.
    pub reductions: Vec<String>,
    /// Notes on searches (bisection, line search).
    pub notes: Vec<String>,
    /// Solver bookkeeping.
    pub log: SolverLog,
    /// Time spent certifying (filled by the caller).
    pub certify_time: Duration,
    /// Whether the solver reached only reduced accuracy (`AlmostSolved`):
    /// such a solution is used only to explain infeasibility, never emitted.
    pub approximate: bool,
    /// The synthesized event trigger (aperiodic trigger with `weight = synthesize`).
    pub trigger: Option<TriggerDesign>,
}

/// A synthesized event trigger for the gains of a [`Design`] (two-step method).
#[derive(Debug, Clone)]
pub struct TriggerDesign {
    /// The problem data (with the certified nu).
    pub plan: TriggerPlan,
    /// Method name for the report.
    pub method: &'static str,
    /// Trigger weight Upsilon (n x n).
    pub weight: DMatrix<f64>,
    /// P of the event-triggered loop's functional: the region is E(P, 1).
    pub p: DMatrix<f64>,
    /// Certified L-inf bound of the event-triggered loop at that nu.
    pub gamma: f64,
    /// xi at that nu.
    pub xi: f64,
    /// Values of every variable of the solved trigger problem.
    pub values: Vec<(String, DMatrix<f64>)>,
    /// Reductions applied to the solved trigger problem.
    pub reductions: Vec<String>,
}

/// Why synthesis produced no design.
#[derive(Debug, Clone)]
pub enum SynthError {
    /// The objectives cannot be met together.
    Infeasible {
        /// What was infeasible.
        message: String,
        /// What is achievable instead, one line each.
        achievable: Vec<String>,
    },
    /// The solver stopped without a verdict.
    Solver {
        /// Its status.
        status: SolveStatus,
        /// Context.
        message: String,
        /// What is achievable when bounds are relaxed one at a time.
        achievable: Vec<String>,
    },
    /// A bug or an unsupported combination.
    Unsupported(String),
}

impl std::fmt::Display for SynthError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SynthError::Infeasible {
                message,
                achievable,
            } => {
                write!(f, "{message}")?;
                for a in achievable {
                    write!(f, "\n  {a}")?;
                }
                Ok(())
            }
            SynthError::Solver {
                status,
                message,
                achievable,
            } => {
                write!(f, "{message} (solver status: {status:?})")?;
                for a in achievable {
                    write!(f, "\n  {a}")?;
                }
                Ok(())
            }
            SynthError::Unsupported(m) => write!(f, "{m}"),
        }
    }
}

/// (largest feasible, smallest infeasible) value found by a bisection.
type Bracket = (f64, f64);

/// Outcome of one SDP.
enum Attempt {
    Solved(Box<Design>),
    Infeasible,
    Trouble(SolveStatus),
}

struct Runner<'a> {
    model: &'a TsModel,
    settings: &'a Settings,
    log: SolverLog,
    /// Accept `AlmostSolved` iterates (only while diagnosing).
    accept_almost: bool,
}

impl Runner<'_> {
    fn attempt(&mut self, plan: &Plan) -> Result<Attempt, SynthError> {
        let relaxation = self.model.spec.relaxation.node;
        let t0 = Instant::now();
        let built = build(self.model, plan, relaxation, self.settings.eps, true)
            .map_err(SynthError::Unsupported)?;
        self.log.build_time += t0.elapsed();
        let sol = built
            .problem
            .solve(&self.settings.solver)
            .map_err(|e| SynthError::Unsupported(format!("solver refused the problem: {e}")))?;
        self.log.solves += 1;
        self.log.solve_time += Duration::from_secs_f64(sol.solve_time.max(0.0));
        let approximate = sol.status == SolveStatus::AlmostSolved && self.accept_almost;
        match sol.status {
            SolveStatus::Solved => {}
            _ if approximate => {}
            s if s.is_primal_infeasible() => return Ok(Attempt::Infeasible),
            s => return Ok(Attempt::Trouble(s)),
        }
        self.log.status = Some(sol.status);
        self.log.iterations = sol.iterations;
        self.log.stats = Some(built.problem.stats());
        let iterate = sol.assignment_any_status();
        let values_of = |v| {
            iterate
                .value(v)
                .cloned()
                .map_err(|e| SynthError::Unsupported(format!("{e}")))
        };
        let x = values_of(built.vars.x)?;
        let Some(chol) = x.clone().cholesky() else {
            return Ok(Attempt::Trouble(SolveStatus::NumericalError));
        };
        let p = chol.inverse();
        let gains = built
            .vars
            .m
            .iter()
            .map(|&mv| values_of(mv).map(|m| chol.solve(&m.transpose()).transpose()))
            .collect::<Result<Vec<_>, _>>()?;
        let values = built
            .problem
            .vars()
            .map(|(name, v)| values_of(v).map(|m| (name.to_string(), m)))
            .collect::<Result<Vec<_>, _>>()?;
        let scalar =
            |v: Option<tsf_lmi::Var>| v.and_then(|v| iterate.value(v).ok().map(|m| m[(0, 0)]));
        let mut achieved = Achieved {
            decay_rate: plan.decay,
            ..Achieved::default()
        };
        if let Some(h) = &plan.hinf {
            achieved.hinf_gamma = Some(match h.bound {
                Bound::Fixed(g) => g,
                _ => scalar(built.vars.hinf_g)
                    .unwrap_or(f64::NAN)
                    .max(0.0)
                    .sqrt(),
            });
        }
        if let Some(l) = &plan.linf {
            achieved.linf_gamma = Some(match l.bound {
                Bound::Fixed(g) => g,
                _ => scalar(built.vars.linf_gamma).unwrap_or(f64::NAN),
            });
            achieved.linf_phi = Some(l.phi);
            achieved.linf_xi = l.xi.or(scalar(built.vars.linf_xi));
        }
        if let Some(u) = &plan.input_norm {
            achieved.input_norm_bound = Some(match u.bound {
                Bound::Fixed(m) => m,
                _ => scalar(built.vars.input_s)
                    .unwrap_or(f64::NAN)
                    .max(0.0)
                    .sqrt(),
            });
        }
        if let Some(o) = &plan.output_norm {
            achieved.output_norm_bound = Some(match o.bound {
                Bound::Fixed(l) => l,
                _ => scalar(built.vars.output_s)
                    .unwrap_or(f64::NAN)
                    .max(0.0)
                    .sqrt(),
            });
        }
        Ok(Attempt::Solved(Box::new(Design {
            plan: plan.clone(),
            gains,
            x,
            p,
            values,
            achieved,
            eps: self.settings.eps,
            reductions: built.reductions,
            notes: Vec::new(),
            log: SolverLog::default(),
            certify_time: Duration::ZERO,
            approximate,
            trigger: None,
        })))
    }

    /// Largest decay rate for which `plan` is feasible: (design, bracket).
    fn max_decay(&mut self, plan: &Plan) -> Result<Option<(Design, Bracket)>, SynthError> {
        let with = |a: f64| Plan {
            decay: Some(a),
            ..plan.clone()
        };
        let mut best = match self.attempt(&with(0.0))? {
            Attempt::Solved(d) => *d,
            Attempt::Infeasible => return Ok(None),
            Attempt::Trouble(s) => {
                return Err(SynthError::Solver {
                    status: s,
                    message: "the solver failed at decay rate 0".into(),
                    achievable: Vec::new(),
                })
            }
        };
        let (mut lo, mut hi) = (0.0, 0.5);
        // Grow the bracket until infeasible.
        while let Attempt::Solved(d) = self.attempt(&with(hi))? {
            best = *d;
            lo = hi;
            hi *= 2.0;
            if hi > 1e6 {
                return Ok(Some((best, (lo, f64::INFINITY))));
            }
        }
        while hi - lo > self.settings.bisection_rel_tol * hi.max(1e-9) {
            let mid = 0.5 * (lo + hi);
            match self.attempt(&with(mid))? {
                Attempt::Solved(d) => {
                    best = *d;
                    lo = mid;
                }
                // Near the supremum the solver may stall instead of proving
                // infeasibility: both count as "not achieved".
                Attempt::Infeasible | Attempt::Trouble(_) => hi = mid,
            }
        }
        Ok(Some((best, (lo, hi))))
    }

    /// Smallest fixed xi for which `plan` is feasible (L-inf with saturation and
    /// a bounded disturbance, where xi enters the linear-region level):
    /// (design, (largest infeasible, smallest feasible)).
    fn min_xi(&mut self, plan: &Plan) -> Result<Option<(Design, Bracket)>, SynthError> {
        let with = |xi: f64| {
            let mut p = plan.clone();
            if let Some(l) = &mut p.linf {
                l.xi = Some(xi);
            }
            p
        };
        // gamma >= xi ((gamma - xi) I > 0): with a fixed bound gamma <= g the
        // search must stay below g, else the growing bracket can jump over the
        // feasible window [xi_min, g).
        let cap = match plan.linf.as_ref().map(|l| &l.bound) {
            Some(Bound::Fixed(g)) => g * (1.0 - XI_CAP_REL),
            _ => 1e8,
        };
        let (mut lo, mut hi) = (0.0, 1e-3f64.min(cap));
        let mut best = None;
        loop {
            if let Attempt::Solved(d) = self.attempt(&with(hi))? {
                best = Some(*d);
                break;
            }
            if hi >= cap {
                break;
            }
            lo = hi;
            hi = (hi * 4.0).min(cap);
        }
        let Some(mut best) = best else {
            return Ok(None);
        };
        while hi - lo > self.settings.bisection_rel_tol * hi {
            let mid = 0.5 * (lo + hi);
            match self.attempt(&with(mid))? {
                Attempt::Solved(d) => {
                    best = *d;
                    hi = mid;
                }
                Attempt::Infeasible | Attempt::Trouble(_) => lo = mid,
            }
        }
        Ok(Some((best, (lo, hi))))
    }

    /// Solves `plan` as the goal says (no diagnosis).
    fn run(&mut self, plan: &Plan, goal: Goal) -> Result<Option<Design>, SynthError> {
        if goal == Goal::MaxDecay {
            return Ok(self.max_decay(plan)?.map(|(mut d, bracket)| {
                d.achieved.decay_bracket = Some(bracket);
                d.notes.push(format!(
                    "decay rate maximized by bisection: feasible at {:.6}, not at {:.6}",
                    bracket.0, bracket.1
                ));
                d
            }));
        }
        let xi_free = plan.linf.as_ref().is_some_and(|l| l.xi.is_none());
        if xi_free
            && plan
                .saturation
                .as_ref()
                .is_some_and(|s| s.disturbance_bound.is_some())
        {
            if self.linf_phi_free() {
                return Err(SynthError::Unsupported("L-inf with saturation and a bounded disturbance needs a fixed phi (`with phi = ...`): the linear-region level depends on xi / phi".into()));
            }
            return Ok(self.min_xi(plan)?.map(|(mut d, (lo, hi))| {
                d.notes.push(format!("xi minimized by bisection (the linear-region level depends on it): feasible at {hi:.6}, not at {lo:.6}"));
                d
            }));
        }
        if plan.linf.is_some() && self.linf_phi_free() {
            return self.linf_line_search(plan);
        }
        match self.attempt(plan)? {
            Attempt::Solved(d) => Ok(Some(*d)),
            Attempt::Infeasible => Ok(None),
            Attempt::Trouble(s) => Err(SynthError::Solver {
                status: s,
                message: "the solver stopped without a verdict".into(),
                achievable: Vec::new(),
            }),
        }
    }

    fn linf_phi_free(&self) -> bool {
        self.model
            .spec
            .objectives
            .iter()
            .any(|o| matches!(o.node, tsf_lang::spec::Objective::Linf { phi: None, .. }))
    }

    /// Line search over phi (log grid, then golden section) for the smallest L-inf gamma.
    fn linf_line_search(&mut self, plan: &Plan) -> Result<Option<Design>, SynthError> {
        let eval = |runner: &mut Self, phi: f64| -> Result<Option<Design>, SynthError> {
            let mut p = plan.clone();
            if let Some(l) = &mut p.linf {
                l.phi = phi;
            }
            Ok(match runner.attempt(&p)? {
                Attempt::Solved(d) => Some(*d),
                _ => None,
            })
        };
        let key = |d: &Design| d.achieved.linf_gamma.unwrap_or(f64::INFINITY);
        let grid: Vec<f64> = (0..13).map(|k| 10f64.powf(-4.0 + 0.4 * k as f64)).collect();
        let mut results: Vec<(f64, Option<Design>)> = Vec::new();
        for &phi in &grid {
            let d = eval(self, phi)?;
            results.push((phi, d));
        }
        let best_k = results
            .iter()
            .enumerate()
            .filter_map(|(k, (_, d))| d.as_ref().map(|d| (k, key(d))))
            .min_by(|x, y| x.1.total_cmp(&y.1))
            .map(|(k, _)| k);
        let Some(best_k) = best_k else {
            return Ok(None);
        };
        let (mut a, mut b) = (
            grid[best_k.saturating_sub(1)].ln(),
            grid[(best_k + 1).min(grid.len() - 1)].ln(),
        );
        let mut best = results.swap_remove(best_k).1;
        let gr = 0.5 * (5f64.sqrt() - 1.0);
        for _ in 0..12 {
            let c = b - gr * (b - a);
            let d = a + gr * (b - a);
            let fc = eval(self, c.exp())?;
            let fd = eval(self, d.exp())?;
            let (kc, kd) = (
                fc.as_ref().map_or(f64::INFINITY, key),
                fd.as_ref().map_or(f64::INFINITY, key),
            );
            for cand in [fc, fd].into_iter().flatten() {
                if best.as_ref().is_none_or(|bd| key(&cand) < key(bd)) {
                    best = Some(cand);
                }
            }
            if kc < kd {
                b = d;
            } else {
                a = c;
            }
        }
        Ok(best.map(|mut d| {
            d.notes.push(format!(
                "L-inf phi chosen by line search over [1e-4, 1e1]: phi = {:.6}",
                d.achieved.linf_phi.unwrap_or(f64::NAN)
            ));
            d
        }))
    }
}

/// Synthesizes gains for `model`'s objectives.
pub fn synthesize(model: &TsModel, settings: &Settings) -> Result<Design, SynthError> {
    if let Some(e) = theorem2::synthesize(model, settings) {
        return Err(e);
    }
    let (plan, goal) = plan::initial_plan(&model.spec, settings.default_phi);
    let mut runner = Runner {
        model,
        settings,
        log: SolverLog::default(),
        accept_almost: false,
    };
    match runner.run(&plan, goal) {
        Ok(Some(mut d)) => {
            if trigger::wanted(model) {
                let (t, notes) = runner.trigger(&d)?;
                d.notes.extend(notes);
                d.trigger = Some(t);
            }
            d.log = std::mem::take(&mut runner.log);
            Ok(d)
        }
        Ok(None) => Err(diagnose(&mut runner, &plan)),
        Err(SynthError::Solver { status, .. }) => {
            // No verdict: still say what relaxing each bound achieves.
            let achievable = match diagnose(&mut runner, &plan) {
                SynthError::Infeasible { achievable, .. } => achievable,
                _ => Vec::new(),
            };
            Err(SynthError::Solver {
                status,
                message: format!(
                    "the solver stopped ({status:?}) without proving the objectives feasible or infeasible; they are most likely infeasible or nearly so{}",
                    if plan.fixed_bounds().is_empty() { String::new() } else { format!(" ({})", plan.fixed_bounds().iter().map(|(n, v)| format!("{n} {v}")).collect::<Vec<_>>().join(", ")) }
                ),
                achievable,
            })
        }
        Err(e) => Err(e),
    }
}

/// Explains an infeasible plan: which fixed bounds conflict, and the best value
/// of each one when the others are kept.
fn diagnose(runner: &mut Runner<'_>, plan: &Plan) -> SynthError {
    let fixed = plan.fixed_bounds();
    let desc = |(name, v): &(&str, f64)| match *name {
        "decay_rate" => format!("decay_rate >= {v}"),
        other => format!("{other} <= {v}"),
    };
    let list = fixed.iter().map(desc).collect::<Vec<_>>().join(", ");
    let mut achievable = Vec::new();
    runner.accept_almost = true;
    for (name, value) in &fixed {
        let relaxed = plan.optimizing(name);
        let goal = if *name == "decay_rate" {
            Goal::MaxDecay
        } else {
            Goal::InSdp
        };
        let line = match runner.run(&relaxed, goal) {
            Ok(Some(d)) => {
                let approx = if d.approximate { " (approximate: the solver reached only reduced accuracy)" } else { "" };
                let best = match *name {
                    "decay_rate" => d.achieved.decay_bracket.map(|b| b.0),
                    "hinf" => d.achieved.hinf_gamma,
                    "linf" => d.achieved.linf_gamma,
                    "input_norm" => d.achieved.input_norm_bound,
                    _ => d.achieved.output_norm_bound,
                };
                match best {
                    Some(b) if *name == "decay_rate" => format!("infeasible with decay_rate >= {value}; the largest feasible decay rate with the other objectives is {b:.6}{approx}"),
                    Some(b) => format!("infeasible with {name} <= {value}; the smallest feasible bound with the other objectives is {b:.6}{approx}"),
                    None => format!("{name}: no value found"),
                }
            }
            Ok(None) => format!("{name}: infeasible whatever its value (the other objectives conflict on their own)"),
            Err(e) => format!("{name}: could not be optimized ({e})"),
        };
        achievable.push(line);
    }
    let message = if fixed.is_empty() {
        "infeasible: no PDC controller with a common quadratic Lyapunov function meets the objectives under this relaxation".to_string()
    } else {
        format!("infeasible: the objectives cannot be met together ({list})")
    };
    SynthError::Infeasible {
        message,
        achievable,
    }
}
