//! Issue 36: the shipped observer spec `pendulum_observer.tsf` (only the
//! angle measured) certifies its SAMPLED loop, so `tsfc compile` emits Rust
//! and C and `tsfc simulate` runs. An RK4 loop written here (the nonlinear
//! pendulum of Tanaka & Wang 2001, not the simulator's plant code), with the
//! report's gains and the runtime observer step every T, converges from a
//! wrong initial estimate and agrees with the simulator. The sampled
//! certificate's looped-functional conditions are re-derived from the report
//! (eigenvalues at every rule triple, the observer tables recomputed by a
//! block matrix exponential), independently of tsfc's LMI code.

use crate::common;
use crate::common::looped::{mat, max_eig, Looped};
use crate::common::observer::{independent_loop, runtime_observer, runtime_terms, HeldPlant};
use nalgebra::DMatrix;
use serde_json::Value;
use tsfc::tables::PremiseCode;

const SPEC: &str = "pendulum_observer.tsf";

/// The shipped period (`trigger periodic { every = 0.01; }`).
const T: f64 = 0.01;

/// The rules' range: |theta| <= 60 deg (the spec's `thmax`).
const THETA_MAX: f64 = 60.0 * std::f64::consts::PI / 180.0;

use crate::common::observer::pendulum;

fn report_gains(report: &Value) -> Vec<[f64; 2]> {
    report["gains"]
        .as_array()
        .expect("gains")
        .iter()
        .map(|g| {
            [
                g["F"][0][0].as_f64().unwrap(),
                g["F"][0][1].as_f64().unwrap(),
            ]
        })
        .collect()
}

/// `tsfc compile` of the shipped spec into `dir`: exit 0, code written, the report.
fn compile(dir: &std::path::Path) -> Value {
    common::observer::compile_code(SPEC, dir)
}

/// `tsfc compile` certifies the sampled loop at the spec's period and
/// decay rate and writes the Rust and C code.
#[test]
fn shipped_pendulum_observer_certifies_its_sampled_loop_and_emits_code() {
    let report = compile(&common::fresh_dir("observer_shipped", "compile"));
    assert_eq!(report["status"], "certified");
    assert_eq!(report["stored_precision_certified"], true);
    let notes = report["notes"].to_string();
    assert!(
        notes.contains("sampled observer-based loop")
            && notes.contains("every 0.01 s")
            && notes.contains("decays at rate 0.5"),
        "{notes}"
    );
    let lmis = report["certificate"]["lmis"].as_array().expect("lmis");
    assert!(lmis.iter().any(|l| l["name"]
        .as_str()
        .is_some_and(|n| n.starts_with("trigger r=2"))));
    assert!(lmis.iter().all(|l| l["ok"] == true));
}

