//! Closed-loop simulation of an adaptive design: the spec's truth plant
//! ([`crate::sim::plant::Plant`], e.g. a time-varying inertia) and
//! disturbance signals, integrated by RK4 with the command held over each
//! step; the runtime's [`tsf_runtime::AdaptiveLaw`] runs once per step (the
//! controller rate is the scenario's step) with the firing strengths of the
//! spec's rules (the nearest rule when none fires). Outputs: metrics with the
//! block's convergence claims, a CSV of states, inputs and every estimate
//! (thinned to at most [`MAX_ROWS`] rows), and a plot of the estimates.

use crate::model::TsModel;
use crate::model::{premise_values, rule_weight};
use crate::sim::plant::Plant;
use crate::sim::plot::chart::{self, colour, Figure, Mark, Panel, Shape, YAxis};
use crate::sim::signal::Signals;
use crate::sim::source::SpecSource;
use crate::sim::{Evaluator, SimError};
use crate::synth::adaptive::Design;
use serde::Serialize;
use tsf_lang::eval::{Mat, Mode};
use tsf_runtime::AdaptiveState;

/// Most rows of the CSV and the plotted trace (the run is thinned to them).
pub const MAX_ROWS: usize = 4000;
/// Most simulation steps of one run.
pub const MAX_STEPS: usize = 10_000_000;
/// A state norm above this is divergence.
pub const DIVERGED_NORM: f64 = 1e8;

/// One recorded sample.
#[derive(Debug, Clone)]
pub struct Sample {
    /// Time.
    pub t: f64,
    /// Plant state (controller states first).
    pub x: Vec<f64>,
    /// Command.
    pub u: Vec<f64>,
    /// Error signal s = C x.
    pub s: Vec<f64>,
    /// a_ik (rules x m x n).
    pub a_hat: Vec<f64>,
    /// b_ik (rules x m).
    pub b_hat: Vec<f64>,
    /// d.
    pub d_hat: f64,
}

/// A convergence claim of the block and whether the run met it.
#[derive(Debug, Clone, Serialize, schemars::JsonSchema)]
pub struct Claim {
    /// `|name| <= tol by t`.
    pub claim: String,
    /// Whether the norm stayed within `tol` from `by` to the end.
    pub held: bool,
    /// The largest norm after `by`.
    pub max_after: f64,
}

/// What the run did.
#[derive(Debug, Clone, Serialize, schemars::JsonSchema)]
pub struct Metrics {
    /// Controller steps.
    pub steps: usize,
    /// Final time.
    pub t_end: f64,
    /// ||x(t_end)||.
    pub final_state_norm: f64,
    /// Per state group, its final norm.
    pub final_norms: Vec<(String, f64)>,
    /// ||s(t_end)||.
    pub final_error_norm: f64,
    /// The block's claims.
    pub claims: Vec<Claim>,
    /// Smallest and largest a_ik, b_ik, d over the run.
    pub a_range: (f64, f64),
    /// b range.
    pub b_range: (f64, f64),
    /// d range.
    pub d_range: (f64, f64),
    /// Whether every estimate stayed within its projection bounds.
    pub estimates_within_bounds: bool,
    /// Steps with some state component outside the rules' operating range.
    pub steps_outside_operating_range: usize,
    /// Last time a state component was outside it.
    pub last_outside_s: Option<f64>,
    /// Steps where no rule fired (the nearest rule was used).
    pub steps_no_rule_fired: usize,
    /// Largest |u_k| per input.
    pub max_abs_u: Vec<f64>,
    /// Why the run stopped early (non-finite command, divergence), if it did.
    pub failure: Option<String>,
}

/// The result of a run.
#[derive(Debug, Clone)]
pub struct Run {
    /// The thinned trace.
    pub trace: Vec<Sample>,
    /// The metrics.
    pub metrics: Metrics,
    /// Controller name.
    pub name: String,
    /// State component names.
    pub state_names: Vec<String>,
}

/// Overrides of the scenario.
#[derive(Debug, Clone, Default)]
pub struct Options {
    /// Simulate `t0 .. t0 + horizon`.
    pub horizon: Option<f64>,
    /// Initial state.
    pub x0: Option<Vec<f64>>,
}

