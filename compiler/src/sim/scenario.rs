//! The closed loop: sample, decide, update the held command, integrate to the
//! next sampling instant.

use super::controller::{law, runtime_terms, Law};
use super::integrator::{Dopri5, Rk4, Stepper};
use super::limits::{step_count, MAX_STATE_MAGNITUDE};
use super::metrics::{Metrics, MismatchTally, RateTally, RunFacts, Sample, Tally, Trace};
use super::modes::{Actuation, ModeProcess, ModeTally};
use super::plant::Plant;
use super::premise::Premises;
use super::region::Region;
use super::signal::Signals;
use super::source::{head, SpecSource};
use super::trigger::{sampler, Sampler};
use super::{Options, Prepared, Progress, SimError};
use crate::tables::Tables;
use std::io::Write;
use std::time::Instant;
use tsf_lang::spec::{Integrator, Monitor, Trigger};
use tsf_lang::Span;
use tsf_runtime::{Flags, Term};

/// The Markov mode process of a run and its bookkeeping.
struct Chain {
    process: ModeProcess,
    tally: ModeTally,
    actuation: Actuation,
    seed: u64,
    /// The input the plant's input term sees in the current mode.
    u_plant: Vec<f64>,
}

/// A finished run.
#[derive(Debug, Clone)]
pub struct Outcome {
    /// Controller name (file stem of the outputs).
    pub name: String,
    /// The spec file's stem (plot titles; empty for a design built without a file).
    pub spec: String,
    /// The trajectory at the sampling instants, thinned for the plots.
    pub trace: Trace,
    /// Figures of merit.
    pub metrics: Metrics,
    /// Saturation levels (for plots).
    pub u_max: Vec<f64>,
    /// Controller state count (the first `n` columns of the trace).
    pub n: usize,
}

fn describe_trigger(t: Option<&Trigger>) -> String {
    match t {
        None | Some(Trigger::Continuous) => "continuous (every integration step)".into(),
        Some(Trigger::Periodic { every }) => format!("periodic every {every} s"),
        Some(Trigger::Jittered { every, jitter }) => {
            format!(
                "jittered periodic every {every} s, jitter {jitter} s; every sample transmitted"
            )
        }
        Some(Trigger::Aperiodic {
            sampling,
            threshold,
            ..
        }) => {
            let law = match threshold {
                None => "every sample transmitted".to_string(),
                Some(th) => match th.adaptive {
                    Some((a, b, c)) => format!(
                        "relative e'Ue >= nu x_k'Ux_k, adaptive nu in [{}, {}] (mu = {a}, {b}, {c})",
                        th.nu,
                        th.ceiling()
                    ),
                    None => format!("relative e'Ue >= nu x_k'Ux_k, nu = {}", th.nu),
                },
            };
            format!(
                "aperiodic sampling in [{}, {}] s; {law}",
                sampling.0, sampling.1
            )
        }
        Some(Trigger::Mixed {
            monitor,
            beta,
            rho,
            on,
        }) => {
            let s = on.as_ref().map_or("x", |s| s.name.as_str());
            let law = format!("mixed ||{s}(t_i) - {s}|| >= {beta} ||{s}|| + {rho}");
            match monitor {
                Monitor::Sampling(lo, hi) => format!("aperiodic sampling in [{lo}, {hi}] s; {law}"),
                Monitor::Step => format!("{law}, checked at every integration step"),
                Monitor::Continuous => {
                    format!("{law}, monitored continuously (crossings located by bisection)")
                }
            }
        }
    }
}

/// What a run does, once every setting and override has been validated.
pub struct Plan<'a> {
    /// Start time.
    pub t0: f64,
    /// End time.
    pub t1: f64,
    /// Integration step (RK4) or largest step (Dormand-Prince).
    pub h: f64,
    /// Step count ([`step_count`]), at most [`super::limits::MAX_STEPS`].
    pub steps: u64,
    /// Initial plant state (controller states, then extra states).
    pub x0: Vec<f64>,
    /// Triggering law (`None`: continuous).
    pub trigger: Option<&'a Trigger>,
    /// Sampling-pattern seed.
    pub seed: u64,
    /// Integrator.
    pub integrator: Integrator,
}

