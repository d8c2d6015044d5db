//! The JSON report of `tsfc compile`: it reads the design and its certificate.

pub mod markov;
pub mod objectives;
pub mod output;
pub mod plant;

use crate::certify::Certificate;
use crate::model::TsModel;
use crate::synth::{Design, SolverLog, SynthError};
pub use objectives::{Objectives, Problem, ProblemSize};
use serde::Serialize;

pub use crate::util::matrix::rows;

pub use crate::util::hash::sha256_hex;

/// `spec` section.
#[derive(Debug, Clone, Serialize, schemars::JsonSchema)]
pub struct SpecInfo {
    /// Path as given.
    pub path: String,
    /// SHA-256 of the file's bytes.
    pub sha256: String,
}

/// One gain.
#[derive(Debug, Serialize, schemars::JsonSchema)]
pub struct Gain {
    /// Rule name.
    pub rule: String,
    /// F (m x n rows).
    #[serde(rename = "F")]
    pub f: Vec<Vec<f64>>,
}

impl Gain {
    /// The gains F_j of `model`'s rules, named by rule.
    pub fn of_rules(model: &TsModel, gains: &[nalgebra::DMatrix<f64>]) -> Vec<Gain> {
        gains
            .iter()
            .zip(&model.rules)
            .map(|(f, r)| Gain {
                rule: r.name.clone(),
                f: rows(f),
            })
            .collect()
    }
}

/// The gains and P of a refused design, not certified, kept so it can be
/// inspected: `gains` and `P` as the certified report writes them.
#[derive(Debug, Serialize, schemars::JsonSchema)]
pub struct CandidateReport {
    /// What refused it (the refusal's first line).
    pub refused_by: String,
    /// The gains F_j by rule (NOT certified).
    pub gains: Vec<Gain>,
    /// The continuous design's Lyapunov matrix P.
    #[serde(rename = "P")]
    pub p: Vec<Vec<f64>>,
    /// Every plant rule i under every controller rule j's gain: the largest
    /// real part of the eigenvalues of A_i + B_i F_j (a sampled or
    /// event-triggered loop needs every one negative).
    pub pairs: Vec<PairReport>,
}

/// The stability of one plant/controller rule pair.
#[derive(Debug, Serialize, schemars::JsonSchema)]
pub struct PairReport {
    /// Plant rule.
    pub plant: String,
    /// Controller rule (whose gain is applied).
    pub controller: String,
    /// max Re eig(A_i + B_i F_j) (null when the eigenvalues did not converge).
    pub abscissa: Option<f64>,
}

impl CandidateReport {
    /// The candidate of gains `gains` and `p`, refused by `refused_by`.
    pub fn of(
        model: &TsModel,
        gains: &[nalgebra::DMatrix<f64>],
        p: &nalgebra::DMatrix<f64>,
        refused_by: String,
    ) -> CandidateReport {
        let name = |k: usize| {
            model
                .rules
                .get(k)
                .map_or_else(String::new, |r| r.name.clone())
        };
        CandidateReport {
            refused_by,
            gains: Gain::of_rules(model, gains),
            p: rows(p),
            pairs: crate::synth::pair_stability::abscissae(model, gains)
                .into_iter()
                .map(|pair| PairReport {
                    plant: name(pair.plant),
                    controller: name(pair.controller),
                    abscissa: pair.abscissa.is_finite().then_some(pair.abscissa),
                })
                .collect(),
        }
    }
}

/// `solver` section.
#[derive(Debug, Serialize, schemars::JsonSchema)]
pub struct SolverInfo {
    /// Solver name.
    pub name: &'static str,
    /// Status of the kept SDP (or of the last attempt).
    pub status: String,
    /// Iterations of the kept SDP.
    pub iterations: u32,
    /// SDPs solved in all (bisections, line searches, diagnosis).
    pub solves: usize,
    /// Of those, SDPs re-solved without the solver's equilibration after a
    /// numerical failure in the first iterations (docs/limits.md, "solver scaling").
    pub unscaled_retries: usize,
    /// Size of the kept SDP.
    pub problem: Problem,
}

