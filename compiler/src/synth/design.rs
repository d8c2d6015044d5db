//! The data synthesis produces: settings in, a [`Design`] (gains, Lyapunov
//! matrix, achieved values, solver log, optional trigger) or a [`SynthError`] out.

use super::achieved::Achieved;
use super::given::Verdict;
use super::objective::BuildError;
use super::plan::Plan;
use super::reduction::Reduction;
use crate::model::TsModel;
use nalgebra::DMatrix;
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
    /// The largest estimated solver memory of one SDP, in bytes; a larger
    /// problem is refused before solving ([`SynthError::TooLarge`]).
    pub memory_limit: u64,
    /// The certificate's verdict on a candidate design, handed in by the
    /// driver (the certificate stage); synthesis asks it where a search must know
    /// whether a candidate certifies (the per-objective verdicts of given
    /// gains). `None`: such searches report that no verdict was available.
    pub verifier: Option<Verifier>,
    /// Transmissions of a candidate event-triggered design in the spec's
    /// scenario, handed in by the driver (which runs the simulator);
    /// `weight = synthesize transmissions;` ships the candidate with the
    /// fewest. `None`: the search ships the softest candidate within the bound.
    pub scorer: Option<Scorer>,
}

/// Transmissions of a candidate: the continuous design and the candidate
/// trigger design (its plan carries the gains); `Ok(None)` without a scenario.
pub type Scorer = fn(&TsModel, &Design, &TriggerDesign) -> Result<Option<u64>, SynthError>;

/// The certificate's verdict on a design: `Ok(true)` when every condition holds.
pub type Verifier = fn(&TsModel, &Design) -> Result<bool, SynthError>;

/// The default [`Settings::memory_limit`]: 8 GiB (a third of the 24 GiB
/// machines tsfc is tested on; `TSFC_SDP_MEMORY_LIMIT_MB` overrides it).
pub const DEFAULT_MEMORY_LIMIT: u64 = 8 << 30;

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
            memory_limit: std::env::var("TSFC_SDP_MEMORY_LIMIT_MB")
                .ok()
                .and_then(|v| v.trim().parse::<u64>().ok())
                .map_or(DEFAULT_MEMORY_LIMIT, |mb| mb << 20),
            verifier: None,
            scorer: None,
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
    /// Estimated solver memory of the largest SDP solved, in bytes.
    pub memory_estimate: u64,
    /// Status of the last SDP solved (what a failed synthesis ended on).
    pub last_status: Option<SolveStatus>,
    /// SDPs whose verdict came from a second run without the solver's
    /// equilibration (the first stopped on a numerical failure at once).
    pub unscaled_retries: usize,
    /// The last design a refused synthesis reached (its gains were found,
    /// a later step refused them), for the failed report.
    pub candidate: Option<Candidate>,
}

/// Gains and Lyapunov matrix that a later step of the synthesis refused
/// (the sampled or event-triggered loop, the saturation level): kept so the
/// refused design can be inspected.
#[derive(Debug, Clone)]
pub struct Candidate {
    /// PDC gains F_j, in rule order.
    pub gains: Vec<DMatrix<f64>>,
    /// The continuous design's Lyapunov matrix P.
    pub p: DMatrix<f64>,
    /// The refusal's first line.
    pub refused_by: String,
}

