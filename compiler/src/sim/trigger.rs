//! Sampling instants and transmission decisions.
//!
//! A [`Schedule`] says when the state is sampled (every integration step,
//! periodically, with jitter around a periodic grid, or aperiodically in
//! `[h_min, h_max]`, the last two from a seeded PRNG);
//! a [`Gate`] says whether a sample is transmitted to the controller. The
//! gates are the runtime's trigger state machines
//! (`tsf_runtime::{PeriodicTrigger, RelativeTrigger, AdaptiveTrigger, MixedTrigger}`),
//! padded like the controller (zero weight rows and columns, zero states).

use super::SimError;
use nalgebra::DMatrix;
use tsf_lang::spec::{Monitor, NamedSignal, Spec, Trigger, Weight};
use tsf_runtime::{AdaptiveTrigger, MixedTrigger, PeriodicTrigger, RelativeTrigger};

pub use crate::util::rng::SplitMix64;

/// When the state is sampled.
#[derive(Debug, Clone)]
pub enum Schedule {
    /// On the grid `t0 + k h` (integration step or base tick).
    Grid {
        /// Start time.
        t0: f64,
        /// Spacing.
        h: f64,
    },
    /// `t_k = t0 + k h + j (r_k - 1/2)` for k >= 1, `r_k` uniform from the
    /// seed: each instant within j/2 of the grid, each interval in [h - j, h + j].
    Jittered {
        /// Start time.
        t0: f64,
        /// Nominal period.
        h: f64,
        /// Jitter.
        jitter: f64,
        /// The pattern's generator.
        rng: SplitMix64,
    },
    /// `t_{k+1} = t_k + h_min + (h_max - h_min) r_k`, `r_k` uniform from the seed.
    Random {
        /// Shortest interval.
        h_min: f64,
        /// Longest interval.
        h_max: f64,
        /// The pattern's generator.
        rng: SplitMix64,
    },
}

impl Schedule {
    /// The sampling instant after sample number `k` taken at `t` (not clamped).
    pub fn next(&mut self, k: u64, t: f64) -> f64 {
        match self {
            Schedule::Grid { t0, h } => *t0 + (k + 1) as f64 * *h,
            Schedule::Jittered { t0, h, jitter, rng } => {
                *t0 + (k + 1) as f64 * *h + *jitter * (rng.next_f64() - 0.5)
            }
            Schedule::Random { h_min, h_max, rng } => {
                t + *h_min + (*h_max - *h_min) * rng.next_f64()
            }
        }
    }
}

/// Whether a sample is transmitted.
pub trait Gate {
    /// Decides on the sampled controller state `x` (length n).
    fn decide(&mut self, x: &[f64]) -> bool;
    /// The current relative threshold, for triggers that have one.
    fn nu(&self) -> Option<f64> {
        None
    }
    /// Whether `decide(x)` would transmit now, without changing anything
    /// (continuous monitoring bisects on it); `false` for gates that are not monitored.
    fn would_transmit(&self, _x: &[f64]) -> bool {
        false
    }
}

/// Longest monitored signal (padding with zeros leaves its norms unchanged).
const MAX_SIGNAL: usize = 16;

/// The mixed trigger on a named signal of the state (or the state itself):
/// the signal is evaluated from the spec each call.
struct SignalGate {
    spec: Spec,
    signal: Option<NamedSignal>,
    law: MixedTrigger<f64, MAX_SIGNAL>,
}

impl SignalGate {
    /// The padded signal at `x` (NaN where it cannot be evaluated: it transmits).
    fn signal(&self, x: &[f64]) -> [f64; MAX_SIGNAL] {
        match &self.signal {
            None => pad(x),
            Some(s) => match s.eval(&self.spec, x) {
                Some(v) => pad(&v),
                None => [f64::NAN; MAX_SIGNAL],
            },
        }
    }
}

impl Gate for SignalGate {
    fn decide(&mut self, x: &[f64]) -> bool {
        let s = self.signal(x);
        self.law.decide(&s)
    }
    fn would_transmit(&self, x: &[f64]) -> bool {
        self.law.would_transmit(&self.signal(x))
    }
}

/// Every sample is transmitted.
struct Always;

impl Gate for Always {
    fn decide(&mut self, _x: &[f64]) -> bool {
        true
    }
}

impl Gate for PeriodicTrigger {
    fn decide(&mut self, _x: &[f64]) -> bool {
        PeriodicTrigger::decide(self)
    }
}

fn pad<const N: usize>(x: &[f64]) -> [f64; N] {
    std::array::from_fn(|i| x.get(i).copied().unwrap_or(0.0))
}

fn pad_matrix<const N: usize>(u: &DMatrix<f64>) -> [[f64; N]; N] {
    std::array::from_fn(|i| {
        std::array::from_fn(|j| {
            if i < u.nrows() && j < u.ncols() {
                u[(i, j)]
            } else {
                0.0
            }
        })
    })
}

