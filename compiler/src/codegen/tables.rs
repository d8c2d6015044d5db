//! The plain data every code generator consumes: dimensions, premise code,
//! rule premises, rule centres, gain tables, saturation levels, header facts.

use super::sym::{premise_entries, Func, Sym};
use crate::certify::Certificate;
use crate::model::{TermSpec, TsModel};
use crate::synth::Design;
use tsf_lang::spec::{Precision, Trigger, Weight};

/// How generated code computes the premise vector z from x.
#[derive(Debug, Clone, PartialEq)]
pub enum PremiseCode {
    /// z = L x (P rows of N): evaluated by the runtime.
    Linear(Vec<Vec<f64>>),
    /// One scalar expression of x per premise component.
    Exprs(Vec<Sym>),
}

/// Facts for the generated file's header comment.
#[derive(Debug, Clone, PartialEq)]
pub struct Header {
    /// tsfc version.
    pub tsfc_version: String,
    /// Spec path as given (relative paths keep outputs reproducible).
    pub spec_path: String,
    /// SHA-256 of the spec.
    pub spec_sha256: String,
    /// Achieved objectives, formatted.
    pub objectives: Vec<(String, String)>,
    /// Certificate's minimum margin.
    pub min_margin: f64,
    /// Relaxation used.
    pub relaxation: String,
}

/// Everything a generator needs.
#[derive(Debug, Clone, PartialEq)]
pub struct Tables {
    /// Controller name (a Rust and C identifier).
    pub name: String,
    /// Header facts.
    pub header: Header,
    /// States.
    pub n: usize,
    /// Inputs.
    pub m: usize,
    /// Premise components.
    pub p: usize,
    /// Rules.
    pub r: usize,
    /// Names of the state components, in order (`w[0]`, ..., `theta`).
    pub state_names: Vec<String>,
    /// Names of the input components.
    pub input_names: Vec<String>,
    /// Rule names.
    pub rule_names: Vec<String>,
    /// Premise computation.
    pub premise: PremiseCode,
    /// Rule premises.
    pub terms: Vec<Vec<TermSpec>>,
    /// Rule centres (R x P).
    pub centres: Vec<Vec<f64>>,
    /// Gains F_j as rows (R x M x N).
    pub gains: Vec<Vec<Vec<f64>>>,
    /// Saturation levels (infinite when a channel is not limited).
    pub u_max: Vec<f64>,
    /// Floating-point type of generated code.
    pub precision: Precision,
    /// The sensor-side event trigger (`trigger aperiodic { .. }` only): the
    /// networked loop is generated as a sensor module (this trigger) and the
    /// controller module (fed the transmitted state x(t_k)).
    pub trigger: Option<SensorTables>,
}

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

fn component_names(signals: &[tsf_lang::spec::Signal]) -> Vec<String> {
    signals.iter().flat_map(|s| s.component_names()).collect()
}

/// Builds the tables of a certified design. Errors say what cannot be generated.
pub fn tables(
    model: &TsModel,
    design: &Design,
    cert: &Certificate,
    spec_path: &str,
    spec_sha256: &str,
) -> Result<Tables, String> {
    let spec = &model.spec;
    let n = model.n;
    let mut entries = Vec::new();
    for p in &spec.premises {
        let all =
            premise_entries(spec, &p.expr).map_err(|e| format!("premise `{}`: {e}", p.name))?;
        match p.component {
            Some(k) => entries.push(
                all.get(k)
                    .cloned()
                    .ok_or_else(|| format!("premise `{}`: component {k} missing", p.name))?,
            ),
            None => entries.extend(all),
        }
    }
    if entries.len() != model.premises.len() {
        return Err(format!(
            "internal error: {} premise entries for {} components",
            entries.len(),
            model.premises.len()
        ));
    }
    let linear: Option<Vec<Vec<f64>>> = entries.iter().map(|s| s.linear(n)).collect();
    let premise = match linear {
        Some(l) => PremiseCode::Linear(l),
        None => PremiseCode::Exprs(entries),
    };
    let objectives = design
        .achieved
        .bounds()
        .map(|(q, v)| (q.key().to_string(), format!("{v:.6e}")))
        .collect();
    Ok(Tables {
        name: spec.controller.node.clone(),
        header: Header {
            tsfc_version: env!("CARGO_PKG_VERSION").to_string(),
            spec_path: spec_path.to_string(),
            spec_sha256: spec_sha256.to_string(),
            objectives,
            min_margin: cert.min_margin,
            relaxation: format!("{:?}", spec.relaxation.node),
        },
        n,
        m: model.m,
        p: model.premises.len(),
        r: model.r(),
        state_names: component_names(&spec.states),
        input_names: component_names(&spec.inputs),
        rule_names: model.rules.iter().map(|r| r.name.clone()).collect(),
        premise,
        terms: model.terms.clone(),
        centres: model.centers.clone(),
        gains: design
            .gains
            .iter()
            .map(|f| {
                (0..f.nrows())
                    .map(|i| f.row(i).iter().copied().collect())
                    .collect()
            })
            .collect(),
        u_max: spec
            .saturation
            .clone()
            .unwrap_or_else(|| vec![f64::INFINITY; model.m]),
        precision: spec.precision,
        trigger: sensor_tables(model, design)?,
    })
}

/// The sensor tables of an aperiodic event trigger (`None` for any other
/// triggering law). A synthesized weight must come from the design: there is
/// no sensor module with a made-up weight.
fn sensor_tables(model: &TsModel, design: &Design) -> Result<Option<SensorTables>, String> {
    let Some(Trigger::Aperiodic {
        sampling: (h_min, h_max),
        threshold,
        weight,
    }) = model.spec.trigger.as_ref().map(|t| &t.node)
    else {
        return Ok(None);
    };
    let n = model.n;
    let (u, weight_source, certified) = match weight {
        Weight::Given(mat) => (
            mat.clone(),
            "given in the spec (tsfc did not synthesize the trigger)".to_string(),
            None,
        ),
        Weight::Synthesize => {
            let Some(td) = design.trigger.as_ref() else {
                return Err(
                    "the trigger weight is `synthesize` but the design has no synthesized trigger weight: no sensor module is generated"
                        .into(),
                );
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
        return Err(format!(
            "the trigger weight is {}x{}, expected {n}x{n}",
            u.nrows(),
            u.ncols()
        ));
    }
    if u.iter().any(|v| !v.is_finite()) {
        return Err("the trigger weight has a non-finite entry".into());
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

impl Tables {
    /// The scalar functions the premise code calls.
    pub fn functions(&self) -> Vec<Func> {
        let mut out = Vec::new();
        if let PremiseCode::Exprs(e) = &self.premise {
            for s in e {
                s.functions(&mut out);
            }
        }
        out
    }
}
