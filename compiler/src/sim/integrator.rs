//! ODE integrators: fixed-step classical Runge-Kutta 4 and adaptive
//! Dormand-Prince 5(4). Both advance exactly from `t0` to `t1` (the caller's
//! sampling and triggering instants), never stepping over `t1`.

use super::limits::MAX_ADAPTIVE_STEPS;
use super::SimError;

/// A right-hand side `dy = f(t, y)`.
pub trait System {
    /// Writes `f(t, y)` into `dy` (same length as `y`).
    fn rhs(&mut self, t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), SimError>;
}

impl<F> System for F
where
    F: FnMut(f64, &[f64], &mut [f64]) -> Result<(), SimError>,
{
    fn rhs(&mut self, t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), SimError> {
        self(t, y, dy)
    }
}

/// `sum_j c_j k_j[i]`, taken from 0 in order of `j` (a missing `k_j[i]` is 0).
#[inline(always)]
fn weighted<const K: usize>(i: usize, c: &[f64; K], k: &[&[f64]; K]) -> f64 {
    let mut s = 0.0;
    for (cj, kj) in c.iter().zip(k) {
        s += cj * kj.get(i).copied().unwrap_or(0.0);
    }
    s
}

/// The stages cut to length `n`, or `None` if one is shorter.
fn cut<'a, const K: usize>(k: &[&'a [f64]; K], n: usize) -> Option<[&'a [f64]; K]> {
    let mut out: [&[f64]; K] = [&[]; K];
    for (o, kj) in out.iter_mut().zip(k) {
        *o = kj.get(..n)?;
    }
    Some(out)
}

/// `out_i = y_i + h * sum_j c_j k_j[i]` (`out` may be `y` itself: `y = None`).
#[inline(always)]
fn update<const K: usize>(
    out: &mut [f64],
    y: Option<&[f64]>,
    h: f64,
    c: &[f64; K],
    k: [&[f64]; K],
) {
    let n = y.map_or(out.len(), |y| y.len().min(out.len()));
    let Some(ks) = cut(&k, n) else {
        for i in 0..n {
            let yi = y.map_or(out[i], |y| y[i]);
            out[i] = yi + h * weighted(i, c, &k);
        }
        return;
    };
    for i in 0..n {
        let mut s = 0.0;
        for (cj, kj) in c.iter().zip(&ks) {
            s += cj * kj[i];
        }
        let yi = y.map_or(out[i], |y| y[i]);
        out[i] = yi + h * s;
    }
}

/// `out = y + h * sum_j c_j k_j`.
fn combine<const K: usize>(out: &mut [f64], y: &[f64], h: f64, c: &[f64; K], k: [&[f64]; K]) {
    update(out, Some(y), h, c, k);
}

/// The classical RK4 weights.
const RK4_WEIGHTS: [f64; 4] = [1.0 / 6.0, 1.0 / 3.0, 1.0 / 3.0, 1.0 / 6.0];

/// Fixed-step classical RK4 with at most `h` per step: an interval is split
/// into `ceil((t1 - t0) / h)` equal steps so that `t1` is hit exactly.
#[derive(Debug, Clone)]
pub struct Rk4 {
    /// Largest step.
    pub h: f64,
    k: [Vec<f64>; 4],
    tmp: Vec<f64>,
    /// Right-hand side evaluations so far.
    pub evals: u64,
}

impl Rk4 {
    /// An integrator for `dim` states with step at most `h`.
    pub fn new(dim: usize, h: f64) -> Self {
        Rk4 {
            h,
            k: std::array::from_fn(|_| vec![0.0; dim]),
            tmp: vec![0.0; dim],
            evals: 0,
        }
    }

    /// One RK4 step of size `h` from `(t, y)`, in place.
    pub fn step(
        &mut self,
        sys: &mut impl System,
        t: f64,
        h: f64,
        y: &mut [f64],
    ) -> Result<(), SimError> {
        self.step_to(sys, t, h, t + h, y)
    }