impl SolverLog {
    /// Adds the work of `other` (an earlier or discarded run of the same
    /// compile) to this log: SDP count, times and the largest memory
    /// estimate; the statuses and sizes of the kept SDP stay this log's.
    pub fn count_also(&mut self, other: &SolverLog) {
        self.solves += other.solves;
        self.unscaled_retries += other.unscaled_retries;
        self.solve_time += other.solve_time;
        self.build_time += other.build_time;
        self.memory_estimate = self.memory_estimate.max(other.memory_estimate);
    }
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
    /// The loop that ships, as its law designed it ([`super::loops`]):
    /// continuous, every sample transmitted, event-triggered or mixed.
    pub loop_design: super::loops::LoopDesign,
    /// Per-objective verdicts when the rules give their gains (analysis);
    /// empty when the gains were synthesized.
    pub verdicts: Vec<Verdict>,
    /// The per-mode design of a spec with `modes` (then `gains`, `x`, `p`
    /// are the first mode's).
    pub modes: Option<super::markov::ModesDesign>,
    /// The fuzzy Lyapunov function of a spec with `lyapunov fuzzy(..)` (then
    /// `x` is the Finsler slack G and `p` is P_1).
    pub fuzzy: Option<super::lyapunov::FuzzyDesign>,
    /// The output-feedback part (`control observer_based` or
    /// `static_output`); `None` for state feedback.
    pub output: Option<super::observer::OutputFeedback>,
}

impl Design {
    /// The sampling intervals [h_min, h_max] of the certified sampled loop
    /// (fault-free or with Markov modes), if the design ships one.
    pub fn sampling(&self) -> Option<(f64, f64)> {
        let law = self.loop_design.certificate();
        law.and_then(|l| l.every_sample())
            .or_else(|| self.loop_design.sampled_modes().map(|s| s.sampling))
    }

    /// The certified region E(P, c) = {x : x'Px <= c} of the loop that ships
    /// under a saturation region, as (P, c): the loop law's region
    /// (event-triggered, sampled), else the continuous design's level. None
    /// without a saturation region, or when the level cannot be computed.
    pub fn certified_region(&self) -> Option<(&DMatrix<f64>, f64)> {
        let sat = self.plan.saturation()?;
        match self.loop_design.certificate().and_then(|l| l.region()) {
            Some(region) => Some(region),
            None => Some((&self.p, sat.level(&self.plan).ok()?)),
        }
    }
}

/// The certificate of the sampled loop for the gains of a [`Design`]: every
/// sample transmitted, intervals in `plan.sampling`.
#[derive(Debug, Clone)]
pub struct SampledDesign {
    /// The problem data.
    pub plan: TriggerPlan,
    /// P of the sampled loop's functional: under saturation the region is
    /// E(P, c), c = [`TriggerPlan::region_level`].
    pub p: DMatrix<f64>,
    /// Values of every variable of the solved problem.
    pub values: Vec<(String, DMatrix<f64>)>,
    /// Reductions applied to the solved problem.
    pub reductions: Vec<Reduction>,
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
    /// P of the event-triggered loop's functional: the region is E(P, c),
    /// c = [`TriggerPlan::region_level`].
    pub p: DMatrix<f64>,
    /// Certified L-inf bound of the event-triggered loop at that nu.
    pub gamma: f64,
    /// xi at that nu.
    pub xi: f64,
    /// Values of every variable of the solved trigger problem.
    pub values: Vec<(String, DMatrix<f64>)>,
    /// Reductions applied to the solved trigger problem.
    pub reductions: Vec<Reduction>,
    /// The co-design's rounds (round 0: the two-step start); empty for the
    /// two-step method.
    pub rounds: Vec<super::codesign::Round>,
    /// The points of a few-transmissions search (`weight = synthesize
    /// transmissions;`), point 0 the two-step start; empty otherwise.
    pub search: Vec<super::transmissions::Point>,
    /// With `region z = auto;`: the scale of the seed box the design's box
    /// was grown to ([`super::region_auto`]); `None` otherwise.
    pub region_scale: Option<f64>,
}