/// `timings_s` section.
#[derive(Debug, Serialize, Default, schemars::JsonSchema)]
pub struct Timings {
    /// Language stage.
    pub parse: f64,
    /// Model stage.
    pub model: f64,
    /// Building LMI problems.
    pub build: f64,
    /// Inside Clarabel.
    pub solve: f64,
    /// Certificate.
    pub certify: f64,
    /// Everything.
    pub total: f64,
}

/// The ellipsoid {x : x' U x <= 1} certified invariant and inside the linear
/// region of the saturation (generalized sector condition).
#[derive(Debug, Serialize, schemars::JsonSchema)]
pub struct RegionOfAttraction {
    /// U = P / c (n x n rows): the certified region E(P, c) is {x : x' U x <= 1}.
    /// For `control observer_based` the region is on the augmented state
    /// (x, e), e = x - x_hat (2n x 2n rows, U = P_aug; with `trigger
    /// periodic` and saturation levels, the sampled loop's E(P, 1), its P on
    /// (x, x_hat) written on (x, e)), and the levels below
    /// are those of (x0, x0 - xhat0): xhat0 = 0 for the objective's x0, the
    /// scenario's `xhat0` (else 0) for the simulate block's.
    #[serde(rename = "U")]
    pub u: Vec<Vec<f64>>,
    /// x0' U x0 for the objective's `for x0 = ...` (a certified containment).
    pub x0_level: Option<f64>,
    /// Whether the objective's x0 lies in the region (certified when present).
    pub contains_x0: Option<bool>,
    /// x0' U x0 for the simulate block's initial state (a check, not a condition).
    pub scenario_x0_level: Option<f64>,
    /// Whether the simulate block's initial state lies in the region: when
    /// false, the simulation starts outside what the certificate covers.
    pub contains_scenario_x0: Option<bool>,
}

pub use crate::synth::loops::{RegionReport, TriggerReport};

/// How far the model the rules blend, sum_i h_i(z(x)) M_i, is from the
/// state-dependent M(x) (M = A, B) on a grid over the rules' operating points,
/// relative to the largest local model (Frobenius norms). The certificate
/// covers the blended model; an exact sector model gives 0.
#[derive(Debug, Serialize, schemars::JsonSchema)]
pub struct ConsistencyReport {
    /// States compared (inside the premise region).
    pub points: usize,
    /// Worst relative mismatch.
    pub worst_relative_mismatch: f64,
    /// The matrix it is in (`A` or `B`).
    pub matrix: &'static str,
    /// The state where it is.
    pub at_state: Vec<f64>,
    /// Rules firing there (normalized weight above 1 %).
    pub rules_firing: Vec<String>,
    /// Their normalized weights.
    pub weights: Vec<f64>,
    /// The warning threshold.
    pub tolerance: f64,
    /// Whether the worst mismatch is within it.
    pub within_tolerance: bool,
}

/// The certified sampled loop: every sample transmitted, the command held
/// (zero-order hold) for intervals in `sampling`.
#[derive(Debug, Serialize, schemars::JsonSchema)]
pub struct SampledReport {
    /// [h_min, h_max] in s (equal for a periodic trigger).
    pub sampling: [f64; 2],
    /// The decay rate a certified for the sampled loop itself
    /// (V(t) <= e^(-2 a t) V(0)); 0: asymptotic (with modes: mean-square)
    /// stability only. The `objectives` decay rate is the continuous loop's.
    pub decay_rate: f64,
    /// What the certificate covers, in words.
    pub covers: String,
    /// P of the sampled loop's functional (n x n rows); under saturation E(P, 1)
    /// is its region of attraction.
    #[serde(rename = "P")]
    pub p: Vec<Vec<f64>>,
    /// Y of the functional's integral term (with modes; it is mode-independent).
    #[serde(rename = "Y", skip_serializing_if = "Option::is_none")]
    pub y: Option<Vec<Vec<f64>>>,
    /// The free matrices L1, L2 of the functional (the sampled observer loop,
    /// on the augmented state (x, xhat)), so the conditions can be re-checked
    /// from the report.
    #[serde(rename = "L", skip_serializing_if = "Option::is_none")]
    pub l: Option<[Vec<Vec<f64>>; 2]>,
    /// With modes: per mode P_a, L1_a, L2_a of the functional (`P` above is
    /// the first mode's).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub modes: Option<Vec<markov::ModeSampledReport>>,
    /// The sampled observer loop on a region: the membership drift bound
    /// (region R, input bound U, rates, steps, sample box R', delta per rule)
    /// its paired vertices are imposed with.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub drift: Option<crate::model::region::drift::DriftBound>,
    /// The H-inf gain certified for the sampled loop: from rest,
    /// ||z||_2 <= gamma ||w||_2 (the sampled observer loop with
    /// `objective hinf`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub hinf_gamma: Option<f64>,
    /// The sampled observer loop's input bound and saturation certificate.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bounds: Option<SampledBoundsReport>,
}

