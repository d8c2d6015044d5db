//! Paper-specific conditions kept for study, outside the main synthesis path:
//! they are reported, never emitted. Each is an [`Experiment`] of
//! [`EXPERIMENTS`], run only for the specs that ask for it.

pub mod theorem2;

use super::design::{Settings, SynthError};
use crate::model::TsModel;

/// A paper's conditions, solved and reported instead of a design.
pub trait Experiment: Sync {
    /// Whether the spec asks for this experiment.
    fn claims(&self, model: &TsModel) -> bool;
    /// Solves it and says what it found (always an error: nothing is emitted).
    fn run(&self, model: &TsModel, settings: &Settings) -> SynthError;
}

/// Every experiment.
pub const EXPERIMENTS: &[&dyn Experiment] = &[&theorem2::Theorem2];

/// The experiment the spec asks for, if any.
pub fn experiment_of(model: &TsModel) -> Option<&'static dyn Experiment> {
    EXPERIMENTS.iter().copied().find(|e| e.claims(model))
}
