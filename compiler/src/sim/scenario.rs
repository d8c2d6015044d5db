//! The closed loop: sample, decide, update the held command, integrate to the
//! next sampling instant.

use super::controller::{law, runtime_terms};
use super::integrator::{Dopri5, Rk4, Stepper};
use super::metrics::{compute, Metrics, RunFacts, Trace};
use super::plant::Plant;
use super::signal::Signals;
use super::trigger::sampler;
use super::{Options, Progress, SimError};
use crate::model::TsModel;
use crate::tables::Tables;
use nalgebra::DMatrix;
use std::time::Instant;
use tsf_lang::spec::{Integrator, Trigger};
use tsf_runtime::Flags;

/// A finished run.
#[derive(Debug, Clone)]
pub struct Outcome {
    /// Controller name (file stem of the outputs).
    pub name: String,
    /// The trajectory at the sampling instants.
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
            sampling,
            beta,
            rho,
        }) => format!(
            "aperiodic sampling in [{}, {}] s; mixed ||e|| >= {beta} ||x|| + {rho}",
            sampling.0, sampling.1
        ),
    }
}

/// Runs the spec's scenario in closed loop with the runtime controller built
/// from `tables`. `p` is the design's Lyapunov matrix and `design_weight` its
/// trigger weight, if any (used for `weight = synthesize`).
pub fn run(
    model: &TsModel,
    tables: &Tables,
    p: &DMatrix<f64>,
    design_weight: Option<&DMatrix<f64>>,
    opts: &Options,
) -> Result<Outcome, SimError> {
    let started = Instant::now();
    let spec = &model.spec;
    let sim = spec
        .simulate
        .as_ref()
        .ok_or_else(|| SimError::spec("the spec has no `simulate { ... }` block"))?;
    let n = spec.n();
    let m = spec.m();
    let (t0, spec_t1, h) = sim.time;
    let t1 = opts.horizon.map_or(spec_t1, |hz| t0 + hz);
    if !(h > 0.0 && t1 > t0 && t1.is_finite()) {
        return Err(SimError::spec(format!(
            "invalid time span {t0} .. {t1} step {h}"
        )));
    }
    let plant = Plant::new(spec)?;
    let dim = plant.dim();
    let mut x = opts.x0.clone().unwrap_or_else(|| sim.x0.clone());
    if x.len() == n {
        x.resize(dim, 0.0);
    }
    if x.len() != dim {
        return Err(SimError::usage(format!(
            "x0 has {} components; the plant has {n} controller states{}",
            x.len(),
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
    let trigger = opts
        .trigger
        .as_ref()
        .or(spec.trigger.as_ref().map(|t| &t.node));
    let seed = opts.seed.unwrap_or(sim.seed);
    let mut sampler = sampler(trigger, n, t0, h, seed, design_weight, p)?;
    let integrator = opts.integrator.unwrap_or(sim.integrator);
    let (rtol, atol) = opts.tolerances;
    let mut stepper = match integrator {
        Integrator::Rk4 => Stepper::Rk4(Rk4::new(dim, h)),
        Integrator::Dopri5 => Stepper::Dopri5(Dopri5::new(dim, rtol, atol, h)),
    };
    let terms = runtime_terms(tables);
    let controller = law(tables, &terms)?;
    let signals = Signals::new(spec);
    let mut w = vec![0.0; signals.len()];
    let mut u = vec![0.0; m];
    let mut trace = Trace {
        state_names: tables
            .state_names
            .iter()
            .cloned()
            .chain(plant.extra_names())
            .collect(),
        input_names: tables.input_names.clone(),
        ..Trace::default()
    };
    let mut saturated = 0u64;
    let mut nonfinite_at = None;
    let mut progress = Progress::new(opts.progress, t0, t1);
    let mut t = t0;
    let mut k = 0u64;
    loop {
        let sent = sampler.gate.decide(&x[..n]);
        if sent {
            let flags = controller.command(&x[..n], &mut u);
            if flags.contains(Flags::SATURATED) {
                saturated += 1;
            }
        }
        trace.t.push(t);
        trace.x.push(x.clone());
        trace.u.push(u.clone());
        trace.sent.push(sent);
        if t >= t1 || nonfinite_at.is_some() {
            break;
        }
        let mut t_next = sampler.schedule.next(k, t).min(t1);
        // Snap to the end instead of leaving a sliver of an interval.
        if t1 - t_next < 1e-9 * h {
            t_next = t1;
        }
        let mut rhs = |tt: f64, y: &[f64], dy: &mut [f64]| {
            signals.eval(tt, &mut w)?;
            plant.rhs(tt, y, &u, &w, dy)
        };
        stepper.advance(&mut rhs, t, t_next, &mut x)?;
        t = t_next;
        k += 1;
        if !x.iter().all(|v| v.is_finite()) {
            nonfinite_at = Some(t);
        }
        progress.update(t);
    }
    progress.finish();
    let mut metrics = compute(
        &trace,
        &RunFacts {
            n,
            u_max: tables.u_max.clone(),
            rel_tol: opts.convergence_rel_tol,
            t_end: t1,
            saturated,
            nonfinite_at,
        },
    );
    metrics.integrator = match &stepper {
        Stepper::Rk4(s) => format!("rk4, fixed step <= {} s", s.h),
        Stepper::Dopri5(s) => format!(
            "dopri5, rtol = {rtol:e}, atol = {atol:e}, h_max = {h} s, {} accepted / {} rejected steps",
            s.accepted, s.rejected
        ),
    };
    metrics.rhs_evaluations = stepper.evals();
    metrics.trigger = describe_trigger(trigger);
    if let Some(src) = sampler.weight_source {
        metrics.trigger.push_str("; trigger weight U: ");
        metrics.trigger.push_str(src.describe());
    }
    metrics.final_nu = sampler.gate.nu();
    metrics.seed = seed;
    metrics.plant = if dim > n || sim.dynamics.is_some() {
        format!(
            "the spec's dynamics block ({dim} states, {} not seen by the controller)",
            dim - n
        )
    } else {
        "the design model x' = A(x) x + B(x) sat(u) + D(x) w".into()
    };
    metrics.wall_time_s = started.elapsed().as_secs_f64();
    Ok(Outcome {
        name: spec.controller.node.clone(),
        trace,
        metrics,
        u_max: tables.u_max.clone(),
        n,
    })
}