/// The input bound and saturation levels certified on the sampled observer
/// loop's E(P, 1) (`synth/observer/sampled_bounds.rs`).
#[derive(Debug, Serialize, schemars::JsonSchema)]
pub struct SampledBoundsReport {
    /// The certified ||u(t)|| <= mu for t >= 0, if an input bound was imposed.
    pub input_norm: Option<f64>,
    /// The actuator's saturation levels u_s (empty: no `saturate`).
    pub saturation_levels: Vec<f64>,
    /// Which certificate the saturation got: `inactive_on_certified_set`
    /// (the linear-region certificate: |u_s| <= u_s on E(P, 1), so the
    /// saturated loop is the certified linear one there) or `active_sector`
    /// (the generalized sector condition: the actuator may saturate on
    /// E(P, 1); `sector_multiplier`, `sector_gains`); `None` without
    /// saturation levels.
    pub saturation: Option<&'static str>,
    /// `active_sector`: the diagonal of the known sector multiplier T (the
    /// functional's term He(dz' T G xi_k) - 2 dz' T dz).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sector_multiplier: Option<Vec<f64>>,
    /// `active_sector`: the solved sector gains G_jl (m x 2n rows, on xi =
    /// (x, xhat)), one per pair (observer rule j outer, controller rule l
    /// inner); E(P, 1) lies inside |((Kbar_l - G_jl) xi)_s| <= u_s.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sector_gains: Option<Vec<Vec<Vec<f64>>>>,
}

/// The `sampled_loop` section of a design with a sampled loop: every sample
/// transmitted (state feedback), the Markov modes' or the observer's.
fn sampled_loop(model: &TsModel, d: &Design) -> Option<SampledReport> {
    let every_sample = match &d.loop_design {
        crate::synth::loops::LoopDesign::EverySample(s) => Some(s),
        _ => None,
    };
    every_sample
        .map(|s| SampledReport {
            sampling: [s.plan.sampling.0, s.plan.sampling.1],
            decay_rate: s.plan.phi / 2.0,
            covers: crate::synth::sampling::covers(&s.plan),
            p: rows(&s.p),
            y: None,
            l: None,
            modes: None,
            drift: None,
            bounds: None,
            hinf_gamma: None,
        })
        .or_else(|| markov::sampled_loop(model, d))
        .or_else(|| observer_sampled_loop(d))
}

