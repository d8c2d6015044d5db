//! The recorded trajectory and the figures of merit computed from it.

use serde::Serialize;

/// The trajectory at the sampling instants (the command is held until the next row).
#[derive(Debug, Clone, Default)]
pub struct Trace {
    /// Column names: states (controller, then extra), inputs.
    pub state_names: Vec<String>,
    /// Input component names.
    pub input_names: Vec<String>,
    /// Sampling instants.
    pub t: Vec<f64>,
    /// Plant state at each instant.
    pub x: Vec<Vec<f64>>,
    /// Command applied from each instant on (saturated).
    pub u: Vec<Vec<f64>>,
    /// Whether the sample was transmitted (the controller recomputed `u`).
    pub sent: Vec<bool>,
}

impl Trace {
    /// The trace as CSV: `t, <states>, <inputs>, transmitted`; numbers in
    /// Rust's shortest round-trip format, so the text is deterministic.
    pub fn csv(&self) -> String {
        let mut out = String::from("t");
        for name in self.state_names.iter().chain(&self.input_names) {
            out.push(',');
            out.push_str(name);
        }
        out.push_str(",transmitted\n");
        for (((t, x), u), sent) in self.t.iter().zip(&self.x).zip(&self.u).zip(&self.sent) {
            out.push_str(&t.to_string());
            for v in x.iter().chain(u) {
                out.push(',');
                out.push_str(&v.to_string());
            }
            out.push_str(if *sent { ",1\n" } else { ",0\n" });
        }
        out
    }
}

/// Figures of merit of one run (written as `<controller>.metrics.json`).
#[derive(Debug, Clone, Serialize)]
pub struct Metrics {
    /// `final_state_norm <= convergence_tolerance` and the run finished.
    pub converged: bool,
    /// The tolerance used: `convergence_rel_tol * ||x0||` (controller states).
    pub convergence_tolerance: f64,
    /// Relative tolerance (fraction of `||x0||`).
    pub convergence_rel_tol: f64,
    /// `||x(t_end)||` over the controller's states.
    pub final_state_norm: f64,
    /// `||x0||` over the controller's states.
    pub initial_state_norm: f64,
    /// `max_t |u_s(t)|` per input channel.
    pub max_abs_u: Vec<f64>,
    /// Saturation levels (null where unlimited).
    pub u_max: Vec<Option<f64>>,
    /// Sampling instants (including t0).
    pub samples: u64,
    /// Transmitted samples (controller updates).
    pub transmissions: u64,
    /// Mean time between transmissions (null with fewer than 2).
    pub mean_inter_event_s: Option<f64>,
    /// Shortest time between transmissions (null with fewer than 2).
    pub min_inter_event_s: Option<f64>,
    /// Longest time between transmissions (null with fewer than 2).
    pub max_inter_event_s: Option<f64>,
    /// `integral ||u||^2 dt` (exact for the held command).
    pub energy: f64,
    /// First time after which `||x|| <= convergence_tolerance` holds at every
    /// sample until the end (null if never).
    pub settle_time_s: Option<f64>,
    /// Samples at which the runtime clipped the command.
    pub saturated_samples: u64,
    /// The time at which the state became NaN or infinite (null if never).
    pub nonfinite_at_s: Option<f64>,
    /// Time span simulated.
    pub time_s: (f64, f64),
    /// Integrator and its settings.
    pub integrator: String,
    /// Right-hand side evaluations.
    pub rhs_evaluations: u64,
    /// Trigger law and, for relative triggers, where the weight came from.
    pub trigger: String,
    /// Final relative threshold nu (relative/adaptive triggers).
    pub final_nu: Option<f64>,
    /// Sampling-pattern seed.
    pub seed: u64,
    /// Truth plant used.
    pub plant: String,
    /// Wall-clock time of the run (not part of any deterministic output).
    #[serde(skip)]
    pub wall_time_s: f64,
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|a| a * a).sum::<f64>().sqrt()
}

/// Facts about the run that the trace does not contain.
pub struct RunFacts {
    /// Controller states.
    pub n: usize,
    /// Saturation levels.
    pub u_max: Vec<f64>,
    /// Relative convergence tolerance.
    pub rel_tol: f64,
    /// Final time of the scenario.
    pub t_end: f64,
    /// Saturated samples.
    pub saturated: u64,
    /// Non-finite time.
    pub nonfinite_at: Option<f64>,
}

/// Computes the figures of merit (descriptive fields left for the caller).
pub fn compute(trace: &Trace, facts: &RunFacts) -> Metrics {
    let n = facts.n;
    let xnorm = |x: &Vec<f64>| norm(&x[..n.min(x.len())]);
    let x0 = trace.x.first().map_or(0.0, xnorm);
    let tol = facts.rel_tol * x0;
    let fin = trace.x.last().map_or(f64::NAN, xnorm);
    let m = trace.input_names.len();
    let mut max_abs_u = vec![0.0f64; m];
    for u in &trace.u {
        for (mx, v) in max_abs_u.iter_mut().zip(u) {
            *mx = mx.max(v.abs());
        }
    }
    let mut energy = 0.0;
    for k in 0..trace.t.len() {
        let t_next = trace
            .t
            .get(k + 1)
            .copied()
            .unwrap_or(facts.t_end.max(trace.t[k]));
        let u2: f64 = trace.u[k].iter().map(|v| v * v).sum();
        energy += u2 * (t_next - trace.t[k]);
    }
    let events: Vec<f64> = trace
        .t
        .iter()
        .zip(&trace.sent)
        .filter_map(|(t, s)| s.then_some(*t))
        .collect();
    let gaps: Vec<f64> = events.windows(2).map(|w| w[1] - w[0]).collect();
    let mut settle = None;
    for (t, x) in trace.t.iter().zip(&trace.x).rev() {
        if xnorm(x) <= tol {
            settle = Some(*t);
        } else {
            break;
        }
    }
    let finished = facts.nonfinite_at.is_none();
    Metrics {
        converged: finished && fin <= tol,
        convergence_tolerance: tol,
        convergence_rel_tol: facts.rel_tol,
        final_state_norm: fin,
        initial_state_norm: x0,
        max_abs_u,
        u_max: facts
            .u_max
            .iter()
            .map(|&v| v.is_finite().then_some(v))
            .collect(),
        samples: trace.t.len() as u64,
        transmissions: events.len() as u64,
        mean_inter_event_s: (!gaps.is_empty())
            .then(|| gaps.iter().sum::<f64>() / gaps.len() as f64),
        min_inter_event_s: gaps.iter().copied().reduce(f64::min),
        max_inter_event_s: gaps.iter().copied().reduce(f64::max),
        energy,
        settle_time_s: if finished { settle } else { None },
        saturated_samples: facts.saturated,
        nonfinite_at_s: facts.nonfinite_at,
        time_s: (trace.t.first().copied().unwrap_or(0.0), facts.t_end),
        integrator: String::new(),
        rhs_evaluations: 0,
        trigger: String::new(),
        final_nu: None,
        seed: 0,
        plant: String::new(),
        wall_time_s: 0.0,
    }
}
