//! The few-transmissions search's scorer (`weight = synthesize
//! transmissions;`): each candidate of the search is simulated in the spec's
//! scenario and its transmissions counted. Synthesis receives this function
//! through [`crate::synth::Settings::scorer`], so the synthesis stage does not
//! depend on the simulator; the driver sequences both.

use crate::certify::Certificate;
use crate::model::TsModel;
use crate::sim::{self, source::SpecSource, Prepared};
use crate::synth::loops::LoopDesign;
use crate::synth::{Design, SynthError, TriggerDesign};
use crate::tables;

/// Transmissions of the candidate trigger design `t` (with its gains) in the
/// spec's `simulate` scenario; `Ok(None)` when the spec has no scenario.
///
/// The candidate is not certified yet (its trigger step is solved, the
/// continuous loop is re-analyzed only for the shipped point), so its tables
/// are built under a scoring certificate that is never reported or emitted.
pub fn score(
    model: &TsModel,
    design: &Design,
    t: &TriggerDesign,
) -> Result<Option<u64>, SynthError> {
    if model.spec.simulate.is_none() {
        return Ok(None);
    }
    let failed = |e: &dyn std::fmt::Display| {
        SynthError::Internal(format!(
            "few-transmissions search: simulating a candidate failed: {e}"
        ))
    };
    let mut candidate = design.clone();
    candidate.gains = t.plan.gains.clone();
    candidate.p = t.p.clone();
    candidate.loop_design = LoopDesign::Event(t.clone());
    let scoring = Certificate {
        rule: "few-transmissions scoring (not a certificate)",
        min_margin: 0.0,
        ok: true,
        worst: String::new(),
        lmis: Vec::new(),
        stored: None,
    };
    let name = model.spec.controller.node.clone();
    let tables = tables::tables(model, &candidate, &scoring, &name, "").map_err(|e| failed(&e))?;
    let prepared = Prepared {
        model: model.clone(),
        tables,
        p: t.p.clone(),
        trigger_weight: Some(t.weight.clone()),
        region: None,
        source: SpecSource {
            name,
            text: String::new(),
        },
    };
    let outcome = sim::simulate(&prepared, &sim::Options::default()).map_err(|e| failed(&e))?;
    Ok(Some(outcome.metrics.transmissions))
}