/// Where a setting came from: the spec (an error points into it, exit 1) or
/// an override in [`Options`] (a usage error, exit 2).
enum Origin<'a> {
    Spec(&'a SpecSource, Span, &'static str),
    Override,
}

impl Origin<'_> {
    fn error(&self, message: String) -> SimError {
        match self {
            Origin::Spec(src, span, help) => src.error_at(*span, message, help),
            Origin::Override => SimError::usage(message),
        }
    }
}

/// `lo` when the sampling interval `lo .. hi` is positive, finite and increasing.
fn interval((lo, hi): (f64, f64)) -> Result<f64, String> {
    if lo > 0.0 && hi >= lo && hi.is_finite() {
        Ok(lo)
    } else {
        Err(format!(
            "the sampling interval {lo} .. {hi} s must be positive, finite and increasing"
        ))
    }
}

/// The shortest sampling interval of `trigger` on a grid of step `h`.
fn shortest_interval(trigger: Option<&Trigger>, h: f64) -> Result<f64, String> {
    match trigger {
        Some(Trigger::Aperiodic { sampling, .. }) => interval(*sampling),
        Some(Trigger::Jittered { every, jitter }) => {
            interval(tsf_lang::spec::jittered_intervals(*every, *jitter))
        }
        Some(Trigger::Mixed { monitor, .. }) => match monitor.sampling() {
            Some(s) => interval(s),
            None => Ok(h),
        },
        Some(Trigger::Periodic { every }) => {
            let ticks = (every / h).round();
            if !(every.is_finite() && *every > 0.0) {
                Err(format!(
                    "the trigger period {every} s must be positive and finite"
                ))
            } else if ticks < 1.0 || (ticks * h - every).abs() > 1e-9 * every {
                let step = every / (every / h).ceil().max(1.0);
                Err(format!(
                    "the trigger period {every} s is not a whole number of time steps ({h} s): the controller would run at another period than the one certified; use a time step that divides it (e.g. step {step:e})"
                ))
            } else {
                Ok(h)
            }
        }
        _ => Ok(h),
    }
}

/// Validates the scenario of `prepared` with the overrides of `opts` for a
/// plant of `dim` states: time span and step count, initial state, trigger,
/// tolerances. The one gate every entry point goes through.
pub fn plan<'a>(
    prepared: &'a Prepared,
    opts: &'a Options,
    dim: usize,
) -> Result<Plan<'a>, SimError> {
    let spec = &prepared.model.spec;
    let src = &prepared.source;
    let n = spec.n();
    let sim = spec.simulate.as_ref().ok_or_else(|| {
        SimError::spec("the spec has no `simulate { ... }` block (add one with `x0` and `time`)")
    })?;
    let block = Origin::Spec(
        src,
        head(sim.span, "simulate".len()),
        "raise the `time` step or shorten the span",
    );
    let (t0, spec_t1, h) = sim.time;
    let t1 = match opts.horizon {
        Some(hz) if hz.is_finite() && hz > 0.0 => t0 + hz,
        Some(hz) => {
            return Err(SimError::usage(format!(
                "the horizon must be a positive number of seconds (got {})",
                tsf_lang::num::Num(hz)
            )))
        }
        None => spec_t1,
    };
    let trigger = opts
        .trigger
        .as_ref()
        .or(spec.trigger.as_ref().map(|t| &t.node));
    let sampling = match (&opts.trigger, &spec.trigger) {
        (None, Some(t)) => Origin::Spec(
            src,
            t.span,
            "the sampling of the trigger must be positive and fit the time step",
        ),
        _ => Origin::Override,
    };
    let shortest = shortest_interval(trigger, h).map_err(|e| sampling.error(e))?;
    let steps = step_count(t0, t1, h, shortest).map_err(|e| {
        let origin = if opts.horizon.is_some() || opts.trigger.is_some() {
            &Origin::Override
        } else {
            &block
        };
        origin.error(format!("cannot simulate: {e}"))
    })?;
    let mut x0 = opts.x0.clone().unwrap_or_else(|| sim.x0.clone());
    if let Some(bad) = x0.iter().find(|v| !v.is_finite()) {
        return Err(SimError::usage(format!(
            "the initial state has a non-finite component ({bad}); every component of x0 must be a finite number"
        )));
    }
    if let Some(big) = x0.iter().find(|v| v.abs() > MAX_STATE_MAGNITUDE) {
        return Err(SimError::usage(format!(
            "the initial state has a component of magnitude {}, beyond {MAX_STATE_MAGNITUDE:e}: the simulator's norms would overflow (docs/limits.md); scale the states",
            tsf_lang::num::Num(*big)
        )));
    }
    if x0.len() == n {
        x0.resize(dim, 0.0);
    }
    if x0.len() != dim {
        return Err(SimError::usage(format!(
            "x0 has {} components; the plant has {n} controller states{}",
            x0.len(),
            if dim > n {
                format!(
                    " and {} extra states ({n} or {dim} values expected)",
                    dim - n
                )
            } else {
                String::new()
            }
        )));
    }
    let rel = opts.convergence_rel_tol;
    let (rtol, atol) = opts.tolerances;
    let positive = |v: f64| v > 0.0 && v.is_finite();
    if !(positive(rel) && rel <= 1.0 && positive(rtol) && positive(atol)) {
        return Err(SimError::usage(format!(
            "tolerances must be positive and finite, the convergence tolerance at most 1 (got {rel}, rtol {rtol}, atol {atol})"
        )));
    }
    Ok(Plan {
        t0,
        t1,
        h,
        steps,
        x0,
        trigger,
        seed: opts.seed.unwrap_or(sim.seed),
        integrator: opts.integrator.unwrap_or(sim.integrator),
    })
}

