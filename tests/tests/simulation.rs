//! Closed-loop simulation (`tsfc simulate`): the shipped specs converge from
//! their papers' initial states, the integrators are accurate, the event
//! trigger saves transmissions, and runs are reproducible. Hardening: the CSV
//! is streamed and the plotted trace bounded, the step limit holds from every
//! entry point, bad overrides are usage errors, spec faults point into the
//! spec, and a run that goes non-finite or leaves the premise region is
//! reported as failed (never "converged").

use nalgebra::DMatrix;
use std::path::PathBuf;
use std::sync::OnceLock;
use tsf_lang::spec::{Threshold, Trigger, Weight};
use tsfc::driver::prepare;
use tsfc::sim::integrator::{Dopri5, Rk4};
use tsfc::sim::limits::{MAX_ADAPTIVE_STEPS, MAX_PLOT_POINTS, MAX_STEPS};
use tsfc::sim::{
    simulate, simulate_csv, simulate_to, ErrorKind, Options, Outcome, Prepared, SimError,
};

fn spec(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../specs")
        .join(name)
}

/// Each design is compiled once per test binary (the Xu & Huang design takes seconds).
fn prepared(name: &'static str) -> &'static Prepared {
    static XU: OnceLock<Prepared> = OnceLock::new();
    static ZHANG: OnceLock<Prepared> = OnceLock::new();
    static PENDULUM: OnceLock<Prepared> = OnceLock::new();
    let cell = match name {
        "xu2020_event_triggered.tsf" => &XU,
        "zhang2013_multiobjective.tsf" => &ZHANG,
        _ => &PENDULUM,
    };
    cell.get_or_init(|| match prepare(&spec(name)) {
        Ok(p) => p,
        Err(e) => panic!("{name}: {e}"),
    })
}

fn run(name: &'static str, opts: &Options) -> Outcome {
    simulate(prepared(name), opts).unwrap_or_else(|e| panic!("{name}: {e}"))
}

fn horizon(s: f64) -> Options {
    Options {
        horizon: Some(s),
        ..Options::default()
    }
}

fn assert_finite(o: &Outcome) {
    assert!(o.metrics.nonfinite_at_s.is_none());
    assert!(!o.metrics.failed, "{:?}", o.metrics.failures());
    for (x, u) in o.trace.x.iter().zip(&o.trace.u) {
        assert!(x.iter().chain(u).all(|v| v.is_finite()));
    }
}

/// The CSV of a run, streamed into memory.
fn csv_of(name: &'static str, opts: &Options) -> (Outcome, String) {
    let mut bytes = Vec::new();
    let o = simulate_csv(prepared(name), opts, &mut bytes).unwrap_or_else(|e| panic!("{e}"));
    (o, String::from_utf8(bytes).expect("CSV is UTF-8"))
}

/// Norm of components `range` of the final state.
fn final_norm(o: &Outcome, range: std::ops::Range<usize>) -> f64 {
    let x = o.trace.x.last().expect("trace is never empty");
    x[range].iter().map(|v| v * v).sum::<f64>().sqrt()
}

#[test]
fn zhang_converges_from_the_papers_initial_state() {
    // Paper's x0 and orbit-rate disturbance (spec), 300 s, RK4 at 0.01 s.
    let o = run("zhang2013_multiobjective.tsf", &Options::default());
    assert_finite(&o);
    assert!(o.metrics.converged, "{:?}", o.metrics);
    // Attitude error ||rho|| (Cayley-Rodrigues) below 1e-3 at 300 s
    // (measured 7.7e-6 for the whole state).
    let rho = final_norm(&o, 3..6);
    assert!(rho < 1e-3, "||rho(300)|| = {rho}");
    // No hard saturation in this paper; the input-norm objective bounds
    // ||u|| by 5 for this x0.
    assert!(
        o.metrics.max_abs_u.iter().all(|&u| u <= 5.0),
        "{:?}",
        o.metrics.max_abs_u
    );
}

#[test]
fn xu_converges_under_saturation_and_disturbance() {
    // Paper's x0 and tau(t) (spec), 100 s, adaptive event trigger.
    let o = run("xu2020_event_triggered.tsf", &Options::default());
    assert_finite(&o);
    assert!(o.metrics.converged, "{:?}", o.metrics);
    // Attitude error ||q|| below 5e-3 at 100 s (measured 1.2e-3 for the whole state).
    let q = final_norm(&o, 3..6);
    assert!(q < 5e-3, "||q(100)|| = {q}");
    // |sat(u_s)| <= 2 N m at every instant.
    for u in &o.trace.u {
        assert!(u.iter().all(|v| v.abs() <= 2.0), "{u:?}");
    }
}

#[test]
fn inverted_pendulum_converges_on_its_nonlinear_truth_model() {
    let o = run("inverted_pendulum.tsf", &Options::default());
    assert_finite(&o);
    assert!(o.metrics.converged, "{:?}", o.metrics);
    // From 60 degrees to below 1e-3 rad within 5 s (decay rate >= 0.5 designed).
    assert!(final_norm(&o, 0..1) < 1e-3);
    assert!(o.metrics.settle_time_s.is_some_and(|t| t < 5.0));
}

fn aperiodic(threshold: Option<Threshold>) -> Trigger {
    Trigger::Aperiodic {
        sampling: (0.001, 0.1),
        threshold,
        weight: Weight::Synthesize,
    }
}

#[test]
fn event_trigger_saves_transmissions_and_still_converges() {
    let every = run(
        "xu2020_event_triggered.tsf",
        &Options {
            trigger: Some(aperiodic(None)),
            ..Options::default()
        },
    );
    let event = run("xu2020_event_triggered.tsf", &Options::default());
    // Same seed, same sampling instants.
    assert_eq!(every.metrics.samples, event.metrics.samples);
    assert_eq!(every.metrics.transmissions, every.metrics.samples);
    assert!(every.metrics.converged && event.metrics.converged);
    eprintln!(
        "every sample: {} transmissions; event trigger: {} of {} samples, inter-event mean {:?} min {:?}",
        every.metrics.transmissions,
        event.metrics.transmissions,
        event.metrics.samples,
        event.metrics.mean_inter_event_s,
        event.metrics.min_inter_event_s
    );
    assert!(
        event.metrics.transmissions * 5 < event.metrics.samples,
        "{} transmissions of {} samples",
        event.metrics.transmissions,
        event.metrics.samples
    );
}

#[test]
fn lowering_nu_raises_the_transmission_count() {
    let count = |nu: f64| {
        run(
            "xu2020_event_triggered.tsf",
            &Options {
                horizon: Some(40.0),
                trigger: Some(aperiodic(Some(Threshold {
                    nu,
                    adaptive: None,
                    max: None,
                }))),
                ..Options::default()
            },
        )
        .metrics
        .transmissions
    };
    // Both thresholds are within the certified nu <= 0.05.
    let (low, high) = (count(0.01), count(0.05));
    eprintln!("static trigger over 40 s: nu = 0.01 -> {low}, nu = 0.05 -> {high} transmissions");
    assert!(
        low > high,
        "nu = 0.01: {low} transmissions, nu = 0.05: {high}"
    );
}

#[test]
fn same_spec_and_seed_give_identical_csv() {
    let (_, a) = csv_of("xu2020_event_triggered.tsf", &horizon(10.0));
    let (_, b) = csv_of("xu2020_event_triggered.tsf", &horizon(10.0));
    assert_eq!(a, b);
    let other_seed = Options {
        seed: Some(8),
        ..horizon(10.0)
    };
    let (_, c) = csv_of("xu2020_event_triggered.tsf", &other_seed);
    assert_ne!(a, c, "the seed must change the sampling pattern");
}

fn tmp_dir(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("tsfc-sim-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

#[test]
fn outputs_are_written() {
    let dir = tmp_dir("outputs");
    let (o, files) =
        simulate_to(prepared("inverted_pendulum.tsf"), &horizon(1.0), &dir).expect("outputs");
    assert!(!o.metrics.failed);
    assert_eq!(
        crate::common::schema::validate_dir(&dir),
        1,
        "the metrics JSON"
    );
    for ext in [
        ".csv",
        ".metrics.json",
        ".states.svg",
        ".states.png",
        ".inputs.png",
        ".events.svg",
    ] {
        assert!(
            files.iter().any(|f| f.to_string_lossy().ends_with(ext)),
            "{ext}"
        );
    }
    let json: serde_json::Value = serde_json::from_slice(
        &std::fs::read(dir.join("inverted_pendulum.metrics.json")).expect("metrics file"),
    )
    .expect("metrics JSON");
    for key in [
        "converged",
        "final_state_norm",
        "max_abs_u",
        "samples",
        "transmissions",
        "mean_inter_event_s",
        "min_inter_event_s",
        "energy",
        "settle_time_s",
        "no_rule_samples",
        "out_of_region_samples",
        "lyapunov_ratio",
        "diverged",
        "failed",
    ] {
        assert!(json.get(key).is_some(), "{key}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

// ---- hardening (issue 12) ----

#[test]
fn the_csv_is_streamed_and_the_plotted_trace_is_bounded() {
    // 20 s at 1 ms: 20001 samples, five times the plot budget.
    let (o, csv) = csv_of("inverted_pendulum.tsf", &horizon(20.0));
    assert_eq!(o.metrics.samples, 20_001);
    assert_eq!(
        csv.lines().count() as u64,
        o.metrics.samples + 1,
        "header + one row per sample"
    );
    assert!(csv.starts_with("t,theta,omega,u,transmitted\n"));
    let rows: Vec<&str> = csv.lines().skip(1).collect();
    assert!(rows[0].starts_with("0,"), "{}", rows[0]);
    assert!(
        rows[rows.len() - 1].starts_with("20,"),
        "{}",
        rows[rows.len() - 1]
    );
    let tr = &o.trace;
    assert!(
        tr.t.len() <= MAX_PLOT_POINTS && tr.t.len() > MAX_PLOT_POINTS / 4,
        "{}",
        tr.t.len()
    );
    assert!(tr.events.len() <= MAX_PLOT_POINTS && tr.gaps.len() <= MAX_PLOT_POINTS);
    assert_eq!(tr.t.first(), Some(&0.0));
    assert_eq!(
        tr.t.last(),
        Some(&20.0),
        "the last sample is always plotted"
    );
    assert_eq!(
        (tr.x.len(), tr.u.len(), tr.sent.len()),
        (tr.t.len(), tr.t.len(), tr.t.len())
    );
    // The thinned trace is a uniform subsequence of the CSV rows.
    let stride = tr.t[1] - tr.t[0];
    assert!(tr
        .t
        .windows(2)
        .rev()
        .skip(1)
        .all(|w| ((w[1] - w[0]) - stride).abs() < 1e-9));
    // Metrics come from every sample, not the thinned ones: the final row's
    // state is the final state.
    let last: Vec<f64> = rows[rows.len() - 1]
        .split(',')
        .skip(1)
        .take(2)
        .map(|v| v.parse().expect("number"))
        .collect();
    assert_eq!(last, tr.x[tr.x.len() - 1]);
}

/// The pendulum spec with its `time` line replaced; `extra` is appended to
/// the `omega'` derivative. Returns the file and the 1-based line of `time`.
fn pendulum_variant(tag: &str, time: &str, extra: &str) -> (PathBuf, usize) {
    let text = std::fs::read_to_string(spec("inverted_pendulum.tsf")).expect("spec");
    let text = text.replace("time = 0 .. 5 step 0.001;", time).replace(
        "/ (4 * l / 3 - a * m * l * cos(theta) ^ 2);",
        &format!("/ (4 * l / 3 - a * m * l * cos(theta) ^ 2){extra};"),
    );
    let line = text
        .lines()
        .position(|l| l.contains(time))
        .expect("time line")
        + 1;
    let dir = tmp_dir(tag);
    std::fs::create_dir_all(&dir).expect("dir");
    let path = dir.join("pendulum_variant.tsf");
    std::fs::write(&path, text).expect("write spec");
    (path, line)
}

#[test]
fn the_step_limit_holds_from_every_entry_point() {
    let p = prepared("inverted_pendulum.tsf");
    // A horizon just over the limit (1 ms steps), through the library API.
    let over = 0.001 * MAX_STEPS as f64 + 0.01;
    let e = simulate(p, &horizon(over)).expect_err("over the step limit");
    assert_eq!(e.kind, ErrorKind::Usage, "{e}");
    assert!(e.message.contains("at most 1e7"), "{e}");
    // The same limit with an initial-state override (the spec's span is fine).
    let with_x0 = Options {
        x0: Some(vec![0.1, 0.0]),
        ..horizon(over)
    };
    assert_eq!(
        simulate(p, &with_x0).map(|_| ()).map_err(|e| e.kind),
        Err(ErrorKind::Usage)
    );
    // A trigger override whose shortest interval multiplies the steps.
    let dense = Options {
        trigger: Some(Trigger::Aperiodic {
            sampling: (1e-9, 1e-3),
            threshold: None,
            weight: Weight::Synthesize,
        }),
        ..Options::default()
    };
    let e = simulate(p, &dense).expect_err("dense sampling");
    assert_eq!(e.kind, ErrorKind::Usage, "{e}");
    // From the spec: 5e7 steps pass `check` (its own cap is coarser) but not
    // the simulator; the error points at the scenario in the spec.
    let (path, _) = pendulum_variant("steps", "time = 0 .. 50000 step 0.001;", "");
    let big = prepare(&path).expect("the design itself is fine");
    let e = simulate(&big, &Options::default()).expect_err("spec over the limit");
    assert_eq!(e.kind, ErrorKind::Spec, "{e}");
    assert!(e.message.starts_with("error: cannot simulate"), "{e}");
    assert!(e.message.contains("pendulum_variant.tsf:"), "{e}");
    assert!(e.message.contains("5.000e7 steps"), "{e}");
    // ... while an override of the horizon makes the same spec usable.
    assert!(simulate(&big, &horizon(0.5)).is_ok());
    let _ = std::fs::remove_dir_all(path.parent().expect("dir"));
    const { assert!(MAX_ADAPTIVE_STEPS >= MAX_STEPS) };
}

#[test]
fn bad_overrides_are_usage_errors() {
    let p = prepared("inverted_pendulum.tsf");
    for hz in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let e = simulate(p, &horizon(hz)).expect_err("bad horizon");
        assert_eq!(e.kind, ErrorKind::Usage, "{hz}: {e}");
        assert!(e.message.contains("horizon"), "{e}");
    }
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        let opts = Options {
            x0: Some(vec![bad, 0.0]),
            ..Options::default()
        };
        let e = simulate(p, &opts).expect_err("non-finite x0");
        assert_eq!(e.kind, ErrorKind::Usage, "{bad}: {e}");
    }
    let opts = Options {
        convergence_rel_tol: f64::INFINITY,
        ..Options::default()
    };
    assert!(
        simulate(p, &opts).is_err(),
        "an infinite tolerance is meaningless"
    );
}

#[test]
fn a_huge_initial_state_is_never_converged() {
    // x0 = [1e160, 0] used to report "final ||x|| = inf (converged, tol inf)";
    // it is now refused (beyond 1e150), and 1e149 runs and fails.
    let refused = Options {
        x0: Some(vec![1e160, 0.0]),
        ..horizon(1.0)
    };
    let e = simulate(prepared("inverted_pendulum.tsf"), &refused).expect_err("beyond 1e150");
    assert_eq!(e.exit_code(), 2, "{e}");
    let opts = Options {
        x0: Some(vec![1e149, 0.0]),
        ..horizon(1.0)
    };
    let m = run("inverted_pendulum.tsf", &opts).metrics;
    assert!(!m.converged, "{m:?}");
    assert!(m.failed && !m.failures().is_empty(), "{m:?}");
    assert_eq!(m.initial_state_norm, 1e149, "the norm does not overflow");
    assert!(m.convergence_tolerance.is_finite());
    assert!(m.settle_time_s.is_none());
    assert!(
        m.out_of_region_samples > 0,
        "sinc(1e149) is far outside 2/pi .. 1"
    );
}

#[test]
fn leaving_the_premise_region_fails_the_run_and_is_counted() {
    // 3 rad (172 degrees): sinc(theta) < 2/pi, outside the premise range.
    let opts = Options {
        x0: Some(vec![3.0, 0.0]),
        ..horizon(1.0)
    };
    let m = run("inverted_pendulum.tsf", &opts).metrics;
    assert!(m.out_of_region_samples > 0 && m.out_of_region_samples <= m.samples);
    assert_eq!(m.left_region_at_s, Some(0.0));
    assert!(m.failed && !m.converged);
    assert!(
        m.failures().iter().any(|f| f.contains("premise region")),
        "{:?}",
        m.failures()
    );
    // The shipped scenario stays inside and contracts V = x'Px.
    let ok = run("inverted_pendulum.tsf", &Options::default()).metrics;
    assert_eq!((ok.out_of_region_samples, ok.no_rule_samples), (0, 0));
    assert!(
        ok.lyapunov_ratio.is_some_and(|r| r < 1e-6),
        "{:?}",
        ok.lyapunov_ratio
    );
    assert!(!ok.diverged && !ok.failed);
}

#[test]
fn an_open_loop_run_diverges_inside_the_region() {
    // Zero gains: the upright pendulum falls; over 0.5 s from 0.05 rad it stays
    // inside the premise range but V = x'Px grows.
    let mut p = prepared("inverted_pendulum.tsf").clone();
    for row in p.tables.gains.iter_mut().flatten() {
        row.iter_mut().for_each(|v| *v = 0.0);
    }
    let opts = Options {
        x0: Some(vec![0.05, 0.0]),
        ..horizon(0.5)
    };
    let m = simulate(&p, &opts).expect("runs").metrics;
    assert_eq!(m.out_of_region_samples, 0);
    assert!(
        m.lyapunov_ratio.is_some_and(|r| r > 1.0),
        "{:?}",
        m.lyapunov_ratio
    );
    assert!(m.diverged && m.failed && !m.converged);
    assert!(
        m.failures().iter().any(|f| f.contains("diverged")),
        "{:?}",
        m.failures()
    );
}

#[test]
fn a_failed_run_replaces_no_file_and_points_into_the_spec() {
    // The derivative divides by zero once t > 1 s (an error of the evaluator).
    let (path, _) = pendulum_variant(
        "atomic",
        "time = 0 .. 2 step 0.001;",
        " + 0 * (1 / (sign(1 - t) + 1))",
    );
    let p = prepare(&path).expect("prepared");
    let dir = path.parent().expect("dir").join("out");
    std::fs::create_dir_all(&dir).expect("out dir");
    let csv = dir.join("inverted_pendulum.csv");
    std::fs::write(&csv, "earlier run\n").expect("old csv");
    let e = simulate_to(&p, &Options::default(), &dir).expect_err("fails at t > 1");
    assert_eq!(e.kind, ErrorKind::Spec, "{e}");
    assert!(e.message.starts_with("error: "), "{e}");
    assert!(e.message.contains("division by zero"), "{e}");
    assert!(e.message.contains("at t = 1.0"), "{e}");
    let text = std::fs::read_to_string(&path).expect("spec");
    let line = text
        .lines()
        .position(|l| l.contains("sign(1 - t)"))
        .expect("line")
        + 1;
    assert!(
        e.message.contains(&format!("pendulum_variant.tsf:{line}:")),
        "{e}"
    );
    assert_eq!(std::fs::read_to_string(&csv).expect("csv"), "earlier run\n");
    let left: Vec<_> = std::fs::read_dir(&dir)
        .expect("dir")
        .map(|f| f.expect("entry").file_name())
        .collect();
    assert_eq!(left.len(), 1, "no temporary file is left behind: {left:?}");
    // The same spec over 1 s succeeds and replaces the CSV.
    simulate_to(&p, &horizon(1.0), &dir).expect("1 s is fine");
    let csv_text = std::fs::read_to_string(&csv).expect("csv");
    assert!(
        csv_text.starts_with("t,theta,omega,u,transmitted\n"),
        "{csv_text:.60}"
    );
    let _ = std::fs::remove_dir_all(path.parent().expect("dir"));
}

// ---- integrators against x(t) = expm(A t) x0 ----

fn linear_system() -> (DMatrix<f64>, Vec<f64>) {
    let a = DMatrix::from_row_slice(3, 3, &[-0.5, 2.0, 0.0, -2.0, -0.5, 0.3, 0.0, -0.3, -1.0]);
    (a, vec![1.0, -0.5, 0.25])
}

fn exact(a: &DMatrix<f64>, x0: &[f64], t: f64) -> DMatrix<f64> {
    (a * t).exp() * DMatrix::from_column_slice(x0.len(), 1, x0)
}

fn rhs(a: &DMatrix<f64>) -> impl FnMut(f64, &[f64], &mut [f64]) -> Result<(), SimError> + '_ {
    move |_t, y, dy| {
        let v = a * DMatrix::from_column_slice(y.len(), 1, y);
        dy.copy_from_slice(v.as_slice());
        Ok(())
    }
}

fn rk4_error(h: f64) -> f64 {
    let (a, x0) = linear_system();
    let mut y = x0.clone();
    Rk4::new(3, h)
        .advance(&mut rhs(&a), 0.0, 2.0, &mut y)
        .expect("rk4");
    (DMatrix::from_column_slice(3, 1, &y) - exact(&a, &x0, 2.0)).norm()
}

#[test]
fn rk4_is_accurate_and_fourth_order() {
    let (e1, e2) = (rk4_error(0.02), rk4_error(0.01));
    assert!(e1 < 1e-6, "error {e1}");
    let ratio = e1 / e2;
    eprintln!("rk4: error {e1:e} at h = 0.02, {e2:e} at h = 0.01, ratio {ratio}");
    assert!(
        (12.0..=20.0).contains(&ratio),
        "halving h divides the error by {ratio}"
    );
}

#[test]
fn dopri5_meets_its_tolerance() {
    let (a, x0) = linear_system();
    for tol in [1e-6, 1e-9] {
        let mut y = x0.clone();
        let mut dp = Dopri5::new(3, tol, tol * 1e-3, 1.0);
        dp.advance(&mut rhs(&a), 0.0, 2.0, &mut y).expect("dopri5");
        let err = (DMatrix::from_column_slice(3, 1, &y) - exact(&a, &x0, 2.0)).norm();
        let scale = tol * exact(&a, &x0, 2.0).norm().max(1e-3);
        eprintln!(
            "dopri5: rtol {tol:e}: error {err:e} ({} steps)",
            dp.accepted
        );
        assert!(err <= 10.0 * scale + 1e-12, "tol {tol}: error {err}");
        assert!(dp.accepted > 0);
    }
}
