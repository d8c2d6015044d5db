//! The Markov mode process of a spec with `modes { ... }`: a seeded
//! continuous-time Markov chain r(t) with the spec's generator Pi, what each
//! mode does to the plant's input, and the per-mode figures of merit.
//!
//! The chain: in mode a it stays an exponential time of rate
//! q_a = sum_{b != a} pi_ab (a mode with q_a = 0 is absorbing), then jumps to
//! b != a with probability pi_ab / q_a. Holding times are
//! -ln(1 - U) / q_a and the next mode is found by inversion, with U uniform
//! from a SplitMix64 stream of the scenario's `mode_seed` (its `seed` when
//! not given): the same seed gives the same mode trajectory. The closed loop
//! ([`super::scenario`]) ends an integration step at each jump, so the plant
//! switches at the jump time exactly.
//!
//! The plant in mode a (the checker's meaning of a mode, `lang::modes`):
//! with `effectiveness = f` it sees B(x) (f o u + b); with a given `B = B_a`
//! it sees B_a u + B(x) b (the design model's or the dynamics block's input
//! term evaluated at the bias b alone, plus B_a u on the controller states),
//! b the mode's bias (0 without one).

use super::limits::{Thinned, MAX_PLOT_POINTS};
use super::trigger::SplitMix64;
use super::SimError;
use serde::Serialize;
use tsf_lang::modes::{Actuator, Modes};
use tsf_lang::spec::Simulation;

/// Most mode jumps a run may expect (`max_a q_a` times the time span).
pub const MAX_EXPECTED_JUMPS: f64 = 1e6;

/// The chain r(t).
#[derive(Debug, Clone)]
pub struct ModeProcess {
    /// Off-diagonal rates (K x K, row-major; the diagonal unused).
    rates: Vec<Vec<f64>>,
    rng: SplitMix64,
    mode: usize,
    next_jump: f64,
}

impl ModeProcess {
    /// The chain of `modes` in mode `mode0` at time `t0`, seeded by `seed`.
    pub fn new(modes: &Modes, mode0: usize, seed: u64, t0: f64) -> Self {
        let k = modes.len();
        let rates = (0..k)
            .map(|a| {
                (0..k)
                    .map(|b| if a == b { 0.0 } else { modes.rates[(a, b)] })
                    .collect()
            })
            .collect();
        let mut p = ModeProcess {
            rates,
            rng: SplitMix64::new(seed),
            mode: mode0.min(k.saturating_sub(1)),
            next_jump: t0,
        };
        p.next_jump = t0 + p.holding_time();
        p
    }

    /// Exit rate q_a of the current mode.
    fn exit_rate(&self) -> f64 {
        self.rates[self.mode].iter().sum()
    }

    /// An exponential holding time of the current mode (infinite when it is absorbing).
    fn holding_time(&mut self) -> f64 {
        let q = self.exit_rate();
        if q > 0.0 {
            -(1.0 - self.rng.next_f64()).ln() / q
        } else {
            f64::INFINITY
        }
    }

    /// The current mode.
    pub fn mode(&self) -> usize {
        self.mode
    }

    /// Time of the next jump (infinite if none).
    pub fn next_jump(&self) -> f64 {
        self.next_jump
    }

    /// Takes the jump due at [`ModeProcess::next_jump`]: the next mode by
    /// inversion of pi_ab / q_a, then a new holding time.
    pub fn jump(&mut self) {
        let q = self.exit_rate();
        if q > 0.0 {
            let target = self.rng.next_f64() * q;
            let row = &self.rates[self.mode];
            let mut acc = 0.0;
            // The last positive rate takes the rounding remainder.
            let mut next = self.mode;
            for (b, &r) in row.iter().enumerate() {
                if r > 0.0 {
                    next = b;
                    acc += r;
                    if target < acc {
                        break;
                    }
                }
            }
            self.mode = next;
        }
        self.next_jump += self.holding_time();
    }
}

/// What each mode does to the plant's input.
#[derive(Debug, Clone)]
pub struct Actuation {
    modes: Vec<(Actuator, Vec<f64>)>,
}

impl Actuation {
    /// The actuators of `modes` for `m` inputs.
    pub fn new(modes: &Modes, m: usize) -> Self {
        Actuation {
            modes: modes
                .modes
                .iter()
                .map(|md| (md.actuator.clone(), md.bias.clone().unwrap_or(vec![0.0; m])))
                .collect(),
        }
    }