/// The `sampled_loop` section of the sampled observer loop: the looped
/// functional's P, Y, L1, L2 on the augmented state (x, xhat).
fn observer_sampled_loop(d: &Design) -> Option<SampledReport> {
    use crate::synth::solved::{names, Solved as _};
    let crate::synth::loops::LoopDesign::ObserverSampled(s) = &d.loop_design else {
        return None;
    };
    let get = |name| s.values.value(name).map(rows);
    Some(SampledReport {
        sampling: [s.period, s.period],
        decay_rate: s.alpha,
        covers: s.covers(),
        p: rows(&s.p),
        y: get(names::LOOP_Y),
        l: get(names::LOOP_L1)
            .zip(get(names::LOOP_L2))
            .map(|(a, b)| [a, b]),
        modes: None,
        drift: s.plan.drift.as_ref().map(|d| d.bound.clone()),
        bounds: s.plan.observer_bounds.as_ref().map(|_| {
            let active = s.saturation_active();
            SampledBoundsReport {
                input_norm: s.input_bound(),
                saturation_levels: s.saturation_levels().to_vec(),
                saturation: (!s.saturation_levels().is_empty()).then_some(if active {
                    "active_sector"
                } else {
                    "inactive_on_certified_set"
                }),
                sector_multiplier: s
                    .plan
                    .sector_multiplier
                    .as_ref()
                    .filter(|_| active)
                    .map(|t| t.diagonal().iter().copied().collect()),
                sector_gains: active.then(|| s.sector_gains().iter().map(rows).collect()),
            }
        }),
        hinf_gamma: s.hinf_gamma(),
    })
}

/// One objective's verdict for given gains (analysis mode).
#[derive(Debug, Serialize, schemars::JsonSchema)]
pub struct VerdictReport {
    /// The objective (or loop) in the spec's words.
    pub objective: String,
    /// Whether the given gains are certified for it.
    pub certified: bool,
    /// The quantity of `value` (`hinf_gamma`, `decay_rate`, ...), if any.
    pub quantity: Option<&'static str>,
    /// Certified: the certified value; not certified: the best value the
    /// gains certify for it alone, if any.
    pub value: Option<f64>,
    /// `together` (with every other objective, one common P) or `alone`.
    pub judged: &'static str,
    /// Why it is not certified, when more than its value.
    pub note: Option<String>,
}

impl From<&crate::synth::Verdict> for VerdictReport {
    fn from(v: &crate::synth::Verdict) -> Self {
        VerdictReport {
            objective: v.objective.clone(),
            certified: v.certified,
            quantity: v.quantity.map(|q| q.key()),
            value: v.value,
            judged: if v.together { "together" } else { "alone" },
            note: v.note.clone(),
        }
    }
}

/// Why there is no certified design.
#[derive(Debug, Serialize, schemars::JsonSchema)]
pub struct Diagnosis {
    /// The verdict.
    pub message: String,
    /// What is achievable instead.
    pub achievable: Vec<String>,
}

/// Version of the JSON Schemas of tsfc's documents (the `vN` of their
/// `$id`, `tsfc schema`): it changes when a document changes incompatibly
/// (a field removed, renamed or retyped).
pub const SCHEMA_VERSION: u32 = 1;

/// The `$id` of the schema of documents of kind `kind` (`report`, ...): the
/// repository URL, `/schema/vN/<kind>.json`.
pub fn schema_id(kind: &str) -> String {
    // The workspace's `repository`.
    let repo = env!("CARGO_PKG_REPOSITORY").trim_end_matches('/');
    format!("{repo}/schema/v{SCHEMA_VERSION}/{kind}.json")
}

