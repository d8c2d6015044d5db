//! The model stage: a checked [`Spec`] becomes a [`TsModel`]: local linear
//! models per rule, the premise layout, the rule premises as runtime terms,
//! the coverage check, the consistency of the blended model with A(x), B(x)
//! and the finiteness of the premises and A(x), B(x) where the controller runs.

mod consistency;
mod coverage;
pub mod error_bound;
pub mod explain;
mod finite;
mod local;
pub mod observability;
pub mod plant_error;
mod premise;
pub mod region;

pub use consistency::{is_mismatch_warning, Consistency, MISMATCH_TOLERANCE};
pub use coverage::{check_coverage, Coverage};
pub use premise::{membership, premise_values, rule_weight, PremiseLayout, PremiseSlot, TermSpec};

use nalgebra::DMatrix;
use tsf_lang::spec::{Output, Spec};
use tsf_lang::Diagnostic;

/// The local linear model of one rule: x' = A x + B u + D w.
#[derive(Debug, Clone, PartialEq)]
pub struct LocalModel {
    /// Rule name.
    pub name: String,
    /// n x n.
    pub a: DMatrix<f64>,
    /// n x m.
    pub b: DMatrix<f64>,
    /// n x q.
    pub d: DMatrix<f64>,
    /// The operating point, when the rule has one.
    pub at: Option<Vec<f64>>,
}

/// The T-S fuzzy model: what synthesis, code generation and simulation consume.
#[derive(Debug, Clone)]
pub struct TsModel {
    /// The checked spec it came from.
    pub spec: Spec,
    /// States.
    pub n: usize,
    /// Inputs.
    pub m: usize,
    /// Disturbances.
    pub q: usize,
    /// One local model per rule, in rule order.
    pub rules: Vec<LocalModel>,
    /// Premise variables flattened into z.
    pub premises: PremiseLayout,
    /// Per rule: its premise terms (product t-norm).
    pub terms: Vec<Vec<TermSpec>>,
    /// Per rule: its centre in premise space (for the nearest-rule fallback).
    pub centers: Vec<Vec<f64>>,
    /// Result of the coverage check.
    pub coverage: Coverage,
    /// The blended model against A(x), B(x) (`None`: neither depends on x).
    pub consistency: Option<Consistency>,
    /// The model error the design must tolerate (robust conditions; `None`:
    /// the nominal design of the rules' blend).
    pub plant_error: Option<plant_error::PlantError>,
}

impl TsModel {
    /// Number of rules.
    pub fn r(&self) -> usize {
        self.rules.len()
    }

    /// The performance outputs.
    pub fn outputs(&self) -> &[Output] {
        &self.spec.outputs
    }
}

/// Builds the model; errors and warnings go to `diags`. `None` if any error.
pub fn build(spec: Spec, diags: &mut Vec<Diagnostic>) -> Option<TsModel> {
    let errors_before = diags.iter().filter(|d| d.is_error()).count();
    let rules = local::local_models(&spec, diags);
    observability::check(&spec, &rules, diags);
    let premises = premise::layout(&spec, diags);
    let terms = premise::rule_terms(&spec, &premises);
    let centers = premise::rule_centers(&spec, &premises, &terms);
    premise::check_operating_points(&spec, &premises, &terms, diags);
    if finite::origin_in_box(&consistency::bounds(&spec, &rules, spec.n())) {
        let origin = vec![0.0; spec.n()];
        if let Some(d) = finite::diagnose_at(&spec, &origin) {
            diags.push(d);
        }
    }
    if diags.iter().filter(|d| d.is_error()).count() > errors_before {
        return None;
    }
    let coverage = check_coverage(&spec, &premises, &terms, diags);
    if !coverage.covered {
        return None;
    }
    if let tsf_lang::spec::Relaxation::Tanaka { s } = spec.relaxation.node {
        if s < coverage.max_firing {
            diags.push(
                Diagnostic::error(
                    spec.relaxation.span,
                    format!(
                        "tanaka(s = {s}) assumes at most {s} rules fire at once, but up to {} do",
                        coverage.max_firing
                    ),
                )
                .with_label("this relaxation would not be sound")
                .with_help(format!(
                    "use `relaxation tanaka(s = {});` or narrower fuzzy sets",
                    coverage.max_firing
                )),
            );
            return None;
        }
    }
    let consistency = consistency::check(&spec, &rules, &premises, &terms, diags);
    if diags.iter().filter(|d| d.is_error()).count() > errors_before {
        return None;
    }
    let model = TsModel {
        consistency,
        plant_error: None,
        n: spec.n(),
        m: spec.m(),
        q: spec.q(),
        rules,
        premises,
        terms,
        centers,
        coverage,
        spec,
    };
    if let Some(d) = region::diagnose(&model) {
        diags.push(d);
        return None;
    }
    Some(model)
}

/// The scalar sector model z' = -z * z + u, premise z on [-lo, lo] (unit
/// tests of later stages).
#[cfg(test)]
pub(crate) fn scalar_sector_model(lo: f64) -> TsModel {
    let text = format!(
        "tsf 1;\ncontroller c;\nstate z;\ninput u;\nA(x) = [-z];\nB = [1];\n\
         premise z range -{lo} .. {lo};\nrules sector;\nobjective stability;\n"
    );
    let spec = match tsf_lang::check_source(&text) {
        (Some(spec), _) => spec,
        (None, diags) => panic!("{diags:#?}"), // ok: unit test
    };
    build(spec, &mut Vec::new()).expect("model") // ok: unit test
}
