//! Issue 36, part B: the observer-based controller in the runtime, the
//! generated code and the simulator, on the inverted pendulum of
//! `specs/inverted_pendulum.tsf` with only the angle measured (the textbook
//! observer example, Tanaka & Wang 2001, ch. 5).
//!
//! The design data are built BY HAND here: the controller gains F_j are the
//! shipped spec's certified ones, C = [1 0], and every rule's observer gain
//! L_i places the poles of A_i - L_i C at -8 and -10 (closed-form pole
//! placement of a 2-state pair, below). Then: the exact discretization
//! against a closed form and against RK4 of the continuous observer; the
//! runtime in Rust against its C mirror and the generated C, bit for bit
//! on 10,000 seeded steps; the closed loop from a wrong initial estimate in
//! the simulator and in an independent RK4 simulation written here with
//! the runtime's step every T, which must agree.

use crate::common;
use common::observer::{
    hex, independent_loop, outputs, run_c_driver, runtime_observer, runtime_premises,
    runtime_terms, HeldPlant, C_BITS,
};
use common::Rng;

use nalgebra::DMatrix;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;
use tsf_lang::spec::CStyle;
use tsf_runtime::Flags;
use tsfc::codegen::{generate, CodegenError};
use tsfc::model::TsModel;
use tsfc::tables::observer::{discretize, period_of};
use tsfc::tables::{ObserverTables, PremiseCode, PremiseFrom, Tables, TablesError};

/// The observer's period (the controller's sampling period) in seconds.
const T: f64 = 0.01;
/// The observer poles every rule's L_i places.
const POLES: (f64, f64) = (-8.0, -10.0);

/// C = [1 0]: the angle.
fn c_matrix() -> DMatrix<f64> {
    DMatrix::from_row_slice(1, 2, &[1.0, 0.0])
}

/// L = [l1; l2] with eig(A - L C) = {p1, p2} for C = [1 0]: A - L C =
/// [[a11 - l1, a12], [a21 - l2, a22]] has trace a11 - l1 + a22 = p1 + p2 and
/// determinant (a11 - l1) a22 - a12 (a21 - l2) = p1 p2.
fn place(a: &DMatrix<f64>) -> DMatrix<f64> {
    let (p1, p2) = POLES;
    let l1 = a[(0, 0)] + a[(1, 1)] - (p1 + p2);
    let l2 = (p1 * p2 - (a[(0, 0)] - l1) * a[(1, 1)] + a[(0, 1)] * a[(1, 0)]) / a[(0, 1)];
    DMatrix::from_row_slice(2, 1, &[l1, l2])
}

/// The pendulum's model and certified tables with the observer by hand.
fn design() -> &'static (TsModel, Tables) {
    static D: OnceLock<(TsModel, Tables)> = OnceLock::new();
    D.get_or_init(|| {
        let (model, compiled) = common::compile_shipped("inverted_pendulum.tsf");
        let (design, cert) = compiled.outcome.expect("certified");
        let mut t = tsfc::tables::tables(&model, &design, &cert, "inverted_pendulum.tsf", "0")
            .expect("tables");
        t.observer = Some(observer_tables(&model, PremiseFrom::Output));
        (model, t)
    })
}

fn observer_tables(model: &TsModel, from: PremiseFrom) -> ObserverTables {
    let a: Vec<DMatrix<f64>> = model.rules.iter().map(|r| r.a.clone()).collect();
    let b: Vec<DMatrix<f64>> = model.rules.iter().map(|r| r.b.clone()).collect();
    let l: Vec<DMatrix<f64>> = a.iter().map(place).collect();
    ObserverTables::from_design(&c_matrix(), &l, &a, &b, T, from).expect("observer tables")
}

fn mat(rows: &[Vec<f64>]) -> DMatrix<f64> {
    let (r, c) = (rows.len(), rows.first().map_or(0, Vec::len));
    DMatrix::from_fn(r, c, |i, j| rows[i][j])
}

/// Pole placement worked: eig(A_i - L_i C) = {-8, -10} for both rules.
#[test]
fn pole_placement_by_hand_places_the_poles() {
    let (model, _) = design();
    for r in &model.rules {
        let ao = &r.a - place(&r.a) * c_matrix();
        let (tr, det) = (ao.trace(), ao.determinant());
        assert!((tr - (POLES.0 + POLES.1)).abs() < 1e-12, "{tr}");
        assert!((det - POLES.0 * POLES.1).abs() < 1e-9, "{det}");
    }
}

