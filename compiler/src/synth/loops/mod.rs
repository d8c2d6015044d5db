//! Loop laws: how the loop that ships closes around the continuous design.
//!
//! The continuous design (objectives, relaxation, gains F_j, P) is the core;
//! the spec's triggering law then decides which loop the certificate must
//! cover. Each law is one [`LoopLaw`] in [`LAWS`] (the registry): whether it
//! closes the spec's loop ([`LoopLaw::claims`]), and how it designs or
//! certifies that loop for the core ([`LoopLaw::design`]). What it designs is
//! one [`LoopDesign`], whose [`LoopCertificate`] says how the certificate
//! rebuilds its conditions (also with the values as generated code stores
//! them), the sampling it certifies, its certified region and its report
//! section. Check-time refusals of a law live with its check
//! (`lang/src/check/trigger.rs`); its sensor tables in the tables stage, its
//! generated sensor code in each backend, its gate in the simulator.
//!
//! Laws: [`continuous`] (no trigger), [`every_sample`] (periodic sampling,
//! or aperiodic sampling without a threshold), [`jittered`] (periodic
//! sampling with jitter, certified as [`every_sample`]'s loop), [`event`] (event trigger with
//! a synthesized weight: two-step, co-design, regional), [`mixed`] (the mixed
//! trigger on a signal), [`modes`] (the sampled loop of a design with Markov
//! modes), [`observer`] (the periodic loop of an observer-based controller). Paper-specific experiments are not laws: they are
//! chosen from `super::experimental::EXPERIMENTS`.

pub mod continuous;
pub mod event;
pub mod every_sample;
pub mod jittered;
pub mod mixed;
pub mod modes;
pub mod observer;

use super::design::{Design, SynthError};
use super::reduction::Reduction;
use super::search::Runner;
use crate::model::TsModel;
use nalgebra::DMatrix;

pub use event::{RegionReport, TriggerReport};

/// One loop law: selection and design.
pub trait LoopLaw: Sync {
    /// The law's name (notes, errors).
    fn name(&self) -> &'static str;
    /// Whether this law closes the loop of `model` (the first law of
    /// [`LAWS`] that claims a spec is its law).
    fn claims(&self, model: &TsModel) -> bool;
    /// Designs or certifies the loop for the continuous design `core`; a
    /// co-design may replace the core (its gains change, and the continuous
    /// loop is re-analyzed for them).
    fn design(
        &self,
        runner: &mut Runner<'_>,
        core: &mut Design,
        start: &Start,
    ) -> Result<LoopDesign, SynthError>;
}

/// Where the continuous design was searched from: the initial plan and goal
/// (a co-design re-analyzes its gains from them).
#[derive(Debug, Clone)]
pub struct Start {
    /// The initial plan.
    pub plan: super::plan::Plan,
    /// Its goal.
    pub goal: super::plan::Goal,
}

/// Every loop law, in the order they are asked ([`law_of`]).
pub const LAWS: &[&dyn LoopLaw] = &[
    &modes::SampledModes,
    &event::Codesign,
    &event::Transmissions,
    &event::TwoStep,
    &mixed::Mixed,
    &observer::ObserverSampled,
    &every_sample::EverySample,
    &jittered::Jittered,
    &continuous::Continuous,
];

/// The law that closes the loop of `model` ([`continuous::Continuous`] claims every spec).
pub fn law_of(model: &TsModel) -> &'static dyn LoopLaw {
    LAWS.iter()
        .copied()
        .find(|l| l.claims(model))
        .unwrap_or(&continuous::Continuous)
}

/// What a loop law designed: the data the certificate rebuilds and the later
/// stages (tables, simulator, report) read.
#[derive(Debug, Clone, Default)]
pub enum LoopDesign {
    /// The continuous loop: the core's certificate is the whole certificate.
    #[default]
    Continuous,
    /// Every sample transmitted (periodic, jittered, or aperiodic without a threshold).
    EverySample(super::design::SampledDesign),
    /// An event trigger with a synthesized weight.
    Event(super::design::TriggerDesign),
    /// The mixed trigger on a signal.
    Mixed(super::signal_trigger::SignalTrigger),
    /// The sampled loop of a design with Markov modes (its certificate is
    /// per mode: [`LoopDesign::certificate`] is `None`).
    SampledModes(super::markov::sampled::ModesSampled),
    /// The periodic loop of an observer-based controller (augmented (x, xhat)).
    ObserverSampled(super::observer::sampled::SampledObserver),
}

