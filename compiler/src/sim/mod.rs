//! `tsfc simulate`: the spec's `simulate` scenario in closed loop.
//!
//! The controller in the loop is `tsf_runtime::Controller` with the design's
//! gain tables ([`controller`]); the truth plant is the design model or the
//! spec's `dynamics` block ([`plant`]); disturbances are the scenario's
//! signals ([`signal`]); sampling and transmission follow the triggering law
//! with the runtime's trigger state machines ([`trigger`]); the plant is
//! integrated with RK4 or Dormand-Prince 5(4) between sampling instants
//! ([`integrator`]) with the command held (zero-order hold). Outputs: a CSV
//! trace and metrics ([`metrics`]), SVG and PNG plots ([`plot`]).

pub mod controller;
pub mod integrator;
pub mod metrics;
pub mod plant;
pub mod plot;
pub mod scenario;
pub mod signal;
pub mod trigger;

pub use metrics::{Metrics, Trace};
pub use scenario::{run, Outcome};

use crate::model::TsModel;
use crate::tables::Tables;
use nalgebra::DMatrix;
use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::time::Instant;
use tsf_lang::spec::{Integrator, Trigger};

/// A simulation failure: the pipeline's error (its kind decides the exit code).
pub type SimError = crate::error::Error;
pub use crate::error::ErrorKind;

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
    /// `converged` means `||x(t_end)|| <= convergence_rel_tol * ||x0||`.
    pub convergence_rel_tol: f64,
    /// Show a progress bar on stderr (only if it is a terminal and the run is long).
    pub progress: bool,
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
}

/// Reads, checks and compiles the spec at `path`; the design must be certified.
/// Spec diagnostics are rendered into the error message.
pub fn prepare(path: &Path) -> Result<Prepared, SimError> {
    let run = crate::pipeline::read(path)?.compile(&crate::synth::Settings::default())?;
    let tables = run.tables()?;
    let design = run.certified()?.0.clone();
    let model = run.model;
    // The synthesized trigger weight Upsilon (two-step method); without one,
    // `weight = synthesize` falls back to P / lambda_max(P) (see
    // `trigger::trigger_weight`).
    let trigger_weight = design.trigger.as_ref().map(|t| t.weight.clone());
    Ok(Prepared {
        model,
        tables,
        p: design.p,
        trigger_weight,
    })
}

/// Runs the scenario of a prepared design.
pub fn simulate(prepared: &Prepared, opts: &Options) -> Result<Outcome, SimError> {
    run(
        &prepared.model,
        &prepared.tables,
        &prepared.p,
        prepared.trigger_weight.as_ref(),
        opts,
    )
}

/// Writes `<name>.csv`, `<name>.metrics.json` and the plots
/// (`<name>.{states,inputs,events}.{svg,png}`) into `dir`, atomically.
pub fn write_outputs(outcome: &Outcome, dir: &Path) -> Result<Vec<PathBuf>, SimError> {
    let name = &outcome.name;
    let json = serde_json::to_string_pretty(&outcome.metrics)
        .map_err(|e| SimError::usage(format!("cannot serialize the metrics: {e}")))?;
    let mut files: Vec<(String, Vec<u8>)> = vec![
        (format!("{name}.csv"), outcome.trace.csv().into_bytes()),
        (format!("{name}.metrics.json"), (json + "\n").into_bytes()),
    ];
    files.extend(plot::plots(outcome)?);
    let mut written = Vec::new();
    for (file, bytes) in files {
        let path = dir.join(file);
        crate::report::write_atomic(&path, &bytes)
            .map_err(|e| SimError::usage(format!("cannot write `{}`: {e}", path.display())))?;
        written.push(path);
    }
    Ok(written)
}

/// A hand-written progress bar on stderr, shown only when stderr is a
/// terminal and the run has taken more than a second.
pub struct Progress {
    enabled: bool,
    started: Instant,
    t0: f64,
    t1: f64,
    last_draw: Option<Instant>,
}

impl Progress {
    /// A bar for simulated time `t0 .. t1`.
    pub fn new(enabled: bool, t0: f64, t1: f64) -> Self {
        Progress {
            enabled: enabled && std::io::stderr().is_terminal(),
            started: Instant::now(),
            t0,
            t1,
            last_draw: None,
        }
    }

    /// Report simulated time `t` (redraws at most 10 times a second).
    pub fn update(&mut self, t: f64) {
        if !self.enabled || self.started.elapsed().as_secs_f64() < 1.0 {
            return;
        }
        if self
            .last_draw
            .is_some_and(|d| d.elapsed().as_millis() < 100)
        {
            return;
        }
        self.last_draw = Some(Instant::now());
        let frac = ((t - self.t0) / (self.t1 - self.t0)).clamp(0.0, 1.0);
        let width = 40;
        let filled = (frac * width as f64) as usize;
        let mut err = std::io::stderr().lock();
        let _ = write!(
            err,
            "\r  simulating [{}{}] {:5.1}%  t = {t:.3} s  ({:.1} s)",
            "#".repeat(filled),
            "-".repeat(width - filled),
            100.0 * frac,
            self.started.elapsed().as_secs_f64()
        );
        let _ = err.flush();
    }

    /// Clears the bar's line if one was drawn.
    pub fn finish(&mut self) {
        if self.last_draw.is_some() {
            let _ = write!(std::io::stderr().lock(), "\r{}\r", " ".repeat(78));
        }
    }
}
