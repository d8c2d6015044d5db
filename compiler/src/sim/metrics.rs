//! The recorded trajectory and the figures of merit computed from it.

use super::limits::{Thinned, MAX_PLOT_POINTS};
use nalgebra::DMatrix;
use serde::Serialize;

/// The trajectory at the sampling instants, thinned for the plots to at
/// most [`MAX_PLOT_POINTS`] rows (every `stride`-th sample and the last; see
/// [`Thinned`]): the full trajectory goes to the CSV as it is computed and
/// is never held in memory.
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
    /// Transmission instants (thinned separately from the samples).
    pub events: Vec<f64>,
    /// `(instant, time since the previous transmission)` at each transmission
    /// after the first (thinned).
    pub gaps: Vec<(f64, f64)>,
    /// Markov mode from each instant on: the initial mode, then each jump
    /// (thinned; empty without modes).
    pub modes: Vec<(f64, usize)>,
    /// Mode names (indices of `modes`).
    pub mode_names: Vec<String>,
    /// An observer-based design: the column of `x` where the estimate xhat
    /// starts (after the plant's states); `None` without an observer.
    pub estimate: Option<usize>,
}

/// Figures of merit of one run (written as `<controller>.metrics.json`).
#[derive(Debug, Clone, Serialize, schemars::JsonSchema)]
pub struct Metrics {
    /// `final_state_norm <= convergence_tolerance`, both finite, and the run
    /// finished.
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
    /// Transmitted samples at which no rule fired (the runtime used the
    /// nearest rule's gain alone).
    pub no_rule_samples: u64,
    /// Samples whose premise vector lies outside the premise region (the
    /// product of the premise ranges), where the design guarantees nothing.
    pub out_of_region_samples: u64,
    /// The first sampling instant outside the premise region (null if none).
    pub left_region_at_s: Option<f64>,
    /// Largest membership mismatch over the run: at each sampling instant,
    /// max_j |h_j(x(t_k)) - k_j| with h the plant's memberships there and k
    /// those the controller held since its last update (0 with fewer than two
    /// updates' worth of samples).
    pub max_membership_mismatch: f64,
    /// max over samples of |dh_k/dt| per rule (finite difference between
    /// consecutive samples), with a fuzzy Lyapunov design; empty otherwise.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub max_membership_rate: Vec<f64>,
    /// The bounds phi_k a fuzzy Lyapunov certificate assumes.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub certified_phi: Option<Vec<f64>>,
    /// Samples at which some |dh_k/dt| exceeded phi_k.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub samples_above_phi: Option<u64>,
    /// The mismatch bound the certificate relies on
    /// (`membership_mismatch(kappa = ..)` in a continuous loop).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub certified_kappa: Option<f64>,
    /// Sampling instants whose mismatch exceeds `certified_kappa` (the run
    /// left the certificate's assumption there).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub samples_above_kappa: Option<u64>,
    /// `V(x(t_end)) / V(x0)` for the certificate's Lyapunov function
    /// `V(x) = x' P x` over the controller's states (null when `x0 = 0` or
    /// the state is not finite).
    pub lyapunov_ratio: Option<f64>,
    /// `lyapunov_ratio > 1`: the run ended with a larger `V` than it began.
    pub diverged: bool,
    /// The run went non-finite, diverged or left the premise region
    /// (`tsfc simulate` exits 4).
    pub failed: bool,
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
    /// How a mixed trigger on a signal is monitored: `step` or `continuous`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub monitor: Option<String>,
    /// Its monitoring step (s): the integration step (`step`), or the time
    /// tolerance to which each crossing is located inside the step (`continuous`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub monitor_step: Option<f64>,
    /// Sampling-pattern seed.
    pub seed: u64,
    /// Truth plant used.
    pub plant: String,
    /// The Markov mode process and per-mode figures (specs with `modes`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub modes: Option<super::modes::ModeMetrics>,
    /// The estimation error of an observer-based design.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub estimation: Option<super::observer::EstimationMetrics>,
    /// Wall-clock time of the run (not part of any deterministic output).
    #[serde(skip)]
    pub wall_time_s: f64,
}