/// The JSON report of `tsfc compile`: the design, its certificate and how it was found.
#[derive(Debug, Serialize, schemars::JsonSchema)]
pub struct Report {
    /// The report's JSON Schema (`report`, or `failed-report` when not
    /// certified; docs/schema/).
    #[serde(rename = "$schema")]
    pub schema: String,
    /// tsfc version.
    pub tsfc_version: &'static str,
    /// The spec.
    pub spec: SpecInfo,
    /// Controller name.
    pub controller: String,
    /// States.
    pub n: usize,
    /// Inputs.
    pub m: usize,
    /// Disturbances.
    pub q: usize,
    /// Number of rules.
    pub rules: usize,
    /// `certified`, `infeasible` or `refused`.
    pub status: &'static str,
    /// `synthesis` (tsfc designs the gains) or `analysis` (the rules give
    /// them; tsfc certifies the objectives for them).
    pub mode: &'static str,
    /// Per-objective verdicts of an analysis (empty for a synthesis).
    pub verdicts: Vec<VerdictReport>,
    /// Relaxation used.
    pub relaxation: String,
    /// What a `membership_mismatch(kappa = ..)` relaxation relies on (absent
    /// under every other relaxation).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub membership_mismatch: Option<MismatchReport>,
    /// The fuzzy Lyapunov function of a `lyapunov fuzzy(..)` design (absent
    /// with the quadratic one).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fuzzy_lyapunov: Option<FuzzyLyapunovReport>,
    /// The controller kind (`state_feedback`, `observer_based`, `static_output`).
    pub control: &'static str,
    /// Every rule's local model (rule, A, B, D), in rule order.
    pub local_models: Vec<output::LocalModelReport>,
    /// The observer of an observer-based design (absent otherwise; present
    /// only when certified).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub observer: Option<output::ObserverReport>,
    /// The gains K_j of a static output-feedback design (absent otherwise;
    /// present only when certified).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub static_output: Option<output::StaticOutputReport>,
    /// Margin eps of strict LMIs.
    pub lmi_margin_eps: Option<f64>,
    /// Achieved objective values.
    pub objectives: Objectives,
    /// Gains (empty unless certified).
    pub gains: Vec<Gain>,
    /// Lyapunov matrix P (empty unless a design was found).
    #[serde(rename = "P")]
    pub p: Vec<Vec<f64>>,
    /// Certificate.
    pub certificate: Option<Certificate>,
    /// The certificate re-checked with the tables as generated code stores
    /// them (`precision f32` or `f64`), with the membership rounding bound.
    pub stored_precision: Option<crate::certify::StoredPrecision>,
    /// Whether the design as stored is certified (`stored_precision.certified`).
    pub stored_precision_certified: Option<bool>,
    /// Reductions applied to the solved problem.
    pub reductions: Vec<String>,
    /// Search notes.
    pub notes: Vec<String>,
    /// Diagnosis when not certified.
    pub diagnosis: Option<Diagnosis>,
    /// The design a refused compile reached (absent when certified, or when
    /// no gains were found): gains, P and every rule pair's stability.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub candidate: Option<CandidateReport>,
    /// Estimated region of attraction E(P, 1) under actuator saturation (with
    /// a synthesized trigger: P of the event-triggered loop's functional).
    pub region_of_attraction: Option<RegionOfAttraction>,
    /// The blended T-S model against the state-dependent A(x), B(x).
    pub model_consistency: Option<ConsistencyReport>,
    /// What is certified of the plant A(x), B(x) the spec declares (not of
    /// the rules' blend), or why nothing is.
    pub plant: plant::PlantSection,
    /// The synthesized event trigger.
    pub trigger: Option<TriggerReport>,
    /// The certified sampled loop (periodic trigger, or aperiodic sampling
    /// without a threshold).
    pub sampled_loop: Option<SampledReport>,
    /// The certified mixed trigger on a named signal (`trigger mixed { on = ..; }`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub signal_trigger: Option<crate::synth::signal_trigger::SignalTrigger>,
    /// Markov-switching modes: per mode P, gains and verdict (specs with `modes`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub modes: Option<Vec<markov::ModeReport>>,
    /// The transition-rate matrix Pi (specs with `modes`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub transition_rates: Option<Vec<Vec<f64>>>,
    /// Solver.
    pub solver: SolverInfo,
    /// Timings.
    pub timings_s: Timings,
}

/// The mismatch bound of `membership_mismatch(kappa = ..)` and whether the
/// certificate relies on it.
#[derive(Debug, Clone, Serialize, schemars::JsonSchema)]
pub struct MismatchReport {
    /// The spec's kappa.
    pub kappa: f64,
    /// The certificate assumes |k_j - h_j| <= kappa for every rule j at every
    /// instant (a continuously updated controller); false when every
    /// plant/controller pair is imposed instead (sampled or event-triggered loops).
    pub relied_on: bool,
    /// The assumption, or why kappa is not used, in words.
    pub statement: String,
}