    /// [`Rk4::step`] whose last stage is evaluated at `t_end` (`t + h` up to
    /// rounding): the time the next step starts from, so a time-only input
    /// such as a disturbance signal is evaluated once for both.
    fn step_to(
        &mut self,
        sys: &mut impl System,
        t: f64,
        h: f64,
        t_end: f64,
        y: &mut [f64],
    ) -> Result<(), SimError> {
        let [k1, k2, k3, k4] = &mut self.k;
        sys.rhs(t, y, k1)?;
        combine(&mut self.tmp, y, 0.5 * h, &[1.0], [k1]);
        sys.rhs(t + 0.5 * h, &self.tmp, k2)?;
        combine(&mut self.tmp, y, 0.5 * h, &[1.0], [k2]);
        sys.rhs(t + 0.5 * h, &self.tmp, k3)?;
        combine(&mut self.tmp, y, h, &[1.0], [k3]);
        sys.rhs(t_end, &self.tmp, k4)?;
        self.evals += 4;
        update(y, None, h, &RK4_WEIGHTS, [k1, k2, k3, k4]);
        Ok(())
    }

    /// Advances `y` from `t0` to `t1` (no-op when `t1 <= t0`).
    pub fn advance(
        &mut self,
        sys: &mut impl System,
        t0: f64,
        t1: f64,
        y: &mut [f64],
    ) -> Result<(), SimError> {
        let span = t1 - t0;
        if span <= 0.0 {
            return Ok(());
        }
        // The 1e-9 slack keeps an interval of exactly k steps from becoming k + 1.
        let steps = ((span / self.h) - 1e-9).ceil().max(1.0);
        let h = span / steps;
        let steps = steps as u64;
        for i in 0..steps {
            let t_end = if i + 1 == steps {
                t1
            } else {
                t0 + (i + 1) as f64 * h
            };
            self.step_to(sys, t0 + i as f64 * h, h, t_end, y)?;
        }
        Ok(())
    }
}

/// Dormand-Prince 5(4) (Dormand & Prince 1980; Hairer, Norsett & Wanner,
/// Table II.5.2) with local extrapolation and a standard step-size controller:
/// the scaled RMS error `sqrt(mean((err_i / (atol + rtol max(|y_i|, |y+_i|)))^2))`
/// must be `<= 1`; the next step is `h * clamp(0.9 err^(-1/5), 0.2, 5)`.
/// At most `max_trials` trial steps are taken over a run.
#[derive(Debug, Clone)]
pub struct Dopri5 {
    /// Relative tolerance.
    pub rtol: f64,
    /// Absolute tolerance.
    pub atol: f64,
    /// Largest step (also the first trial step).
    pub h_max: f64,
    h: f64,
    k: [Vec<f64>; 7],
    tmp: Vec<f64>,
    ynew: Vec<f64>,
    /// Accepted steps so far.
    pub accepted: u64,
    /// Rejected steps so far.
    pub rejected: u64,
    /// Right-hand side evaluations so far.
    pub evals: u64,
    /// Most trial steps (accepted and rejected) over the integrator's life.
    pub max_trials: u64,
}

const C: [f64; 7] = [0.0, 0.2, 0.3, 0.8, 8.0 / 9.0, 1.0, 1.0];
const A2: [f64; 1] = [0.2];
const A3: [f64; 2] = [3.0 / 40.0, 9.0 / 40.0];
const A4: [f64; 3] = [44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0];
const A5: [f64; 4] = [
    19372.0 / 6561.0,
    -25360.0 / 2187.0,
    64448.0 / 6561.0,
    -212.0 / 729.0,
];
const A6: [f64; 5] = [
    9017.0 / 3168.0,
    -355.0 / 33.0,
    46732.0 / 5247.0,
    49.0 / 176.0,
    -5103.0 / 18656.0,
];
/// Fifth-order weights (also the stage-7 row: first same as last).
const B5: [f64; 6] = [
    35.0 / 384.0,
    0.0,
    500.0 / 1113.0,
    125.0 / 192.0,
    -2187.0 / 6784.0,
    11.0 / 84.0,
];
/// Fifth minus fourth-order weights (error estimate).
const E: [f64; 7] = [
    71.0 / 57600.0,
    0.0,
    -71.0 / 16695.0,
    71.0 / 1920.0,
    -17253.0 / 339200.0,
    22.0 / 525.0,
    -1.0 / 40.0,
];

impl Dopri5 {
    /// An integrator for `dim` states with tolerances and a largest step.
    pub fn new(dim: usize, rtol: f64, atol: f64, h_max: f64) -> Self {
        Dopri5 {
            rtol,
            atol,
            h_max,
            h: h_max,
            k: std::array::from_fn(|_| vec![0.0; dim]),
            tmp: vec![0.0; dim],
            ynew: vec![0.0; dim],
            accepted: 0,
            rejected: 0,
            evals: 0,
            max_trials: MAX_ADAPTIVE_STEPS,
        }
    }