/// Normalized firing strengths at `x` (premises by the spec's evaluator);
/// `false` when no rule fired (one-hot at the nearest rule centre instead).
pub fn strengths(model: &TsModel, x: &[f64], h: &mut [f64]) -> Result<bool, SimError> {
    let z = premise_values(&model.spec, x).map_err(|d| SimError::spec(d.message))?;
    let mut sum = 0.0;
    for (hi, terms) in h.iter_mut().zip(&model.terms) {
        *hi = rule_weight(terms, &z);
        sum += *hi;
    }
    if sum > 0.0 && sum.is_finite() {
        h.iter_mut().for_each(|v| *v /= sum);
        return Ok(true);
    }
    let dist = |c: &Vec<f64>| {
        c.iter()
            .zip(&z)
            .map(|(a, b)| (a - b) * (a - b))
            .sum::<f64>()
    };
    let nearest = model
        .centers
        .iter()
        .enumerate()
        .min_by(|a, b| dist(a.1).total_cmp(&dist(b.1)))
        .map_or(0, |(i, _)| i);
    h.iter_mut()
        .enumerate()
        .for_each(|(i, v)| *v = f64::from(u8::from(i == nearest)));
    Ok(false)
}

fn widen(r: &mut (f64, f64), v: &[f64]) {
    for x in v {
        r.0 = r.0.min(*x);
        r.1 = r.1.max(*x);
    }
}

/// What a run tallies step by step for its [`Metrics`].
struct Tally {
    /// Smallest and largest a_ik, b_ik, d so far.
    a_range: (f64, f64),
    b_range: (f64, f64),
    d_range: (f64, f64),
    /// Steps outside the rules' operating range, and the last of them.
    outside: usize,
    last_outside: Option<f64>,
    /// Steps where no rule fired.
    no_rule: usize,
    /// Largest |u_k| per input.
    max_u: Vec<f64>,
    /// Per claim, the largest norm from its time on.
    claims_max: Vec<f64>,
    /// Why the run stopped early, if it did.
    failure: Option<String>,
}

impl Tally {
    /// The tally before the first step: the ranges hold the initial estimates.
    fn new(design: &Design, claims: usize) -> Self {
        let mut tally = Tally {
            a_range: (f64::INFINITY, f64::NEG_INFINITY),
            b_range: (f64::INFINITY, f64::NEG_INFINITY),
            d_range: (design.d0, design.d0),
            outside: 0,
            last_outside: None,
            no_rule: 0,
            max_u: vec![0.0_f64; design.m],
            claims_max: vec![0.0_f64; claims],
            failure: None,
        };
        widen(&mut tally.a_range, &design.a0);
        widen(&mut tally.b_range, &design.b0);
        tally
    }

    /// The metrics of a run that ended after step `k_done` at `t_end` in
    /// state `x`, with its recorded `trace`.
    fn metrics(
        self,
        spec: &tsf_lang::Spec,
        design: &Design,
        x: &[f64],
        trace: &[Sample],
        k_done: usize,
        t_end: f64,
    ) -> Metrics {
        let n = design.n;
        let converged = spec.adaptive.as_ref().map_or(&[][..], |a| &a.converged);
        let norm = |v: &[f64]| v.iter().map(|a| a * a).sum::<f64>().sqrt();
        let last = trace.last().cloned();
        let in_bounds = |r: (f64, f64), lo: f64, hi: f64| r.0 >= lo && r.1 <= hi;
        let estimates_within_bounds = in_bounds(self.a_range, design.a.lo, design.a.hi)
            && in_bounds(self.b_range, design.b.lo, design.b.hi)
            && in_bounds(self.d_range, design.d.lo, design.d.hi);
        let failure = self.failure;
        let claims = converged
            .iter()
            .zip(&self.claims_max)
            .map(|(c, mx)| Claim {
                claim: format!("|{}| <= {} by {}", c.name, c.tol, c.by),
                held: failure.is_none() && t_end >= c.by && *mx <= c.tol,
                max_after: *mx,
            })
            .collect();
        let final_norms = spec
            .states
            .iter()
            .map(|s| (s.name.clone(), norm(&x[s.offset..s.offset + s.len])))
            .collect();
        Metrics {
            steps: k_done,
            t_end,
            final_state_norm: norm(&x[..n]),
            final_norms,
            final_error_norm: last.as_ref().map_or(f64::NAN, |s| norm(&s.s)),
            claims,
            a_range: self.a_range,
            b_range: self.b_range,
            d_range: self.d_range,
            estimates_within_bounds,
            steps_outside_operating_range: self.outside,
            last_outside_s: self.last_outside,
            steps_no_rule_fired: self.no_rule,
            max_abs_u: self.max_u,
            failure,
        }
    }
}