/// A diagonal observer in closed form: A = diag(-1, -2), C = I,
/// L = diag(1, 0.5): A - L C = diag(-2, -2.5), so Phi = diag(e^{-2T},
/// e^{-2.5T}), Gu = [(1 - e^{-2T})/2 b1; (1 - e^{-2.5T})/2.5 b2], Gy = the
/// same factors times L.
#[test]
fn discretization_matches_a_closed_form() {
    let a = DMatrix::from_row_slice(2, 2, &[-1.0, 0.0, 0.0, -2.0]);
    let b = DMatrix::from_row_slice(2, 1, &[1.0, 2.0]);
    let c = DMatrix::identity(2, 2);
    let l = DMatrix::from_row_slice(2, 2, &[1.0, 0.0, 0.0, 0.5]);
    for t in [1e-3, T, 0.3] {
        let (phi, gu, gy) = discretize(&a, &b, &c, &l, t);
        let (e1, e2) = ((-2.0 * t).exp(), (-2.5 * t).exp());
        let (g1, g2) = ((1.0 - e1) / 2.0, (1.0 - e2) / 2.5);
        let want_phi = DMatrix::from_row_slice(2, 2, &[e1, 0.0, 0.0, e2]);
        let want_gu = DMatrix::from_row_slice(2, 1, &[g1, 2.0 * g2]);
        let want_gy = DMatrix::from_row_slice(2, 2, &[g1, 0.0, 0.0, 0.5 * g2]);
        assert!((phi - want_phi).amax() < 1e-15, "T = {t}");
        assert!((gu - want_gu).amax() < 1e-15, "T = {t}");
        assert!((gy - want_gy).amax() < 1e-15, "T = {t}");
    }
}

/// Every rule's discretized observer against RK4 of the continuous observer
/// xhat' = (A_i - L_i C) xhat + B_i u + L_i y with u and y held, from seeded
/// starts and inputs.
#[test]
fn discretization_matches_rk4_of_the_continuous_observer() {
    let (model, t) = design();
    let o = t.observer.as_ref().expect("observer");
    let mut rng = Rng::new(0x0b5e);
    let c = c_matrix();
    for (i, r) in model.rules.iter().enumerate() {
        let l = place(&r.a);
        let ao = &r.a - &l * &c;
        let (phi, gu, gy) = (mat(&o.phi[i]), mat(&o.gu[i]), mat(&o.gy[i]));
        for _ in 0..20 {
            let x0 = DMatrix::from_fn(2, 1, |_, _| rng.uniform(-2.0, 2.0));
            let u = DMatrix::from_element(1, 1, rng.uniform(-50.0, 50.0));
            let y = DMatrix::from_element(1, 1, rng.uniform(-1.5, 1.5));
            let f = |x: &DMatrix<f64>| &ao * x + &r.b * &u + &l * &y;
            let steps = 1000;
            let h = T / steps as f64;
            let mut x = x0.clone();
            for _ in 0..steps {
                let k1 = f(&x);
                let k2 = f(&(&x + &k1 * (h / 2.0)));
                let k3 = f(&(&x + &k2 * (h / 2.0)));
                let k4 = f(&(&x + &k3 * h));
                x += (k1 + k2 * 2.0 + k3 * 2.0 + k4) * (h / 6.0);
            }
            let exact = &phi * &x0 + &gu * &u + &gy * &y;
            let scale = 1.0 + x.amax();
            assert!(
                (&exact - &x).amax() < 1e-11 * scale,
                "rule {i}: {exact} vs RK4 {x}"
            );
        }
    }
}

/// The period comes from `trigger periodic { every = T; }`: the shipped
/// spec (continuous loop) is refused with that advice; a bad period and an
/// unobservable C are refused with their reason.
#[test]
fn observer_tables_refuse_what_they_cannot_build() {
    let (model, _) = design();
    let e = period_of(&model.spec).expect_err("no periodic trigger");
    assert_eq!(e, TablesError::ObserverPeriod);
    assert!(
        e.to_string().contains("trigger periodic { every = T; }"),
        "{e}"
    );
    let text = std::fs::read_to_string(common::spec_path("inverted_pendulum.tsf")).expect("spec");
    let periodic = text.replace(
        "objective stability;",
        "trigger periodic { every = 0.01; }\nobjective stability;",
    );
    let m = common::model_of("periodic.tsf", &periodic);
    assert_eq!(period_of(&m.spec), Ok(0.01));
}

fn work_dir(tag: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("observer_code")
        .join(tag);
    std::fs::create_dir_all(&d).expect("temp dir");
    d
}

