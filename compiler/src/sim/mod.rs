//! `tsfc simulate`: the spec's `simulate` scenario in closed loop.
//!
//! The controller in the loop is `tsf_runtime::Controller` with the design's
//! gain tables ([`controller`]); the truth plant is the design model or the
//! spec's `dynamics` block ([`plant`]); disturbances are the scenario's
//! signals ([`signal`]); the plant, the signals and the premise vector
//! ([`premise`]) run as straight-line code compiled once per run ([`tape`]),
//! or through the language's evaluator ([`Evaluator`]); sampling and
//! transmission follow the triggering law with the runtime's trigger state
//! machines ([`trigger`]); the plant is integrated with RK4 or
//! Dormand-Prince 5(4) between sampling instants ([`integrator`]) with the
//! command held (zero-order hold). Outputs: a CSV
//! trace streamed to disk ([`csv`]), metrics ([`metrics`]), SVG and PNG plots
//! of a thinned trace ([`plot`]); memory does not grow with the run's length,
//! and the run's size is bounded by [`limits`]. Samples outside the premise
//! region ([`region`]) are counted; errors caused by a spec item point into
//! the spec ([`source`]). The design comes from the driver
//! (`crate::driver::prepare`). Monte Carlo campaigns
//! ([`campaign`]) and sweeps of triggering laws with a comparison table
//! ([`sweep`]) run many scenarios on a worker pool. A spec with `modes`
//! runs under a seeded Markov mode process ([`modes`]).

pub mod adaptive;
pub mod campaign;
pub mod controller;
pub mod csv;
pub mod integrator;
pub mod limits;
pub mod measure;
pub mod metrics;
pub mod modes;
pub mod observer;
pub mod plant;
pub mod plot;
pub mod premise;
pub mod region;
pub mod scenario;
pub mod signal;
pub mod source;
pub mod sweep;
#[cfg(test)]
mod tape_agreement;
pub use crate::tape;
pub mod trigger;

pub use metrics::{Metrics, Trace};
pub use scenario::{run, run_truth, Outcome};

use crate::model::TsModel;
use crate::tables::Tables;
use nalgebra::DMatrix;
use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::time::Instant;
use tsf_lang::spec::{Integrator, Trigger};

/// A simulation failure: the pipeline's error (its kind decides the exit code).
pub type SimError = crate::util::error::Error;
pub use crate::util::error::ErrorKind;

/// How the plant, the disturbance signals and the premise vector are evaluated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Evaluator {
    /// Compiled once into straight-line code ([`tape`]); an expression the
    /// tape cannot express, and any evaluation that divides by zero, goes
    /// to the interpreter.
    #[default]
    Compiled,
    /// The language's evaluator at every call (the reference path the
    /// compiled code is tested against).
    Interpreter,
}

/// Overrides of the spec's scenario.
#[derive(Debug, Clone)]
pub struct Options {
    /// Simulate `t0 .. t0 + horizon` instead of the spec's span.
    pub horizon: Option<f64>,
    /// Initial state (n values, or n + extra states).
    pub x0: Option<Vec<f64>>,
    /// Triggering law instead of the spec's.
    pub trigger: Option<Trigger>,
    /// Integrator instead of the spec's.
    pub integrator: Option<Integrator>,
    /// Sampling-pattern seed instead of the spec's.
    pub seed: Option<u64>,
    /// Dormand-Prince `(rtol, atol)`.
    pub tolerances: (f64, f64),
    /// `converged` means `||x(t_end)|| <= convergence_rel_tol * ||x0||` (in `(0, 1]`).
    pub convergence_rel_tol: f64,
    /// Show progress on stderr for runs longer than a second: a bar on a
    /// terminal, else a line every [`limits::PROGRESS_LOG_PERIOD_S`] seconds.
    pub progress: bool,
    /// How expressions are evaluated.
    pub evaluator: Evaluator,
    /// The initial estimate and the measurement noise of an observer-based
    /// design (ignored otherwise).
    pub observer: observer::ObserverScenario,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            horizon: None,
            x0: None,
            trigger: None,
            integrator: None,
            seed: None,
            tolerances: (1e-6, 1e-9),
            convergence_rel_tol: 0.05,
            progress: false,
            evaluator: Evaluator::Compiled,
            observer: observer::ObserverScenario::default(),
        }
    }
}

/// A certified design ready to simulate.
#[derive(Debug, Clone)]
pub struct Prepared {
    /// The checked model.
    pub model: TsModel,
    /// The gain tables (what generated code declares).
    pub tables: Tables,
    /// Lyapunov matrix P.
    pub p: DMatrix<f64>,
    /// The design's trigger weight, if it has one.
    pub trigger_weight: Option<DMatrix<f64>>,
    /// The certified region of attraction {x : x'Ux <= 1} as U, when the
    /// design certifies one (saturation region): a scenario that starts
    /// outside it is warned about.
    pub region: Option<DMatrix<f64>>,
    /// The spec's text, for errors that point into it.
    pub source: source::SpecSource,
}

