//! Issue 36: the textbook 88-degree observer pendulum
//! (`pendulum_observer_88.tsf`) certified for its sampled observer by a bound
//! of the membership drift on a region (paired plant/observer vertices,
//! `synth/observer/drift.rs`). Checked independently of tsfc's LMI code:
//! (a) the nonlinear pendulum (RK4 here) with the generated tables and the
//! runtime observer, from states on the boundary of the certified set
//! E(P, 1): the drift of h_1 and of theta within every period stay below the
//! reported bounds, and the state stays in the region; (b) the paired
//! conditions rebuilt from the report with eigenvalues, which fail with a
//! larger drift or with the controller switched off. The gyro-less
//! spacecraft (`amrr2019_gyroless.tsf`) certifies its decay rate this way:
//! its paired conditions re-derived, and V(t_k) along a run of its T-S
//! plant checked against e^(-2 alpha t_k) V(0).

use crate::common;
use crate::common::looped::{mat, report_gains, Looped};
use crate::common::observer::{rk4_held, runtime_observer, runtime_terms};
use crate::common::Rng;
use nalgebra::{DMatrix, DVector};
use serde_json::Value;
use std::f64::consts::PI;
use tsfc::tables::PremiseCode;

const SPEC: &str = "pendulum_observer_88.tsf";

use crate::common::observer::pendulum;

/// h_1 of the textbook's rules: (sinc(theta) - 2/pi) / (1 - 2/pi) on
/// |theta| <= 90 deg.
fn h1(theta: f64) -> f64 {
    let s = if theta == 0.0 {
        1.0
    } else {
        theta.sin() / theta
    };
    (s - 2.0 / PI) / (1.0 - 2.0 / PI)
}

/// `tsfc compile` of the shipped spec into `dir`: exit 0, code written, the report.
fn compile(dir: &std::path::Path) -> Value {
    common::observer::compile_code(SPEC, dir)
}

fn num(v: &Value) -> f64 {
    v.as_f64().expect("a number")
}

fn nums(v: &Value) -> Vec<f64> {
    v.as_array().expect("an array").iter().map(num).collect()
}

/// The worst eigenvalue of the paired conditions with the drift `delta` (of
/// h_2) at both signs, K of observer j and controller l
/// ([`crate::common::looped::worst_paired`]).
fn worst_paired(report: &Value, gains: &[DMatrix<f64>], delta: f64, phi: f64) -> f64 {
    let lp = Looped::of(report);
    common::looped::worst_paired(&lp, delta, |plant, j, l| {
        lp.blocks(plant, &lp.gain(j, &gains[l]), phi)
    })
}

/// E(P, 1) of the report's sampled loop lies in the reported sample box
/// and in |(F_l xhat)_s| <= U for every gain and input (the reach of
/// E(P, 1) along a row r is sqrt(r P^-1 r')); returns the sample box.
fn inside_sample_box(report: &Value, gains: &[DMatrix<f64>]) -> Vec<Vec<f64>> {
    let s = &report["sampled_loop"];
    let drift = &s["drift"];
    let p_inv = mat(&s["P"]).try_inverse().expect("P invertible");
    let n = p_inv.nrows() / 2;
    let samples: Vec<Vec<f64>> = serde_json::from_value(drift["samples"].clone()).expect("box");
    assert_eq!(samples.len(), n, "a sample interval per state");
    for (k, b) in samples.iter().enumerate() {
        let reach = p_inv[(k, k)].sqrt();
        assert!(
            reach <= b[1].min(-b[0]),
            "state {k}: E(P, 1) reaches {reach}, box {b:?}"
        );
    }
    let u_bound = num(&drift["input_bound"]);
    for f in gains {
        for row in f.row_iter() {
            let r = DVector::from_fn(2 * n, |k, _| if k < n { 0.0 } else { row[k - n] });
            let reach = (r.transpose() * &p_inv * &r)[(0, 0)].sqrt();
            assert!(reach <= u_bound, "|u| reaches {reach} > U = {u_bound}");
        }
    }
    samples
}

