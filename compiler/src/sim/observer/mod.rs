//! The closed loop of an observer-based design (output feedback): the
//! controller sees only the measured output y = C x + noise, sampled every
//! period T; the runtime's [`tsf_runtime::Observer`] ([`law`]) returns the
//! command and advances its estimate, which starts at `xhat0`; the command is
//! held over the period while the truth plant is integrated.
//!
//! Metrics gain an `estimation` section ([`EstimationMetrics`]): the
//! estimation error e = x - xhat at each sample (before the update, the
//! estimate the command was computed from): its norm at the start, its
//! peak, at the end, and the time after which it stays within 1 % of its
//! start. The trace carries the estimate after the plant's states (the
//! `estimate` plot, the CSV's `<state>_hat` columns).

pub mod law;

use super::integrator::{Dopri5, Rk4, Stepper};
use super::limits::{step_count, MAX_STATE_MAGNITUDE};
use super::measure::Measure;
use super::metrics::{norm, RunFacts, Sample, Tally, Trace};
use super::plant::Plant;
use super::premise::Premises;
use super::region::Region;
use super::scenario::{plan, Outcome, Plan};
use super::signal::Signals;
use super::{Options, Prepared, Progress, SimError};
use crate::tables::{ObserverTables, PremiseCode, PremiseFrom};
use crate::util::rng::SplitMix64;
use law::{factored_terms, observer_law, ObserverLaw};
use serde::Serialize;
use std::io::Write;
use std::time::Instant;
use tsf_lang::spec::{Integrator, Trigger};

/// Measurement noise added to y = C x at every sample (seeded by the
/// scenario's seed), per output component.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Noise {
    /// No noise.
    #[default]
    None,
    /// Uniform in `[-bound, bound]`.
    Uniform(f64),
    /// Gaussian with standard deviation `sigma` (Box-Muller).
    Gaussian(f64),
}

impl Noise {
    /// How the metrics describe it.
    pub fn describe(&self) -> String {
        match self {
            Noise::None => "none".into(),
            Noise::Uniform(b) => format!("uniform in [-{b}, {b}] per output"),
            Noise::Gaussian(s) => format!("gaussian, sigma = {s} per output"),
        }
    }

    /// One draw.
    pub(crate) fn draw(&self, rng: &mut SplitMix64) -> f64 {
        match *self {
            Noise::None => 0.0,
            Noise::Uniform(b) => rng.uniform(-b, b),
            Noise::Gaussian(s) => {
                // 1 - U in (0, 1]: the logarithm stays finite.
                let u1 = 1.0 - rng.next_f64();
                let u2 = rng.next_f64();
                s * (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
            }
        }
    }

    /// Whether its parameter is a finite number `>= 0`.
    pub(crate) fn valid(&self) -> bool {
        match *self {
            Noise::None => true,
            Noise::Uniform(v) | Noise::Gaussian(v) => v.is_finite() && v >= 0.0,
        }
    }
}

/// The observer's part of a scenario.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ObserverScenario {
    /// The initial estimate (n values; default the scenario's `xhat0`, else
    /// 0, the generated `INIT`).
    pub xhat0: Option<Vec<f64>>,
    /// Measurement noise.
    pub noise: Noise,
}

/// The estimation figures of a run of an observer-based design.
#[derive(Debug, Clone, Serialize, schemars::JsonSchema)]
pub struct EstimationMetrics {
    /// The observer's period T in seconds.
    pub period_s: f64,
    /// Measured outputs.
    pub outputs: usize,
    /// `output` or `estimate`: what the premises are computed from.
    pub premises_from: String,
    /// The measurement noise.
    pub noise: String,
    /// The initial estimate.
    pub xhat0: Vec<f64>,
    /// ||x - xhat|| at the first sample.
    pub initial_error_norm: f64,
    /// Largest ||x - xhat|| over the samples.
    pub peak_error_norm: f64,
    /// ||x - xhat|| at the last sample.
    pub final_error_norm: f64,
    /// The time after which ||x - xhat|| stays <= 1 % of its initial value
    /// (`None`: it does not by the end).
    pub time_to_1pct_s: Option<f64>,
    /// Samples whose estimate was reset (non-finite estimate).
    pub estimate_resets: u64,
}

/// Running figures of the estimation error.
struct ErrorTally {
    initial: Option<f64>,
    peak: f64,
    last: f64,
    within: Option<f64>,
    resets: u64,
}