impl Metrics {
    /// Why the run failed (non-finite state, divergence, leaving the premise
    /// region), one phrase per reason; empty when it did not.
    pub fn failures(&self) -> Vec<String> {
        let mut out = Vec::new();
        if let Some(t) = self.nonfinite_at_s {
            out.push(format!(
                "the state became NaN, infinite or beyond 1e150 in magnitude at t = {t} s"
            ));
        }
        if self.diverged {
            let ratio = self.lyapunov_ratio.unwrap_or(f64::NAN);
            out.push(format!(
                "the run diverged: V(x) = x'Px ended {ratio:.3e} times its initial value"
            ));
        }
        if let Some(t) = self.left_region_at_s {
            out.push(format!(
                "the state left the premise region at t = {t} s ({} of {} samples outside)",
                self.out_of_region_samples, self.samples
            ));
        }
        out
    }
}

impl Metrics {
    /// Warnings about the run that do not fail it: samples whose membership
    /// mismatch exceeds the kappa the certificate relies on.
    pub fn warnings(&self) -> Vec<String> {
        let mut out = Vec::new();
        if let (Some(kappa), Some(above)) = (self.certified_kappa, self.samples_above_kappa) {
            if above > 0 {
                out.push(format!(
                "the membership mismatch exceeded the certified kappa = {kappa} at {above} of {} samples (max {:.3e}): the certificate assumes |k_j - h_j| <= kappa at every instant",
                self.samples, self.max_membership_mismatch
            ));
            }
        }
        if let (Some(phi), Some(above)) = (&self.certified_phi, self.samples_above_phi) {
            if above > 0 {
                out.push(format!(
                    "|dh_k/dt| exceeded the certified phi_k = {phi:?} at {above} of {} samples (max {:?}): the fuzzy Lyapunov certificate assumes |dh_k/dt| <= phi_k at every instant",
                    self.samples, self.max_membership_rate
                ));
            }
        }
        out
    }
}

/// The membership mismatch of a run: the plant's memberships at each
/// sampling instant against those the controller holds since its last update.
pub struct MismatchTally {
    held: Option<Vec<f64>>,
    max: f64,
    above: u64,
    kappa: Option<f64>,
}

impl MismatchTally {
    /// A tally checking against `kappa` (the certified bound, if any).
    pub fn new(kappa: Option<f64>) -> Self {
        MismatchTally {
            held: None,
            max: 0.0,
            above: 0,
            kappa,
        }
    }

    /// Records the plant's memberships `h` at a sampling instant, before the
    /// controller's update; `sent`: the controller takes `h` from now on.
    pub fn sample(&mut self, h: &[f64], sent: bool) {
        if let Some(k) = &self.held {
            let d = h
                .iter()
                .zip(k)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            if d.is_finite() {
                self.max = self.max.max(d);
                if self.kappa.is_some_and(|kappa| d > kappa) {
                    self.above += 1;
                }
            }
        }
        if sent {
            match &mut self.held {
                Some(k) => k.copy_from_slice(h),
                None => self.held = Some(h.to_vec()),
            }
        }
    }

    /// Writes the mismatch figures into `metrics`.
    pub fn finish(&self, metrics: &mut Metrics) {
        metrics.max_membership_mismatch = self.max;
        metrics.certified_kappa = self.kappa;
        metrics.samples_above_kappa = self.kappa.map(|_| self.above);
    }
}

/// The membership rates of a run: |dh_k/dt| by finite differences between
/// consecutive samples, against the phi_k a fuzzy Lyapunov certificate assumes.
pub struct RateTally {
    phi: Option<Vec<f64>>,
    last: Option<(f64, Vec<f64>)>,
    max: Vec<f64>,
    above: u64,
}

impl RateTally {
    /// A tally checking against `phi` (the certified bounds, if any).
    pub fn new(phi: Option<Vec<f64>>) -> Self {
        RateTally {
            phi,
            last: None,
            max: Vec::new(),
            above: 0,
        }
    }

