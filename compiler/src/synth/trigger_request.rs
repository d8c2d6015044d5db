//! What a spec asks of its event trigger's synthesis: a synthesized weight
//! (two-step, co-design or few transmissions) and the threshold the trigger
//! LMIs are solved for. Plain queries of the spec, used by the loop laws.

use crate::model::TsModel;
use tsf_lang::spec::{Trigger, TriggerSynthesis, Weight};

/// Whether the spec asks for a synthesized trigger weight with the two-step
/// method (`weight = synthesize;`, the default, or `weight = synthesize two_step;`)
/// or by co-design (`weight = synthesize codesign;`, which starts from it).
pub fn wanted(model: &TsModel) -> bool {
    matches!(
        model.spec.trigger.as_ref().map(|t| &t.node),
        Some(Trigger::Aperiodic {
            weight: Weight::Synthesize,
            ..
        })
    ) && matches!(
        model.spec.trigger_synthesis,
        None | Some(TriggerSynthesis::TwoStep)
            | Some(TriggerSynthesis::Codesign { .. })
            | Some(TriggerSynthesis::Transmissions { .. })
    )
}

/// The rounds of `weight = synthesize codesign(rounds = ..);`, if the spec asks for co-design.
pub fn codesign_rounds(model: &TsModel) -> Option<u32> {
    match model.spec.trigger_synthesis {
        Some(TriggerSynthesis::Codesign { rounds }) if wanted(model) => Some(rounds),
        _ => None,
    }
}

/// The points of `weight = synthesize transmissions(points = ..);`, if the
/// spec asks for a few-transmissions design.
pub fn transmission_points(model: &TsModel) -> Option<(u32, Option<f64>)> {
    match model.spec.trigger_synthesis {
        Some(TriggerSynthesis::Transmissions { points, gamma }) if wanted(model) => {
            Some((points, gamma))
        }
        _ => None,
    }
}

/// The threshold the trigger LMIs are solved for: the adaptive law's ceiling,
/// else the static nu, else 0 (no threshold: every sample transmitted).
pub fn certified_threshold(model: &TsModel) -> f64 {
    match model.spec.trigger.as_ref().map(|t| &t.node) {
        Some(Trigger::Aperiodic {
            threshold: Some(t), ..
        }) => t.ceiling(),
        _ => 0.0,
    }
}