impl ErrorTally {
    fn sample(&mut self, t: f64, e: f64) {
        let start = *self.initial.get_or_insert(e);
        self.peak = self.peak.max(e);
        self.last = e;
        if e.is_finite() && e <= 0.01 * start {
            self.within.get_or_insert(t);
        } else {
            self.within = None;
        }
    }
}

/// The observer's period checked against the scenario: the loop's trigger
/// must be the spec's periodic one (sweeps of triggering laws and overrides
/// do not apply), and the run's sample count within the limits.
fn period(o: &ObserverTables, plan: &Plan, opts: &Options) -> Result<f64, SimError> {
    let t = o.period;
    match plan.trigger {
        Some(Trigger::Periodic { every }) if *every == t && opts.trigger.is_none() => {}
        None if opts.trigger.is_none() => {}
        _ => {
            return Err(SimError::unsupported(format!(
                "an observer-based controller runs at its period T = {t} s: another triggering law (an override or a sweep) does not apply"
            )))
        }
    }
    step_count(plan.t0, plan.t1, plan.h, t.min(plan.h))
        .map_err(|e| SimError::usage(format!("cannot simulate the observer: {e}")))?;
    Ok(t)
}

/// Runs the scenario of an observer-based design (`prepared.tables.observer`
/// set) with the truth plant of `truth`, streaming the CSV to `csv`; the
/// `observer` callback sees every sample (time, plant state, command).
pub fn run(
    prepared: &Prepared,
    truth: &tsf_lang::Spec,
    opts: &Options,
    csv: Option<&mut dyn Write>,
    observer: Option<super::scenario::Observer<'_>>,
) -> Result<Outcome, SimError> {
    let started = Instant::now();
    let tables = &prepared.tables;
    let Some(o) = tables.observer.as_ref() else {
        return Err(SimError::unsupported("internal error: no observer tables"));
    };
    if prepared.model.spec.modes.is_some() {
        let no = "an observer-based controller with `modes` is not simulated (docs/limits.md)";
        return Err(SimError::unsupported(no));
    }
    let mut plant = Plant::new(truth, &prepared.source, opts.evaluator)?;
    let plan = plan(prepared, opts, plant.dim())?;
    let period = period(o, &plan, opts)?;
    let n = tables.n;
    let xhat0 = initial_estimate(&opts.observer, &prepared.model.spec, n)?;
    let terms = factored_terms(tables);
    let law = observer_law(tables, o, &terms)?;
    let mut signals = Signals::new(truth, &prepared.source, opts.evaluator);
    let dim = plant.dim();
    let (rtol, atol) = opts.tolerances;
    let mut stepper = match plan.integrator {
        Integrator::Rk4 => Stepper::Rk4(Rk4::new(dim, plan.h)),
        Integrator::Dopri5 => Stepper::Dopri5(Dopri5::new(dim, rtol, atol, plan.h)),
    };
    let hat_names: Vec<String> = tables
        .state_names
        .iter()
        .map(|s| format!("{s}_hat"))
        .collect();
    let state_names: Vec<String> = tables
        .state_names
        .iter()
        .cloned()
        .chain(plant.extra_names())
        .collect();
    let mut trace = Trace {
        state_names: state_names.clone(),
        input_names: tables.input_names.clone(),
        estimate: Some(dim),
        ..Trace::default()
    };
    let write_err = |e: std::io::Error| SimError::usage(format!("cannot write the CSV trace: {e}"));
    let mut csv = csv;
    if let Some(out) = csv.as_mut() {
        let mut names = state_names;
        names.extend(hat_names);
        super::csv::header(*out, &names, &trace.input_names, false).map_err(write_err)?;
    }
    let mut lp = Loop::new(law.as_ref(), tables, o, opts, plan.seed, &xhat0);
    lp.measure.noise = or_spec_noise(lp.measure.noise, &prepared.model.spec);
    let mut tally = Tally::new(n, tables.m, &plan.x0, opts.convergence_rel_tol);
    let region = Region::new(&prepared.model, tables);
    let mut progress = Progress::new(opts.progress, plan.t0, plan.t1);
    let mut x = plan.x0.clone();
    let mut observer = observer;
    let (mut t, mut k, mut nonfinite_at) = (plan.t0, 0u64, None);
    let mut row = Vec::with_capacity(dim + n);
    loop {
        let (no_rule, xhat_k) = lp.sample(&x[..n]);
        row.clear();
        row.extend_from_slice(&x);
        row.extend_from_slice(&xhat_k);
        lp.err.sample(t, error_norm(&x[..n], &xhat_k));
        tally.sample(&Sample {
            t,
            x: &row,
            u: &lp.u,
            sent: true,
            no_rule,
            in_region: region.contains(&x[..n]),
        });
        if let Some(obs) = observer.as_mut() {
            obs(t, &x, &lp.u);
        }
        if let Some(out) = csv.as_mut() {
            super::csv::row(*out, t, &row, &lp.u, true, None).map_err(write_err)?;
        }
        if t >= plan.t1 || nonfinite_at.is_some() {
            break;
        }
        k += 1;
        let mut t_next = (plan.t0 + k as f64 * period).min(plan.t1);
        if plan.t1 - t_next < 1e-9 * period {
            t_next = plan.t1;
        }
        let u = &lp.u;
        let mut rhs = |tt: f64, s: &[f64], ds: &mut [f64]| {
            let w = signals.at(tt)?;
            plant.rhs(tt, s, u, w, ds)
        };
        stepper.advance(&mut rhs, t, t_next, &mut x)?;
        t = t_next;
        if !x
            .iter()
            .all(|v| v.is_finite() && v.abs() <= MAX_STATE_MAGNITUDE)
        {
            nonfinite_at = Some(t);
        }
        progress.update(t);
    }
    progress.finish();
    if let Some(out) = csv.as_mut() {
        out.flush().map_err(write_err)?;
    }
    let last = Sample {
        t,
        x: &row,
        u: &lp.u,
        sent: true,
        no_rule: false,
        in_region: true,
    };
    let facts = RunFacts {
        u_max: tables.u_max.clone(),
        t_end: plan.t1,
        saturated: lp.saturated,
        nonfinite_at,
        p: &prepared.p,
    };
    let (mut metrics, trace) = tally.finish(&facts, &last, std::mem::take(&mut trace));
    describe(&mut metrics, &stepper, &plan, opts, (dim, n));
    metrics.trigger = format!(
        "observer-based controller every T = {period} s (y = C x{} sampled, command held)",
        if lp.measure.noise == Noise::None {
            ""
        } else {
            " + noise"
        }
    );
    metrics.estimation = Some(lp.estimation(period, xhat0));
    metrics.wall_time_s = started.elapsed().as_secs_f64();
    let spec = &prepared.model.spec;
    Ok(Outcome {
        name: spec.controller.node.clone(),
        spec: std::path::Path::new(&prepared.source.name)
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default(),
        trace,
        metrics,
        u_max: tables.u_max.clone(),
        n,
    })
}