impl LoopDesign {
    /// The law's certificate and report (`None` for the continuous loop).
    pub fn certificate(&self) -> Option<&dyn LoopCertificate> {
        match self {
            LoopDesign::Continuous | LoopDesign::SampledModes(_) => None,
            LoopDesign::EverySample(s) => Some(s),
            LoopDesign::Event(t) => Some(t),
            LoopDesign::Mixed(m) => Some(m),
            LoopDesign::ObserverSampled(o) => Some(o),
        }
    }

    /// The event trigger's design, if the loop has one.
    pub fn event(&self) -> Option<&super::design::TriggerDesign> {
        match self {
            LoopDesign::Event(t) => Some(t),
            _ => None,
        }
    }

    /// The sampled loop's design, if every sample is transmitted.
    pub fn every_sample(&self) -> Option<&super::design::SampledDesign> {
        match self {
            LoopDesign::EverySample(s) => Some(s),
            _ => None,
        }
    }

    /// The sampled loop of a mode design, if it ships one.
    pub fn sampled_modes(&self) -> Option<&super::markov::sampled::ModesSampled> {
        match self {
            LoopDesign::SampledModes(s) => Some(s),
            _ => None,
        }
    }

    /// The sampled observer loop's certificate, if the loop has one.
    pub fn observer_sampled(&self) -> Option<&super::observer::sampled::SampledObserver> {
        match self {
            LoopDesign::ObserverSampled(o) => Some(o),
            _ => None,
        }
    }

    /// The mixed trigger's design, if the loop has one.
    pub fn mixed(&self) -> Option<&super::signal_trigger::SignalTrigger> {
        match self {
            LoopDesign::Mixed(m) => Some(m),
            _ => None,
        }
    }
}

/// One condition the certificate re-checks for a loop.
#[derive(Debug)]
pub enum Condition {
    /// A problem re-checked at its solved values (reductions inverted first).
    Problem {
        /// The unreduced problem, rebuilt.
        problem: Box<tsf_lmi::Problem>,
        /// Names of its constraints that are not strict.
        nonstrict: Vec<String>,
        /// The solved values, by variable name.
        values: Vec<(String, DMatrix<f64>)>,
        /// The reductions the solved problem had.
        reductions: Vec<Reduction>,
    },
    /// A condition checked directly.
    Margin {
        /// Its name.
        name: String,
        /// Its margin (positive: it holds).
        margin: f64,
        /// Bound on the rounding error of the margin.
        error_bound: f64,
        /// Matrix size (1 for scalars).
        size: usize,
        /// Whether it is strict.
        strict: bool,
        /// Whether it passes.
        ok: bool,
    },
}

/// How the generated tables store numbers: the stored-precision check
/// rebuilds a loop's conditions with every stored value passed through it.
pub type Rounding<'a> = &'a dyn Fn(f64) -> f64;

/// A designed loop: what the certificate rebuilds and what reports show.
pub trait LoopCertificate {
    /// The conditions of the loop rebuilt with `gains` (the emitted ones,
    /// or their stored rounding with `stored`), at margin `eps`.
    fn conditions(
        &self,
        model: &TsModel,
        eps: f64,
        gains: &[DMatrix<f64>],
        stored: Option<Rounding<'_>>,
    ) -> Result<Vec<Condition>, SynthError>;
    /// The reductions applied to the loop's solved problem.
    fn reductions(&self) -> &[Reduction];
    /// Matrices the tables store besides the gains (their rounding is reported).
    fn stored_matrices(&self) -> Vec<&DMatrix<f64>> {
        Vec::new()
    }
    /// The certified sampling intervals [h_min, h_max] of a loop that
    /// transmits every sample (the constant `SAMPLE_PERIOD` of generated code).
    fn every_sample(&self) -> Option<(f64, f64)> {
        None
    }
    /// The certified region E(P, c) of the loop, as (P, c), if it has one.
    fn region(&self) -> Option<(&DMatrix<f64>, f64)> {
        None
    }
}