    /// The input the plant's input term is evaluated at in mode `a`: f o u + b
    /// (effectiveness) or b (a given B; [`Actuation::add_given`] adds B_a u).
    pub fn plant_input(&self, a: usize, u: &[f64], out: &mut [f64]) {
        let Some((act, bias)) = self.modes.get(a) else {
            out.copy_from_slice(u);
            return;
        };
        for (k, o) in out.iter_mut().enumerate() {
            let b = bias.get(k).copied().unwrap_or(0.0);
            let uk = u.get(k).copied().unwrap_or(0.0);
            *o = match act {
                Actuator::Effectiveness(f) => f.get(k).copied().unwrap_or(1.0) * uk + b,
                Actuator::Given(_) => b,
            };
        }
    }

    /// Adds B_a u to the controller states' derivatives in a mode with a given B.
    pub fn add_given(&self, a: usize, u: &[f64], dx: &mut [f64]) {
        if let Some((Actuator::Given(b), _)) = self.modes.get(a) {
            for i in 0..b.nrows().min(dx.len()) {
                for (k, uk) in u.iter().enumerate().take(b.ncols()) {
                    dx[i] += b[(i, k)] * uk;
                }
            }
        }
    }
}

/// Per-mode figures of a run (in `<controller>.metrics.json`).
#[derive(Debug, Clone, Serialize, schemars::JsonSchema)]
pub struct ModeMetrics {
    /// `mode_dependent` (the controller is told the mode) or `mode_independent` (fault-blind).
    pub design: String,
    /// Seed of the mode process.
    pub seed: u64,
    /// Initial mode.
    pub mode0: String,
    /// Mode jumps in the run.
    pub transitions: u64,
    /// Per mode, in the spec's order.
    pub modes: Vec<ModeStat>,
}

/// One mode's share of a run.
#[derive(Debug, Clone, Serialize, schemars::JsonSchema)]
pub struct ModeStat {
    /// Its name.
    pub name: String,
    /// Time spent in it (s).
    pub time_s: f64,
    /// Fraction of the run's time span.
    pub fraction: f64,
    /// Times the chain entered it (the initial mode counts once).
    pub entries: u64,
    /// `max |u_s|` per channel over the samples taken in it.
    pub max_abs_u: Vec<f64>,
}

/// Accumulates [`ModeMetrics`] and the thinned mode trace during a run.
pub struct ModeTally {
    names: Vec<String>,
    time: Vec<f64>,
    entries: Vec<u64>,
    max_abs_u: Vec<Vec<f64>>,
    last: (f64, usize),
    transitions: u64,
    trace: Thinned<(f64, usize)>,
}

impl ModeTally {
    /// A tally of `modes` starting in `mode0` at `t0` with `m` inputs.
    pub fn new(modes: &Modes, mode0: usize, t0: f64, m: usize) -> Self {
        let k = modes.len();
        let mut entries = vec![0; k];
        entries[mode0] = 1;
        let mut trace = Thinned::new(MAX_PLOT_POINTS);
        trace.push_with(|| (t0, mode0));
        ModeTally {
            names: modes.modes.iter().map(|m| m.name.clone()).collect(),
            time: vec![0.0; k],
            entries,
            max_abs_u: vec![vec![0.0; m]; k],
            last: (t0, mode0),
            transitions: 0,
            trace,
        }
    }

    /// The command `u` held in mode `a` from a sample.
    pub fn sample(&mut self, a: usize, u: &[f64]) {
        for (mx, v) in self.max_abs_u[a].iter_mut().zip(u) {
            *mx = mx.max(v.abs());
        }
    }

    /// The chain jumped to `a` at `t`.
    pub fn jump(&mut self, t: f64, a: usize) {
        let (t_prev, prev) = self.last;
        self.time[prev] += t - t_prev;
        self.entries[a] += 1;
        self.transitions += 1;
        self.last = (t, a);
        self.trace.push_with(|| (t, a));
    }

    /// The figures at the end time `t1`, and the mode trace (mode from each instant on).
    pub fn finish(mut self, t1: f64, design: &str, seed: u64) -> (ModeMetrics, Vec<(f64, usize)>) {
        let (t_prev, prev) = self.last;
        self.time[prev] += (t1 - t_prev).max(0.0);
        let span: f64 = self.time.iter().sum();
        let trace = self.trace.finish_with(|| self.last);
        let metrics = ModeMetrics {
            design: design.to_string(),
            seed,
            mode0: trace
                .first()
                .map_or(String::new(), |(_, a)| self.names[*a].clone()),
            transitions: self.transitions,
            modes: self
                .names
                .iter()
                .enumerate()
                .map(|(a, name)| ModeStat {
                    name: name.clone(),
                    time_s: self.time[a],
                    fraction: if span > 0.0 { self.time[a] / span } else { 0.0 },
                    entries: self.entries[a],
                    max_abs_u: self.max_abs_u[a].clone(),
                })
                .collect(),
        };
        (metrics, trace)
    }
}

