//! The model error in the sampled loop's blocks (issue 34): the looped
//! functional made robust to ||A(x) - A_h(x)|| <= a (synth/loop_error.rs),
//! nominal bit for bit at a = 0, infeasible for a large error, re-checked by
//! the certificate, and the plant claim of a loop sampled every h seconds;
//! plus `plant region` over a vector state.

use crate::common;
use crate::common::plant::{known, run, textbook_error};
use tsfc::driver::compile::{Compiled, Status};
use tsfc::driver::plant::PlantRequest;
use tsfc::model::TsModel;
use tsfc::synth::loops::LoopDesign;

/// The textbook spec (rules at x1 = -r, 0, r; shipped with r = 2) sampled
/// every 10 ms.
fn sampled_textbook(r: f64) -> TsModel {
    let text =
        std::fs::read_to_string(common::spec_path("textbook_operating_points.tsf")).expect("spec");
    assert!(text.contains("const r = 2;"));
    let text = text.replace("const r = 2;", &format!("const r = {r};"));
    common::model_of(
        "sampled.tsf",
        &format!("{text}trigger periodic {{ every = 0.01; }}\n"),
    )
}

/// The sampled loop's solved values (name, value).
fn loop_values(c: &Compiled) -> Vec<(String, nalgebra::DMatrix<f64>)> {
    match &c.outcome.as_ref().expect("a design").0.loop_design {
        LoopDesign::EverySample(s) => s.values.clone(),
        _ => panic!("an every-sample loop"),
    }
}

#[test]
fn robust_sampled_blocks_are_nominal_at_zero_and_infeasible_for_a_large_error() {
    // Rules at x1 = -0.5, 0, 0.5: the nominal gains certify every pair.
    let mut model = sampled_textbook(0.5);
    let base = run(&model, PlantRequest::default());
    assert_eq!(
        base.status,
        Status::Certified,
        "{:?}",
        base.report.diagnosis
    );
    model.plant_error = Some(known(0.0));
    let zero = run(&model, PlantRequest::default());
    assert_eq!(zero.status, Status::Certified);
    assert_eq!(loop_values(&zero), loop_values(&base), "bit for bit at 0");
    model.plant_error = Some(known(0.05));
    let small = run(&model, PlantRequest::default());
    assert_eq!(
        small.status,
        Status::Certified,
        "{:?}",
        small.report.diagnosis
    );
    let values = loop_values(&small);
    for r in [1, 2] {
        let name = format!("trigger robust r={r} eps_a");
        let eps = values.iter().find(|(n, _)| *n == name);
        assert!(eps.is_some_and(|(_, v)| v[(0, 0)] > 0.0), "{name}");
    }
    assert!(
        values.iter().all(|(n, _)| !n.ends_with("eps_b")),
        "no dB column when b = 0"
    );
    // The certificate rebuilt the robust blocks: its sampled-loop LMIs are
    // larger than the nominal ones (k + n rows plus one n column per term).
    let size = |c: &Compiled| {
        let cert = c.report.certificate.as_ref().expect("certificate");
        cert.lmis
            .iter()
            .filter(|l| l.name.starts_with("trigger r=1"))
            .map(|l| l.size)
            .max()
            .unwrap_or(0)
    };
    assert!(
        size(&small) > size(&base),
        "{} vs {}",
        size(&small),
        size(&base)
    );
    model.plant_error = Some(known(50.0));
    let large = run(&model, PlantRequest::default());
    assert_ne!(large.status, Status::Certified);
}

#[test]
fn a_sampled_loop_gets_a_plant_claim_on_a_shrunk_region() {
    let model = sampled_textbook(2.0);
    let c = run(
        &model,
        PlantRequest {
            bound: Some(&textbook_error),
            region: None,
        },
    );
    assert_eq!(c.status, Status::Certified, "{:?}", c.report.diagnosis);
    let plant = &c.report.plant;
    let claim = plant.claim.as_deref().expect("a plant claim");
    assert!(claim.contains("sampled every 0.01 s"), "{claim}");
    assert!(claim.contains("is asymptotically stable"), "{claim}");
    let (lo, hi) = plant.region[0].expect("x1 bounded");
    assert!(lo > -2.0 && hi < 2.0, "shrunk: [{lo}, {hi}]");
    // P of the claim is the sampled loop's, not the continuous design's.
    let d = &c.outcome.as_ref().expect("design").0;
    let LoopDesign::EverySample(s) = &d.loop_design else {
        panic!("every sample")
    };
    let p = plant.p.as_ref().expect("P");
    assert_eq!(p[0][0], s.p[(0, 0)]);
    let level = plant.level.expect("level");
    let extents = plant.extents.as_ref().expect("extents");
    assert!(
        extents[0] <= hi.min(-lo) * (1.0 + 1e-12),
        "{extents:?} inside x1's bound"
    );
    assert!(level > 0.0);
}

#[test]
fn a_vector_state_s_plant_region_reaches_the_driver() {
    let xu = std::fs::read_to_string(common::spec_path("xu2020_regional.tsf")).expect("spec");
    let model = common::model_of(
        "xu.tsf",
        &format!("{xu}plant region w = -0.01 .. 0.01, q[2] = -0.02 .. 0.03;\n"),
    );
    let region = model.spec.plant_region.as_ref().expect("region");
    let inf = (f64::NEG_INFINITY, f64::INFINITY);
    assert_eq!(
        region,
        &vec![
            (-0.01, 0.01),
            (-0.01, 0.01),
            (-0.01, 0.01),
            inf,
            inf,
            (-0.02, 0.03)
        ]
    );
    let words = tsfc::report::plant::region_words(&model, region);
    assert_eq!(
        words,
        "w[0] in [-0.010000, 0.010000], w[1] in [-0.010000, 0.010000], w[2] in [-0.010000, 0.010000], q[2] in [-0.020000, 0.030000]"
    );
}