    /// One trial step of size `h`; returns the scaled error (new state in `ynew`).
    fn trial(&mut self, sys: &mut impl System, t: f64, h: f64, y: &[f64]) -> Result<f64, SimError> {
        let [k1, k2, k3, k4, k5, k6, k7] = &mut self.k;
        let tmp = &mut self.tmp;
        sys.rhs(t, y, k1)?;
        combine(tmp, y, h, &A2, [k1]);
        sys.rhs(t + C[1] * h, tmp, k2)?;
        combine(tmp, y, h, &A3, [k1, k2]);
        sys.rhs(t + C[2] * h, tmp, k3)?;
        combine(tmp, y, h, &A4, [k1, k2, k3]);
        sys.rhs(t + C[3] * h, tmp, k4)?;
        combine(tmp, y, h, &A5, [k1, k2, k3, k4]);
        sys.rhs(t + C[4] * h, tmp, k5)?;
        combine(tmp, y, h, &A6, [k1, k2, k3, k4, k5]);
        sys.rhs(t + C[5] * h, tmp, k6)?;
        combine(&mut self.ynew, y, h, &B5, [k1, k2, k3, k4, k5, k6]);
        sys.rhs(t + h, &self.ynew, k7)?;
        self.evals += 7;
        let all = [&k1[..], k2, k3, k4, k5, k6, k7];
        let mut sum = 0.0;
        for (i, (&yi, &yn)) in y.iter().zip(&self.ynew).enumerate() {
            let err = h * weighted(i, &E, &all);
            let sc = self.atol + self.rtol * yi.abs().max(yn.abs());
            sum += (err / sc) * (err / sc);
        }
        Ok((sum / y.len().max(1) as f64).sqrt())
    }

    /// Advances `y` from `t0` to `t1` with error control, landing on `t1` exactly.
    pub fn advance(
        &mut self,
        sys: &mut impl System,
        t0: f64,
        t1: f64,
        y: &mut [f64],
    ) -> Result<(), SimError> {
        let mut t = t0;
        while t < t1 {
            let remaining = t1 - t;
            let planned = self.h.min(self.h_max);
            let mut h = planned.min(remaining);
            // Do not leave a sliver: stretch to the end when it is within 1e-3 h.
            if remaining - h < 1e-3 * h {
                h = remaining;
            }
            if h.is_nan() || h <= 1e-14 * (t.abs() + 1.0) {
                return Err(SimError::numeric(format!(
                    "dopri5: step size underflow at t = {t} (h = {h:e}); the system is too stiff or not finite"
                )));
            }
            if self.accepted + self.rejected >= self.max_trials {
                return Err(SimError::numeric(format!(
                    "dopri5: more than {} steps by t = {t} (h = {h:e}); the system is too stiff for this integrator (try `integrator = rk4` with a small step)",
                    self.max_trials
                )));
            }
            let err = self.trial(sys, t, h, y)?;
            if err <= 1.0 {
                self.accepted += 1;
                t = if h == remaining { t1 } else { t + h };
                y.copy_from_slice(&self.ynew);
                let grow = if err == 0.0 {
                    5.0
                } else {
                    (0.9 * err.powf(-0.2)).clamp(0.2, 5.0)
                };
                // A step shortened to hit t1 does not shrink the planned step.
                if !(h < planned && grow >= 1.0) {
                    self.h = h * grow;
                }
            } else if err.is_finite() {
                self.rejected += 1;
                self.h = h * (0.9 * err.powf(-0.2)).clamp(0.2, 1.0);
            } else {
                self.rejected += 1;
                self.h = h * 0.2;
            }
        }
        Ok(())
    }
}

/// The integrator a simulation uses.
#[derive(Debug, Clone)]
pub enum Stepper {
    /// Fixed-step RK4.
    Rk4(Rk4),
    /// Adaptive Dormand-Prince 5(4).
    Dopri5(Dopri5),
}

impl Stepper {
    /// Advances `y` from `t0` to `t1` exactly.
    pub fn advance(
        &mut self,
        sys: &mut impl System,
        t0: f64,
        t1: f64,
        y: &mut [f64],
    ) -> Result<(), SimError> {
        match self {
            Stepper::Rk4(s) => s.advance(sys, t0, t1, y),
            Stepper::Dopri5(s) => s.advance(sys, t0, t1, y),
        }
    }

    /// Right-hand side evaluations so far.
    pub fn evals(&self) -> u64 {
        match self {
            Stepper::Rk4(s) => s.evals,
            Stepper::Dopri5(s) => s.evals,
        }
    }
}