/// The initial mode and the seed of the scenario's mode process; refuses a
/// chain expected to jump more than [`MAX_EXPECTED_JUMPS`] times.
pub fn setup(modes: &Modes, sim: &Simulation, span: f64) -> Result<(usize, u64), SimError> {
    let mode0 = match &sim.mode0 {
        Some(name) => modes
            .modes
            .iter()
            .position(|m| m.name == name.node)
            .ok_or_else(|| SimError::spec(format!("`mode0 = {}` is not a mode", name.node)))?,
        None => 0,
    };
    let q_max = (0..modes.len())
        .map(|a| -modes.rates[(a, a)])
        .fold(0.0f64, f64::max);
    if q_max * span > MAX_EXPECTED_JUMPS {
        return Err(SimError::unsupported(format!(
            "the mode process is expected to jump up to {:.3e} times in this run (fastest exit rate {q_max} per s over {span} s); the simulator takes at most {MAX_EXPECTED_JUMPS:.0e}",
            q_max * span
        )));
    }
    Ok((mode0, sim.mode_seed.unwrap_or(sim.seed)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::DMatrix;
    use tsf_lang::modes::{Mode, ModeDesign};
    use tsf_lang::Span;

    fn modes(rates: &[f64], k: usize) -> Modes {
        Modes {
            modes: (0..k)
                .map(|a| Mode {
                    name: format!("m{a}"),
                    actuator: Actuator::Effectiveness(vec![1.0]),
                    bias: None,
                    span: Span::new(0, 0),
                })
                .collect(),
            rates: DMatrix::from_row_slice(k, k, rates),
            design: ModeDesign::Dependent,
            span: Span::new(0, 0),
        }
    }

    #[test]
    fn holding_times_have_the_exit_rate_and_jumps_the_right_odds() {
        let md = modes(&[-3.0, 1.0, 2.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0], 3);
        let (mut to1, mut to2, mut total) = (0u32, 0u32, 0.0);
        let n = 20_000;
        for seed in 0..n {
            let mut p = ModeProcess::new(&md, 0, seed, 0.0);
            total += p.next_jump();
            p.jump();
            match p.mode() {
                1 => to1 += 1,
                2 => to2 += 1,
                m => panic!("jumped to {m}"), // ok: unit test
            }
            // Modes 1 and 2 are absorbing.
            assert_eq!(p.next_jump(), f64::INFINITY);
        }
        let mean = total / n as f64;
        assert!((mean - 1.0 / 3.0).abs() < 0.01, "mean holding time {mean}");
        let share = f64::from(to1) / n as f64;
        assert!((share - 1.0 / 3.0).abs() < 0.015, "P(0 -> 1) = {share}");
        assert_eq!(to1 + to2, n as u32);
    }

    #[test]
    fn the_same_seed_gives_the_same_trajectory() {
        let md = modes(&[-1.0, 1.0, 2.0, -2.0], 2);
        let path = |seed| {
            let mut p = ModeProcess::new(&md, 1, seed, 0.0);
            (0..50)
                .map(|_| {
                    p.jump();
                    (p.next_jump().to_bits(), p.mode())
                })
                .collect::<Vec<_>>()
        };
        assert_eq!(path(7), path(7));
        assert_ne!(path(7), path(8));
    }

    #[test]
    fn effectiveness_scales_and_bias_adds() {
        let mut md = modes(&[-1.0, 1.0, 1.0, -1.0], 2);
        md.modes[1].actuator = Actuator::Effectiveness(vec![0.5]);
        md.modes[1].bias = Some(vec![0.25]);
        let act = Actuation::new(&md, 1);
        let mut out = [0.0];
        act.plant_input(0, &[2.0], &mut out);
        assert_eq!(out, [2.0]);
        act.plant_input(1, &[2.0], &mut out);
        assert_eq!(out, [1.25]);
        md.modes[1].actuator = Actuator::Given(DMatrix::from_row_slice(2, 1, &[0.0, 3.0]));
        let act = Actuation::new(&md, 1);
        act.plant_input(1, &[2.0], &mut out);
        assert_eq!(out, [0.25]);
        let mut dx = [1.0, 1.0];
        act.add_given(1, &[2.0], &mut dx);
        assert_eq!(dx, [1.0, 7.0]);
    }
}