/// The spec's measurement noise: uniform within the smallest `noise <= e`
/// bound of the `measure` rows when every row has one (seeded by the
/// scenario's seed), else none.
pub fn spec_noise(spec: &tsf_lang::Spec) -> Noise {
    let Some(m) = &spec.measure else {
        return Noise::None;
    };
    let bounds: Option<Vec<f64>> = m.noise.iter().copied().collect();
    match bounds {
        Some(b) if !b.is_empty() => Noise::Uniform(b.iter().copied().fold(f64::INFINITY, f64::min)),
        _ => Noise::None,
    }
}

/// `noise`, or the spec's ([`spec_noise`]) when it is none.
pub fn or_spec_noise(noise: Noise, spec: &tsf_lang::Spec) -> Noise {
    match noise {
        Noise::None => spec_noise(spec),
        n => n,
    }
}

/// The initial estimate of the run (the options', else the scenario's
/// `xhat0`, else 0), checked, and the noise checked.
fn initial_estimate(
    sc: &ObserverScenario,
    spec: &tsf_lang::Spec,
    n: usize,
) -> Result<Vec<f64>, SimError> {
    let xhat0 = sc
        .xhat0
        .clone()
        .or_else(|| {
            let sim = spec.simulate.as_ref()?;
            sim.xhat0.as_ref().map(|x| x.node.clone())
        })
        .unwrap_or_else(|| vec![0.0; n]);
    if xhat0.len() != n || xhat0.iter().any(|v| !v.is_finite()) {
        return Err(SimError::usage(format!(
            "xhat0 must have {n} finite components (got {xhat0:?})"
        )));
    }
    if !sc.noise.valid() {
        return Err(SimError::usage(
            "the measurement noise level must be a finite number >= 0",
        ));
    }
    Ok(xhat0)
}

