//! The plant claim (issue 34, part B): the model error as norm-bounded
//! uncertainty in the decrease LMIs, the certified set E(P, c) inside the
//! region, and the claim checked independently on the nonlinear plant.
//!
//! The model-error bounds here are known in closed form and passed through
//! the driver's seam ([`tsfc::driver::plant::ErrorBound`]); the rigorous bound
//! of the model stage plugs into the same seam.

use crate::common;
use crate::common::plant::{known, run, textbook_error};
use nalgebra::{DMatrix, DVector};
use tsfc::driver::compile::{Compiled, Status};
use tsfc::driver::plant::PlantRequest;
use tsfc::model::plant_error::{PlantError, StateBox};
use tsfc::model::TsModel;

const TEXTBOOK: &str = "textbook_operating_points.tsf";
/// The rules of the textbook spec sit at x1 = -R, 0, R.
const R: f64 = 2.0;
const DELTA: f64 = 0.25;

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
    assert_eq!(
        small.status,
        Status::Certified,
        "{:?}",
        small.report.diagnosis
    );
    let cert = small.report.certificate.as_ref().expect("certificate");
    assert!(
        cert.lmis.iter().any(|l| l.name.starts_with("robust decay")),
        "the certificate re-checks the robust conditions"
    );
    model.plant_error = Some(known(5.0));
    let large = nominal(&model);
    assert_ne!(large.status, Status::Certified);
}

/// The textbook plant x' = A(x) x + B u under the PDC law of the gains.
fn textbook_rhs(x: &DVector<f64>, gains: &[DMatrix<f64>]) -> DVector<f64> {
    let x1 = x[0].clamp(-R, R);
    let h = [(-x1 / R).max(0.0), 1.0 - x1.abs() / R, (x1 / R).max(0.0)];
    let u: f64 = gains
        .iter()
        .zip(h)
        .map(|(f, hj)| hj * (f * x)[(0, 0)])
        .sum();
    DVector::from_vec(vec![x[1], (1.0 - x[0] * x[0]) * x[0] - DELTA * x[1] + u])
}

fn rk4(x: &DVector<f64>, dt: f64, gains: &[DMatrix<f64>]) -> DVector<f64> {
    let k1 = textbook_rhs(x, gains);
    let k2 = textbook_rhs(&(x + &k1 * (dt / 2.0)), gains);
    let k3 = textbook_rhs(&(x + &k2 * (dt / 2.0)), gains);
    let k4 = textbook_rhs(&(x + &k3 * dt), gains);
    x + (k1 + k2 * 2.0 + k3 * 2.0 + k4) * (dt / 6.0)
}

#[test]
fn the_plant_claim_holds_on_the_nonlinear_plant_from_the_boundary_of_its_set() {
    let model = common::shipped(TEXTBOOK);
    let c = run(
        &model,
        PlantRequest {
            bound: Some(&textbook_error),
            region: None,
        },
    );
    assert_eq!(c.status, Status::Certified, "{:?}", c.report.diagnosis);
    let plant = &c.report.plant;
    let claim = plant.claim.as_ref().expect("a plant claim");
    let (lo, hi) = plant.region[0].expect("x1 bounded");
    assert!(plant.region[1].is_none(), "x2 unbounded");
    // The blend's region is [-R, R]; the error r^2/4 there is too large.
    assert!(hi < R && lo > -R, "shrunk: [{lo}, {hi}]");
    assert!(plant
        .note
        .as_deref()
        .unwrap_or("")
        .contains("largest region"));
    let bound = plant.error_bound.as_ref().expect("the bound");
    assert!(bound.a > 0.0, "a positive error bound");
    let p = DMatrix::from_fn(2, 2, |i, j| plant.p.as_ref().expect("P")[i][j]);
    let level = plant.level.expect("a level");
    let alpha = c.report.objectives.decay_rate.expect("decay rate");
    assert!(
        claim.contains(&format!("decays at rate >= {alpha}")),
        "{claim}"
    );
    // The extents put E(P, c) inside the region: the nearer face binds.
    let ext = plant.extents.as_ref().expect("extents");
    assert!(ext[0] <= hi.min(-lo) * (1.0 + 1e-12), "{ext:?}");
    let gains = design(&c).gains.clone();
    let chol = p.clone().cholesky().expect("P > 0");
    let lt_inv = chol.l().transpose().try_inverse().expect("L' invertible");
    let v = |x: &DVector<f64>| (x.transpose() * &p * x)[(0, 0)];
    let dt = 1e-4;
    for k in 0..48 {
        let th = std::f64::consts::TAU * k as f64 / 48.0;
        let mut x = &lt_inv * DVector::from_vec(vec![th.cos(), th.sin()]) * level.sqrt();
        let v0 = v(&x);
        assert!((v0 - level).abs() < 1e-9 * level, "on the boundary");
        for step in 1..=40_000 {
            x = rk4(&x, dt, &gains);
            let t = step as f64 * dt;
            let vt = v(&x);
            assert!(
                vt <= v0 * (-2.0 * alpha * t).exp() * (1.0 + 1e-6) + 1e-15,
                "angle {k}, t = {t}: V = {vt} above the claimed decay {}",
                v0 * (-2.0 * alpha * t).exp()
            );
            assert!(vt <= level * (1.0 + 1e-9), "left E(P, c)");
            assert!(x[0] >= lo && x[0] <= hi, "left the region");
        }
    }
}