/// A driver that includes the generated `<name>.c` (so its static tables
/// are visible) and, per input line `y z` (hex bits), runs the runtime's
/// `tsf_observer_step` on the tables with the given z, and the generated
/// `<name>_step` (premises computed by the generated code); prints u, the
/// estimate and the flags of both as hex bits.
fn driver(name: &str) -> String {
    format!(
        r#"#include "{name}.c"
{C_BITS}
int main(void) {{
    {name}_state_t a = {name}_init, g = {name}_init;
    double y[1], z[1], u[1], ug[1], deg[2], h[2], next[2];
    unsigned long long by, bz;
    while (scanf("%llx %llx", &by, &bz) == 2) {{
        uint8_t f;
        y[0] = real(by);
        z[0] = real(bz);
        f = tsf_observer_step(&{name}_observer, a.xhat, y, z, deg, h, u, next);
        {name}_step(&g, y, ug);
        printf("%llx %llx %llx %u %llx %llx %llx %u\n", bits(u[0]), bits(a.xhat[0]),
               bits(a.xhat[1]), (unsigned)f, bits(ug[0]), bits(g.xhat[0]), bits(g.xhat[1]),
               (unsigned)g.flags);
    }}
    return 0;
}}
"#
    )
}

/// Builds the generated C of `t` with the runtime and the driver, feeds it
/// `cases` (y, z) and returns its output lines.
fn run_c(t: &Tables, cases: &[(f64, f64)]) -> Vec<String> {
    let dir = work_dir(&t.name);
    for f in generate(t, &[tsf_lang::spec::Emit::C]).expect("generated C") {
        std::fs::write(dir.join(&f.name), &f.text).expect("write");
    }
    let mut input = String::new();
    for (y, z) in cases {
        let _ = writeln!(input, "{:x} {:x}", y.to_bits(), z.to_bits());
    }
    run_c_driver(&dir, &driver(&t.name), &input)
}

/// The pendulum (premises sinc(theta) from the measured angle): the Rust
/// runtime and the C runtime's `tsf_observer_step` on the generated tables,
/// given the same premises, bit for bit on 10,000 seeded steps (the
/// estimate carried from step to step); the generated step, whose premise
/// calls the C runtime's `tsf_sinc`, bit for bit too (issue 36).
#[test]
fn rust_and_c_runtime_observers_agree_bit_for_bit() {
    let (_, t) = design();
    let PremiseCode::Exprs(exprs) = &t.premise else {
        panic!("sinc(theta) is a premise expression")
    };
    let terms = runtime_terms(t);
    let obs = runtime_observer::<2, 1, 1, 1, 2, 2>(t, &terms);
    let ys = outputs(10_000, 0x36b);
    let mut xhat = [0.0; 2];
    let mut cases = Vec::new();
    let mut want = Vec::new();
    let (mut resets, mut faults) = (0, 0);
    for &y in &ys {
        let v = obs.premise_state(&xhat, &[y]);
        let [z] = runtime_premises::<1>(exprs, &v);
        let s = obs.step_with_premises(&mut xhat, &[y], &[z]);
        resets += usize::from(s.flags.contains(Flags::ESTIMATE_RESET));
        faults += usize::from(s.flags.is_fault());
        cases.push((y, z));
        want.push((s.u[0], xhat, s.flags.0));
    }
    assert!(
        faults >= 10 && resets >= 1,
        "fault paths exercised: {faults} faults, {resets} resets"
    );
    let lines = run_c(t, &cases);
    assert_eq!(lines.len(), cases.len());
    for (k, (line, (u, x, f))) in lines.iter().zip(&want).enumerate() {
        let cols: Vec<&str> = line.split(' ').collect();
        let runtime = format!("{} {} {} {f}", hex(*u), hex(x[0]), hex(x[1]));
        assert_eq!(cols[..4].join(" "), runtime, "step {k}, y = {}", cases[k].0);
        assert_eq!(cols[4..].join(" "), runtime, "generated step {k}");
    }
    println!(
        "observer: C runtime and generated step vs Rust runtime bit-identical on {} steps ({faults} fault steps, {resets} resets)",
        cases.len()
    );
}

