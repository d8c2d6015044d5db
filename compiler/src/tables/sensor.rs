//! The sensor-side tables of an aperiodic event trigger: sampling bounds,
//! weight, threshold law and what tsfc certified about the loop.

use super::TablesError;
use crate::model::TsModel;
use crate::synth::Design;
use tsf_lang::spec::{Trigger, Weight};

/// The threshold law of a sensor-side trigger.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SensorLaw {
    /// No threshold in the spec: every sample is transmitted.
    EverySample,
    /// Static relative trigger: transmit iff `e'U e >= nu x_k'U x_k`
    /// (`tsf_runtime::RelativeTrigger`, `nu = nu_min = nu_max`).
    Relative,
    /// Adaptive threshold (Xu & Huang 2020) with `(mu1, mu2, mu3)`,
    /// `nu(t_k)` kept in `[nu_min, nu_max]` (`tsf_runtime::AdaptiveTrigger`
    /// with `with_max(nu_max)`).
    Adaptive(f64, f64, f64),
}

/// What the sensor module of an aperiodic event trigger needs.
#[derive(Debug, Clone, PartialEq)]
pub struct SensorTables {
    /// Shortest sampling interval h_min (s).
    pub h_min: f64,
    /// Longest sampling interval h_max (s).
    pub h_max: f64,
    /// Trigger weight U (N rows of N).
    pub weight: Vec<Vec<f64>>,
    /// Lower bound and initial value of the threshold (0 without a threshold).
    pub nu_min: f64,
    /// Ceiling of the threshold: the value the loop is certified for
    /// (`Threshold::ceiling`; 0 without a threshold).
    pub nu_max: f64,
    /// Threshold law (with `(mu1, mu2, mu3)` when adaptive).
    pub law: SensorLaw,
    /// Where the weight comes from, for the header (`given in the spec` or
    /// `synthesized by tsfc ...`).
    pub weight_source: String,
    /// Certified threshold and L-inf bound of the event-triggered loop, when
    /// tsfc synthesized (and so certified) the trigger.
    pub certified: Option<(f64, f64)>,
}

/// The sensor tables of an aperiodic event trigger (`None` for any other
/// triggering law). A synthesized weight must come from the design: there is
/// no sensor module with a made-up weight.
pub(super) fn sensor_tables(
    model: &TsModel,
    design: &Design,
) -> Result<Option<SensorTables>, TablesError> {
    let Some(Trigger::Aperiodic {
        sampling: (h_min, h_max),
        threshold,
        weight,
    }) = model.spec.trigger.as_ref().map(|t| &t.node)
    else {
        return Ok(None);
    };
    // With modes the aperiodic trigger has no threshold (the checker refuses
    // one): every sample is transmitted and no sensor module is generated.
    if model.spec.modes.is_some() {
        return Ok(None);
    }
    let n = model.n;
    let (u, weight_source, certified) = match weight {
        Weight::Given(mat) => (
            mat.clone(),
            "given in the spec (tsfc did not synthesize the trigger)".to_string(),
            None,
        ),
        Weight::Synthesize => {
            let Some(td) = design.loop_design.event() else {
                return Err(TablesError::TriggerWeightMissing);
            };
            (
                td.weight.clone(),
                format!(
                    "synthesized by tsfc ({}: for the fixed PDC gains)",
                    td.method
                ),
                Some((td.plan.nu, td.gamma)),
            )
        }
    };
    if u.nrows() != n || u.ncols() != n {
        return Err(TablesError::TriggerWeightShape {
            rows: u.nrows(),
            cols: u.ncols(),
            n,
        });
    }
    if u.iter().any(|v| !v.is_finite()) {
        return Err(TablesError::TriggerWeightNonFinite);
    }
    let (nu_min, nu_max, adaptive) = match threshold {
        Some(th) => (th.nu, th.ceiling(), th.adaptive),
        None => (0.0, 0.0, None),
    };
    let law = match (threshold, adaptive) {
        (None, _) => SensorLaw::EverySample,
        (Some(_), None) => SensorLaw::Relative,
        (Some(_), Some((a, b, c))) => SensorLaw::Adaptive(a, b, c),
    };
    Ok(Some(SensorTables {
        h_min: *h_min,
        h_max: *h_max,
        weight: (0..n).map(|i| u.row(i).iter().copied().collect()).collect(),
        nu_min,
        nu_max,
        law,
        weight_source,
        certified,
    }))
}

impl SensorTables {
    /// `(mu1, mu2, mu3)` of the adaptive law, if adaptive.
    pub fn adaptive(&self) -> Option<(f64, f64, f64)> {
        match self.law {
            SensorLaw::Adaptive(a, b, c) => Some((a, b, c)),
            _ => None,
        }
    }
}
