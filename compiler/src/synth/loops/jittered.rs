//! A jittered periodic sampler: `trigger jittered { every = h; jitter = j; }`.
//! The state is sampled nominally every h seconds, each interval in
//! [h - j, h + j]; every sample is transmitted and the command held. The
//! continuous design's gains are certified for that loop by the looped
//! functional of [`crate::synth::sampling`] with intervals in [h - j, h + j]
//! (the certificate of [`super::every_sample`], whose
//! [`crate::synth::design::SampledDesign`] it returns); refused with the longest nominal period and jitter that are.

use super::{LoopDesign, LoopLaw, Start};
use crate::model::TsModel;
use crate::synth::advice::round_down;
use crate::synth::design::{Design, SynthError};
use crate::synth::given;
use crate::synth::search::Runner;
use tsf_lang::spec::{jittered_intervals, Trigger};

/// The jittered periodic sampler.
#[derive(Debug, Clone, Copy)]
pub struct Jittered;

/// The nominal period h and jitter j of the spec's trigger, if it is jittered.
fn wanted(model: &TsModel) -> Option<(f64, f64)> {
    match model.spec.trigger.as_ref().map(|t| &t.node)? {
        Trigger::Jittered { every, jitter } => Some((*every, *jitter)),
        _ => None,
    }
}

/// The jittered law scaled to the longest interval `advice`: its intervals
/// and its trigger text (h and j rounded down, j kept below h).
fn advise((h, j): (f64, f64), advice: f64) -> ((f64, f64), String) {
    let every = round_down(advice * h / (h + j));
    let jitter = round_down(every * j / h);
    (
        jittered_intervals(every, jitter),
        format!("`trigger jittered {{ every = {every}; jitter = {jitter}; }}`"),
    )
}

impl LoopLaw for Jittered {
    fn name(&self) -> &'static str {
        "jittered"
    }

    fn claims(&self, model: &TsModel) -> bool {
        model.spec.modes.is_none() && wanted(model).is_some()
    }

    fn design(
        &self,
        runner: &mut Runner<'_>,
        d: &mut Design,
        _: &Start,
    ) -> Result<LoopDesign, SynthError> {
        let Some((h, j)) = wanted(runner.model) else {
            return Err(SynthError::Internal(
                "internal error: no jittered trigger".into(),
            ));
        };
        let sampling = jittered_intervals(h, j);
        let out = runner.sampled_with(d, sampling, &|a| advise((h, j), a));
        let (s, note) = given::looped(runner.model, d, &given::sampled_loop(sampling), out)?;
        d.notes
            .push(format!("nominal period {h} s, jitter {j} s: {note}"));
        Ok(LoopDesign::EverySample(s))
    }
}

#[cfg(test)]
mod tests {
    use super::advise;

    #[test]
    fn advice_keeps_the_jitter_below_the_period_within_the_longest_interval() {
        for (h, j, a) in [(0.01, 0.005, 0.0123), (0.1, 0.0999, 0.05), (1.0, 0.0, 0.7)] {
            let ((lo, hi), text) = advise((h, j), a);
            assert!(
                lo > 0.0 && lo <= hi && hi <= a * (1.0 + 1e-12),
                "{h} {j} {a}: {lo} {hi}"
            );
            assert!(text.starts_with("`trigger jittered { every = "), "{text}");
        }
        assert_eq!(
            advise((0.01, 0.005), 0.012).1,
            "`trigger jittered { every = 0.008; jitter = 0.004; }`"
        );
    }
}
