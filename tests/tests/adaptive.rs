//! Adaptive model-reference controllers (issue 15): the textbook scalar MRAC
//! against its closed form, projection keeping estimates inside their bounds,
//! well-posedness refusals, and the Wang et al. (2013) spacecraft spec
//! converging with the time-varying inertia.

use crate::common;
use tsfc::model::TsModel;
use tsfc::sim::adaptive::{self as sim, Options, Run};
use tsfc::sim::source::SpecSource;
use tsfc::synth::adaptive::{design, Design, Outcome};

/// Plant x' = a x + b u with a = 1, b = 1 (b known), reference model
/// a_m = -2, Q = 2 (so p = 1/2), a_hat(0) = 0, gamma = 4, x(0) = 1, r = 0.
const SCALAR: &str = "tsf 1; controller mrac;
state v; input u; A = 1; B = 1;
premise v range -1 .. 1 { all = trap(-1e3, -1e3, 1e3, 1e3); }
rule R: v is all => A = 1;
adaptive {
    error = v;
    reference = -2;
    Q = 2;
    estimate a rate 4 bounds -10 .. HI init 0;
}
simulate { x0 = 1; time = 0 .. 6 step 1e-3; integrator = rk4; }
";

fn scalar(hi: &str) -> TsModel {
    common::model_of("mrac.tsf", &SCALAR.replace("HI", hi))
}

fn run(model: &TsModel) -> (Design, Run) {
    let Outcome { design, report } = design(model);
    let design = design.unwrap_or_else(|| panic!("refused: {:?}", report.refusals));
    let source = SpecSource {
        name: "spec".into(),
        text: String::new(),
    };
    let run = sim::run(model, &design, &source, &Options::default()).expect("run");
    (design, run)
}

/// With c = a_m + (a - a_hat), the loop is x' = c x and c' = -gamma p x^2, so
/// K = gamma p x^2 + c^2 is constant and c' = c^2 - K:
/// c(t) = -sqrt(K) tanh(sqrt(K) t + atanh(-c(0) / sqrt(K))),
/// x(t)^2 = (K - c(t)^2) / (gamma p), a_hat(inf) = a + a_m + sqrt(K) = sqrt(3) - 1.
#[test]
fn scalar_mrac_follows_its_closed_form() {
    let (gamma, p, a, a_m, x0) = (4.0_f64, 0.5, 1.0, -2.0, 1.0_f64);
    let c0 = a_m + a;
    let k = gamma * p * x0 * x0 + c0 * c0;
    let theta0 = (-c0 / k.sqrt()).atanh();
    let model = scalar("10");
    let (d, run) = run(&model);
    assert_eq!(d.p, vec![0.5], "p = -q / (2 a_m)");
    let mut worst_x: f64 = 0.0;
    let mut worst_a: f64 = 0.0;
    for s in &run.trace {
        let c = -k.sqrt() * (k.sqrt() * s.t + theta0).tanh();
        let x = ((k - c * c).max(0.0) / (gamma * p)).sqrt();
        let a_hat = a + a_m - c;
        worst_x = worst_x.max((s.x[0] - x).abs());
        worst_a = worst_a.max((s.a_hat[0] - a_hat).abs());
    }
    // Euler updates and a held command at 1 ms: first-order errors, measured
    // 4.5e-4 (x) and 5.4e-4 (a_hat).
    eprintln!(
        "scalar MRAC vs closed form: max |x error| {worst_x:.3e}, max |a_hat error| {worst_a:.3e}"
    );
    assert!(
        worst_x < 3e-3 && worst_a < 3e-3,
        "x error {worst_x:.3e}, a_hat error {worst_a:.3e}"
    );
    let last = run.trace.last().expect("samples");
    let limit = 3.0_f64.sqrt() - 1.0;
    assert!(
        (last.a_hat[0] - limit).abs() < 3e-3,
        "a_hat(6) = {} vs sqrt(3) - 1",
        last.a_hat[0]
    );
    assert!(run.metrics.estimates_within_bounds);
}

/// An upper bound below the closed-form limit: projection holds a_hat at it
/// (the loop x' = (a + a_m - 0.5) x = -1.5 x still converges).
#[test]
fn projection_keeps_the_estimate_at_its_bound() {
    let (_, run) = run(&scalar("0.5"));
    let m = &run.metrics;
    assert!(m.estimates_within_bounds, "{m:?}");
    assert_eq!(m.a_range.1, 0.5);
    let last = run.trace.last().expect("samples");
    assert_eq!(last.a_hat[0], 0.5);
    assert!(last.x[0].abs() < 1e-3, "x(6) = {}", last.x[0]);
}

/// Tracking: with the true a (a_hat(0) = 1), x(0) = s_m(0) = 0 and r = 1,
/// eps stays 0 and x follows the reference model s_m' = -2 (s_m - r):
/// x(t) = 1 - exp(-2 t), a_hat unchanged.
#[test]
fn a_matched_loop_tracks_the_reference_model() {
    let text = SCALAR
        .replace("HI init 0", "10 init 1")
        .replace("x0 = 1;", "x0 = 0;")
        .replace("Q = 2;", "Q = 2;\n    r(t) = 1;");
    let (_, run) = run(&common::model_of("track.tsf", &text));
    let mut worst: f64 = 0.0;
    for s in &run.trace {
        worst = worst.max((s.x[0] - (1.0 - (-2.0 * s.t).exp())).abs());
        // Only the O(h) gap between the Euler reference model and the RK4
        // plant moves it.
        assert!(
            (s.a_hat[0] - 1.0).abs() < 1e-3,
            "a_hat moved: {}",
            s.a_hat[0]
        );
    }
    eprintln!("tracking: max |x - (1 - exp(-2t))| = {worst:.3e}");
    assert!(worst < 2e-3, "tracking error {worst:.3e}");
}

