//! The plant-claim seam in tests: a closed-form model-error bound, the
//! textbook spec's exact error, and the driver's plant compile with the
//! report checked against its schema.

use super::schema::report_json;
use tsfc::driver::compile::Compiled;
use tsfc::driver::plant::{compile, PlantRequest};
use tsfc::model::plant_error::{PlantError, StateBox};
use tsfc::model::TsModel;
use tsfc::report::SpecInfo;
use tsfc::synth::Settings;

/// A closed-form bound: ||dA|| <= a, ||dB|| = 0.
pub fn known(a: f64) -> PlantError {
    PlantError {
        a,
        b: 0.0,
        d: None,
        boxes: 1,
        converged: true,
        sampled_max: (a, 0.0),
    }
}

/// The textbook spec's exact error over a box: max over |x1| <= w of
/// 2 |x1| - x1^2 (the blend interpolates the stiffness 1 - x1^2 linearly
/// between rules at x1 = -2, 0, 2).
#[allow(clippy::result_large_err)] // the seam's error is the model stage's Diagnostic
pub fn textbook_error(_: &TsModel, region: &StateBox) -> Result<PlantError, tsf_lang::Diagnostic> {
    let w = region[0].0.abs().max(region[0].1.abs()).min(2.0);
    let top = w.min(1.0);
    Ok(known(2.0 * top - top * top))
}

/// The driver's plant compile of `model` for `request`, its report checked
/// against the schema.
pub fn run(model: &TsModel, request: PlantRequest<'_>) -> Compiled {
    let info = SpecInfo {
        path: "test.tsf".into(),
        sha256: String::new(),
    };
    let c = compile(
        model,
        info,
        &Settings::default(),
        Default::default(),
        request,
    );
    report_json(&c.report);
    c
}