/// (b) The paired conditions rebuilt from the report (P, Y, L1, L2, the
/// local models, F_l, L_j, C, T, the reported drift bound): negative at the
/// certified rate 0.5; E(P, 1) inside the sample box and |u| <= U; the
/// reported drift at least the largest sampled |h_1(theta + step) -
/// h_1(theta)| on the sample box. Not vacuous: ten times the drift, or
/// F = 0, fail.
#[test]
fn pendulum_88_paired_drift_conditions_rederived_from_the_report() {
    let report = compile(&common::fresh_dir("observer_drift", "lmis"));
    let s = &report["sampled_loop"];
    let covers = s["covers"].as_str().expect("covers");
    assert!(covers.contains("decays at rate 0.5"), "{covers}");
    assert!(covers.contains("E(P, 1)"), "{covers}");
    let drift = &s["drift"];
    let delta = nums(&drift["delta"]);
    let gains = report_gains(&report);
    let worst = worst_paired(&report, &gains, delta[1], 1.0);
    assert!(worst < 0.0, "a paired condition is not negative: {worst:e}");
    let larger = worst_paired(&report, &gains, 10.0 * delta[1], 1.0);
    assert!(larger > 0.0, "ten times the drift passes: {larger:e}");
    let off: Vec<DMatrix<f64>> = gains.iter().map(|g| g * 0.0).collect();
    let open = worst_paired(&report, &off, delta[1], 1.0);
    assert!(open > 0.0, "open loop passes: {open:e}");
    let samples = inside_sample_box(&report, &gains);
    // The drift bound covers the sampled drift on the sample box.
    let (step, th_box) = (nums(&drift["steps"])[0], samples[0][1]);
    let sampled = (0..=20_000)
        .map(|k| -th_box + 2.0 * th_box * f64::from(k) / 20_000.0)
        .flat_map(|th| [(th, th + step), (th, th - step)])
        .map(|(a, b)| (h1(a) - h1(b)).abs())
        .fold(0.0, f64::max);
    assert!(
        sampled <= delta[0] && delta[0] < 1.5 * sampled,
        "sampled {sampled} vs bound {}",
        delta[0]
    );
}

/// (a) The nonlinear pendulum with the generated tables (runtime observer
/// every T, RK4 at T / 10) from 40 states on the boundary of E(P, 1)
/// (xi = (x, xhat), random directions): within every period
/// |h_1(t) - h_1(t_k)| and |theta(t) - theta(t_k)| stay below the reported
/// bounds, and |theta| <= 88 deg, |omega| <= 1 (the region) throughout.
#[test]
fn pendulum_88_drift_bounds_hold_along_simulated_runs() {
    let report = compile(&common::fresh_dir("observer_drift", "runs"));
    let s = &report["sampled_loop"];
    let drift = &s["drift"];
    let (t, delta, steps) = (
        num(&drift["period"]),
        nums(&drift["delta"]),
        nums(&drift["steps"]),
    );
    let region: Vec<Vec<f64>> = serde_json::from_value(drift["region"].clone()).expect("R");
    let p = mat(&s["P"]);
    let prepared = tsfc::driver::prepare(&common::spec_path(SPEC)).expect("prepared");
    let tables = &prepared.tables;
    let PremiseCode::Exprs(exprs) = &tables.premise else {
        panic!("sinc premise")
    };
    let terms = runtime_terms(tables);
    let obs = runtime_observer::<2, 1, 1, 1, 2, 2>(tables, &terms);
    let mut rng = Rng::new(36);
    let (mut dh, mut dth, mut vmax): (f64, f64, f64) = (0.0, 0.0, 0.0);
    for _ in 0..40 {
        let v = DVector::from_fn(4, |_, _| rng.uniform(-1.0, 1.0));
        let xi = &v / (v.transpose() * &p * &v)[(0, 0)].sqrt();
        let (mut x, mut xhat) = ([xi[0], xi[1]], [xi[2], xi[3]]);
        for _ in 0..1000 {
            let xk = nalgebra::dvector![x[0], x[1], xhat[0], xhat[1]];
            vmax = vmax.max((xk.transpose() * &p * &xk)[(0, 0)]);
            let y = [x[0]];
            let pv = obs.premise_state(&xhat, &y);
            let u = obs
                .step_with_premises(&mut xhat, &y, &[exprs[0].eval(&pv)])
                .u[0];
            let th_k = x[0];
            for _ in 0..10 {
                rk4_held(&mut x, u, t / 10.0, 1, pendulum);
                assert!(
                    x[0].abs() <= region[0][1] && x[1].abs() <= region[1][1],
                    "left R: {x:?}"
                );
                dth = dth.max((x[0] - th_k).abs());
                dh = dh.max((h1(x[0]) - h1(th_k)).abs());
            }
        }
    }
    assert!(dth <= steps[0], "theta drift {dth} > {}", steps[0]);
    assert!(dh <= delta[0], "membership drift {dh} > {}", delta[0]);
    assert!(dh > 0.0 && dth > 0.0, "the runs moved");
    eprintln!("max |theta(t) - theta(t_k)| = {dth:e} (bound {:e}), max |h1 drift| = {dh:e} (bound {:e}), max V(t_k) = {vmax}", steps[0], delta[0]);
}