impl MismatchReport {
    /// The report of `model`'s relaxation (None unless `membership_mismatch`).
    pub fn of(model: &TsModel) -> Option<MismatchReport> {
        let tsf_lang::spec::Relaxation::MembershipMismatch { kappa } = model.spec.relaxation.node
        else {
            return None;
        };
        let relied_on = crate::synth::relaxations::kappa_relied_on(model).is_some();
        let statement = if relied_on {
            format!(
                "the certificate holds for controller memberships k within kappa = {kappa} of the plant's h: |k_j - h_j| <= {kappa} for every rule j at every instant (bounded-mismatch LMIs with slacks Pk, Gk, after Arino & Sala 2008)"
            )
        } else {
            format!(
                "kappa = {kappa} is not used: the controller holds its memberships from the last transmitted sample, so no kappa bounds the mismatch; every plant/controller rule pair Q_ij < 0 is imposed (sufficient for any mismatch)"
            )
        };
        Some(MismatchReport {
            kappa,
            relied_on,
            statement,
        })
    }
}

/// Assembles the report.
pub fn report(
    model: &TsModel,
    spec: SpecInfo,
    outcome: &Result<(Design, Certificate), SynthError>,
    log: &SolverLog,
    timings: Timings,
) -> Report {
    let (status, design, cert, diagnosis) = status_of(outcome);
    let verdicts = match outcome {
        Ok((d, _)) => d.verdicts.iter().map(VerdictReport::from).collect(),
        Err(SynthError::NotCertified { verdicts, .. }) => {
            verdicts.iter().map(VerdictReport::from).collect()
        }
        Err(_) => Vec::new(),
    };
    let certified = status == "certified";
    let problem = Problem::of(log);
    let (modes, transition_rates) = markov::sections(model, design, cert.as_ref(), certified);
    let (observer, static_output) = output::sections(
        model,
        design.filter(|_| certified).and_then(|d| d.output.as_ref()),
    );
    Report {
        control: model.spec.control.kind.keyword(),
        local_models: output::local_models(model),
        observer,
        static_output,
        schema: schema_id(if certified { "report" } else { "failed-report" }),
        modes,
        transition_rates,
        tsfc_version: env!("CARGO_PKG_VERSION"),
        spec,
        controller: model.spec.controller.node.clone(),
        n: model.n,
        m: model.m,
        q: model.q,
        rules: model.r(),
        status,
        mode: if crate::synth::given::analysis(model) {
            "analysis"
        } else {
            "synthesis"
        },
        verdicts,
        relaxation: model.spec.relaxation.node.to_string(),
        membership_mismatch: MismatchReport::of(model),
        fuzzy_lyapunov: design
            .and_then(|d| d.fuzzy.as_ref())
            .map(FuzzyLyapunovReport::of),
        lmi_margin_eps: design.map(|d| d.eps),
        objectives: design.map(|d| Objectives::of(model, d)).unwrap_or_default(),
        gains: if certified {
            design
                .map(|d| Gain::of_rules(model, &d.gains))
                .unwrap_or_default()
        } else {
            Vec::new()
        },
        p: design.map(|d| rows(&d.p)).unwrap_or_default(),
        stored_precision: cert.as_ref().and_then(|c| c.stored.clone()),
        stored_precision_certified: cert
            .as_ref()
            .and_then(|c| c.stored.as_ref().map(|s| s.certified)),
        certificate: cert,
        reductions: design
            .map(|d| {
                let looped = d
                    .loop_design
                    .certificate()
                    .map_or(&[][..], |l| l.reductions());
                d.reductions
                    .iter()
                    .chain(looped)
                    .map(|r| r.to_string())
                    .collect()
            })
            .unwrap_or_default(),
        notes: design.map(|d| d.notes.clone()).unwrap_or_default(),
        candidate: match (outcome, &diagnosis) {
            (Ok((d, c)), Some(why)) if !c.ok => Some(CandidateReport::of(
                model,
                &d.gains,
                &d.p,
                why.message.clone(),
            )),
            (Err(_), _) => log
                .candidate
                .as_ref()
                .map(|c| CandidateReport::of(model, &c.gains, &c.p, c.refused_by.clone())),
            _ => None,
        },
        diagnosis,
        plant: plant::nominal(model, design.filter(|_| certified).map(|d| &d.p)),
        model_consistency: model.consistency.as_ref().map(|c| ConsistencyReport {
            points: c.points,
            worst_relative_mismatch: c.worst,
            matrix: c.matrix,
            at_state: c.at.clone(),
            rules_firing: c.firing.iter().map(|(r, _)| r.clone()).collect(),
            weights: c.firing.iter().map(|(_, h)| *h).collect(),
            tolerance: crate::model::MISMATCH_TOLERANCE,
            within_tolerance: c.worst <= crate::model::MISMATCH_TOLERANCE,
        }),
        region_of_attraction: design
            .filter(|_| certified)
            .and_then(|d| region_of_attraction(model, d)),
        trigger: design
            .filter(|_| certified)
            .and_then(|d| d.loop_design.event())
            .map(|t| t.report(model)),
        signal_trigger: design
            .filter(|_| certified)
            .and_then(|d| d.loop_design.mixed().cloned()),
        sampled_loop: design
            .filter(|_| certified)
            .and_then(|d| sampled_loop(model, d)),
        solver: SolverInfo {
            name: "clarabel",
            // A failed synthesis ends on its last SDP; a design on the kept one.
            status: if design.is_some() {
                log.status
            } else {
                log.last_status
            }
            .map_or_else(|| "none".to_string(), |s| format!("{s:?}")),
            iterations: log.iterations,
            solves: log.solves,
            unscaled_retries: log.unscaled_retries,
            problem,
        },
        timings_s: timings,
    }
}

