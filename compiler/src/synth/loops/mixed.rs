//! The mixed trigger on a signal (`trigger mixed { on = ..; beta = ..;
//! rho = ..; monitor = continuous; }`): transmit when ||e_s|| >= beta
//! ||s|| + rho. Certified for the continuous design's gains with an ultimate
//! bound ([`crate::synth::signal_trigger`]).

use super::{Condition, LoopCertificate, LoopDesign, LoopLaw, Rounding, Start};
use crate::model::TsModel;
use crate::synth::design::{Design, SynthError};
use crate::synth::reduction::Reduction;
use crate::synth::search::Runner;
use crate::synth::signal_trigger::{self, SignalTrigger};
use nalgebra::DMatrix;
use tsf_lang::spec::Trigger;

/// The mixed trigger monitored continuously.
#[derive(Debug, Clone, Copy)]
pub struct Mixed;

impl LoopLaw for Mixed {
    fn name(&self) -> &'static str {
        "mixed trigger"
    }

    fn claims(&self, model: &TsModel) -> bool {
        signal_trigger::wanted(model).is_some()
    }

    fn design(
        &self,
        runner: &mut Runner<'_>,
        d: &mut Design,
        _: &Start,
    ) -> Result<LoopDesign, SynthError> {
        let gains = d.gains.clone();
        let cert = signal_trigger::certify_loop(runner, runner.model, &gains)?;
        d.notes.push(format!(
            "mixed trigger on `{}`: certified with lambda = {:.4e}, tau = {:.4e}, eps = {}, ultimate bound ||x|| <= {:.4e}",
            cert.signal, cert.lambda, cert.tau, cert.eps, cert.x_bound
        ));
        Ok(LoopDesign::Mixed(cert))
    }
}

impl LoopCertificate for SignalTrigger {
    fn conditions(
        &self,
        model: &TsModel,
        _eps: f64,
        gains: &[DMatrix<f64>],
        stored: Option<Rounding<'_>>,
    ) -> Result<Vec<Condition>, SynthError> {
        // b1 scales with beta: the stored beta over the spec's.
        let beta_scale = match (stored, model.spec.trigger.as_ref().map(|t| &t.node)) {
            (Some(s), Some(Trigger::Mixed { beta, .. })) if *beta > 0.0 => s(*beta) / beta,
            _ => 1.0,
        };
        Ok(signal_trigger::margins(model, gains, self, beta_scale)
            .into_iter()
            .map(|(name, margin, error_bound, size)| {
                // The image identity is a tolerance check, not a strict LMI.
                let strict = size > 1 || name.ends_with("tau > 0");
                Condition::Margin {
                    ok: if strict {
                        margin > error_bound
                    } else {
                        margin >= 0.0
                    },
                    strict,
                    name,
                    margin,
                    error_bound,
                    size,
                }
            })
            .collect())
    }

    fn reductions(&self) -> &[Reduction] {
        &[]
    }
}
