//! The plant claim (issue 34, part B): the model error as norm-bounded
//! uncertainty in the decrease LMIs, the certified set E(P, c) inside the
//! region, and the claim checked independently on the nonlinear plant.
//!
//! The model-error bounds here are known in closed form and passed through
//! the driver's seam ([`tsfc::driver::plant::ErrorBound`]); the rigorous bound
//! of the model stage plugs into the same seam.

use crate::common;
use nalgebra::{DMatrix, DVector};
use tsfc::driver::compile::{Compiled, Status};
use tsfc::driver::plant::{compile, PlantRequest};
use tsfc::model::plant_error::{PlantError, StateBox};
use tsfc::model::TsModel;
use tsfc::report::SpecInfo;
use tsfc::synth::Settings;

const TEXTBOOK: &str = "textbook_operating_points.tsf";
/// The rules of the textbook spec sit at x1 = -R, 0, R.
const R: f64 = 2.0;
const DELTA: f64 = 0.25;

/// A closed-form bound: ||dA|| <= a, ||dB|| = 0.
fn known(a: f64) -> PlantError {
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
/// R |x1| - x1^2 (the blend interpolates the stiffness 1 - x1^2 linearly).
fn textbook_error(_: &TsModel, region: &StateBox) -> Result<PlantError, tsf_lang::Diagnostic> {
    let w = region[0].0.abs().max(region[0].1.abs()).min(R);
    let top = (R / 2.0).min(w);
    Ok(known(R * top - top * top))
}

fn run(model: &TsModel, request: PlantRequest<'_>) -> Compiled {
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
    common::schema::report_json(&c.report);
    c
}

fn nominal(model: &TsModel) -> Compiled {
    run(model, PlantRequest::default())
}

fn design(c: &Compiled) -> &tsfc::synth::Design {
    &c.outcome.as_ref().expect("a design").0
}

#[test]
fn robust_lmis_are_the_nominal_ones_at_zero_and_infeasible_for_a_large_error() {
    let mut model = common::shipped(TEXTBOOK);
    let base = nominal(&model);
    assert_eq!(base.status, Status::Certified);
    model.plant_error = Some(known(0.0));
    let zero = nominal(&model);
    assert_eq!(zero.status, Status::Certified);
    assert_eq!(design(&zero).gains, design(&base).gains, "bit for bit at 0");
    assert_eq!(design(&zero).p, design(&base).p);
    model.plant_error = Some(known(0.05));
    let small = nominal(&model);
    assert_eq!(small.status, Status::Certified, "{:?}", small.report.diagnosis);
    let cert = small.report.certificate.as_ref().expect("certificate");
    assert!(
        cert.lmis.iter().any(|l| l.name.starts_with("robust decay")),
        "the certificate re-checks the robust conditions"
    );
    model.plant_error = Some(known(5.0));
    let large = nominal(&model);
    assert_ne!(large.status, Status::Certified);
}