/// Linear premises from the estimate (z = theta_hat, the same sets and
/// gains): the generated C step against the Rust runtime's `step`, bit for
/// bit on 10,000 seeded steps.
#[test]
fn generated_c_observer_matches_the_runtime_bit_for_bit() {
    let (model, base) = design();
    let t = Tables {
        name: "pend_lin".into(),
        premise: PremiseCode::Linear(vec![vec![1.0, 0.0]]),
        observer: Some(observer_tables(model, PremiseFrom::Estimate)),
        ..base.clone()
    };
    let terms = runtime_terms(&t);
    let obs = runtime_observer::<2, 1, 1, 1, 2, 2>(&t, &terms);
    assert!(obs.output_map.is_none());
    let ys = outputs(10_000, 0x36b);
    // The C side starts from INIT (estimate 0).
    let mut xhat = [0.0; 2];
    let mut want = Vec::new();
    let cases: Vec<(f64, f64)> = ys.iter().map(|&y| (y, 0.0)).collect();
    for &y in &ys {
        let s = obs.step(&mut xhat, &[y]);
        want.push(format!(
            "{} {} {} {}",
            hex(s.u[0]),
            hex(xhat[0]),
            hex(xhat[1]),
            s.flags.0
        ));
    }
    let lines = run_c(&t, &cases);
    assert_eq!(lines.len(), want.len());
    for (k, (line, w)) in lines.iter().zip(&want).enumerate() {
        let cols: Vec<&str> = line.split(' ').collect();
        assert_eq!(cols[4..].join(" "), *w, "step {k}, y = {}", ys[k]);
    }
}

/// Generated Rust and C of the observer-based pendulum (snapshots); the
/// straight C style is refused for observers.
#[test]
fn generated_observer_code_is_snapshotted() {
    let (_, t) = design();
    let files = generate(t, &[tsf_lang::spec::Emit::Rust, tsf_lang::spec::Emit::C]).expect("code");
    let get = |name: &str| {
        files
            .iter()
            .find(|f| f.name == name)
            .unwrap_or_else(|| panic!("{name}"))
            .text
            .clone()
    };
    let rust = get("inverted_pendulum.rs");
    assert!(
        rust.contains("pub fn step(s: &mut State, y: &[f64; Q]) -> [f64; M]"),
        "{rust}"
    );
    assert!(rust.contains("pub const INIT: State"));
    syn::parse_file(&rust).expect("generated Rust parses");
    let h = get("inverted_pendulum.h");
    assert!(h.contains("typedef struct inverted_pendulum_state_t"));
    assert!(h.contains("extern const inverted_pendulum_state_t inverted_pendulum_init;"));
    assert!(h.contains(
        "void inverted_pendulum_step(inverted_pendulum_state_t *s, const INVERTED_PENDULUM_REAL y[INVERTED_PENDULUM_Q], INVERTED_PENDULUM_REAL u[INVERTED_PENDULUM_M]);"
    ));
    insta::assert_snapshot!("observer_pendulum_rs", rust);
    insta::assert_snapshot!("observer_pendulum_h", h);
    insta::assert_snapshot!("observer_pendulum_c", get("inverted_pendulum.c"));
    let straight = Tables {
        c_style: CStyle::Straight,
        ..t.clone()
    };
    let e = generate(&straight, &[tsf_lang::spec::Emit::C]).expect_err("straight refused");
    assert_eq!(e, CodegenError::ObserverStraight);
    assert!(e.to_string().contains("style = table"), "{e}");
}

/// The pendulum's right-hand side (the spec's `dynamics` block).
fn pendulum(x: [f64; 2], u: f64) -> [f64; 2] {
    let (g, m, mc, l) = (9.8, 2.0, 8.0, 0.5);
    let a = 1.0 / (m + mc);
    let (th, om) = (x[0], x[1]);
    let num = g * th.sin() - a * m * l * om * om * (2.0 * th).sin() / 2.0 - a * th.cos() * u;
    let den = 4.0 * l / 3.0 - a * m * l * th.cos().powi(2);
    [om, num / den]
}