/// Runs the scenario of `prepared` in closed loop with the runtime controller
/// built from its tables, streaming the CSV rows to `csv` if given; memory
/// does not grow with the run's length.
pub fn run(
    prepared: &Prepared,
    opts: &Options,
    csv: Option<&mut dyn Write>,
) -> Result<Outcome, SimError> {
    run_truth(prepared, &prepared.model.spec, opts, csv, None)
}

/// What sees every sampling instant of a run (time, plant state, held command).
pub type Observer<'o> = &'o mut dyn FnMut(f64, &[f64], &[f64]);

/// [`run`] with the truth plant and disturbance signals of `truth` (the
/// design's spec with perturbed constants or signals: the controller, the
/// scenario's settings and the certificate stay those of `prepared`), and an
/// `observer` of every sampling instant.
pub fn run_truth(
    prepared: &Prepared,
    truth: &tsf_lang::Spec,
    opts: &Options,
    mut csv: Option<&mut dyn Write>,
    mut observer: Option<Observer<'_>>,
) -> Result<Outcome, SimError> {
    if prepared.tables.observer.is_some() {
        return super::observer::run(prepared, truth, opts, csv, observer);
    }
    let started = Instant::now();
    let tables = &prepared.tables;
    let plant = Plant::new(truth, &prepared.source, opts.evaluator)?;
    let plan = plan(prepared, opts, plant.dim())?;
    let terms = runtime_terms(tables);
    let mode_tables = mode_tables(tables);
    let mut run = Run::new(prepared, truth, opts, plant, &plan, &terms, &mode_tables)?;
    let trace = Trace {
        state_names: tables
            .state_names
            .iter()
            .cloned()
            .chain(run.plant.extra_names())
            .collect(),
        input_names: tables.input_names.clone(),
        ..Trace::default()
    };
    let write_err = |e: std::io::Error| SimError::usage(format!("cannot write the CSV trace: {e}"));
    if let Some(out) = csv.as_mut() {
        super::csv::header(
            *out,
            &trace.state_names,
            &trace.input_names,
            run.chain.is_some(),
        )
        .map_err(write_err)?;
    }
    let last_sent = loop {
        let (sent, mode) = run.sample();
        if let Some(obs) = observer.as_mut() {
            obs(run.t, &run.x, &run.u);
        }
        if let Some(out) = csv.as_mut() {
            super::csv::row(*out, run.t, &run.x, &run.u, sent, mode).map_err(write_err)?;
        }
        if run.t >= plan.t1 || run.nonfinite_at.is_some() {
            break sent;
        }
        run.advance(mode)?;
    };
    run.progress.finish();
    if let Some(out) = csv.as_mut() {
        out.flush().map_err(write_err)?;
    }
    Ok(run.finish(prepared, opts, last_sent, trace, started))
}