impl TriggerDesign {
    /// The level c of the certified set E(P, c): xi tau_bar^2 / phi with the
    /// solved xi when the LMIs tie it to xi (a premise region,
    /// [`crate::synth::trigger::joint_level`]), else [`TriggerPlan::region_level`].
    pub fn level(&self) -> f64 {
        crate::synth::trigger::joint_level(&self.plan)
            .map_or_else(|| self.plan.region_level(), |per_xi| per_xi * self.xi)
    }
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
    /// Given gains (analysis) that are not certified for the objectives:
    /// what holds and what fails, objective by objective.
    NotCertified {
        /// The verdict.
        message: String,
        /// Per objective, alone when they fail together.
        verdicts: Vec<Verdict>,
    },
    /// A combination of objectives tsfc does not support.
    Unsupported(String),
    /// The SDP would need more memory than the limit allows.
    TooLarge {
        /// Which problem.
        what: String,
        /// Estimated bytes.
        estimate: u64,
        /// The limit in bytes.
        limit: u64,
        /// Its largest LMI (rows).
        largest_lmi: usize,
        /// Whether `estimate` is a lower bound (found before building).
        floor: bool,
    },
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

impl SynthError {
    /// The first line of the refusal (its message without the advice).
    pub fn first_line(&self) -> String {
        let text = self.to_string();
        text.lines().next().map_or_else(String::new, str::to_string)
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
                write!(f, "{message} (solver status: {status})")?;
                for a in achievable {
                    write!(f, "\n  {a}")?;
                }
                Ok(())
            }
            SynthError::NotCertified { message, verdicts } => {
                write!(f, "{message}")?;
                for v in verdicts {
                    write!(f, "\n  {v}")?;
                }
                Ok(())
            }
            SynthError::Unsupported(m) | SynthError::Internal(m) => write!(f, "{m}"),
            SynthError::TooLarge {
                what,
                estimate,
                limit,
                largest_lmi,
                floor,
            } => write!(
                f,
                "the {what} is too large to solve: the solver would need {} {:.1} GiB (largest LMI {largest_lmi} x {largest_lmi}), over the limit of {:.1} GiB; reduce the number of states or rules, or raise the limit with TSFC_SDP_MEMORY_LIMIT_MB",
                if *floor { "at least" } else { "about" },
                *estimate as f64 / f64::from(1u32 << 30),
                *limit as f64 / f64::from(1u32 << 30)
            ),
        }
    }
}

/// Data of the sampled-loop problem (everything but nu is fixed by step 1 and
/// the spec): the event-triggered loop, or with `event` false a loop that
/// transmits every sample (periodic or aperiodic sampling without a threshold).
/// Empty `levels` leave the dead zone out; `linf` false the disturbance.
#[derive(Debug, Clone, PartialEq)]
pub struct TriggerPlan {
    /// Sampling intervals [h_min, h_max].
    pub sampling: (f64, f64),
    /// Whether an event condition decides transmissions (the error e enters).
    pub event: bool,
    /// Whether the L-inf channel (`d`, `c`, `g`, `xi_max`, `tau_bar`) enters.
    pub linf: bool,
    /// Initial sets E(P, 1) must contain (named), for a region of attraction.
    pub contain: Vec<(String, tsf_lang::spec::InitialSet)>,
    /// Threshold nu (bisected).
    pub nu: f64,
    /// phi of V' + phi V - xi tau' tau < 0.
    pub phi: f64,
    /// Upper bound on xi; it sets the region level ([`TriggerPlan::region_level`]).
    pub xi_max: f64,
    /// Bound tau_bar on ||tau(t)||.
    pub tau_bar: f64,
    /// Saturation levels u_bar_s.
    pub levels: Vec<f64>,
    /// PDC gains F_j (m x n), fixed.
    pub gains: Vec<DMatrix<f64>>,
    /// Sector gains G_j (m x n), fixed.
    pub sector: Vec<DMatrix<f64>>,
    /// Per controller vertex q (no premise region), the map M_q of the dead
    /// zone into the held input: the loop gets v_k = K_q x(t_k) - M_q dz_k
    /// (the sampled observer loop: M_jl = [I; Gu_j / T], the observer is fed
    /// the saturated command). Empty: M = I (the input is the command).
    pub dz_input: Vec<DMatrix<f64>>,
    /// `Some(T)`: the sector multiplier T (diagonal) is KNOWN and the sector
    /// gains unknown, one per controller vertex q (`G_sector{q}`; `sector`
    /// unused), so the generalized sector terms stay linear; `None`: T
    /// unknown with the gains `sector`.
    pub sector_multiplier: Option<DMatrix<f64>>,
    /// Disturbance columns D_i of the L-inf channel, per rule.
    pub d: Vec<DMatrix<f64>>,
    /// Output map y = C x + G_y tau.
    pub c: DMatrix<f64>,
    /// Disturbance feedthrough G_y.
    pub g: DMatrix<f64>,
    /// The premise box of a local certificate (`region z = lo .. hi;`): the
    /// LMIs are imposed at vertices of the blended model over the memberships
    /// the box allows, and E(P, c) is kept inside the box ([`crate::synth::vertices`]).
    pub region: Option<crate::model::region::PremiseBox>,
    /// The model error the loop's blocks carry ([`crate::synth::loop_error`];
    /// zero: the nominal blocks).
    pub model_error: crate::synth::loop_error::LoopError,
    /// The membership drift of the sampled observer loop on a region
    /// ([`crate::synth::observer::drift`]): plant and observer vertices
    /// paired, the drift terms, the sample box. `None`: free vertices.
    pub drift: Option<crate::synth::observer::drift::Drift>,
    /// The input bound, saturation levels and initial set of the sampled
    /// observer loop ([`crate::synth::observer::sampled_bounds`]).
    pub observer_bounds: Option<crate::synth::observer::sampled_bounds::SampledBounds>,
    /// The H-inf (L2-gain) channel from the disturbance columns `d` to
    /// z = C x + E u_k + G tau (`None`: none; [`L2Channel`]).
    pub l2: Option<super::l2_channel::L2Channel>,
}