/// The closed loop from a wrong initial estimate: the simulator (the spec's
/// truth plant, RK4 at 1 ms, the runtime's observer every T) converges, and
/// an independent simulation written here (RK4 of the pendulum equation at
/// 1 ms, the runtime's step every T) agrees with it at every sample.
#[test]
fn closed_loop_from_a_wrong_estimate_converges_and_agrees() {
    let (_, t) = design();
    let mut prepared =
        tsfc::driver::prepare(&common::spec_path("inverted_pendulum.tsf")).expect("prepared");
    prepared.tables.observer = t.observer.clone();
    let xhat0 = vec![0.0, 1.0];
    let mut opts = tsfc::sim::Options::default();
    opts.observer.xhat0 = Some(xhat0.clone());
    let mut samples: Vec<(f64, Vec<f64>, Vec<f64>)> = Vec::new();
    let mut see = |tt: f64, x: &[f64], u: &[f64]| samples.push((tt, x.to_vec(), u.to_vec()));
    let spec = prepared.model.spec.clone();
    let outcome =
        tsfc::sim::run_truth(&prepared, &spec, &opts, None, Some(&mut see)).expect("runs");
    let m = &outcome.metrics;
    let est = m.estimation.as_ref().expect("estimation metrics");
    assert!(m.converged, "{:?}", m.failures());
    assert!(est.initial_error_norm > 1.0, "{}", est.initial_error_norm);
    assert!(
        est.final_error_norm < 1e-3 * est.initial_error_norm,
        "{est:?}"
    );
    let settle = est.time_to_1pct_s.expect("error within 1 %");
    assert!(settle > 0.1 && settle < 2.0, "{settle}");
    assert_eq!(samples.len(), 501, "0 .. 5 s every 10 ms");
    // The independent loop.
    let PremiseCode::Exprs(exprs) = &t.premise else {
        panic!("sinc premise")
    };
    let terms = runtime_terms(t);
    let obs = runtime_observer::<2, 1, 1, 1, 2, 2>(t, &terms);
    for (k, (tt, _, _)) in samples.iter().enumerate() {
        assert!((tt - k as f64 * T).abs() < 1e-12);
    }
    let plant = HeldPlant {
        f: pendulum,
        h: 0.001,
        steps: 10,
    };
    let samples = samples.iter().map(|(_, x, u)| (x.as_slice(), u[0]));
    let start = ([60f64.to_radians(), 0.0], [xhat0[0], xhat0[1]]);
    let worst = independent_loop(&obs, exprs, samples, plant, start).worst;
    assert!(worst < 1e-8, "simulator vs independent loop: {worst:e}");
    // The estimate plot is drawn.
    let svgs = tsfc::sim::plot::svgs(&outcome).expect("plots");
    let est_svg = svgs
        .iter()
        .find(|(n, _)| n.ends_with(".estimate.svg"))
        .expect("estimate plot");
    assert!(est_svg.1.contains("omega estimate"), "legend");
    println!(
        "observer closed loop: ||e|| {:.3} -> {:.2e}, within 1 % from t = {settle} s; simulator vs independent RK4 {worst:.1e}",
        est.initial_error_norm, est.final_error_norm
    );
}

/// Seeded measurement noise: the run is reproducible (same seed, same
/// metrics), the estimate still converges to within a multiple of the noise
/// bound, and the metrics and the estimate plot are written.
#[test]
fn noisy_measurements_are_seeded_and_the_estimate_stays_near_the_state() {
    let (_, t) = design();
    let mut prepared =
        tsfc::driver::prepare(&common::spec_path("inverted_pendulum.tsf")).expect("prepared");
    prepared.tables.observer = t.observer.clone();
    let mut opts = tsfc::sim::Options::default();
    opts.observer.xhat0 = Some(vec![0.0, 1.0]);
    opts.observer.noise = tsfc::sim::observer::Noise::Uniform(1e-3);
    let a = tsfc::sim::simulate(&prepared, &opts).expect("runs");
    let b = tsfc::sim::simulate(&prepared, &opts).expect("runs");
    let ja = serde_json::to_string(&a.metrics).expect("json");
    assert_eq!(ja, serde_json::to_string(&b.metrics).expect("json"));
    let est = a.metrics.estimation.as_ref().expect("estimation");
    assert!(est.noise.contains("uniform"), "{}", est.noise);
    assert!(
        est.final_error_norm > 0.0 && est.final_error_norm < 0.05,
        "{est:?}"
    );
    assert!(a.metrics.converged || a.metrics.final_state_norm < 0.1);
    // Another seed, other noise: another trajectory.
    opts.seed = Some(99);
    let c = tsfc::sim::simulate(&prepared, &opts).expect("runs");
    assert_ne!(ja, serde_json::to_string(&c.metrics).expect("json"));
    // A sweep-style trigger override is refused with its reason.
    opts.trigger = Some(tsf_lang::spec::Trigger::Continuous);
    let e = tsfc::sim::simulate(&prepared, &opts).expect_err("override refused");
    assert!(e.to_string().contains("runs at its period"), "{e}");
    let dir = common::fresh_dir("observer_code", "noisy");
    let (_, files) = tsfc::sim::simulate_to(
        &prepared,
        &tsfc::sim::Options {
            trigger: None,
            seed: None,
            ..opts.clone()
        },
        &dir,
    )
    .expect("written");
    assert!(files
        .iter()
        .any(|f| f.to_string_lossy().ends_with(".estimate.png")));
    let csv = std::fs::read_to_string(dir.join("inverted_pendulum.csv")).expect("csv");
    assert!(csv
        .lines()
        .next()
        .expect("header")
        .contains("theta_hat,omega_hat"));
}