impl<const N: usize> Gate for RelativeTrigger<f64, N> {
    fn decide(&mut self, x: &[f64]) -> bool {
        RelativeTrigger::decide(self, &pad(x))
    }
    fn nu(&self) -> Option<f64> {
        Some(self.nu)
    }
}

impl<const N: usize> Gate for AdaptiveTrigger<f64, N> {
    fn decide(&mut self, x: &[f64]) -> bool {
        AdaptiveTrigger::decide(self, &pad(x))
    }
    fn nu(&self) -> Option<f64> {
        Some(AdaptiveTrigger::nu(self))
    }
}

impl<const N: usize> Gate for MixedTrigger<f64, N> {
    fn decide(&mut self, x: &[f64]) -> bool {
        MixedTrigger::decide(self, &pad(x))
    }
}

/// Relative/adaptive/mixed gate of padded size `N`.
fn event_gate<const N: usize>(kind: &EventKind, weight: &DMatrix<f64>) -> Box<dyn Gate> {
    match *kind {
        EventKind::Relative { nu } => {
            Box::new(RelativeTrigger::<f64, N>::new(pad_matrix(weight), nu))
        }
        EventKind::Adaptive {
            nu,
            max,
            mu1,
            mu2,
            mu3,
        } => Box::new(
            AdaptiveTrigger::<f64, N>::new(pad_matrix(weight), nu, mu1, mu2, mu3).with_max(max),
        ),
        EventKind::Mixed { beta, rho } => Box::new(MixedTrigger::<f64, N>::new(beta, rho)),
    }
}

enum EventKind {
    Relative {
        nu: f64,
    },
    Adaptive {
        nu: f64,
        /// Ceiling of the law (the certified threshold).
        max: f64,
        mu1: f64,
        mu2: f64,
        mu3: f64,
    },
    Mixed {
        beta: f64,
        rho: f64,
    },
}

/// Where the trigger weight `U` came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WeightSource {
    /// Given in the spec.
    Spec,
    /// The design's synthesized trigger weight.
    Design,
    /// `weight = synthesize` but the design has none: `P / lambda_max(P)`.
    LyapunovNormalized,
}

impl WeightSource {
    /// A sentence for the metrics file.
    pub fn describe(self) -> &'static str {
        match self {
            WeightSource::Spec => "the spec's weight matrix",
            WeightSource::Design => "the design's synthesized trigger weight (two-step: for the fixed PDC gains)",
            WeightSource::LyapunovNormalized => {
                "weight = synthesize and the design has no trigger weight: the Lyapunov matrix P divided by its largest eigenvalue"
            }
        }
    }
}

/// The trigger weight `U` for `weight`: the given matrix, else the design's
/// trigger weight, else `P / lambda_max(P)` (P is positive definite, so this
/// is a PSD weight with the same level sets as the Lyapunov function and
/// entries of order 1).
pub fn trigger_weight(
    weight: &Weight,
    design_weight: Option<&DMatrix<f64>>,
    p: &DMatrix<f64>,
) -> Result<(DMatrix<f64>, WeightSource), SimError> {
    match (weight, design_weight) {
        (Weight::Given(u), _) => Ok((u.clone(), WeightSource::Spec)),
        (Weight::Synthesize, Some(u)) => Ok((u.clone(), WeightSource::Design)),
        (Weight::Synthesize, None) => {
            let lmax = p.clone().symmetric_eigen().eigenvalues.max();
            if !(lmax > 0.0 && lmax.is_finite()) {
                return Err(SimError::unsupported(
                    "the design's Lyapunov matrix P has no positive eigenvalue; cannot form the trigger weight",
                ));
            }
            Ok((p / lmax, WeightSource::LyapunovNormalized))
        }
    }
}

/// The sampling schedule and transmission gate of a triggering law.
pub struct Sampler {
    /// When samples are taken.
    pub schedule: Schedule,
    /// Which samples are transmitted.
    pub gate: Box<dyn Gate>,
    /// Where the weight came from (relative and adaptive triggers).
    pub weight_source: Option<WeightSource>,
    /// Whether the gate is monitored continuously: the run locates each
    /// crossing inside the integration step ([`Gate::would_transmit`]).
    pub continuous: bool,
}

