//! The plain data of a well-posed adaptive design (docs/adaptive.md) that the
//! code generators render: the premise code and factored rule premises (as
//! for a PDC controller, so the firing strengths are the runtime's), the
//! law's tables and initial estimates, and the controller period.

use super::{premise_code, FactoredTerms, Header, Tables, TablesError};
use crate::model::TsModel;
use crate::synth::adaptive::Design;
use tsf_lang::spec::Signal;

/// Everything a generator needs for an adaptive controller.
#[derive(Debug, Clone)]
pub struct AdaptiveTables {
    /// Name, header facts, dimensions, names, premise code, factored rule
    /// premises and centres (no gains: `gains` is empty, `u_max` infinite).
    pub base: Tables,
    /// The law's numbers: C, A_m, P, rates, bounds, layer, initial estimates
    /// (negative zeros made +0).
    pub design: Design,
    /// Controller period in seconds (the `simulate` block's step): the
    /// update laws are integrated over it at every step.
    pub dt: f64,
}

/// Builds the tables of a well-posed adaptive design. The period is the
/// `simulate` block's step ([`TablesError::AdaptivePeriod`] without one).
pub fn adaptive_tables(
    model: &TsModel,
    design: &Design,
    spec_path: &str,
    spec_sha256: &str,
) -> Result<AdaptiveTables, TablesError> {
    let spec = &model.spec;
    let dt = spec
        .simulate
        .as_ref()
        .map(|s| s.time.2)
        .filter(|h| h.is_finite() && *h > 0.0)
        .ok_or(TablesError::AdaptivePeriod)?;
    let base = Tables {
        name: spec.controller.node.clone(),
        header: Header {
            tsfc_version: env!("CARGO_PKG_VERSION").to_string(),
            spec_path: spec_path.to_string(),
            spec_sha256: spec_sha256.to_string(),
            objectives: Vec::new(),
            min_margin: f64::NAN,
            precision: spec.precision,
            stored_margin: None,
            relaxation: String::new(),
            sampling: Some((dt, dt)),
            reads: None,
        },
        n: model.n,
        m: model.m,
        p: model.premises.len(),
        r: model.r(),
        state_names: Signal::names_of(&spec.states),
        input_names: Signal::names_of(&spec.inputs),
        rule_names: model.rules.iter().map(|r| r.name.clone()).collect(),
        premise: premise_code(model)?,
        terms: model.terms.clone(),
        factored: FactoredTerms::new(&model.terms),
        centres: model.centers.clone(),
        gains: Vec::new(),
        u_max: vec![f64::INFINITY; model.m],
        precision: spec.precision,
        c_style: spec.c_style,
        sensor: crate::tables::Sensor::None,
        modes: None,
        observer: None,
        static_output: None,
    };
    let mut design = design.clone();
    for table in [
        &mut design.c,
        &mut design.a_m,
        &mut design.p,
        &mut design.a0,
        &mut design.b0,
    ] {
        table.iter_mut().for_each(|v| *v = positive_zero(*v));
    }
    design.d0 = positive_zero(design.d0);
    Ok(AdaptiveTables { base, design, dt })
}

/// `v` with a negative zero made +0 (`-1 * eye(3)` has -0 entries): the
/// Rust literals have no sign on zero, so both languages get +0 and the same
/// bits.
fn positive_zero(v: f64) -> f64 {
    v + 0.0
}