/// Markov modes with mode-dependent gains: the tables of each mode's
/// controller (empty without modes, or with one gain set for all).
fn mode_tables(tables: &Tables) -> Vec<Tables> {
    tables.modes.as_ref().map_or(Vec::new(), |mt| {
        mt.gains
            .iter()
            .map(|g| Tables {
                gains: g.clone(),
                modes: None,
                ..tables.clone()
            })
            .collect()
    })
}

/// The Markov mode chain of a run of `spec` (what each mode does to the
/// input: from `truth`), if the spec has `modes`; refused for a trigger
/// other than continuous, periodic or threshold-free aperiodic.
fn mode_chain(
    spec: &tsf_lang::Spec,
    truth: &tsf_lang::Spec,
    plan: &Plan,
) -> Result<Option<Chain>, SimError> {
    let (t0, t1, m) = (plan.t0, plan.t1, spec.m());
    Ok(match &spec.modes {
        Some(modes) => {
            if !plan.trigger.is_none_or(|t| {
                matches!(
                    t,
                    Trigger::Continuous
                        | Trigger::Periodic { .. }
                        | Trigger::Aperiodic {
                            threshold: None,
                            ..
                        }
                )
            }) {
                return Err(SimError::unsupported(
                    "a spec with `modes` is simulated in a continuous loop or a sampled one (`periodic`, or `aperiodic` without a threshold)",
                ));
            }
            let sim = spec
                .simulate
                .as_ref()
                .ok_or_else(|| SimError::spec("the spec has no `simulate { ... }` block"))?;
            let (mode0, seed) = super::modes::setup(modes, sim, t1 - t0)?;
            let actuation = Actuation::new(truth.modes.as_ref().unwrap_or(modes), m);
            Some(Chain {
                process: ModeProcess::new(modes, mode0, seed, t0),
                tally: ModeTally::new(modes, mode0, t0, m),
                actuation,
                seed,
                u_plant: vec![0.0; m],
            })
        }
        None => None,
    })
}

/// A run between two sampling instants: the plant and its integrator, the
/// controllers, the sampler, the mode chain, the state, and the tallies of
/// the metrics.
struct Run<'a> {
    plan: &'a Plan<'a>,
    /// Controller states (the first `n` of the plant's).
    n: usize,
    plant: Plant<'a>,
    signals: Signals<'a>,
    stepper: Stepper,
    sampler: Sampler,
    controller: Box<dyn Law + 'a>,
    /// The controller of each mode (mode-dependent gains); empty: `controller`.
    mode_laws: Vec<Box<dyn Law + 'a>>,
    chain: Option<Chain>,
    region: Region<'a>,
    premises: Option<Premises>,
    /// Plant state.
    x: Vec<f64>,
    /// Static output feedback: the measured output the controller reads.
    measure: Option<super::measure::Measure>,
    /// What the controller reads at the sample: the state, or y = C x + noise.
    seen: Vec<f64>,
    /// Premise vector z(x).
    z: Vec<f64>,
    /// Held command.
    u: Vec<f64>,
    /// Firing strengths at the sample.
    h_now: Vec<f64>,
    tally: Tally,
    mismatch: MismatchTally,
    rates: RateTally,
    saturated: u64,
    nonfinite_at: Option<f64>,
    progress: Progress,
    t: f64,
    /// Grid index of the sampling schedule.
    k: u64,
    /// A sampled loop with modes: a mode jump between samples is not a
    /// sample; the command is re-blended from the held sample with the new
    /// mode's gains (the mode is known continuously, docs/xue2024.md).
    sampled_modes: bool,
    /// The held sample (state, premise vector).
    held: (Vec<f64>, Vec<f64>),
    /// Whether the last step ended at a mode jump.
    at_jump: bool,
    /// The sampling instant a jump cut the step short of, still ahead.
    pending: Option<f64>,
    /// Continuous monitoring: each crossing is located to this time tolerance.
    monitor_tol: f64,
}