/// The spec's scenario starts inside the certified set (x0 and xhat0
/// stacked: xi' P xi <= 1), and `tsfc simulate` converges from it on the
/// nonlinear pendulum (the estimate starts wrong).
#[test]
fn pendulum_88_scenario_starts_in_the_certified_set_and_converges() {
    let report = compile(&common::fresh_dir("observer_drift", "scenario"));
    let p = mat(&report["sampled_loop"]["P"]);
    let prepared = tsfc::driver::prepare(&common::spec_path(SPEC)).expect("prepared");
    let sim = prepared.model.spec.simulate.as_ref().expect("simulate");
    let (x0, xhat0) = (sim.x0.clone(), sim.xhat0.clone().expect("xhat0").node);
    assert_ne!(x0, xhat0, "a wrong initial estimate");
    let xi = DVector::from_vec([x0, xhat0].concat());
    let level = (xi.transpose() * &p * &xi)[(0, 0)];
    assert!(level < 1.0, "the scenario is outside E(P, 1): {level}");
    let dir = common::fresh_dir("observer_drift", "simulate");
    let out = std::process::Command::new(common::tsfc_binary())
        .arg("simulate")
        .arg(common::spec_path(SPEC))
        .arg("--out")
        .arg(&dir)
        .output()
        .expect("run tsfc");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    let metrics: Value = serde_json::from_slice(
        &std::fs::read(dir.join("pendulum_observer_88.metrics.json")).expect("metrics"),
    )
    .expect("json");
    assert_eq!(metrics["converged"], Value::Bool(true), "{metrics}");
    assert!(dir.join("pendulum_observer_88.estimate.svg").exists());
}

/// Wrong uses of the region of the sampled observer loop are check-time
/// errors at the setting (file:line:col): a state left unbounded, and a
/// periodic region without an observer.
#[test]
fn pendulum_88_region_misuse_is_a_check_error_at_the_setting() {
    let text = std::fs::read_to_string(common::spec_path(SPEC)).expect("spec");
    let cases = [
        (
            text.replace("region omega = -1 .. 1;", ""),
            "region theta",
            "leaves omega unbounded",
        ),
        (
            text.replace("control observer_based(decay = 10);", "")
                .replace("measure y = theta noise <= 0.001;", ""),
            "region theta",
            "`region` needs an event trigger",
        ),
    ];
    for (spec, at, want) in cases {
        let errors = common::errors_of("pendulum_observer_88.tsf", &spec);
        let e = errors
            .iter()
            .find(|e| e.message.contains(want))
            .unwrap_or_else(|| panic!("no `{want}` error: {errors:?}"));
        let line = spec[..e.span.start].lines().count();
        let written = spec.lines().nth(line.max(1) - 1).expect("the line");
        assert!(written.contains(at), "{want}: at line {line} `{written}`");
    }
}

/// The gyro-less spacecraft's decay rate (the spec's objective).
const GYROLESS_ALPHA: f64 = 0.05;

/// V(t_k) = xi_k' P xi_k at the samples of the gyro-less spacecraft's loop
/// from `(x0, xhat0)`: the T-S plant x' = sum_i h_i(p'p) (A_i x + B_i u)
/// of the report's local models (h_1 = 1 - p'p, h_2 = p'p, the spec's
/// triangles on [0, 1]; nonlinear through the memberships, which move
/// within every period), RK4 at T / 10 with u held, and the runtime
/// observer on the generated tables every T (y = p, premise y'y).
fn gyroless_run(
    report: &Value,
    tables: &tsfc::tables::Tables,
    xi0: &[f64],
    samples: usize,
) -> Vec<f64> {
    let s = &report["sampled_loop"];
    let (p, t) = (mat(&s["P"]), num(&s["sampling"][0]));
    let models: Vec<(DMatrix<f64>, DMatrix<f64>)> = report["local_models"]
        .as_array()
        .expect("local models")
        .iter()
        .map(|m| (mat(&m["A"]), mat(&m["B"])))
        .collect();
    let terms = runtime_terms(tables);
    let obs = runtime_observer::<6, 3, 3, 1, 2, 2>(tables, &terms);
    let field = |x: &DVector<f64>, u: &DVector<f64>| {
        let z = (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).clamp(0.0, 1.0);
        let (a1, b1) = &models[0];
        let (a2, b2) = &models[1];
        (a1 * x + b1 * u) * (1.0 - z) + (a2 * x + b2 * u) * z
    };
    let mut x = DVector::from_column_slice(&xi0[..6]);
    let mut xhat: [f64; 6] = std::array::from_fn(|k| xi0[6 + k]);
    let h = t / 10.0;
    let mut v = Vec::with_capacity(samples);
    for _ in 0..samples {
        let xi = DVector::from_iterator(12, x.iter().copied().chain(xhat));
        v.push((xi.transpose() * &p * &xi)[(0, 0)]);
        let y = [x[0], x[1], x[2]];
        let z = y.iter().map(|c| c * c).sum::<f64>();
        let u = DVector::from_column_slice(&obs.step_with_premises(&mut xhat, &y, &[z]).u);
        for _ in 0..10 {
            let k1 = field(&x, &u);
            let k2 = field(&(&x + &k1 * (h / 2.0)), &u);
            let k3 = field(&(&x + &k2 * (h / 2.0)), &u);
            let k4 = field(&(&x + &k3 * h), &u);
            x += (k1 + k2 * 2.0 + k3 * 2.0 + k4) * (h / 6.0);
        }
    }
    v
}

