//! The measured output of an output-feedback loop: y = C x plus seeded
//! noise at every sample ([`Measure::sample`]). The observer-based loop
//! ([`super::observer`]) feeds it to the observer; a static-output-feedback
//! loop feeds it to the PDC controller on y
//! ([`crate::tables::static_output`]).

use super::observer::Noise;
use crate::util::rng::SplitMix64;

/// The measurement of a run: C, the noise and its seeded stream.
#[derive(Debug, Clone)]
pub struct Measure {
    c: Vec<Vec<f64>>,
    /// The noise added to every component.
    pub noise: Noise,
    rng: SplitMix64,
}

impl Measure {
    /// The measurement `y = C x + noise` (C as rows) with the noise stream
    /// of the scenario's `seed`.
    pub fn new(c: Vec<Vec<f64>>, noise: Noise, seed: u64) -> Self {
        Measure {
            c,
            noise,
            rng: SplitMix64::new(seed ^ 0x6f62_7365_7276_6572),
        }
    }

    /// Outputs (rows of C).
    pub fn q(&self) -> usize {
        self.c.len()
    }

    /// Writes `y = C x + noise` (one draw per component, in order) into `y`.
    pub fn sample(&mut self, x: &[f64], y: &mut [f64]) {
        for (yq, row) in y.iter_mut().zip(&self.c) {
            let clean: f64 = row.iter().zip(x).map(|(c, v)| c * v).sum();
            *yq = clean + self.noise.draw(&mut self.rng);
        }
    }
}