/// The outcome's status (`certified`, `refused`, `infeasible`), its design
/// and certificate, and the diagnosis of a refusal.
fn status_of(
    outcome: &Result<(Design, Certificate), SynthError>,
) -> (
    &'static str,
    Option<&Design>,
    Option<Certificate>,
    Option<Diagnosis>,
) {
    match outcome {
        Ok((d, c)) if c.ok => ("certified", Some(d), Some(c.clone()), None),
        Ok((d, c)) => (
            "refused",
            Some(d),
            Some(c.clone()),
            Some(Diagnosis {
                message: match c.stored.as_ref().filter(|s| !s.certified) {
                    Some(s) => format!(
                        "certificate refused in stored precision {}: `{}` fails with the tables as generated code stores them (margin {:.3e})",
                        s.precision, s.worst_lmi, s.worst_margin
                    ),
                    None => format!("certificate refused: the worst condition is `{}`", c.worst),
                },
                achievable: Vec::new(),
            }),
        ),
        Err(SynthError::Infeasible {
            message,
            achievable,
        }) => (
            "infeasible",
            None,
            None,
            Some(Diagnosis {
                message: message.clone(),
                achievable: achievable.clone(),
            }),
        ),
        Err(SynthError::Solver {
            message,
            achievable,
            status,
        }) => (
            "refused",
            None,
            None,
            Some(Diagnosis {
                message: format!("{message} (solver status: {status})"),
                achievable: achievable.clone(),
            }),
        ),
        Err(SynthError::NotCertified { message, verdicts }) => (
            "refused",
            None,
            None,
            Some(Diagnosis {
                message: message.clone(),
                achievable: verdicts.iter().map(|v| v.to_string()).collect(),
            }),
        ),
        Err(e) => (
            "refused",
            None,
            None,
            Some(Diagnosis {
                message: e.to_string(),
                achievable: Vec::new(),
            }),
        ),
    }
}

