//! The plain data of a certified design that every consumer of the gains
//! reads: dimensions, premise code, rule premises, rule centres, gain tables,
//! saturation levels, header facts and the sensor-side trigger. The code
//! generators render it ([`crate::codegen`]); the simulator runs it in closed
//! loop ([`crate::sim`]).

mod adaptive;
mod error;
mod f32_range;
mod factored;
pub mod observer;
mod sensor;
mod signal;
pub mod static_output;
pub mod sym;

pub use adaptive::{adaptive_tables, AdaptiveTables};
pub use error::TablesError;
pub use factored::FactoredTerms;
pub use observer::{ObserverTables, PremiseFrom};
pub use sensor::{SensorLaw, SensorTables};
pub use signal::SignalSensorTables;

use crate::certify::Certificate;
use crate::model::{TermSpec, TsModel};
use crate::synth::{Achieved, Design};
use sym::{premise_entries, Func, Sym};
use tsf_lang::spec::{CStyle, Precision};

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
    /// Floating-point type the tables are stored in.
    pub precision: Precision,
    /// Worst margin of the certificate re-checked with the tables as stored
    /// (`None` if the certificate carries no stored-precision check).
    pub stored_margin: Option<f64>,
    /// Relaxation used (with the membership-mismatch bound the certificate
    /// relies on, if any).
    pub relaxation: String,
    /// Certified sampling intervals [h_min, h_max] in s (equal: a period) of a
    /// loop that transmits every sample; `None` for a continuous loop or an
    /// event trigger (its sensor module carries its sampling).
    pub sampling: Option<(f64, f64)>,
    /// What the step reads when it is not the state (static output
    /// feedback: the measured output), one sentence for every file's header.
    pub reads: Option<String>,
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
    /// The rule premises over their distinct terms (what generated code
    /// evaluates: each distinct term once per step).
    pub factored: FactoredTerms,
    /// Rule centres (R x P).
    pub centres: Vec<Vec<f64>>,
    /// Gains F_j as rows (R x M x N).
    pub gains: Vec<Vec<Vec<f64>>>,
    /// Saturation levels (infinite when a channel is not limited).
    pub u_max: Vec<f64>,
    /// Floating-point type of generated code.
    pub precision: Precision,
    /// Style of the generated C step (`emit c(style = ..)`).
    pub c_style: CStyle,
    /// The sensor-side module of the loop's law, if it has one.
    pub sensor: Sensor,
    /// Per-mode gains of a mode-dependent design (`modes { design =
    /// mode_dependent; }`): generated code takes the active mode each step.
    /// `None` without modes and for fault-blind (mode-independent) gains,
    /// which are `gains` in every mode.
    pub modes: Option<ModeTables>,
    /// The observer of an observer-based design (output feedback): the
    /// generated step takes the measured output y and a caller-owned state
    /// holding the estimate. `None`: state feedback.
    pub observer: Option<ObserverTables>,
    /// A static-output-feedback design: the tables are the controller on y
    /// (`n` outputs named in `state_names`, gains K_j); this holds the plant's
    /// C and state names. `None` otherwise.
    pub static_output: Option<static_output::StaticOutputTables>,
}

/// The sensor-side module of a networked loop: one variant per loop law
/// that has one. The loop is generated as this sensor module and the
/// controller module (fed what the sensor transmits).
#[derive(Debug, Clone, PartialEq, Default)]
pub enum Sensor {
    /// No sensor module (continuous or periodic loop, or a loop with modes).
    #[default]
    None,
    /// An aperiodic trigger (`trigger aperiodic { .. }`): every sample, or
    /// an event condition with a weight and a threshold.
    Aperiodic(SensorTables),
    /// The mixed trigger on a signal (`trigger mixed { on = ..; }`).
    Mixed(SignalSensorTables),
}

impl Sensor {
    /// The aperiodic trigger's tables, if the loop has one.
    pub fn aperiodic(&self) -> Option<&SensorTables> {
        match self {
            Sensor::Aperiodic(s) => Some(s),
            _ => None,
        }
    }

    /// The aperiodic trigger's tables, mutable.
    pub fn aperiodic_mut(&mut self) -> Option<&mut SensorTables> {
        match self {
            Sensor::Aperiodic(s) => Some(s),
            _ => None,
        }
    }

    /// The mixed trigger's tables, if the loop has one.
    pub fn mixed(&self) -> Option<&SignalSensorTables> {
        match self {
            Sensor::Mixed(s) => Some(s),
            _ => None,
        }
    }

    /// Whether the loop has a sensor module.
    pub fn is_some(&self) -> bool {
        !matches!(self, Sensor::None)
    }
}

/// The gain sets of a mode-dependent design.
#[derive(Debug, Clone, PartialEq)]
pub struct ModeTables {
    /// Mode names, in the spec's order (mode index = position).
    pub names: Vec<String>,
    /// Gains F_aj as rows (K x R x M x N); mode 0's are [`Tables::gains`].
    pub gains: Vec<Vec<Vec<Vec<f64>>>>,
}