    /// Records the memberships `h` at time `t` (nothing without phi).
    pub fn sample(&mut self, t: f64, h: &[f64]) {
        let Some(phi) = &self.phi else {
            return;
        };
        if let Some((t0, h0)) = &self.last {
            let dt = t - t0;
            if dt > 0.0 {
                self.max.resize(h.len(), 0.0);
                let mut over = false;
                for (k, (a, b)) in h.iter().zip(h0).enumerate() {
                    let rate = ((a - b) / dt).abs();
                    if rate.is_finite() {
                        self.max[k] = self.max[k].max(rate);
                        over |= phi.get(k).is_some_and(|p| rate > *p);
                    }
                }
                self.above += u64::from(over);
            }
        }
        match &mut self.last {
            Some((t0, h0)) if h0.len() == h.len() => {
                *t0 = t;
                h0.copy_from_slice(h);
            }
            _ => self.last = Some((t, h.to_vec())),
        }
    }

    /// Writes the rate figures into `metrics`.
    pub fn finish(self, metrics: &mut Metrics) {
        if self.phi.is_some() {
            metrics.max_membership_rate = self.max;
            metrics.samples_above_phi = Some(self.above);
        }
        metrics.certified_phi = self.phi;
    }
}

/// Euclidean norm, without overflow or underflow for finite vectors.
pub fn norm(v: &[f64]) -> f64 {
    let s = v.iter().map(|a| a * a).sum::<f64>();
    if s.is_finite() && s >= f64::MIN_POSITIVE {
        return s.sqrt();
    }
    let scale = v.iter().fold(0.0f64, |m, a| m.max(a.abs()));
    if scale == 0.0 || scale.is_infinite() {
        return if v.iter().any(|a| a.is_nan()) {
            f64::NAN
        } else {
            scale
        };
    }
    scale * v.iter().map(|a| (a / scale).powi(2)).sum::<f64>().sqrt()
}

/// The largest Euclidean norm of state groups over a time window, sample by
/// sample (the steady-state columns of a sweep table).
#[derive(Debug, Clone)]
pub struct WindowedNorms {
    window: (f64, f64),
    groups: Vec<(usize, usize)>,
    max: Vec<f64>,
    seen: bool,
}

impl WindowedNorms {
    /// Norms of the groups `(offset, len)` of the plant state over `window` (both ends included).
    pub fn new(window: (f64, f64), groups: Vec<(usize, usize)>) -> Self {
        let max = vec![0.0; groups.len()];
        WindowedNorms {
            window,
            groups,
            max,
            seen: false,
        }
    }

    /// Records the state `x` at time `t`.
    pub fn sample(&mut self, t: f64, x: &[f64]) {
        if t < self.window.0 || t > self.window.1 {
            return;
        }
        self.seen = true;
        for (m, &(at, len)) in self.max.iter_mut().zip(&self.groups) {
            let r = x.get(at..at + len).map_or(f64::NAN, norm);
            // A non-finite norm sticks (NaN is not absorbed by `max`).
            *m = if r.is_nan() || m.is_nan() {
                f64::NAN
            } else {
                m.max(r)
            };
        }
    }

    /// Per group the largest norm (`None`: no sample in the window, or not finite).
    pub fn finish(&self) -> Vec<Option<f64>> {
        self.max
            .iter()
            .map(|m| (self.seen && m.is_finite()).then_some(*m))
            .collect()
    }
}

/// `V(x1) / V(x0)` with `V(x) = x' P x`, computed on unit vectors so that
/// large finite states do not overflow; `None` when `V(x0)` is 0 or a value
/// is not finite.
pub fn lyapunov_ratio(p: &DMatrix<f64>, x0: &[f64], x1: &[f64]) -> Option<f64> {
    let unit_v = |x: &[f64]| -> Option<(f64, f64)> {
        let r = norm(x);
        if !r.is_finite() || x.len() != p.nrows() || p.nrows() != p.ncols() {
            return None;
        }
        if r == 0.0 {
            return Some((0.0, 0.0));
        }
        let e = DMatrix::from_iterator(x.len(), 1, x.iter().map(|v| v / r));
        Some((r, (e.transpose() * p * &e)[(0, 0)]))
    };
    let (r0, v0) = unit_v(x0)?;
    let (r1, v1) = unit_v(x1)?;
    if v0.is_nan() || v0 <= 0.0 {
        return None;
    }
    let ratio = (r1 / r0).powi(2) * v1 / v0;
    ratio.is_finite().then_some(ratio)
}

