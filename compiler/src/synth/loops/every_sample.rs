//! Every sample transmitted: `trigger periodic { every = h; }`, or
//! `trigger aperiodic` without a threshold. The continuous design's gains
//! are certified for the sampled loop by the looped functional
//! ([`crate::synth::sampling`]); refused with the longest interval that is.

use super::{Condition, LoopCertificate, LoopDesign, LoopLaw, Rounding, Start};
use crate::model::TsModel;
use crate::synth::design::{Design, SampledDesign, SynthError, TriggerPlan};
use crate::synth::reduction::Reduction;
use crate::synth::search::Runner;
use crate::synth::{given, sampling, trigger};
use nalgebra::DMatrix;
use tsf_lang::spec::Trigger;

/// The loop that transmits every sample.
#[derive(Debug, Clone, Copy)]
pub struct EverySample;

impl LoopLaw for EverySample {
    fn name(&self) -> &'static str {
        "every sample"
    }

    fn claims(&self, model: &TsModel) -> bool {
        model.spec.modes.is_none() && sampling::wanted(model).is_some()
    }

    fn design(
        &self,
        runner: &mut Runner<'_>,
        d: &mut Design,
        _: &Start,
    ) -> Result<LoopDesign, SynthError> {
        let Some(h) = sampling::wanted(runner.model) else {
            return Err(SynthError::Internal(
                "internal error: no sampled loop".into(),
            ));
        };
        let out = runner.sampled(d, h);
        let (s, note) = given::looped(runner.model, d, &given::sampled_loop(h), out)?;
        d.notes.push(note);
        Ok(LoopDesign::EverySample(s))
    }
}

/// The sampled loop's problem rebuilt with `gains`, rounded as stored when
/// `stored` is given (levels; the sampling bounds too when a sensor module
/// stores them, `sensor`).
pub(super) fn rebuilt_plan(
    plan: &TriggerPlan,
    gains: &[DMatrix<f64>],
    stored: Option<Rounding<'_>>,
    sensor: bool,
) -> TriggerPlan {
    let Some(s) = stored else {
        return TriggerPlan {
            gains: gains.to_vec(),
            ..plan.clone()
        };
    };
    TriggerPlan {
        gains: gains.to_vec(),
        levels: plan.levels.iter().map(|v| s(*v)).collect(),
        nu: s(plan.nu),
        sampling: if sensor {
            (s(plan.sampling.0), s(plan.sampling.1))
        } else {
            plan.sampling
        },
        ..plan.clone()
    }
}

/// The conditions of a looped-functional problem at its solved values.
pub(super) fn looped_conditions(
    model: &TsModel,
    plan: &TriggerPlan,
    eps: f64,
    values: Vec<(String, DMatrix<f64>)>,
    reductions: &[Reduction],
) -> Result<Vec<Condition>, SynthError> {
    let tb = trigger::build(model, plan, eps, false)?;
    Ok(vec![Condition::Problem {
        problem: Box::new(tb.problem),
        nonstrict: tb.nonstrict,
        values,
        reductions: reductions.to_vec(),
    }])
}

/// Whether the spec's trigger is generated as a sensor module (an aperiodic
/// trigger stores its sampling bounds there).
pub(super) fn has_sensor(model: &TsModel) -> bool {
    matches!(
        model.spec.trigger.as_ref().map(|t| &t.node),
        Some(Trigger::Aperiodic { .. })
    )
}

impl LoopCertificate for SampledDesign {
    fn conditions(
        &self,
        model: &TsModel,
        eps: f64,
        gains: &[DMatrix<f64>],
        stored: Option<Rounding<'_>>,
    ) -> Result<Vec<Condition>, SynthError> {
        let plan = rebuilt_plan(&self.plan, gains, stored, has_sensor(model));
        looped_conditions(model, &plan, eps, self.values.clone(), &self.reductions)
    }

    fn reductions(&self) -> &[Reduction] {
        &self.reductions
    }

    fn every_sample(&self) -> Option<(f64, f64)> {
        Some(self.plan.sampling)
    }

    fn region(&self) -> Option<(&DMatrix<f64>, f64)> {
        Some((&self.p, self.plan.region_level()))
    }
}
