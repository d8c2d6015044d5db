//! Issue 36, part C: the certificate of the SAMPLED observer-based loop
//! (continuous T-S plant, discrete observer and controller every T) and the
//! release of its code and simulation.
//!
//! The spec is a two-rule unstable oscillator x1'' = x1 + 0.1 sin(x1) + u
//! with only x1 measured (B the same in both rules): the shipped pendulum
//! observer ships its own test (`observer_shipped`).

use crate::common;
use common::observer::{
    independent_loop, osc_spec_at as spec_at, runtime_observer, runtime_terms, tsfc, HeldPlant,
};

use nalgebra::DMatrix;
use serde_json::Value;
use tsfc::tables::PremiseCode;

/// The period the spec certifies at.
const T: f64 = 0.01;

/// x2' of the nonlinear plant, x' = A(x) x + B u written out.
fn plant(x: [f64; 2], u: f64) -> [f64; 2] {
    [x[1], x[0] + 0.1 * x[0].sin() + u]
}

/// Certified at T: exit 0, the report's note says what the sampled
/// certificate covers, Rust and C are written; the tables' discrete
/// observer is the exact discretization of the reported gains L_i; the
/// simulator converges from a wrong estimate and agrees with an RK4 loop
/// written here (nonlinear plant, the runtime's observer step every T).
#[test]
fn sampled_observer_loop_certifies_generates_and_converges() {
    let dir = common::fresh_dir("observer_sampled", "certified");
    let spec = spec_at(T, &dir);
    let out = tsfc(&["compile"], &spec, &dir);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    for f in ["osc_observer.rs", "osc_observer.c", "osc_observer.h"] {
        assert!(dir.join(f).exists(), "{f}: {stderr}");
    }
    let report: Value = serde_json::from_slice(
        &std::fs::read(dir.join("osc_observer.report.json")).expect("report"),
    )
    .expect("JSON");
    let notes = report["notes"].to_string();
    assert!(
        notes.contains("sampled observer-based loop") && notes.contains("every 0.01 s"),
        "{notes}"
    );
    assert!(report["certificate"]["lmis"]
        .as_array()
        .expect("lmis")
        .iter()
        .any(|l| l["name"]
            .as_str()
            .is_some_and(|n| n.starts_with("trigger r=2"))));
    let prepared = tsfc::driver::prepare(&spec).expect("prepared");
    let t = &prepared.tables;
    let o = t.observer.as_ref().expect("observer tables");
    assert_eq!(o.period, T);
    // The tables are the ZOH of the reported L_i (re-derived here).
    let l_rows = &report["observer"]["gains"];
    for (i, rule) in prepared.model.rules.iter().enumerate() {
        let l = &l_rows[i]["L"];
        let li = DMatrix::from_row_slice(
            2,
            1,
            &[l[0][0].as_f64().unwrap(), l[1][0].as_f64().unwrap()],
        );
        let c = DMatrix::from_row_slice(1, 2, &[1.0, 0.0]);
        let (phi, _, gy) = tsfc::tables::observer::discretize(&rule.a, &rule.b, &c, &li, T);
        for r in 0..2 {
            assert!((phi[(r, 0)] - o.phi[i][r][0]).abs() < 1e-12);
            assert!((gy[(r, 0)] - o.gy[i][r][0]).abs() < 1e-12);
        }
    }
    let xhat0 = vec![0.0, 0.8];
    let mut opts = tsfc::sim::Options::default();
    opts.observer.xhat0 = Some(xhat0.clone());
    opts.observer.noise = tsfc::sim::observer::Noise::Uniform(0.0);
    let mut samples: Vec<(f64, Vec<f64>, f64)> = Vec::new();
    let mut see = |tt: f64, x: &[f64], u: &[f64]| samples.push((tt, x.to_vec(), u[0]));
    let spec_data = prepared.model.spec.clone();
    let outcome = tsfc::sim::run_truth(&prepared, &spec_data, &opts, None, Some(&mut see))
        .expect("simulated");
    let est = outcome.metrics.estimation.as_ref().expect("estimation");
    assert!(
        outcome.metrics.converged,
        "{:?}",
        outcome.metrics.failures()
    );
    assert!(
        est.final_error_norm < 1e-3 * est.initial_error_norm,
        "{est:?}"
    );
    let PremiseCode::Exprs(exprs) = &t.premise else {
        panic!("sinc premise")
    };
    let terms = runtime_terms(t);
    let obs = runtime_observer::<2, 1, 1, 1, 2, 2>(t, &terms);
    assert!(samples.iter().all(|(tt, _, _)| tt.is_finite()));
    let held = HeldPlant {
        f: plant,
        h: 0.001,
        steps: 10,
    };
    let samples = samples.iter().map(|(_, x, u)| (x.as_slice(), *u));
    let run = independent_loop(
        &obs,
        exprs,
        samples,
        held,
        ([0.5, 0.0], [xhat0[0], xhat0[1]]),
    );
    let (worst, x, xhat) = (run.worst, run.x, run.xhat);
    assert!(worst < 1e-8, "simulator vs independent loop: {worst:e}");
    assert!(
        x[0].abs() < 1e-3 && (x[0] - xhat[0]).abs() < 1e-3,
        "{x:?} {xhat:?}"
    );
    // `tsfc simulate` runs end to end with the spec's noise and the plot.
    let sim = tsfc(&["simulate"], &spec, &dir);
    let err = String::from_utf8_lossy(&sim.stderr);
    assert_eq!(sim.status.code(), Some(0), "{err}");
    assert!(dir.join("osc_observer.estimate.svg").exists(), "{err}");
    let metrics: Value = serde_json::from_slice(
        &std::fs::read(dir.join("osc_observer.metrics.json")).expect("metrics"),
    )
    .expect("JSON");
    assert!(
        metrics["estimation"]["noise"]
            .as_str()
            .is_some_and(|n| n.contains("0.001")),
        "{metrics}"
    );
    // The scenario's `xhat0`, then `--xhat0` over it.
    assert_eq!(
        metrics["estimation"]["xhat0"],
        serde_json::json!([0.0, 0.8])
    );
    let sim = tsfc(&["simulate", "--xhat0=-0.25,0.5"], &spec, &dir);
    let err = String::from_utf8_lossy(&sim.stderr);
    assert_eq!(sim.status.code(), Some(0), "{err}");
    let metrics: Value = serde_json::from_slice(
        &std::fs::read(dir.join("osc_observer.metrics.json")).expect("metrics"),
    )
    .expect("JSON");
    assert_eq!(
        metrics["estimation"]["xhat0"],
        serde_json::json!([-0.25, 0.5])
    );
    let bad = tsfc(&["simulate", "--xhat0", "1,2,3"], &spec, &dir);
    let err = String::from_utf8_lossy(&bad.stderr);
    assert_eq!(bad.status.code(), Some(2), "{err}");
    assert!(err.contains("xhat0 must have 2 finite components"), "{err}");
}

/// A period too long: exit 3 naming the longest certified period, and that
/// period, written as advised, certifies.
#[test]
fn too_long_a_period_is_refused_with_the_longest_that_certifies() {
    let dir = common::fresh_dir("observer_sampled", "refused");
    let spec = spec_at(0.5, &dir);
    let out = tsfc(&["compile"], &spec, &dir);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(3), "{stderr}");
    assert!(!dir.join("osc_observer.c").exists());
    let at = stderr.find("trigger periodic { every = ").expect("advice")
        + "trigger periodic { every = ".len();
    let rest = &stderr[at..];
    let advised: f64 = rest[..rest.find(';').expect(";")]
        .parse()
        .expect("a number");
    assert!(advised > 0.01 && advised < 0.5, "{advised}");
    assert!(stderr.contains("(certified)"), "{stderr}");
    let ok_dir = common::fresh_dir("observer_sampled", "advised");
    let spec = spec_at(advised, &ok_dir);
    let out = tsfc(&["compile"], &spec, &ok_dir);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}