/// Facts about the run that the samples do not contain.
pub struct RunFacts<'a> {
    /// Saturation levels.
    pub u_max: Vec<f64>,
    /// Final time of the scenario.
    pub t_end: f64,
    /// Saturated samples.
    pub saturated: u64,
    /// Non-finite time.
    pub nonfinite_at: Option<f64>,
    /// The certificate's Lyapunov matrix (controller states).
    pub p: &'a DMatrix<f64>,
}

/// One sampling instant, as the loop records it.
pub struct Sample<'a> {
    /// Time.
    pub t: f64,
    /// Plant state.
    pub x: &'a [f64],
    /// Held command.
    pub u: &'a [f64],
    /// Transmitted to the controller.
    pub sent: bool,
    /// The controller found no rule firing (transmitted samples only).
    pub no_rule: bool,
    /// The premise vector is inside the premise region.
    pub in_region: bool,
}

/// The figures of merit and the plotted trace, accumulated sample by sample
/// in memory independent of the run's length.
pub struct Tally {
    n: usize,
    rel_tol: f64,
    tol: f64,
    x0: Vec<f64>,
    x_last: Vec<f64>,
    t_first: Option<f64>,
    max_abs_u: Vec<f64>,
    energy: f64,
    /// `(t, ||u||^2)` of the previous sample.
    prev: Option<(f64, f64)>,
    transmissions: u64,
    last_event: Option<f64>,
    gap_sum: f64,
    gap_count: u64,
    gap_min: Option<f64>,
    gap_max: Option<f64>,
    last_gap: (f64, f64),
    settle: Option<f64>,
    no_rule: u64,
    out_of_region: u64,
    left_region_at: Option<f64>,
    rows: Thinned<(f64, Vec<f64>, Vec<f64>, bool)>,
    events: Thinned<f64>,
    gaps: Thinned<(f64, f64)>,
}

impl Tally {
    /// A tally for `n` controller states and `m` inputs starting from `x0`,
    /// with `converged` meaning `||x(t_end)|| <= rel_tol ||x0||`.
    pub fn new(n: usize, m: usize, x0: &[f64], rel_tol: f64) -> Self {
        let x0: Vec<f64> = x0[..n.min(x0.len())].to_vec();
        Tally {
            n,
            rel_tol,
            tol: rel_tol * norm(&x0),
            x_last: x0.clone(),
            x0,
            t_first: None,
            max_abs_u: vec![0.0; m],
            energy: 0.0,
            prev: None,
            transmissions: 0,
            last_event: None,
            gap_sum: 0.0,
            gap_count: 0,
            gap_min: None,
            gap_max: None,
            last_gap: (0.0, 0.0),
            settle: None,
            no_rule: 0,
            out_of_region: 0,
            left_region_at: None,
            rows: Thinned::new(MAX_PLOT_POINTS),
            events: Thinned::new(MAX_PLOT_POINTS),
            gaps: Thinned::new(MAX_PLOT_POINTS),
        }
    }

    /// Records one sampling instant.
    pub fn sample(&mut self, s: &Sample) {
        let xc = &s.x[..self.n.min(s.x.len())];
        self.t_first.get_or_insert(s.t);
        self.x_last.clear();
        self.x_last.extend_from_slice(xc);
        for (mx, v) in self.max_abs_u.iter_mut().zip(s.u) {
            *mx = mx.max(v.abs());
        }
        if let Some((t_prev, u2_prev)) = self.prev {
            self.energy += u2_prev * (s.t - t_prev);
        }
        self.prev = Some((s.t, s.u.iter().map(|v| v * v).sum()));
        if s.sent {
            self.transmissions += 1;
            if let Some(last) = self.last_event {
                let gap = s.t - last;
                self.gap_sum += gap;
                self.gap_count += 1;
                self.gap_min = Some(self.gap_min.map_or(gap, |g| g.min(gap)));
                self.gap_max = Some(self.gap_max.map_or(gap, |g| g.max(gap)));
                self.last_gap = (s.t, gap);
                self.gaps.push(self.last_gap);
            }
            self.last_event = Some(s.t);
            self.events.push(s.t);
        }
        let r = norm(xc);
        if r.is_finite() && self.tol.is_finite() && r <= self.tol {
            self.settle.get_or_insert(s.t);
        } else {
            self.settle = None;
        }
        self.no_rule += u64::from(s.no_rule);
        if !s.in_region {
            self.out_of_region += 1;
            self.left_region_at.get_or_insert(s.t);
        }
        self.rows
            .push_with(|| (s.t, s.x.to_vec(), s.u.to_vec(), s.sent));
    }