/// Issue 36: the gyro-less spacecraft (`amrr2019_gyroless.tsf`, the
/// suite's one compile of it) certifies its sampled loop at T = 0.1 s with
/// the decay rate 0.05 on the drift route. From the report alone: the
/// paired conditions at phi = 2 alpha are negative (and fail with the
/// controller off); E(P, 1) lies in the sample box and |u| <= U; the spec's
/// scenario (x0, xhat0 = 0) lies in E(P, 1). Along a run of the T-S plant
/// written here (memberships moving within the periods) with the runtime
/// observer, V(t_k) <= e^(-2 alpha t_k) V(0) at every sample, which fails
/// with alpha doubled.
#[test]
fn gyroless_drift_route_certifies_its_decay_rate_and_the_run_keeps_it() {
    let (c, _) = common::observer::gyroless();
    let report = &c.report;
    let s = &report["sampled_loop"];
    let covers = s["covers"].as_str().expect("covers");
    assert!(
        covers.contains("every 0.1 s") && covers.contains("decays at rate 0.05"),
        "{covers}"
    );
    assert!(covers.contains("E(P, 1)"), "{covers}");
    let delta = nums(&s["drift"]["delta"]);
    let gains = report_gains(report);
    let phi = 2.0 * GYROLESS_ALPHA;
    let worst = worst_paired(report, &gains, delta[1], phi);
    assert!(worst < 0.0, "a paired condition is not negative: {worst:e}");
    let off: Vec<DMatrix<f64>> = gains.iter().map(|g| g * 0.0).collect();
    let open = worst_paired(report, &off, delta[1], phi);
    assert!(open > 0.0, "open loop passes: {open:e}");
    inside_sample_box(report, &gains);
    // The scenario: x0 of the simulate block, the estimate at 0 (`INIT`).
    let text = std::fs::read_to_string(common::spec_path("amrr2019_gyroless.tsf")).expect("spec");
    let model = common::model_of("amrr2019_gyroless.tsf", &text);
    let sim = model.spec.simulate.as_ref().expect("simulate");
    assert!(sim.xhat0.is_none(), "the scenario's estimate starts at 0");
    let xi0: Vec<f64> = sim.x0.iter().copied().chain([0.0; 6]).collect();
    let p = mat(&s["P"]);
    let xi = DVector::from_column_slice(&xi0);
    let level = (xi.transpose() * &p * &xi)[(0, 0)];
    assert!(level < 1.0, "the scenario is outside E(P, 1): {level}");
    // 200 s of the loop: V(t_k) against e^(-2 a t_k) V(0).
    let t = num(&s["sampling"][0]);
    let v = gyroless_run(report, &c.tables, &xi0, 2000);
    let ratio = |a: f64| {
        v.iter()
            .enumerate()
            .map(|(k, vk)| vk / v[0] * (2.0 * a * t * k as f64).exp())
            .fold(0.0, f64::max)
    };
    let (kept, doubled) = (ratio(GYROLESS_ALPHA), ratio(2.0 * GYROLESS_ALPHA));
    eprintln!("V(0) = {:e}, V(200 s) = {:e}, max V(t_k) e^(2 a t_k) / V(0) = {kept} (a = 0.05), {doubled} (a = 0.1)", v[0], v[v.len() - 1]);
    assert!(kept <= 1.0 + 1e-9, "V(t_k) above e^(-2 a t_k) V(0): {kept}");
    assert!(doubled > 1.0, "V(t_k) decays at twice the rate: {doubled}");
}