/// The certified region of attraction of design `d`'s shipped loop, and
/// whether it contains the initial states of the objective and the scenario.
fn region_of_attraction(model: &TsModel, d: &Design) -> Option<RegionOfAttraction> {
    let sat = d.plan.saturation()?;
    let observer = match &d.output {
        Some(crate::synth::observer::OutputFeedback::Observer(o)) => Some(&o.augmented),
        _ => None,
    };
    // The certified region E(P, c) as E(U, 1); an observer loop's is the
    // augmented E(P_aug, 1) on (x, e), the sampled observer loop's its
    // E(P, 1) on (x, xhat) written on (x, e).
    let u = match (observer, sampled_region(d)) {
        (Some(_), Some(u)) => u,
        (Some(aug), None)
            if aug
                .bounded
                .as_ref()
                .is_some_and(|b| b.bounds.saturation.is_some()) =>
        {
            aug.p.clone()
        }
        (Some(_), None) => return None,
        (None, _) => {
            let (p, c) = d.certified_region()?;
            p / c
        }
    };
    let p = &u;
    let level = |x0: &[f64], xhat0: &[f64]| {
        let xi: Vec<f64> = match observer {
            Some(_) => x0
                .iter()
                .copied()
                .chain(x0.iter().zip(xhat0).map(|(x, xh)| x - xh))
                .collect(),
            None => x0.to_vec(),
        };
        let xi = nalgebra::DVector::from_column_slice(&xi);
        (xi.transpose() * p * &xi)[(0, 0)]
    };
    let zero = vec![0.0; model.n];
    let objective_x0 = match &sat.contain {
        Some(tsf_lang::spec::InitialSet::Point(x0)) => Some(level(x0, &zero)),
        _ => None,
    };
    let scenario = model.spec.simulate.as_ref().map(|sim| {
        let xhat0 = sim.xhat0.as_ref().map_or(&zero, |x| &x.node);
        level(&sim.x0, xhat0)
    });
    Some(RegionOfAttraction {
        u: rows(p),
        x0_level: objective_x0,
        contains_x0: objective_x0.map(|l| l <= 1.0),
        scenario_x0_level: scenario,
        contains_scenario_x0: scenario.map(|l| l <= 1.0),
    })
}

/// The sampled observer loop's certified set under saturation, E(P, 1) with
/// P on xi = (x, xhat), as a matrix on (x, e): xi = S (x, e) with
/// S = [I, 0; I, -I] (xhat = x - e), so U = S' P S. `None` for any other
/// loop, or without saturation levels (then the sampled certificate holds
/// for every state the rules cover, or in its sample box, not on a set).
fn sampled_region(d: &Design) -> Option<nalgebra::DMatrix<f64>> {
    let crate::synth::loops::LoopDesign::ObserverSampled(s) = &d.loop_design else {
        return None;
    };
    if s.saturation_levels().is_empty() {
        return None;
    }
    let n = s.p.nrows() / 2;
    let mut to_xi = nalgebra::DMatrix::<f64>::zeros(2 * n, 2 * n);
    for i in 0..n {
        to_xi[(i, i)] = 1.0;
        to_xi[(n + i, i)] = 1.0;
        to_xi[(n + i, n + i)] = -1.0;
    }
    Some(to_xi.transpose() * &s.p * &to_xi)
}

/// A fuzzy Lyapunov function V = x' (sum_k h_k P_k) x and what its
/// certificate assumes.
#[derive(Debug, Clone, Serialize, schemars::JsonSchema)]
pub struct FuzzyLyapunovReport {
    /// The assumption the certificate relies on.
    pub assumption: &'static str,
    /// phi_k, in rule order.
    pub phi: Vec<f64>,
    /// The Finsler scalar mu of the LMIs.
    pub mu: f64,
    /// P_k, in rule order.
    #[serde(rename = "P_k")]
    pub p_k: Vec<Vec<Vec<f64>>>,
    /// Where the assumption was checked (sampled) to hold: the level c of
    /// V <= c; absent when no level passed (the design is refused).
    pub region: Option<crate::synth::lyapunov::Region>,
}

impl FuzzyLyapunovReport {
    fn of(f: &crate::synth::lyapunov::FuzzyDesign) -> Self {
        FuzzyLyapunovReport {
            assumption: "|dh_k/dt| <= phi_k for every rule k along the closed loop (checked by sampling on the level set region.level of V)",
            phi: f.phi.clone(),
            mu: f.mu,
            p_k: f.p.iter().map(rows).collect(),
            region: f.region.clone(),
        }
    }
}