#[test]
fn a_region_too_large_is_refused_with_the_largest_that_certifies() {
    let model = common::shipped(TEXTBOOK);
    let asked: StateBox = vec![(-R, R), (f64::NEG_INFINITY, f64::INFINITY)];
    let c = run(
        &model,
        PlantRequest {
            bound: Some(&textbook_error),
            region: Some(&asked),
        },
    );
    assert_eq!(c.status, Status::Refused);
    let message = &c.report.diagnosis.as_ref().expect("diagnosis").message;
    assert!(
        message.contains("the largest region that certifies is x1 in ["),
        "{message}"
    );
    assert!(c.report.plant.claim.is_none());
    // The same region the default request certifies.
    let default = run(
        &model,
        PlantRequest {
            bound: Some(&textbook_error),
            region: None,
        },
    );
    let (lo, hi) = default.report.plant.region[0].expect("x1 bounded");
    assert!(
        message.contains(&format!("x1 in [{lo:.6}, {hi:.6}]")),
        "{message}"
    );
}

/// The Lorenz sector model with its two rules swapped: the sets are linear in
/// x1, so the blend at x1 is A(-x1) and the error A(x1) - A(-x1) has the
/// spectral norm 2 |x1| (entries (2,3) and (3,2)).
const SWAPPED_LORENZ: &str = "tsf 1;\ncontroller lorenz;\nstate x1, x2, x3;\ninput u;\n\
     A(x) = [-10, 10, 0; 28, -1, -x1; 0, x1, -8 / 3];\nB = [1; 0; 0];\n\
     premise z = x1 range -25 .. 25 { neg = trap(-26, -25, -25, 25); pos = trap(-25, 25, 25, 26); }\n\
     rule R1: z is pos => at(x1 = -25, x2 = 0, x3 = 0);\n\
     rule R2: z is neg => at(x1 = 25, x2 = 0, x3 = 0);\n\
     objective decay_rate >= 0.5;\nrelaxation basic;\n";

#[allow(clippy::result_large_err)] // the seam's error is the model stage's Diagnostic
fn swapped_error(_: &TsModel, region: &StateBox) -> Result<PlantError, tsf_lang::Diagnostic> {
    Ok(known(
        2.0 * region[0].0.abs().max(region[0].1.abs()).min(25.0),
    ))
}

#[test]
fn the_blend_certifies_but_the_plant_claim_fails_for_a_far_model() {
    let model = common::model_of("swapped.tsf", SWAPPED_LORENZ);
    let blend = nominal(&model);
    assert_eq!(
        blend.status,
        Status::Certified,
        "the blend's certificate passes"
    );
    assert!(blend.report.plant.claim.is_none());
    let asked: StateBox = vec![
        (-25.0, 25.0),
        (f64::NEG_INFINITY, f64::INFINITY),
        (f64::NEG_INFINITY, f64::INFINITY),
    ];
    let c = run(
        &model,
        PlantRequest {
            bound: Some(&swapped_error),
            region: Some(&asked),
        },
    );
    assert_eq!(c.status, Status::Refused, "the plant claim must fail");
    assert!(c.report.plant.claim.is_none());
    let message = &c.report.diagnosis.as_ref().expect("diagnosis").message;
    assert!(message.contains("||dA|| <= 5.000000e1"), "{message}");
}

#[test]
fn every_seed_spec_has_a_plant_section_without_a_claim_until_the_bound_is_wired() {
    let mut names: Vec<String> = std::fs::read_dir(common::spec_path(""))
        .expect("specs")
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|n| n.ends_with(".tsf"))
        .collect();
    names.sort();
    for name in &names {
        let model = common::shipped(name);
        let section = tsfc::report::plant::nominal(&model, None);
        assert!(section.claim.is_none(), "{name}");
        let note = section.note.unwrap_or_default();
        assert!(note.starts_with("no plant claim: "), "{name}: {note}");
        assert_eq!(section.region.len(), model.n, "{name}");
    }
    let (_, c) = common::compile_shipped("lorenz_sector.tsf");
    let json = common::schema::report_json(&c.report);
    assert!(json["plant"]["claim"].is_null());
    assert!(json["plant"]["note"]
        .as_str()
        .is_some_and(|n| n.contains("rigorous")));
    assert!(
        json["plant"]["truth_plant"].as_str().is_some(),
        "lorenz has `dynamics`"
    );
}

