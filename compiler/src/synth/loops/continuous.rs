//! The continuous loop (no `trigger` item): the core design is the loop that
//! ships, and its certificate is the whole certificate.

use super::{LoopDesign, LoopLaw, Start};
use crate::model::TsModel;
use crate::synth::design::{Design, SynthError};
use crate::synth::search::Runner;

/// The continuous loop: the law of every spec no other law claims.
#[derive(Debug, Clone, Copy)]
pub struct Continuous;

impl LoopLaw for Continuous {
    fn name(&self) -> &'static str {
        "continuous"
    }

    fn claims(&self, _model: &TsModel) -> bool {
        true
    }

    fn design(
        &self,
        _: &mut Runner<'_>,
        _: &mut Design,
        _: &Start,
    ) -> Result<LoopDesign, SynthError> {
        Ok(LoopDesign::Continuous)
    }
}