/// An unstable reference model is refused with exit 3 (after the checker
/// accepted it: eigenvalues are the compiler's).
#[test]
fn an_unstable_reference_model_is_refused() {
    let model = common::model_of(
        "bad.tsf",
        &SCALAR
            .replace("HI", "10")
            .replace("reference = -2", "reference = 0.5"),
    );
    let o = design(&model);
    assert!(o.design.is_none());
    assert_eq!(o.exit_code(), 3);
    assert_eq!(o.report.status, tsfc::synth::adaptive::REFUSED);
    assert!(
        o.report.refusals[0].contains("not Hurwitz"),
        "{:?}",
        o.report.refusals
    );
}

/// Input gains of the wrong sign for the declared bounds are refused.
#[test]
fn input_gain_bounds_of_the_wrong_sign_are_refused() {
    let text = SCALAR.replace("HI", "10").replace(
        "init 0;",
        "init 0;\n    estimate b rate 1 bounds -2 .. -0.1;",
    );
    let o = design(&common::model_of("sign.tsf", &text));
    assert!(
        o.report.refusals.iter().any(|r| r.contains("other sign")),
        "{:?}",
        o.report.refusals
    );
}

/// An estimate that starts at the design model's value (no `init`) outside
/// its box is refused: it would start outside its bounds.
#[test]
fn a_model_value_outside_the_box_without_init_is_refused() {
    let text = SCALAR.replace("bounds -10 .. HI init 0", "bounds -10 .. 0.5");
    let o = design(&common::model_of("box.tsf", &text));
    assert!(o.design.is_none());
    assert!(
        o.report
            .refusals
            .iter()
            .any(|r| r.contains("`a` starts at the design model's values")),
        "{:?}",
        o.report.refusals
    );
    assert!(!o.report.nominal_inside_bounds);
}

fn wang() -> (TsModel, Design, Run) {
    let model = common::shipped("wang2013_adaptive_mrac.tsf");
    let (d, run) = run(&model);
    (model, d, run)
}

#[test]
fn wang2013_is_well_posed_and_says_what_it_does_not_guarantee() {
    let model = common::shipped("wang2013_adaptive_mrac.tsf");
    let o = design(&model);
    let r = &o.report;
    assert_eq!(
        r.status,
        tsfc::synth::adaptive::WELL_POSED,
        "{:?}",
        r.refusals
    );
    // Independent check: A_m = -I, Q = I gives P = I / 2.
    for (k, v) in r.p.iter().enumerate() {
        let want = if k % 4 == 0 { 0.5 } else { 0.0 };
        assert!((v - want).abs() < 1e-12, "P[{k}] = {v}");
    }
    // C B_i = J^-1 on every rule.
    for g in &r.input_gains {
        for (gk, jk) in g.iter().zip([2043.0, 3044.0, 1989.0]) {
            assert!((gk * jk - 1.0).abs() < 1e-12);
        }
    }
    assert_eq!(r.matching_offdiagonal, 0.0);
    assert!(r.nominal_inside_bounds);
    assert_eq!(r.adapted, 9 * 3 * 6 + 9 * 3 + 1);
    assert_eq!(
        r.x0_outside_operating_range,
        vec!["rho[2] = 2.17 outside [-2, 2]".to_string()]
    );
    assert!(r.not_guaranteed.iter().any(|s| s.contains("time-varying")));
}

#[test]
fn wang2013_converges_with_the_time_varying_inertia_and_estimates_stay_bounded() {
    let (_, d, run) = wang();
    let m = &run.metrics;
    assert!(m.failure.is_none(), "{:?}", m.failure);
    for c in &m.claims {
        assert!(c.held, "{c:?}");
    }
    assert!(m.estimates_within_bounds, "{m:?}");
    assert!(m.a_range.0 >= d.a.lo && m.a_range.1 <= d.a.hi);
    assert!(m.b_range.0 >= d.b.lo && m.b_range.1 <= d.b.hi);
    assert!(m.d_range.0 >= d.d.lo && m.d_range.1 <= d.d.hi);
    // rho3(0) = 2.17 is outside the rules' range: the run counts it.
    assert!(m.steps_outside_operating_range > 0);
    let last_out = m.last_outside_s.expect("outside at t = 0");
    assert!(last_out < 5.0, "left the operating range at {last_out} s");
    // The CSV has one column per estimate.
    let csv = sim::csv(&run, &d);
    let header = csv.lines().next().expect("header");
    assert_eq!(
        header.split(',').count(),
        1 + 6 + 3 + 3 + 9 * 3 * 6 + 9 * 3 + 1
    );
    let (svg, png) = sim::plot(&run, &d).expect("plot");
    assert!(svg.starts_with(b"<svg") || String::from_utf8_lossy(&svg).contains("<svg"));
    assert!(png.starts_with(b"\x89PNG"));
}

#[test]
fn the_lmi_pipeline_refuses_an_adaptive_spec_clearly() {
    let e = tsfc::pipeline::read(&common::spec_path("wang2013_adaptive_mrac.tsf"))
        .and_then(|f| f.compile(&tsfc::synth::Settings::default()))
        .expect_err("no LMI design");
    assert!(
        e.message.contains("adaptive controller has no LMI design"),
        "{}",
        e.message
    );
    assert_eq!(e.exit_code(), 1);
}