/// The nonlinear pendulum from 50 deg with the estimate at 0: an RK4 loop
/// written here (step 1 ms, the runtime observer step every T with the
/// report's gains) against the simulator's samples, then `tsfc simulate`.
#[test]
fn shipped_pendulum_observer_converges_from_a_wrong_estimate_like_the_simulator() {
    let spec = common::spec_path(SPEC);
    let prepared = tsfc::driver::prepare(&spec).expect("prepared");
    let t = &prepared.tables;
    assert_eq!(t.observer.as_ref().expect("observer tables").period, T);
    // The tables' gains are the report's F_j.
    let report = compile(&common::fresh_dir("observer_shipped", "gains"));
    for (j, f) in report_gains(&report).iter().enumerate() {
        assert_eq!(t.gains[j][0], f.to_vec(), "rule {j}");
    }
    let x0 = [50.0 * std::f64::consts::PI / 180.0, 0.0];
    let xhat0 = vec![0.0, 0.0];
    let mut opts = tsfc::sim::Options::default();
    opts.observer.xhat0 = Some(xhat0.clone());
    opts.observer.noise = tsfc::sim::observer::Noise::Uniform(0.0);
    let mut samples: Vec<(Vec<f64>, f64)> = Vec::new();
    let mut see = |_: f64, x: &[f64], u: &[f64]| samples.push((x.to_vec(), u[0]));
    let spec_data = prepared.model.spec.clone();
    let outcome = tsfc::sim::run_truth(&prepared, &spec_data, &opts, None, Some(&mut see))
        .expect("simulated");
    assert!(
        outcome.metrics.converged,
        "{:?}",
        outcome.metrics.failures()
    );
    assert_eq!(samples.len(), 501);
    let PremiseCode::Exprs(exprs) = &t.premise else {
        panic!("sinc premise")
    };
    let terms = runtime_terms(t);
    let obs = runtime_observer::<2, 1, 1, 1, 2, 2>(t, &terms);
    let plant = HeldPlant {
        f: pendulum,
        h: T / 10.0,
        steps: 10,
    };
    let samples = samples.iter().map(|(x, u)| (x.as_slice(), *u));
    let run = independent_loop(&obs, exprs, samples, plant, (x0, [xhat0[0], xhat0[1]]));
    let (worst, theta_max, u_max) = (run.worst, run.max_abs_x1, run.max_abs_u);
    let (x, xhat) = (run.x, run.xhat);
    assert!(worst < 1e-8, "simulator vs independent loop: {worst:e}");
    // The trajectory stays inside the rules' range, where the T-S model
    // is the pendulum.
    assert!(theta_max < THETA_MAX, "max |theta| {theta_max}");
    // From an estimation error of 0.87 rad to below 1e-4 in 5 s; the state
    // to below 1e-2 (decay rate 0.5 certified: V(5) <= e^-5 V(0)).
    let err = ((x[0] - xhat[0]).powi(2) + (x[1] - xhat[1]).powi(2)).sqrt();
    assert!(err < 1e-4, "estimation error {err:e}: {x:?} {xhat:?}");
    assert!(x[0].abs() < 1e-2 && x[1].abs() < 1e-2, "{x:?}");
    assert!(u_max > 100.0, "the loop acted: max |u| {u_max}");
    // `tsfc simulate` runs end to end (spec noise, estimate plot).
    let dir = common::fresh_dir("observer_shipped", "simulate");
    let sim = std::process::Command::new(common::tsfc_binary())
        .arg("simulate")
        .arg(&spec)
        .arg("--out")
        .arg(&dir)
        .output()
        .expect("run tsfc");
    let stderr = String::from_utf8_lossy(&sim.stderr);
    assert_eq!(sim.status.code(), Some(0), "{stderr}");
    assert!(
        dir.join("pendulum_observer.estimate.svg").exists(),
        "{stderr}"
    );
}

/// The worst (largest) eigenvalue over the looped-functional conditions of
/// the sampled observer loop at every vertex (plant i, observer j,
/// controller l), built from the report alone ([`Looped`]).
fn worst_looped(report: &Value, gains: &[DMatrix<f64>], phi: f64) -> f64 {
    let lp = Looped::of(report);
    let mut worst = f64::NEG_INFINITY;
    for (a, b) in &lp.models {
        let plant = lp.plant(a, b);
        for j in 0..lp.rules() {
            for f in gains {
                let (r1, r2) = lp.blocks(&plant, &lp.gain(j, f), phi);
                worst = worst.max(max_eig(&r1)).max(max_eig(&r2));
            }
        }
    }
    worst
}

/// The sampled certificate re-derived from the report (P, Y, L1, L2 of the
/// looped functional, the local models, F_l, L_j, C, T) with eigenvalues, at
/// every rule triple: negative definite at the certified rate 0.5 (phi = 1).
/// Not vacuous: with the controller switched off (F = 0, the pendulum
/// unstable) the same matrices fail.
#[test]
fn shipped_pendulum_observer_sampled_conditions_rederived_from_the_report() {
    let report = compile(&common::fresh_dir("observer_shipped", "lmis"));
    let covers = report["sampled_loop"]["covers"].as_str().expect("covers");
    assert!(covers.contains("decays at rate 0.5"), "{covers}");
    // The report's own field for the sampled loop's rate, re-derived below.
    let rate = report["sampled_loop"]["decay_rate"]
        .as_f64()
        .expect("decay_rate");
    assert_eq!(rate, 0.5);
    let gains: Vec<DMatrix<f64>> = report["gains"]
        .as_array()
        .expect("gains")
        .iter()
        .map(|g| mat(&g["F"]))
        .collect();
    let worst = worst_looped(&report, &gains, 2.0 * rate);
    assert!(worst < 0.0, "a looped condition is not negative: {worst:e}");
    // The rate is not loose: the same matrices at twice the rate fail.
    let faster = worst_looped(&report, &gains, 4.0 * rate);
    assert!(
        faster > 0.0,
        "passes at twice the reported rate: {faster:e}"
    );
    let off: Vec<DMatrix<f64>> = gains.iter().map(|g| g * 0.0).collect();
    let open = worst_looped(&report, &off, 1.0);
    assert!(open > 0.0, "open loop passes: {open:e}");
}