/// Runs the scenario of a prepared design (no CSV; the outcome's trace is
/// thinned for plotting).
pub fn simulate(prepared: &Prepared, opts: &Options) -> Result<Outcome, SimError> {
    run(prepared, opts, None)
}

/// Runs the scenario, streaming the CSV trace to `csv` as it is computed.
pub fn simulate_csv(
    prepared: &Prepared,
    opts: &Options,
    csv: &mut dyn Write,
) -> Result<Outcome, SimError> {
    run(prepared, opts, Some(csv))
}

/// Runs the scenario and writes `<name>.csv` (streamed while the loop runs),
/// `<name>.metrics.json` and the plots (`<name>.{states,inputs,events}.{svg,png}`)
/// into `dir`, each atomically: if the run fails, no existing file changes.
pub fn simulate_to(
    prepared: &Prepared,
    opts: &Options,
    dir: &Path,
) -> Result<(Outcome, Vec<PathBuf>), SimError> {
    // Refuse bad settings before touching the folder.
    let dim = plant::Plant::new(
        &prepared.model.spec,
        &prepared.source,
        Evaluator::Interpreter,
    )?
    .dim();
    scenario::plan(prepared, opts, dim)?;
    let path = dir.join(format!("{}.csv", prepared.model.spec.controller.node));
    let io_err =
        |e: std::io::Error| SimError::usage(format!("cannot write `{}`: {e}", path.display()));
    let mut file = csv::AtomicFile::create(&path).map_err(io_err)?;
    let outcome = run(prepared, opts, Some(file.writer()))?;
    file.commit().map_err(io_err)?;
    let mut written = vec![path.clone()];
    written.extend(write_outputs(&outcome, dir)?);
    Ok((outcome, written))
}

/// Writes `<name>.metrics.json` and the plots of `outcome` into `dir`, atomically.
pub fn write_outputs(outcome: &Outcome, dir: &Path) -> Result<Vec<PathBuf>, SimError> {
    let name = &outcome.name;
    let json = serde_json::to_string_pretty(&outcome.metrics)
        .map_err(|e| SimError::usage(format!("cannot serialize the metrics: {e}")))?;
    let mut files: Vec<(String, Vec<u8>)> =
        vec![(format!("{name}.metrics.json"), (json + "\n").into_bytes())];
    files.extend(plot::plots(outcome)?);
    let mut written = Vec::new();
    for (file, bytes) in files {
        let path = dir.join(file);
        crate::util::output::write_atomic(&path, &bytes)
            .map_err(|e| SimError::usage(format!("cannot write `{}`: {e}", path.display())))?;
        written.push(path);
    }
    Ok(written)
}

/// Progress on stderr for runs longer than a second: a bar redrawn at most
/// 10 times a second when stderr is a terminal, else a plain line every
/// [`limits::PROGRESS_LOG_PERIOD_S`] seconds.
pub struct Progress {
    enabled: bool,
    terminal: bool,
    started: Instant,
    t0: f64,
    t1: f64,
    last_draw: Option<Instant>,
}

impl Progress {
    /// Progress of simulated time `t0 .. t1`.
    pub fn new(enabled: bool, t0: f64, t1: f64) -> Self {
        Progress {
            enabled,
            terminal: std::io::stderr().is_terminal(),
            started: Instant::now(),
            t0,
            t1,
            last_draw: None,
        }
    }

    /// Reports simulated time `t`.
    pub fn update(&mut self, t: f64) {
        if !self.enabled {
            return;
        }
        let elapsed = self.started.elapsed().as_secs_f64();
        let period = if self.terminal {
            0.1
        } else {
            limits::PROGRESS_LOG_PERIOD_S
        };
        let since = self
            .last_draw
            .map_or(elapsed, |d| d.elapsed().as_secs_f64());
        if elapsed < 1.0_f64.max(if self.terminal { 0.0 } else { period }) || since < period {
            return;
        }
        self.last_draw = Some(Instant::now());
        let frac = ((t - self.t0) / (self.t1 - self.t0)).clamp(0.0, 1.0);
        let mut err = std::io::stderr().lock();
        if self.terminal {
            let width = 40;
            let filled = (frac * width as f64) as usize;
            let _ = write!(
                err,
                "\r  simulating [{}{}] {:5.1}%  t = {t:.3} s  ({elapsed:.1} s)",
                "#".repeat(filled),
                "-".repeat(width - filled),
                100.0 * frac,
            );
        } else {
            let _ = writeln!(
                err,
                "  simulating: {:5.1}% (t = {t:.3} s of {} s), {elapsed:.0} s elapsed",
                100.0 * frac,
                self.t1
            );
        }
        let _ = err.flush();
    }

    /// Clears the bar's line if one was drawn.
    pub fn finish(&mut self) {
        if self.terminal && self.last_draw.is_some() {
            let _ = write!(std::io::stderr().lock(), "\r{}\r", " ".repeat(78));
        }
    }
}