#[test]
fn the_textbook_spec_gets_a_positive_bound_and_a_smaller_region_from_the_real_bound() {
    let model = common::shipped(TEXTBOOK);
    let bound = tsfc::driver::plant::production_bound().expect("the bound is wired");
    let c = run(
        &model,
        PlantRequest {
            bound: Some(bound),
            region: None,
        },
    );
    let plant = &c.report.plant;
    assert!(plant.claim.is_some());
    let b = plant.error_bound.as_ref().expect("bound");
    let (lo, hi) = plant.region[0].expect("x1 bounded");
    assert!(hi < R && lo > -R);
    // The exact error on |x1| <= h is max r|x1| - x1^2 = r h - h^2 (h <= r/2),
    // else r^2/4: the reported bound is an upper bound of it.
    let h = hi.min(-lo);
    let exact = if h <= R / 2.0 {
        R * h - h * h
    } else {
        R * R / 4.0
    };
    assert!(
        b.a >= exact - 1e-12,
        "at least the exact maximum {exact} on |x1| <= {h}: {}",
        b.a
    );
}

#[test]
fn the_sector_specs_get_error_bound_zero_and_a_plant_claim_from_the_real_bound() {
    let bound = tsfc::driver::plant::production_bound().expect("the bound is wired");
    for name in ["lorenz_sector.tsf", "truck_trailer_sector.tsf"] {
        let model = common::shipped(name);
        let c = run(
            &model,
            PlantRequest {
                bound: Some(bound),
                region: None,
            },
        );
        let plant = &c.report.plant;
        let b = plant.error_bound.as_ref().expect("bound");
        assert!(b.a <= 1e-9 && b.b <= 1e-9, "{name}: {} {}", b.a, b.b);
        assert!(plant.claim.is_some(), "{name}: {:?}", plant.note);
        assert!(
            plant
                .note
                .as_deref()
                .is_none_or(|n| !n.contains("largest region")),
            "{name}: the whole region certifies: {:?}",
            plant.note
        );
    }
}

/// The textbook spec with a `plant region` line.
fn textbook_asking(region: &str) -> TsModel {
    let text = std::fs::read_to_string(common::spec_path(TEXTBOOK)).expect("spec");
    common::model_of("asked.tsf", &format!("{text}plant region {region};\n"))
}

#[test]
fn the_spec_s_plant_region_is_certified_or_refused_with_the_largest_region() {
    let small = textbook_asking("x1 = -0.5 .. 0.5");
    assert_eq!(
        small.spec.plant_region.as_ref().map(|r| r[0]),
        Some((-0.5, 0.5))
    );
    assert!(small
        .spec
        .plant_region
        .as_ref()
        .is_some_and(|r| r[1].1.is_infinite()));
    let c = run(
        &small,
        PlantRequest {
            bound: Some(&textbook_error),
            region: None,
        },
    );
    assert_eq!(c.status, Status::Certified);
    assert_eq!(c.report.plant.region[0], Some((-0.5, 0.5)));
    assert!(c.report.plant.claim.is_some() && c.report.plant.note.is_none());
    let large = textbook_asking("x1 = -2 .. 2");
    let c = run(
        &large,
        PlantRequest {
            bound: Some(&textbook_error),
            region: None,
        },
    );
    assert_eq!(c.status, Status::Refused);
    let message = &c.report.diagnosis.as_ref().expect("diagnosis").message;
    assert!(
        message.contains("the largest region that certifies is x1 in ["),
        "{message}"
    );
}

#[test]
fn a_plant_region_must_name_scalar_states_around_zero() {
    let text = std::fs::read_to_string(common::spec_path(TEXTBOOK)).expect("spec");
    let errors = common::errors_of(
        "bad.tsf",
        &format!("{text}plant region x9 = -1 .. 1, x1 = 1 .. 2;\n"),
    );
    let messages: Vec<&str> = errors.iter().map(|d| d.message.as_str()).collect();
    assert!(messages.contains(&"`x9` is not a state"), "{messages:?}");
    assert!(
        messages
            .iter()
            .any(|m| m.contains("needs lo < 0 < hi, found 1 .. 2")),
        "{messages:?}"
    );
}

#[test]
fn tsfc_compile_exits_3_with_the_largest_region_when_the_plant_region_is_too_large() {
    let dir = common::fresh_dir("plant", "too-large");
    let text = std::fs::read_to_string(common::spec_path(TEXTBOOK)).expect("spec");
    let spec = dir.join("asked.tsf");
    std::fs::write(&spec, format!("{text}plant region x1 = -2 .. 2;\n")).expect("write");
    let out = std::process::Command::new(common::tsfc_binary())
        .args(["compile", spec.to_str().expect("path"), "--out"])
        .arg(dir.join("out"))
        .output()
        .expect("tsfc runs");
    assert_eq!(out.status.code(), Some(3));
    let said = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        said.contains("the largest region that certifies is x1 in ["),
        "{said}"
    );
}
