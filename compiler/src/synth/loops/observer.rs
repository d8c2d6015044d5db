//! The sampled observer-based loop: `control observer_based;` with
//! `trigger periodic { every = T; }`. The observer and controller run every T
//! on the continuous plant; the certificate is the looped functional on the
//! augmented state (x, xhat) ([`crate::synth::observer::sampled`]), rebuilt
//! from the shipped gains F_l and observer tables (Phi_j, Gu_j, Gy_j), also
//! as stored, with the input bound and the saturation levels (as stored) of
//! [`crate::synth::observer::sampled_bounds`]; with the saturation active,
//! the dead-zone maps [I; Gu_j / T] from the (rounded) tables, the same known
//! multiplier T (any diagonal T > 0 is valid), the solved sector gains and the
//! rounded levels in the sector region. Refused with the
//! longest period that certifies.

use super::every_sample::looped_conditions;
use super::{Condition, LoopCertificate, LoopDesign, LoopLaw, Rounding, Start};
use crate::model::TsModel;
use crate::synth::design::{Design, SynthError};
use crate::synth::observer::sampled::{augmented_model, SampledObserver};
use crate::synth::observer::OutputFeedback;
use crate::synth::search::Runner;
use nalgebra::DMatrix;
use tsf_lang::spec::{ControlKind, Trigger};

/// The periodic loop of an observer-based controller.
#[derive(Debug, Clone, Copy)]
pub struct ObserverSampled;

/// The period of an observer-based spec's periodic trigger, if it has one.
pub fn period(model: &TsModel) -> Option<f64> {
    if model.spec.control.kind != ControlKind::ObserverBased {
        return None;
    }
    match model.spec.trigger.as_ref().map(|t| &t.node) {
        Some(Trigger::Periodic { every }) => Some(*every),
        _ => None,
    }
}

impl LoopLaw for ObserverSampled {
    fn name(&self) -> &'static str {
        "sampled observer"
    }

    fn claims(&self, model: &TsModel) -> bool {
        model.spec.modes.is_none() && period(model).is_some()
    }

    fn design(
        &self,
        runner: &mut Runner<'_>,
        d: &mut Design,
        _: &Start,
    ) -> Result<LoopDesign, SynthError> {
        let (Some(t), Some(OutputFeedback::Observer(o))) = (period(runner.model), &d.output) else {
            return Err(SynthError::Internal(
                "internal error: the sampled observer loop needs the observer design".into(),
            ));
        };
        let alpha = d.plan.decay().map_or(0.0, |dec| dec.alpha);
        let o = o.clone();
        let s = runner.sampled_observer(d, &o, t, alpha)?;
        if let Some(mu) = s.input_bound() {
            // The loop that ships is the sampled one: its bound replaces the
            // state-feedback design's.
            d.achieved
                .set(crate::synth::achieved::Quantity::InputNormBound, mu);
            d.notes.push(format!(
                "sampled observer-based input bound: ||u(t)|| <= {mu:.6} for t >= 0 from the initial set with x_hat(0) = 0 (the command held between samples; xi(t_k) stays in E(P, 1) of the sampled loop)"
            ));
        }
        if s.saturation_active() {
            d.notes.push(format!(
                "sampled observer-based saturation: ACTIVE-saturation certificate (the linear-region one does not hold): generalized sector condition with a known diagonal multiplier T and solved sector gains G_jl, E(P, 1) of the sampled loop inside |((Kbar_l - G_jl) xi)_s| <= {:?}; the plant and the observer get the saturated command",
                s.saturation_levels()
            ));
        } else if !s.saturation_levels().is_empty() {
            d.notes.push(format!(
                "sampled observer-based saturation: linear-region certificate, saturation inactive on the certified set (|u_s| <= {:?} on E(P, 1) of the sampled loop, so the saturated loop is the certified linear one there)",
                s.saturation_levels()
            ));
        }
        d.notes
            .push(format!("sampled loop certified: {}", s.covers()));
        Ok(LoopDesign::ObserverSampled(s))
    }
}

impl LoopCertificate for SampledObserver {
    fn conditions(
        &self,
        model: &TsModel,
        eps: f64,
        gains: &[DMatrix<f64>],
        stored: Option<Rounding<'_>>,
    ) -> Result<Vec<Condition>, SynthError> {
        let steps = match stored {
            Some(round) => self.steps.rounded(round),
            None => self.steps.clone(),
        };
        let mut plan = self.plan_with(gains, &steps);
        // The saturation levels as stored (the step clips at those).
        if let (Some(round), Some(b)) = (stored, plan.observer_bounds.as_mut()) {
            b.levels = b.levels.iter().map(|v| round(*v)).collect();
            plan.levels = plan.levels.iter().map(|v| round(*v)).collect();
        }
        let aug = augmented_model(model);
        looped_conditions(&aug, &plan, eps, self.values.clone(), &self.reductions)
    }

    fn reductions(&self) -> &[crate::synth::reduction::Reduction] {
        &self.reductions
    }

    fn stored_matrices(&self) -> Vec<&DMatrix<f64>> {
        self.steps.matrices()
    }

    fn every_sample(&self) -> Option<(f64, f64)> {
        Some((self.period, self.period))
    }
}