    /// The figures of merit (descriptive fields left for the caller) and the
    /// thinned trace; `last` is the final sample (always plotted).
    pub fn finish(self, facts: &RunFacts, last: &Sample, mut trace: Trace) -> (Metrics, Trace) {
        let samples = self.rows.seen();
        let mut energy = self.energy;
        if let Some((t, u2)) = self.prev {
            energy += u2 * (facts.t_end.max(t) - t);
        }
        let fin = if samples == 0 {
            f64::NAN
        } else {
            norm(&self.x_last)
        };
        let finished = facts.nonfinite_at.is_none();
        let lyapunov_ratio = lyapunov_ratio(facts.p, &self.x0, &self.x_last);
        let diverged = lyapunov_ratio.is_some_and(|r| r > 1.0);
        let events = self
            .events
            .finish_with(|| self.last_event.unwrap_or(last.t));
        let gaps = self.gaps.finish_with(|| self.last_gap);
        let rows = self
            .rows
            .finish_with(|| (last.t, last.x.to_vec(), last.u.to_vec(), last.sent));
        for (t, x, u, sent) in rows {
            trace.t.push(t);
            trace.x.push(x);
            trace.u.push(u);
            trace.sent.push(sent);
        }
        trace.events = events;
        trace.gaps = gaps;
        let metrics = Metrics {
            converged: finished && fin.is_finite() && self.tol.is_finite() && fin <= self.tol,
            convergence_tolerance: self.tol,
            convergence_rel_tol: self.rel_tol,
            final_state_norm: fin,
            initial_state_norm: norm(&self.x0),
            max_abs_u: self.max_abs_u,
            u_max: facts
                .u_max
                .iter()
                .map(|&v| v.is_finite().then_some(v))
                .collect(),
            samples,
            transmissions: self.transmissions,
            mean_inter_event_s: (self.gap_count > 0).then(|| self.gap_sum / self.gap_count as f64),
            min_inter_event_s: self.gap_min,
            max_inter_event_s: self.gap_max,
            energy,
            settle_time_s: if finished { self.settle } else { None },
            saturated_samples: facts.saturated,
            nonfinite_at_s: facts.nonfinite_at,
            no_rule_samples: self.no_rule,
            out_of_region_samples: self.out_of_region,
            left_region_at_s: self.left_region_at,
            max_membership_mismatch: 0.0,
            max_membership_rate: Vec::new(),
            certified_phi: None,
            samples_above_phi: None,
            certified_kappa: None,
            samples_above_kappa: None,
            lyapunov_ratio,
            diverged,
            failed: !finished || diverged || self.out_of_region > 0,
            time_s: (self.t_first.unwrap_or(0.0), facts.t_end),
            integrator: String::new(),
            rhs_evaluations: 0,
            trigger: String::new(),
            final_nu: None,
            monitor: None,
            monitor_step: None,
            seed: 0,
            plant: String::new(),
            modes: None,
            estimation: None,
            wall_time_s: 0.0,
        };
        (metrics, trace)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn norms_neither_overflow_nor_underflow() {
        assert_eq!(norm(&[3.0, 4.0]), 5.0);
        assert_eq!(norm(&[1e160, 0.0]), 1e160);
        assert!((norm(&[3e-170, 4e-170]) / 5e-170 - 1.0).abs() < 1e-15);
        assert_eq!(norm(&[0.0, 0.0]), 0.0);
        assert_eq!(norm(&[f64::INFINITY, 1.0]), f64::INFINITY);
        assert!(norm(&[f64::NAN, 1.0]).is_nan());
        let p = DMatrix::from_row_slice(2, 2, &[2.0, 0.0, 0.0, 1.0]);
        assert_eq!(lyapunov_ratio(&p, &[1.0, 0.0], &[0.0, 2.0]), Some(2.0));
        assert_eq!(lyapunov_ratio(&p, &[1e160, 0.0], &[1e160, 0.0]), Some(1.0));
        assert_eq!(lyapunov_ratio(&p, &[0.0, 0.0], &[1.0, 0.0]), None);
        assert_eq!(lyapunov_ratio(&p, &[1.0, 0.0], &[f64::NAN, 0.0]), None);
    }

    fn tally(x0: &[f64], norms: &[f64], sent: &[bool], nonfinite_at: Option<f64>) -> Metrics {
        let mut t = Tally::new(x0.len(), 1, x0, 0.05);
        let u = [1.0];
        let xs: Vec<Vec<f64>> = norms.iter().map(|&r| vec![r, 0.0]).collect();
        for (k, (x, &s)) in xs.iter().zip(sent).enumerate() {
            t.sample(&Sample {
                t: k as f64,
                x,
                u: &u,
                sent: s,
                no_rule: k == 1,
                in_region: k != 2,
            });
        }
        let p = DMatrix::identity(2, 2);
        let k = xs.len() - 1;
        let last = Sample {
            t: k as f64,
            x: &xs[k],
            u: &u,
            sent: sent[k],
            no_rule: false,
            in_region: true,
        };
        let facts = RunFacts {
            u_max: vec![f64::INFINITY],
            t_end: 5.0,
            saturated: 0,
            nonfinite_at,
            p: &p,
        };
        t.finish(&facts, &last, Trace::default()).0
    }

    #[test]
    fn streamed_metrics_follow_their_definitions() {
        let norms = [1.0, 0.5, 0.01, 0.2, 0.01];
        let sent = [true, false, true, true, false];
        let m = tally(&[1.0, 0.0], &norms, &sent, None);
        assert!(m.converged);
        assert_eq!(
            m.settle_time_s,
            Some(4.0),
            "the last entry into the tolerance"
        );
        assert_eq!(m.energy, 5.0, "|u| = 1 held over 0 .. 5");
        assert_eq!((m.samples, m.transmissions), (5, 3));
        assert_eq!(m.mean_inter_event_s, Some(1.5));
        assert_eq!(
            (m.min_inter_event_s, m.max_inter_event_s),
            (Some(1.0), Some(2.0))
        );
        assert_eq!((m.no_rule_samples, m.out_of_region_samples), (1, 1));
        assert_eq!(m.left_region_at_s, Some(2.0));
        assert!(m.failed, "a sample left the region");
        assert_eq!(m.lyapunov_ratio, Some(1e-4));
        // A run that went non-finite is never converged nor settled.
        let m = tally(&[1.0, 0.0], &norms, &sent, Some(4.5));
        assert!(!m.converged && m.settle_time_s.is_none() && m.failed);
        // An infinite tolerance (||x0|| overflows) is never met.
        let m = tally(&[f64::MAX, f64::MAX], &norms, &sent, None);
        assert_eq!(m.convergence_tolerance, f64::INFINITY);
        assert!(!m.converged && m.settle_time_s.is_none());
    }

    #[test]
    fn windowed_norms_take_the_largest_norm_inside_the_window() {
        let mut w = WindowedNorms::new((1.0, 2.0), vec![(0, 2), (2, 1)]);
        w.sample(0.5, &[10.0, 10.0, 10.0]);
        w.sample(1.0, &[3.0, 4.0, -1.0]);
        w.sample(2.0, &[0.0, 1.0, -2.0]);
        w.sample(2.5, &[10.0, 10.0, 10.0]);
        assert_eq!(w.finish(), vec![Some(5.0), Some(2.0)]);
        w.sample(1.5, &[f64::NAN, 0.0, 0.0]);
        assert_eq!(w.finish(), vec![None, Some(2.0)]);
        let empty = WindowedNorms::new((3.0, 4.0), vec![(0, 1)]);
        assert_eq!(empty.finish(), vec![None]);
    }
}