impl TriggerPlan {
    /// The dead-zone map M_q of controller vertex `q` ([`TriggerPlan::dz_input`]),
    /// `m` x (the saturated channels); the identity when none is given.
    pub fn dz_map(&self, q: usize, m: usize) -> DMatrix<f64> {
        self.dz_input
            .get(q)
            .cloned()
            .unwrap_or_else(|| DMatrix::identity(m, self.levels.len()))
    }

    /// The level c of the certified region E(P, c) inside the linear region:
    /// with the L-inf channel, the level reached from rest, xi_max tau_bar^2 /
    /// phi ([`crate::synth::objectives::reach_level`]), raised to 1 when
    /// initial sets must lie in E(P, 1); 1 otherwise.
    pub fn region_level(&self) -> f64 {
        if !self.linf {
            return 1.0;
        }
        let reach = crate::synth::objectives::reach_level(self.xi_max, self.tau_bar, self.phi);
        if self.contain.is_empty() {
            reach
        } else {
            reach.max(1.0)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::SolverLog;
    use std::time::Duration;
    use tsf_lmi::SolveStatus;

    #[test]
    fn counting_a_second_run_adds_its_work_and_keeps_the_kept_status() {
        let mut kept = SolverLog {
            solves: 3,
            status: Some(SolveStatus::Solved),
            iterations: 19,
            solve_time: Duration::from_secs(2),
            build_time: Duration::from_millis(300),
            memory_estimate: 10,
            last_status: Some(SolveStatus::Solved),
            unscaled_retries: 1,
            ..SolverLog::default()
        };
        let other = SolverLog {
            solves: 25,
            status: Some(SolveStatus::NumericalError),
            iterations: 40,
            solve_time: Duration::from_secs(990),
            build_time: Duration::from_millis(200),
            memory_estimate: 50,
            last_status: Some(SolveStatus::NumericalError),
            unscaled_retries: 2,
            ..SolverLog::default()
        };
        kept.count_also(&other);
        assert_eq!(kept.solves, 28);
        assert_eq!(kept.solve_time, Duration::from_secs(992));
        assert_eq!(kept.build_time, Duration::from_millis(500));
        assert_eq!(kept.memory_estimate, 50);
        assert_eq!(kept.unscaled_retries, 3);
        assert_eq!(kept.status, Some(SolveStatus::Solved));
        assert_eq!(kept.iterations, 19);
        assert_eq!(kept.last_status, Some(SolveStatus::Solved));
    }
}