/// The descriptive fields of the metrics: integrator, trigger, seed, plant
/// (`dims`: the plant's and the controller's state counts).
fn describe(
    metrics: &mut super::metrics::Metrics,
    stepper: &Stepper,
    plan: &Plan,
    opts: &Options,
    (dim, n): (usize, usize),
) {
    let (rtol, atol) = opts.tolerances;
    metrics.integrator = match stepper {
        Stepper::Rk4(s) => format!("rk4, fixed step <= {} s", s.h),
        Stepper::Dopri5(s) => format!(
            "dopri5, rtol = {rtol:e}, atol = {atol:e}, h_max = {} s, {} accepted / {} rejected steps",
            plan.h, s.accepted, s.rejected
        ),
    };
    metrics.rhs_evaluations = stepper.evals();
    metrics.seed = plan.seed;
    metrics.plant = if dim > n {
        format!(
            "the spec's dynamics block ({dim} states, {} not seen by the controller)",
            dim - n
        )
    } else {
        "the spec's truth plant".into()
    };
}

/// ||x - xhat||.
fn error_norm(x: &[f64], xhat: &[f64]) -> f64 {
    let e: Vec<f64> = x.iter().zip(xhat).map(|(a, b)| a - b).collect();
    norm(&e)
}

/// The controller's side of the loop: the runtime observer, the premise
/// code, the noise, the estimate and the held command.
struct Loop<'a> {
    law: &'a dyn ObserverLaw,
    o: &'a ObserverTables,
    /// The premise expressions' tape (premise expressions, compiled evaluator).
    premises: Option<Option<Premises>>,
    exprs: Option<&'a [crate::tables::sym::Sym]>,
    measure: Measure,
    xhat: Vec<f64>,
    y: Vec<f64>,
    v: Vec<f64>,
    z: Vec<f64>,
    u: Vec<f64>,
    err: ErrorTally,
    saturated: u64,
}

impl<'a> Loop<'a> {
    /// The controller's side of the loop of `tables` with the observer `o`
    /// (run by `law`), starting from the estimate `xhat0`.
    fn new(
        law: &'a dyn ObserverLaw,
        tables: &'a crate::tables::Tables,
        o: &'a ObserverTables,
        opts: &Options,
        seed: u64,
        xhat0: &[f64],
    ) -> Self {
        let n = tables.n;
        Loop {
            law,
            o,
            premises: match &tables.premise {
                PremiseCode::Exprs(_) => Some(Premises::new(tables, opts.evaluator)),
                PremiseCode::Linear(_) => None,
            },
            exprs: match &tables.premise {
                PremiseCode::Exprs(e) => Some(e.as_slice()),
                PremiseCode::Linear(_) => None,
            },
            measure: Measure::new(o.c.clone(), opts.observer.noise, seed),
            xhat: xhat0.to_vec(),
            y: vec![0.0; o.q],
            v: vec![0.0; n],
            z: vec![0.0; tables.p],
            u: vec![0.0; tables.m],
            err: ErrorTally {
                initial: None,
                peak: 0.0,
                last: f64::NAN,
                within: None,
                resets: 0,
            },
            saturated: 0,
        }
    }

    /// The estimation section of the metrics.
    fn estimation(&self, period: f64, xhat0: Vec<f64>) -> EstimationMetrics {
        EstimationMetrics {
            period_s: period,
            outputs: self.o.q,
            premises_from: match self.o.premise_from {
                PremiseFrom::Output => "output".into(),
                PremiseFrom::Estimate => "estimate".into(),
            },
            noise: self.measure.noise.describe(),
            xhat0,
            initial_error_norm: self.err.initial.unwrap_or(f64::NAN),
            peak_error_norm: self.err.peak,
            final_error_norm: self.err.last,
            time_to_1pct_s: self.err.within,
            estimate_resets: self.err.resets,
        }
    }

    /// One sample: y = C x + noise, the runtime's step (new held command,
    /// estimate advanced). Returns whether no rule fired and the estimate
    /// the command was computed from.
    fn sample(&mut self, x: &[f64]) -> (bool, Vec<f64>) {
        self.measure.sample(x, &mut self.y);
        let xhat_k = self.xhat.clone();
        let z = match (&mut self.premises, self.exprs) {
            (Some(tape), Some(exprs)) => {
                self.law.premise_state(&self.xhat, &self.y, &mut self.v);
                match tape {
                    Some(p) => p.eval(&self.v, &mut self.z),
                    None => {
                        for (zp, e) in self.z.iter_mut().zip(exprs) {
                            *zp = e.eval(&self.v);
                        }
                    }
                }
                Some(&self.z[..])
            }
            _ => None,
        };
        let flags = self.law.step(&mut self.xhat, &self.y, z, &mut self.u);
        self.saturated += u64::from(flags.contains(tsf_runtime::Flags::SATURATED));
        self.err.resets += u64::from(flags.contains(tsf_runtime::Flags::ESTIMATE_RESET));
        (flags.contains(tsf_runtime::Flags::NO_RULE_FIRED), xhat_k)
    }
}