/// Builds the sampler for `trigger` (`None`: continuous) on a grid of step `h`.
#[allow(clippy::too_many_arguments)]
pub fn sampler(
    spec: &Spec,
    trigger: Option<&Trigger>,
    n: usize,
    t0: f64,
    h: f64,
    seed: u64,
    design_weight: Option<&DMatrix<f64>>,
    p: &DMatrix<f64>,
) -> Result<Sampler, SimError> {
    let grid = Schedule::Grid { t0, h };
    let random = |(h_min, h_max): (f64, f64)| Schedule::Random {
        h_min,
        h_max,
        rng: SplitMix64::new(seed),
    };
    let (schedule, kind, weight) = match trigger {
        None | Some(Trigger::Continuous) => (grid, None, None),
        Some(Trigger::Periodic { every }) => {
            let ticks = (every / h).round().max(1.0);
            if ticks > f64::from(u32::MAX) {
                return Err(SimError::unsupported(
                    "the trigger period is too long for the time step",
                ));
            }
            return Ok(Sampler {
                schedule: grid,
                gate: Box::new(PeriodicTrigger::new(ticks as u32)),
                weight_source: None,
                continuous: false,
            });
        }
        Some(Trigger::Jittered { every, jitter }) => (
            Schedule::Jittered {
                t0,
                h: *every,
                jitter: *jitter,
                rng: SplitMix64::new(seed),
            },
            None,
            None,
        ),
        Some(Trigger::Aperiodic {
            sampling,
            threshold,
            weight,
        }) => {
            let kind = threshold.as_ref().map(|th| match th.adaptive {
                Some((mu1, mu2, mu3)) => EventKind::Adaptive {
                    nu: th.nu,
                    max: th.ceiling(),
                    mu1,
                    mu2,
                    mu3,
                },
                None => EventKind::Relative { nu: th.nu },
            });
            (random(*sampling), kind, Some(weight))
        }
        Some(Trigger::Mixed {
            monitor: Monitor::Sampling(lo, hi),
            beta,
            rho,
            on: None,
        }) => (
            random((*lo, *hi)),
            Some(EventKind::Mixed {
                beta: *beta,
                rho: *rho,
            }),
            None,
        ),
        Some(Trigger::Mixed {
            monitor,
            beta,
            rho,
            on,
        }) => {
            let dim = on.as_ref().map_or(n, |s| s.dim);
            if dim > MAX_SIGNAL {
                return Err(SimError::unsupported(format!(
                    "the monitored signal has {dim} components; the simulator monitors at most {MAX_SIGNAL}"
                )));
            }
            let schedule = match monitor.sampling() {
                Some(s) => random(s),
                None => grid,
            };
            return Ok(Sampler {
                schedule,
                gate: Box::new(SignalGate {
                    spec: spec.clone(),
                    signal: on.clone(),
                    law: MixedTrigger::new(*beta, *rho),
                }),
                weight_source: None,
                continuous: *monitor == Monitor::Continuous,
            });
        }
    };
    let Some(kind) = kind else {
        return Ok(Sampler {
            schedule,
            gate: Box::new(Always),
            weight_source: None,
            continuous: false,
        });
    };
    let (u, source) = match weight {
        Some(w) if !matches!(kind, EventKind::Mixed { .. }) => {
            let (u, s) = trigger_weight(w, design_weight, p)?;
            (u, Some(s))
        }
        _ => (DMatrix::zeros(n, n), None),
    };
    if u.nrows() != n || u.ncols() != n {
        return Err(SimError::unsupported(format!(
            "the trigger weight is {}x{}, the controller has {n} states",
            u.nrows(),
            u.ncols()
        )));
    }
    let gate = if n <= 8 {
        event_gate::<8>(&kind, &u)
    } else if n <= 16 {
        event_gate::<16>(&kind, &u)
    } else {
        return Err(SimError::unsupported(format!(
            "event triggers are simulated for at most 16 states (this controller has {n})"
        )));
    };
    Ok(Sampler {
        schedule,
        gate,
        weight_source: source,
        continuous: false,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn splitmix_is_deterministic_and_uniform() {
        let mut a = SplitMix64::new(7);
        let mut b = SplitMix64::new(7);
        let xs: Vec<f64> = (0..10_000).map(|_| a.next_f64()).collect();
        assert!(xs.iter().all(|&x| (0.0..1.0).contains(&x)));
        assert_eq!(
            xs[..5],
            (0..5).map(|_| b.next_f64()).collect::<Vec<_>>()[..]
        );
        let mean = xs.iter().sum::<f64>() / xs.len() as f64;
        assert!((mean - 0.5).abs() < 0.01, "mean {mean}");
    }

    #[test]
    fn a_jittered_schedule_stays_near_its_grid_with_intervals_in_the_certified_range() {
        let (t0, h, jitter) = (1.0, 0.01, 0.005);
        let mut s = Schedule::Jittered {
            t0,
            h,
            jitter,
            rng: SplitMix64::new(3),
        };
        let mut t = t0;
        let (mut lo, mut hi) = (f64::INFINITY, 0.0_f64);
        for k in 0..10_000_u64 {
            let next = s.next(k, t);
            let grid = t0 + (k + 1) as f64 * h;
            assert!(
                (next - grid).abs() <= jitter / 2.0 + 1e-12,
                "{k}: {next} vs {grid}"
            );
            lo = lo.min(next - t);
            hi = hi.max(next - t);
            t = next;
        }
        assert!(
            lo >= h - jitter - 1e-12 && hi <= h + jitter + 1e-12,
            "[{lo}, {hi}]"
        );
        // The pattern reaches close to both ends of [h - j, h + j].
        assert!(
            lo < h - 0.9 * jitter && hi > h + 0.9 * jitter,
            "[{lo}, {hi}]"
        );
    }
}
