//! The sensor-side tables of a mixed trigger on a named signal
//! (`trigger mixed { on = s; monitor = ..; }`): the signal's scalar
//! expressions of the state, beta, rho and what tsfc certified.

use super::sym::{premise_entries, Sym};
use super::TablesError;
use crate::model::TsModel;
use crate::synth::Design;
use tsf_lang::spec::{Monitor, Trigger};

/// What the sensor module of a mixed trigger on a signal needs.
#[derive(Debug, Clone, PartialEq)]
pub struct SignalSensorTables {
    /// The signal's name (`x` when the trigger monitors the state).
    pub signal: String,
    /// One scalar expression of the state per component.
    pub exprs: Vec<Sym>,
    /// Relative coefficient beta.
    pub beta: f64,
    /// Absolute offset rho.
    pub rho: f64,
    /// `continuous` or `step`.
    pub monitor: &'static str,
    /// The certificate in one line (decay rate and ultimate bound).
    pub certificate: String,
}

/// The tables of a mixed trigger monitored per step or continuously (`None`
/// for any other law). The design must carry its certificate.
pub(super) fn signal_sensor_tables(
    model: &TsModel,
    design: &Design,
) -> Result<Option<SignalSensorTables>, TablesError> {
    let Some(Trigger::Mixed {
        monitor,
        beta,
        rho,
        on,
    }) = model.spec.trigger.as_ref().map(|t| &t.node)
    else {
        return Ok(None);
    };
    if monitor.sampling().is_some() {
        return Ok(None);
    }
    let Some(cert) = design.loop_design.mixed() else {
        return Err(TablesError::TriggerWeightMissing);
    };
    let (signal, exprs) = match on {
        Some(s) => (
            s.name.clone(),
            premise_entries(&model.spec, &s.expr).map_err(|e| TablesError::Premise {
                name: s.name.clone(),
                reason: e,
            })?,
        ),
        None => ("x".to_string(), (0..model.n).map(Sym::X).collect()),
    };
    Ok(Some(SignalSensorTables {
        signal,
        exprs,
        beta: *beta,
        rho: *rho,
        monitor: if *monitor == Monitor::Step {
            "step"
        } else {
            "continuous"
        },
        certificate: format!(
            "certified by tsfc for continuous monitoring: V = x'Px decays at rate lambda = {:.4e} to x'Px <= {:.4e} (||x|| <= {:.4e})",
            cert.lambda, cert.v_inf, cert.x_bound
        ),
    }))
}