impl<'a> Run<'a> {
    /// The run of `prepared` with the `plant` of `truth` at the start of `plan`.
    fn new(
        prepared: &'a Prepared,
        truth: &'a tsf_lang::Spec,
        opts: &Options,
        plant: Plant<'a>,
        plan: &'a Plan<'a>,
        terms: &'a [Vec<Term<'a, f64>>],
        mode_tables: &'a [Tables],
    ) -> Result<Self, SimError> {
        let (model, tables) = (&prepared.model, &prepared.tables);
        let spec = &model.spec;
        let n = spec.n();
        let m = spec.m();
        let dim = plant.dim();
        let (t0, t1, h) = (plan.t0, plan.t1, plan.h);
        let x = plan.x0.clone();
        let sampler = sampler(
            spec,
            plan.trigger,
            n,
            t0,
            h,
            plan.seed,
            prepared.trigger_weight.as_ref(),
            &prepared.p,
        )?;
        let (rtol, atol) = opts.tolerances;
        let stepper = match plan.integrator {
            Integrator::Rk4 => Stepper::Rk4(Rk4::new(dim, h)),
            Integrator::Dopri5 => Stepper::Dopri5(Dopri5::new(dim, rtol, atol, h)),
        };
        let controller = law(tables, terms)?;
        let mode_laws = mode_tables
            .iter()
            .map(|t| law(t, terms))
            .collect::<Result<Vec<_>, _>>()?;
        let chain = mode_chain(spec, truth, plan)?;
        let z = vec![0.0; tables.p];
        let sampled_modes =
            chain.is_some() && plan.trigger.is_some_and(|t| *t != Trigger::Continuous);
        Ok(Run {
            plan,
            n,
            region: Region::new(model, tables),
            premises: Premises::new(tables, opts.evaluator),
            signals: Signals::new(truth, &prepared.source, opts.evaluator),
            u: vec![0.0; m],
            tally: Tally::new(n, m, &x, opts.convergence_rel_tol),
            mismatch: MismatchTally::new(crate::synth::relaxations::kappa_relied_on(model)),
            rates: RateTally::new(crate::synth::lyapunov::fuzzy::phi(model).map(<[f64]>::to_vec)),
            h_now: vec![0.0; tables.r],
            saturated: 0,
            nonfinite_at: None,
            progress: Progress::new(opts.progress, t0, t1),
            t: t0,
            k: 0,
            sampled_modes,
            held: (vec![0.0; tables.n], z.clone()),
            measure: tables.static_output.as_ref().map(|so| {
                let noise = super::observer::or_spec_noise(opts.observer.noise, spec);
                super::measure::Measure::new(so.c.clone(), noise, plan.seed)
            }),
            seen: vec![0.0; tables.n],
            at_jump: false,
            pending: None,
            monitor_tol: (h * 1e-6).max(1e-12),
            plant,
            stepper,
            sampler,
            controller,
            mode_laws,
            chain,
            x,
            z,
        })
    }

    /// The sampling instant `t`: the mode jumps due by now, the gate's
    /// decision, the command, the tallies. Returns whether the sample was
    /// transmitted and the mode.
    fn sample(&mut self) -> (bool, Option<usize>) {
        let (n, t) = (self.n, self.t);
        // Jumps of the mode process due by now.
        let mode = self.chain.as_mut().map(|c| {
            while c.process.next_jump() <= t {
                let at = c.process.next_jump();
                c.process.jump();
                c.tally.jump(at, c.process.mode());
            }
            c.process.mode()
        });
        let rejump = self.sampled_modes && std::mem::take(&mut self.at_jump);
        let sent = !rejump && self.sampler.gate.decide(&self.x[..n]);
        let mut no_rule = false;
        match self.measure.as_mut() {
            Some(m) => m.sample(&self.x[..n], &mut self.seen),
            None => self.seen.copy_from_slice(&self.x[..n]),
        }
        if let Some(p) = self.premises.as_mut() {
            p.eval(&self.seen, &mut self.z);
        }
        self.controller.strengths(
            &self.seen,
            self.premises.as_ref().map(|_| &self.z[..]),
            &mut self.h_now,
        );
        self.mismatch.sample(&self.h_now, sent);
        self.rates.sample(t, &self.h_now);
        if sent && self.sampled_modes {
            self.held.0.copy_from_slice(&self.seen);
            self.held.1.copy_from_slice(&self.z);
        }
        if sent || (rejump && !self.mode_laws.is_empty()) {
            no_rule = self.command(mode, sent);
        }
        let in_region = match &self.premises {
            Some(_) => self.region.contains_premises(&self.z),
            None => self.region.contains(&self.seen),
        };
        self.tally.sample(&Sample {
            t,
            x: &self.x,
            u: &self.u,
            sent,
            no_rule,
            in_region,
        });
        if let (Some(c), Some(a)) = (self.chain.as_mut(), mode) {
            c.tally.sample(a, &self.u);
        }
        (sent, mode)
    }

    /// A new held command: the mode's controller (mode-dependent gains), else
    /// the one law, on the sample (`sent`; at a jump of a sampled loop: the
    /// held one). Whether no rule fired.
    fn command(&mut self, mode: Option<usize>, sent: bool) -> bool {
        let ctl = match mode {
            Some(a) if !self.mode_laws.is_empty() => {
                &self.mode_laws[a.min(self.mode_laws.len() - 1)]
            }
            _ => &self.controller,
        };
        let (xs, zs) = if sent {
            (&self.seen[..], &self.z[..])
        } else {
            (&self.held.0[..], &self.held.1[..])
        };
        let flags = match &self.premises {
            Some(_) => ctl.command_with(xs, zs, &mut self.u),
            None => ctl.command(xs, &mut self.u),
        };
        self.saturated += u64::from(flags.contains(Flags::SATURATED) && sent);
        flags.contains(Flags::NO_RULE_FIRED)
    }

    /// Integrates the plant with the held command to the next sampling
    /// instant, or to a mode jump, or to the crossing of a continuously
    /// monitored trigger, whichever comes first (the `mode` of this sample).
    fn advance(&mut self, mode: Option<usize>) -> Result<(), SimError> {
        let (n, t, t1, h) = (self.n, self.t, self.plan.t1, self.plan.h);
        let mut t_next = self
            .pending
            .take()
            .unwrap_or_else(|| self.sampler.schedule.next(self.k, t))
            .min(t1);
        // Snap to the end instead of leaving a sliver of an interval.
        if t1 - t_next < 1e-9 * h {
            t_next = t1;
        }
        // A mode jump ends the step early: the plant switches at the jump.
        let mut jumps = false;
        if let Some(c) = self.chain.as_mut() {
            if c.process.next_jump() < t_next {
                self.pending = Some(t_next);
                t_next = c.process.next_jump();
                jumps = true;
            }
            if let Some(a) = mode {
                c.actuation.plant_input(a, &self.u, &mut c.u_plant);
            }
        }
        let (u_plant, given) = match (&self.chain, mode) {
            (Some(c), Some(a)) => (&c.u_plant, Some((&c.actuation, a))),
            _ => (&self.u, None),
        };
        let (signals, plant, u) = (&mut self.signals, &mut self.plant, &self.u);
        let mut rhs = |tt: f64, y: &[f64], dy: &mut [f64]| {
            let w = signals.at(tt)?;
            plant.rhs(tt, y, u_plant, w, dy)?;
            if let Some((act, a)) = given {
                act.add_given(a, u, &mut dy[..n]);
            }
            Ok::<(), SimError>(())
        };
        let start = self.sampler.continuous.then(|| self.x.clone());
        self.stepper.advance(&mut rhs, t, t_next, &mut self.x)?;
        let mut located = false;
        if let Some(x_start) = start {
            let tol = self.monitor_tol;
            if self.sampler.gate.would_transmit(&self.x[..n]) && t_next - t > tol {
                // Bisect the crossing: re-integrate from the step's start state.
                let (mut lo, mut hi) = (t, t_next);
                let mut x_hi = self.x.clone();
                while hi - lo > tol {
                    let mid = 0.5 * (lo + hi);
                    let mut y = x_start.clone();
                    self.stepper.advance(&mut rhs, t, mid, &mut y)?;
                    if self.sampler.gate.would_transmit(&y[..n]) {
                        hi = mid;
                        x_hi = y;
                    } else {
                        lo = mid;
                    }
                }
                located = hi < t_next;
                t_next = hi;
                self.x = x_hi;
            }
        }
        self.t = t_next;
        // A located crossing or a mode jump ends the step early: the grid
        // point is still ahead.
        if !located && !jumps {
            self.k += 1;
        }
        self.at_jump = jumps;
        if !self
            .x
            .iter()
            .all(|v| v.is_finite() && v.abs() <= MAX_STATE_MAGNITUDE)
        {
            self.nonfinite_at = Some(self.t);
        }
        self.progress.update(self.t);
        Ok(())
    }

    /// The outcome of the finished run (`last_sent`: whether its last sample
    /// was transmitted), with the `trace` to fill.
    fn finish(
        self,
        prepared: &Prepared,
        opts: &Options,
        last_sent: bool,
        trace: Trace,
        started: Instant,
    ) -> Outcome {
        let (spec, tables) = (&prepared.model.spec, &prepared.tables);
        let (n, dim, plan) = (self.n, self.plant.dim(), self.plan);
        let (t1, h) = (plan.t1, plan.h);
        let (rtol, atol) = opts.tolerances;
        let last = Sample {
            t: self.t,
            x: &self.x,
            u: &self.u,
            sent: last_sent,
            no_rule: false,
            in_region: true,
        };
        let facts = RunFacts {
            u_max: tables.u_max.clone(),
            t_end: t1,
            saturated: self.saturated,
            nonfinite_at: self.nonfinite_at,
            p: &prepared.p,
        };
        let (mut metrics, trace) = self.tally.finish(&facts, &last, trace);
        self.mismatch.finish(&mut metrics);
        self.rates.finish(&mut metrics);
        metrics.integrator = match &self.stepper {
            Stepper::Rk4(s) => format!("rk4, fixed step <= {} s", s.h),
            Stepper::Dopri5(s) => format!(
                "dopri5, rtol = {rtol:e}, atol = {atol:e}, h_max = {h} s, {} accepted / {} rejected steps",
                s.accepted, s.rejected
            ),
        };
        metrics.rhs_evaluations = self.stepper.evals();
        metrics.trigger = describe_trigger(plan.trigger);
        if let Some(src) = self.sampler.weight_source {
            metrics.trigger.push_str("; trigger weight U: ");
            metrics.trigger.push_str(src.describe());
        }
        metrics.final_nu = self.sampler.gate.nu();
        if let Some(Trigger::Mixed { monitor, .. }) = plan.trigger {
            (metrics.monitor, metrics.monitor_step) = match monitor {
                Monitor::Step => (Some("step".into()), Some(h)),
                Monitor::Continuous => (Some("continuous".into()), Some(self.monitor_tol)),
                Monitor::Sampling(..) => (None, None),
            };
        }
        metrics.seed = plan.seed;
        let mut trace = trace;
        if let (Some(c), Some(modes)) = (self.chain, &spec.modes) {
            let (mm, switches) = c.tally.finish(t1, modes.design.keyword(), c.seed);
            metrics.modes = Some(mm);
            trace.modes = switches;
            trace.mode_names = modes.modes.iter().map(|m| m.name.clone()).collect();
        }
        let sim_dynamics = spec.simulate.as_ref().is_some_and(|s| s.dynamics.is_some());
        metrics.plant = if dim > n || sim_dynamics {
            format!(
                "the spec's dynamics block ({dim} states, {} not seen by the controller)",
                dim - n
            )
        } else {
            "the design model x' = A(x) x + B(x) sat(u) + D(x) w".into()
        };
        metrics.wall_time_s = started.elapsed().as_secs_f64();
        Outcome {
            name: spec.controller.node.clone(),
            spec: std::path::Path::new(&prepared.source.name)
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default(),
            trace,
            metrics,
            u_max: tables.u_max.clone(),
            n,
        }
    }
}