/// The start, the step and the step count of a scenario's `time = t0 .. t1
/// step h` (the end moved by a `horizon` override); at most [`MAX_STEPS`].
fn time_grid(time: (f64, f64, f64), horizon: Option<f64>) -> Result<(f64, f64, usize), SimError> {
    let (t0, mut t1, h) = time;
    if let Some(hz) = horizon {
        t1 = t0 + hz;
    }
    let steps = ((t1 - t0) / h).round();
    if !(1.0..=MAX_STEPS as f64).contains(&steps) {
        return Err(SimError::spec(format!(
            "the run has {steps} steps; at most {MAX_STEPS} (docs/limits.md)"
        )));
    }
    Ok((t0, h, steps as usize))
}

/// One RK4 step of `x' = f(t, x)` from `t` over `h`, in the scratch vectors
/// `work` (k1, k2, k3, k4 and the stage state, each as long as `x`).
fn rk4_step(
    f: &mut impl FnMut(f64, &[f64], &mut [f64]) -> Result<(), SimError>,
    t: f64,
    h: f64,
    x: &mut [f64],
    work: &mut [Vec<f64>; 5],
) -> Result<(), SimError> {
    let [k1, k2, k3, k4, tmp] = work;
    let dim = x.len();
    f(t, x, k1)?;
    for i in 0..dim {
        tmp[i] = x[i] + 0.5 * h * k1[i];
    }
    f(t + 0.5 * h, tmp, k2)?;
    for i in 0..dim {
        tmp[i] = x[i] + 0.5 * h * k2[i];
    }
    f(t + 0.5 * h, tmp, k3)?;
    for i in 0..dim {
        tmp[i] = x[i] + h * k3[i];
    }
    f(t + h, tmp, k4)?;
    for i in 0..dim {
        x[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
    }
    Ok(())
}

/// Runs the scenario of `model` with `design`.
pub fn run(
    model: &TsModel,
    design: &Design,
    source: &SpecSource,
    opts: &Options,
) -> Result<Run, SimError> {
    let spec = &model.spec;
    let (Some(scenario), Some(ad)) = (spec.simulate.as_ref(), spec.adaptive.as_ref()) else {
        return Err(SimError::spec("the spec has no `simulate` scenario"));
    };
    let (n, m) = (design.n, design.m);
    let mut plant = Plant::new(spec, source, Evaluator::Compiled)?;
    let dim = plant.dim();
    let mut signals = Signals::new(spec, source, Evaluator::Compiled);
    let (t0, h, steps) = time_grid(scenario.time, opts.horizon)?;
    let mut x = opts.x0.clone().unwrap_or_else(|| scenario.x0.clone());
    x.resize(dim, 0.0);
    let range = crate::synth::adaptive::operating_range(model);
    let mut st_a = design.a0.clone();
    let mut st_b = design.b0.clone();
    let mut st_d = design.d0;
    let mut s_m = vec![0.0; m];
    let mut hw = vec![0.0; model.r()];
    let mut u = vec![0.0; m];
    let mut r = vec![0.0; m];
    let law = design.law();
    let r_env = spec.state_env(&[], Mode::Exact);
    let stride = steps.div_ceil(MAX_ROWS).max(1);
    let mut tally = Tally::new(design, ad.converged.len());
    let mut trace = Vec::new();
    let mut k_done = 0;
    let mut work: [Vec<f64>; 5] = std::array::from_fn(|_| vec![0.0; dim]);
    let mut w = vec![0.0; spec.q()];
    for k in 0..=steps {
        let t = t0 + k as f64 * h;
        if !strengths(model, &x[..n], &mut hw)? {
            tally.no_rule += 1;
        }
        if let Some(rg) = &range {
            if x[..n]
                .iter()
                .zip(rg)
                .any(|(v, (lo, hi))| *v < *lo || *v > *hi)
            {
                tally.outside += 1;
                tally.last_outside = Some(t);
            }
        }
        if let Some(e) = &ad.r {
            let mut env = r_env.clone();
            env.locals.push(("t".into(), Mat::from_element(1, 1, t)));
            let v = env.eval(e).map_err(|d| source.eval_error("r", t, d))?;
            r.iter_mut().zip(v.iter()).for_each(|(a, b)| *a = *b);
        }
        // A recorded sample holds the estimates the command at t was computed with.
        let record = k % stride == 0 || k == steps;
        let used = record.then(|| (st_a.clone(), st_b.clone(), st_d));
        let mut st = AdaptiveState {
            a_hat: &mut st_a,
            b_hat: &mut st_b,
            d_hat: &mut st_d,
            s_m: &mut s_m,
        };
        // The last sample is recorded, not stepped.
        let dt = if k == steps { 0.0 } else { h };
        if let Err(e) = law.step(&mut st, &x[..n], &hw, &r, dt, &mut u) {
            tally.failure = Some(format!(
                "the adaptive law refused the step at t = {t}: {e:?}"
            ));
            break;
        }
        widen(&mut tally.a_range, &st_a);
        widen(&mut tally.b_range, &st_b);
        widen(&mut tally.d_range, &[st_d]);
        for (mu, uk) in tally.max_u.iter_mut().zip(&u) {
            *mu = mu.max(uk.abs());
        }
        for (c, mx) in ad.converged.iter().zip(tally.claims_max.iter_mut()) {
            if t >= c.by {
                let (off, len) = c.signal;
                *mx = mx.max(x[off..off + len].iter().map(|v| v * v).sum::<f64>().sqrt());
            }
        }
        k_done = k;
        if let Some((a_hat, b_hat, d_hat)) = used {
            let s: Vec<f64> = design
                .c
                .chunks_exact(n)
                .map(|row| row.iter().zip(&x).map(|(a, b)| a * b).sum())
                .collect();
            trace.push(Sample {
                t,
                x: x.clone(),
                u: u.clone(),
                s,
                a_hat,
                b_hat,
                d_hat,
            });
        }
        if k == steps {
            break;
        }
        // RK4 with u held over [t, t + h].
        let mut f = |tt: f64, xs: &[f64], out: &mut [f64]| -> Result<(), SimError> {
            signals.eval(tt, &mut w)?;
            plant.rhs(tt, xs, &u, &w, out)
        };
        rk4_step(&mut f, t, h, &mut x, &mut work)?;
        let norm = x.iter().map(|v| v * v).sum::<f64>().sqrt();
        if norm.is_nan() || norm >= DIVERGED_NORM {
            tally.failure = Some(format!(
                "the state diverged at t = {} (||x|| = {norm:.3e})",
                t + h
            ));
            break;
        }
    }
    let metrics = tally.metrics(spec, design, &x, &trace, k_done, t0 + k_done as f64 * h);
    Ok(Run {
        trace,
        metrics,
        name: spec.controller.node.clone(),
        state_names: tsf_lang::spec::Signal::names_of(&spec.states),
    })
}

/// The CSV of a run: time, states, inputs, error signal, then every estimate.
pub fn csv(run: &Run, design: &Design) -> String {
    let mut head = vec!["t".to_string()];
    head.extend(run.state_names.iter().cloned());
    head.extend((0..design.m).map(|k| format!("u[{k}]")));
    head.extend((0..design.m).map(|k| format!("s[{k}]")));
    for i in 0..design.rules {
        for k in 0..design.m {
            head.extend((0..design.n).map(|j| format!("a_hat[{i}][{k}][{j}]")));
        }
    }
    for i in 0..design.rules {
        head.extend((0..design.m).map(|k| format!("b_hat[{i}][{k}]")));
    }
    head.push("d_hat".into());
    let mut out = head.join(",") + "\n";
    for s in &run.trace {
        let mut row = vec![s.t];
        row.extend(s.x.iter().take(design.n));
        row.extend(&s.u);
        row.extend(&s.s);
        row.extend(&s.a_hat);
        row.extend(&s.b_hat);
        row.push(s.d_hat);
        out += &row
            .iter()
            .map(|v| format!("{v:e}"))
            .collect::<Vec<_>>()
            .join(",");
        out.push('\n');
    }
    out
}

/// The plot of the estimates (SVG, PNG): per input, the input gains b_ik of
/// every rule relative to their initial values and the distance
/// ||a_ik - a_ik(0)||; then d with its projection bounds.
pub fn plot(run: &Run, design: &Design) -> Result<(Vec<u8>, Vec<u8>), SimError> {
    let span = (
        run.trace.first().map_or(0.0, |s| s.t),
        run.trace.last().map_or(1.0, |s| s.t),
    );
    let panel = |y_label: String, marks: Vec<Mark>| Panel {
        x: span,
        y_label,
        y: YAxis::Data,
        marks,
        notes: Vec::new(),
    };
    let limit = |v: f64| Shape::Line(vec![(span.0, v), (span.1, v)]);
    let series = |get: &dyn Fn(&Sample) -> f64| -> Vec<(f64, f64)> {
        run.trace.iter().map(|s| (s.t, get(s))).collect()
    };
    let per_rule = |get: &dyn Fn(&Sample, usize) -> f64| -> Vec<Mark> {
        (0..design.rules)
            .map(|i| {
                Mark::labelled(
                    format!("R{}", i + 1),
                    colour(i),
                    Shape::Line(series(&|s| get(s, i))),
                )
            })
            .collect()
    };
    let (n, m) = (design.n, design.m);
    let mut panels = Vec::new();
    for k in 0..m {
        panels.push(panel(
            format!("b_hat[.][{k}] / b_hat(0) - 1"),
            per_rule(&|s, i| s.b_hat[i * m + k] / design.b0[i * m + k] - 1.0),
        ));
        panels.push(panel(
            format!("||a_hat[.][{k}] - a_hat(0)||"),
            per_rule(&|s, i| {
                let at = (i * m + k) * n;
                let d0 = &design.a0[at..at + n];
                s.a_hat[at..at + n]
                    .iter()
                    .zip(d0)
                    .map(|(a, b)| (a - b) * (a - b))
                    .sum::<f64>()
                    .sqrt()
            }),
        ));
    }
    let mut marks = vec![Mark::labelled(
        "d_hat",
        colour(0),
        Shape::Line(series(&|s| s.d_hat)),
    )];
    if design.d.rate > 0.0 {
        marks.push(Mark::labelled("bounds", chart::RED, limit(design.d.lo)).beneath());
        marks.push(Mark::plain(chart::RED, limit(design.d.hi)).beneath());
    }
    panels.push(panel("d_hat".into(), marks));
    let mt = &run.metrics;
    let range = |r: (f64, f64)| format!("[{:.4e}, {:.4e}]", r.0, r.1);
    let fig = Figure {
        title: format!("{}: adaptive estimates", run.name),
        caption: vec![
            format!(
                "estimates within their projection bounds: {}; final ||x|| = {:.3e}",
                mt.estimates_within_bounds, mt.final_state_norm
            ),
            format!(
                "ranges over the run: a {} in [{}, {}], b {} in [{}, {}], d {} in [{}, {}]",
                range(mt.a_range),
                design.a.lo,
                design.a.hi,
                range(mt.b_range),
                design.b.lo,
                design.b.hi,
                range(mt.d_range),
                design.d.lo,
                design.d.hi
            ),
        ],
        x_label: "time [s]".into(),
        panels,
    };
    chart::render(&fig)
}