/// The rows of a matrix.
fn matrix_rows(f: &nalgebra::DMatrix<f64>) -> Vec<Vec<f64>> {
    (0..f.nrows())
        .map(|i| f.row(i).iter().copied().collect())
        .collect()
}

/// The per-mode gains of a mode-dependent design, `None` otherwise.
fn mode_tables(model: &TsModel, design: &Design) -> Option<ModeTables> {
    let modes = model.spec.modes.as_ref()?;
    let md = design.modes.as_ref()?;
    (modes.design == tsf_lang::modes::ModeDesign::Dependent).then(|| ModeTables {
        names: modes.modes.iter().map(|m| m.name.clone()).collect(),
        gains: md
            .gains
            .iter()
            .map(|set| set.iter().map(matrix_rows).collect())
            .collect(),
    })
}

/// The achieved objectives named in generated headers, `(name, value)` with
/// the value formatted.
fn achieved_objectives(a: &Achieved) -> Vec<(String, String)> {
    a.bounds()
        .map(|(q, v)| (q.key().to_string(), format!("{v:.6e}")))
        .collect()
}

/// The premise code of the model: `z = L x` when every premise component is
/// linear in x, else one scalar expression per component.
pub(crate) fn premise_code(model: &TsModel) -> Result<PremiseCode, TablesError> {
    let spec = &model.spec;
    let mut entries = Vec::new();
    for p in &spec.premises {
        let all = premise_entries(spec, &p.expr).map_err(|e| TablesError::Premise {
            name: p.name.clone(),
            reason: e,
        })?;
        match p.component {
            Some(k) => {
                entries.push(
                    all.get(k)
                        .cloned()
                        .ok_or_else(|| TablesError::PremiseComponent {
                            name: p.name.clone(),
                            component: k,
                        })?,
                )
            }
            None => entries.extend(all),
        }
    }
    if entries.len() != model.premises.len() {
        return Err(TablesError::PremiseCount {
            entries: entries.len(),
            components: model.premises.len(),
        });
    }
    let linear: Option<Vec<Vec<f64>>> = entries.iter().map(|s| s.linear(model.n)).collect();
    Ok(match linear {
        Some(l) => PremiseCode::Linear(l),
        None => PremiseCode::Exprs(entries),
    })
}

/// Builds the tables of a certified design (a refused certificate has none).
/// Errors say what cannot be generated.
pub fn tables(
    model: &TsModel,
    design: &Design,
    cert: &Certificate,
    spec_path: &str,
    spec_sha256: &str,
) -> Result<Tables, TablesError> {
    if !cert.ok {
        return Err(TablesError::NotCertified);
    }
    let spec = &model.spec;
    let premise = premise_code(model)?;
    f32_range::checked(Tables {
        name: spec.controller.node.clone(),
        header: Header {
            tsfc_version: env!("CARGO_PKG_VERSION").to_string(),
            spec_path: spec_path.to_string(),
            spec_sha256: spec_sha256.to_string(),
            objectives: achieved_objectives(&design.achieved),
            min_margin: cert.min_margin,
            precision: spec.precision,
            stored_margin: cert.stored.as_ref().map(|s| s.worst_margin),
            relaxation: match crate::synth::relaxations::kappa_relied_on(model) {
                Some(kappa) => format!(
                    "{}; valid while the controller's memberships are within {kappa} of the plant's",
                    spec.relaxation.node
                ),
                None => match &design.fuzzy {
                    Some(f) => format!(
                        "{}, lyapunov {}; valid while |dh_k/dt| <= phi_k for every rule{}",
                        spec.relaxation.node,
                        spec.lyapunov.node,
                        f.region.as_ref().map_or(String::new(), |r| format!(
                            " (checked by sampling on the level set V <= {:.6e})",
                            r.level
                        ))
                    ),
                    None => spec.relaxation.node.to_string(),
                },
            },
            sampling: design.sampling(),
            reads: None,
        },
        n: model.n,
        m: model.m,
        p: model.premises.len(),
        r: model.r(),
        state_names: tsf_lang::spec::Signal::names_of(&spec.states),
        input_names: tsf_lang::spec::Signal::names_of(&spec.inputs),
        rule_names: model.rules.iter().map(|r| r.name.clone()).collect(),
        premise,
        terms: model.terms.clone(),
        factored: FactoredTerms::new(&model.terms),
        centres: model.centers.clone(),
        gains: design.gains.iter().map(matrix_rows).collect(),
        u_max: spec
            .saturation
            .clone()
            .unwrap_or_else(|| vec![f64::INFINITY; model.m]),
        precision: spec.precision,
        c_style: spec.c_style,
        sensor: match (
            sensor::sensor_tables(model, design)?,
            signal::signal_sensor_tables(model, design)?,
        ) {
            (Some(s), _) => Sensor::Aperiodic(s),
            (None, Some(s)) => Sensor::Mixed(s),
            (None, None) => Sensor::None,
        },
        modes: mode_tables(model, design),
        observer: observer::of_design(model, design)?,
        static_output: None,
    })
    .and_then(|t| static_output::on_output(t, design))
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
