//! Synthesis: a [`TsModel`] and its objectives become PDC gains F_j = M_j X^{-1}.
//!
//! One SDP per [`Plan`] ([`build`]); a maximized decay rate is found by
//! bisection over feasibility problems, an L-inf gain without a fixed phi by a
//! line search over phi ([`search`]). Infeasible specs are diagnosed: each
//! fixed bound is optimized with the others kept, to say what is achievable.
//! Objective families live in [`objectives`], one file each; relaxations in
//! [`relaxations`]. This stage knows nothing about Clarabel: it talks to
//! `tsf_lmi`.

pub mod achieved;
mod blocks;
pub mod build;
mod diagnose;
pub mod experimental;
pub mod objectives;
pub mod plan;
pub mod reduction;
pub mod relaxations;
mod sampled;
mod search;
pub mod trigger;

pub use achieved::{Achieved, Quantity};
pub use blocks::common_b;
pub use build::{build, BuildError, Built};
pub use plan::{Bound, Goal, Plan};
pub use reduction::Reduction;
pub use sampled::Block12;
pub use trigger::{TriggerBuilt, TriggerPlan};

use crate::model::TsModel;
use nalgebra::DMatrix;
use search::Runner;
use std::time::Duration;
use tsf_lmi::{ProblemStats, SolveSettings, SolveStatus};

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
    /// Problem reductions applied (the certificate inverts them).
    pub reductions: Vec<Reduction>,
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
    pub reductions: Vec<Reduction>,
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
    /// A combination of objectives tsfc does not support.
    Unsupported(String),
    /// A bug in tsfc (malformed LMI, solver interface).
    Internal(String),
}

impl From<BuildError> for SynthError {
    fn from(e: BuildError) -> Self {
        match e {
            BuildError::Unsupported(m) => SynthError::Unsupported(m),
            e @ BuildError::Lmi(_) => SynthError::Internal(e.to_string()),
        }
    }
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
            SynthError::Unsupported(m) | SynthError::Internal(m) => write!(f, "{m}"),
        }
    }
}

/// Synthesizes gains for `model`'s objectives.
pub fn synthesize(model: &TsModel, settings: &Settings) -> Result<Design, SynthError> {
    if let Some(e) = experimental::theorem2::synthesize(model, settings) {
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
        Ok(None) => Err(diagnose::diagnose(&mut runner, &plan)),
        Err(SynthError::Solver { status, .. }) => {
            // No verdict: still say what relaxing each bound achieves.
            let achievable = match diagnose::diagnose(&mut runner, &plan) {
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
