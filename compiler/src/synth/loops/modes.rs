//! The sampled loop of a design with Markov modes (`trigger periodic`, or
//! `trigger aperiodic` without a threshold, with a `modes` block): the mode
//! gains of the core design certified for sampled-and-held state with the
//! input-delay functional of `crate::synth::markov::sampled`, every mode and
//! rule pair at h_max; refused with the longest certified interval. Its
//! certificate is per mode (P_a), so it is rebuilt with the modes' own
//! conditions by the certificate stage's Markov module, not through
//! [`super::LoopCertificate`].

use super::{LoopDesign, LoopLaw, Start};
use crate::model::TsModel;
use crate::synth::design::{Design, SynthError};
use crate::synth::markov::sampled;
use crate::synth::search::Runner;

/// The sampled loop with Markov modes.
#[derive(Debug, Clone, Copy)]
pub struct SampledModes;

impl LoopLaw for SampledModes {
    fn name(&self) -> &'static str {
        "sampled loop with modes"
    }

    fn claims(&self, model: &TsModel) -> bool {
        model.spec.modes.is_some() && sampled::wanted(&model.spec).is_some()
    }

    fn design(
        &self,
        runner: &mut Runner<'_>,
        d: &mut Design,
        _: &Start,
    ) -> Result<LoopDesign, SynthError> {
        let model = runner.model;
        let (Some(modes), Some(md), Some(h)) = (
            model.spec.modes.as_ref(),
            d.modes.as_ref(),
            sampled::wanted(&model.spec),
        ) else {
            return Err(SynthError::Internal(
                "internal error: a sampled loop with modes needs a mode design".into(),
            ));
        };
        let (s, note) = sampled::certify_loop(runner, modes, md, h)?;
        d.notes.push(note);
        Ok(LoopDesign::SampledModes(s))
    }
}
