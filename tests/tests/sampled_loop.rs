//! The sampled loop a spec ships is inside the certificate (issue: periodic
//! triggers were certified for the continuous loop only). Checked against an
//! independent computation: the exact zero-order-hold discretization of every
//! frozen rule pair (A_i, B_i, F_j), whose spectral radius must be below 1
//! wherever the looped-functional certificate holds (the frozen pair is a
//! special case of the blended, sampled loop in the linear region).

use crate::common;

use nalgebra::DMatrix;
use tsf_lang::spec::Emit;
use tsfc::synth::{self, Settings, SynthError};

/// The mass-spring-damper with a hardening spring and an input limit, with
/// `trigger`.
pub(crate) fn msd(trigger: &str) -> String {
    format!(
        "tsf 1;\ncontroller msd;\nstate x1, x2;\ninput u saturate 0.7;\n\
         A(x) = [0, 1; -(1 + x1 ^ 2), -0.5];\nB = [0; 1];\n\
         premise p = x1 ^ 2 range 0 .. 1 {{ small = trap(-1, -1, 0, 1); large = trap(0, 1, 2, 2); }}\n\
         rule R1: p is small => at(x1 = 0, x2 = 0);\nrule R2: p is large => at(x1 = 1, x2 = 0);\n\
         objective decay_rate >= 0.5;\nrelaxation basic;\n{trigger}\n\
         simulate {{ x0 = [0.3, 0]; time = 0 .. 20 step 0.001; }}\n"
    )
}

/// The same plant without the input limit (the discrete-time design route
/// has no saturation condition and refuses `saturate`).
fn msd_unlimited(trigger: &str) -> String {
    msd(trigger).replace("input u saturate 0.7;", "input u;")
}

/// The spec `text` written to a fresh folder: (folder, file).
fn spec_file(tag: &str, text: &str) -> (std::path::PathBuf, std::path::PathBuf) {
    let dir = std::env::temp_dir().join(format!("tsfc-sampled-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("dir");
    let path = dir.join("msd.tsf");
    std::fs::write(&path, text).expect("write");
    (dir, path)
}

fn spectral_radius(m: &DMatrix<f64>) -> f64 {
    m.complex_eigenvalues()
        .iter()
        .map(|l| l.norm())
        .fold(0.0, f64::max)
}

/// The largest spectral radius over the frozen rule pairs sampled every `h`.
fn worst_frozen_radius(model: &tsfc::model::TsModel, gains: &[DMatrix<f64>], h: f64) -> f64 {
    let mut worst: f64 = 0.0;
    for rule in &model.rules {
        let (phi, gamma) = tsfc::synth::objectives::discrete::zoh(&rule.a, &rule.b, h);
        for f in gains {
            worst = worst.max(spectral_radius(&(&phi + &gamma * f)));
        }
    }
    worst
}

#[test]
fn a_period_outside_the_certificate_is_refused_with_a_period_that_certifies() {
    let model = common::model_of("msd.tsf", &msd("trigger periodic { every = 1.5; }"));
    let err = synth::synthesize(&model, &Settings::default()).expect_err("1.5 s is refused");
    let SynthError::Infeasible {
        message,
        achievable,
    } = &err
    else {
        panic!("{err}");
    };
    assert!(message.contains("every 1.5 s"), "{message}");
    // The advice is a value, and that value certifies when written.
    let advice = &achievable[0];
    let at = advice.find("every = ").expect("advised period") + "every = ".len();
    let h: f64 = advice[at..]
        .split(';')
        .next()
        .and_then(|s| s.trim().parse().ok())
        .expect("a number");
    assert!(h > 0.01 && h < 1.5, "{advice}");
    let text = msd(&format!("trigger periodic {{ every = {h}; }}"));
    let model = common::model_of("msd.tsf", &text);
    let d = synth::synthesize(&model, &Settings::default()).expect("the advised period certifies");
    let sampled = d
        .loop_design
        .every_sample()
        .expect("a sampled-loop certificate");
    assert_eq!(sampled.plan.sampling, (h, h));
    let cert = tsfc::certify::certify(&model, &d).expect("certify");
    assert!(cert.ok, "{}", cert.worst);
    assert!(
        cert.lmis
            .iter()
            .any(|l| l.name.starts_with("trigger r=2 h=")),
        "the certificate re-checks the sampled-loop LMIs"
    );
    // Independent: every frozen pair sampled at the certified period is stable.
    let rho = worst_frozen_radius(&model, &d.gains, h);
    assert!(rho < 1.0, "spectral radius {rho} at h = {h}");
}

#[test]
fn the_certified_period_ships_in_the_generated_code_and_the_loop_converges() {
    let (dir, path) = spec_file("every-0.25", &msd("trigger periodic { every = 0.25; }"));
    let run = tsfc::pipeline::read(&path)
        .expect("read")
        .compile(&Settings::default())
        .expect("compile");
    assert_eq!(run.exit_code(), 0);
    let files = run.generate(&[Emit::Rust, Emit::C]).expect("generate");
    let text = |suffix: &str| {
        files
            .iter()
            .find(|f| f.name.ends_with(suffix))
            .map(|f| f.text.clone())
            .unwrap_or_else(|| panic!("no {suffix}"))
    };
    assert!(
        text(".rs").contains("pub const SAMPLE_PERIOD: f64 = 0.25;"),
        "Rust constant"
    );
    assert!(
        text("msd.h").contains("#define MSD_SAMPLE_PERIOD 0.25 "),
        "C constant"
    );
    let (design, _) = run.certified().expect("certified");
    let rho = worst_frozen_radius(&run.model, &design.gains, 0.25);
    assert!(rho < 1.0, "{rho}");
    // The simulated loop holds the command for the same 0.25 s and converges.
    let prepared = tsfc::driver::prepare(&path).expect("prepare");
    let out = tsfc::sim::simulate(&prepared, &tsfc::sim::Options::default()).expect("simulate");
    assert!(out.metrics.converged && !out.metrics.failed);
    assert_eq!(
        out.metrics.transmissions, 81,
        "20 s / 0.25 s + the first sample"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_period_that_is_not_a_whole_number_of_steps_is_not_simulated() {
    let (dir, path) = spec_file("every-0.0125", &msd("trigger periodic { every = 0.0125; }"));
    let prepared = tsfc::driver::prepare(&path).expect("prepare");
    let err = tsfc::sim::simulate(&prepared, &tsfc::sim::Options::default())
        .expect_err("0.0125 s is 12.5 steps of 1 ms");
    assert!(
        err.to_string().contains("not a whole number of time steps"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn triggers_outside_every_certificate_are_refused() {
    // A spec error at check time (exit 1, at the `sampling` setting).
    let e = common::errors_of(
        "msd.tsf",
        &msd("trigger mixed { sampling = 0.01 .. 0.1; beta = 0.5; rho = 1e-4; }"),
    );
    assert!(
        e.iter()
            .any(|d| d.message.contains("not covered by a certificate")),
        "{e:?}"
    );
}

/// (Phi, Gamma) over `h` by RK4 integration of Phi' = A Phi, Gamma' = A Gamma + B
/// (a second method, independent of the matrix exponential the compiler uses).
fn zoh_by_integration(a: &DMatrix<f64>, b: &DMatrix<f64>, h: f64) -> (DMatrix<f64>, DMatrix<f64>) {
    let (n, m) = (a.nrows(), b.ncols());
    let mut s = DMatrix::zeros(n, n + m);
    s.view_mut((0, 0), (n, n)).fill_with_identity();
    let mut forcing = DMatrix::zeros(n, n + m);
    forcing.view_mut((0, n), (n, m)).copy_from(b);
    let f = |s: &DMatrix<f64>| a * s + &forcing;
    let steps = 2000;
    let dt = h / steps as f64;
    for _ in 0..steps {
        let k1 = f(&s);
        let k2 = f(&(&s + &k1 * (dt / 2.0)));
        let k3 = f(&(&s + &k2 * (dt / 2.0)));
        let k4 = f(&(&s + &k3 * dt));
        s += (k1 + k2 * 2.0 + k3 * 2.0 + k4) * (dt / 6.0);
    }
    (s.columns(0, n).into_owned(), s.columns(n, m).into_owned())
}

#[test]
fn a_discrete_time_design_certifies_a_period_the_emulated_design_does_not() {
    let (h, alpha) = (0.55, 0.5);
    let emulated = common::model_of(
        "msd.tsf",
        &msd_unlimited(&format!("trigger periodic {{ every = {h}; }}")),
    );
    let err = synth::synthesize(&emulated, &Settings::default())
        .expect_err("the continuous design is not certified sampled every 0.55 s");
    assert!(err.to_string().contains("every 0.55 s"), "{err}");

    let text = msd_unlimited(&format!(
        "trigger periodic {{ every = {h}; design = discrete; }}"
    ));
    let model = common::model_of("msd.tsf", &text);
    let d = synth::synthesize(&model, &Settings::default()).expect("the discrete design certifies");
    let cert = tsfc::certify::certify(&model, &d).expect("certify");
    assert!(cert.ok, "{}", cert.worst);
    assert!(
        cert.lmis
            .iter()
            .any(|l| l.name.contains("discrete, h = 0.55")),
        "the certificate re-checks the discrete-time conditions"
    );
    assert!(
        d.loop_design.every_sample().is_some(),
        "the shipped loop (continuous plant, held command) is certified too"
    );
    // Independent: with the ZOH model integrated numerically, every blend of
    // the rules (memberships frozen over the period) contracts V = x'Px by
    // e^{-2 alpha h} per period: G'PG - e^{-2 alpha h} P < 0.
    let discrete: Vec<_> = model
        .rules
        .iter()
        .map(|r| zoh_by_integration(&r.a, &r.b, h))
        .collect();
    let rho2 = (-2.0 * alpha * h).exp();
    for k in 0..=20 {
        let w = [k as f64 / 20.0, 1.0 - k as f64 / 20.0];
        let mut g = DMatrix::zeros(2, 2);
        for (i, (phi, gamma)) in discrete.iter().enumerate() {
            for (j, f) in d.gains.iter().enumerate() {
                g += (phi + gamma * f) * (w[i] * w[j]);
            }
        }
        let m = g.transpose() * &d.p * &g - &d.p * rho2;
        let worst = m.symmetric_eigen().eigenvalues.max();
        assert!(worst < 0.0, "memberships {w:?}: lambda_max {worst}");
    }
    // The generated code holds the command for h and the nonlinear loop converges.
    let (dir, path) = spec_file("discrete", &text);
    let run = tsfc::pipeline::read(&path)
        .expect("read")
        .compile(&Settings::default())
        .expect("compile");
    assert_eq!(run.exit_code(), 0);
    let files = run.generate(&[Emit::Rust]).expect("generate");
    assert!(files
        .iter()
        .any(|f| f.text.contains("pub const SAMPLE_PERIOD: f64 = 0.55;")));
    let prepared = tsfc::driver::prepare(&path).expect("prepare");
    let out = tsfc::sim::simulate(&prepared, &tsfc::sim::Options::default()).expect("simulate");
    assert!(out.metrics.converged && !out.metrics.failed);
    assert_eq!(out.metrics.transmissions, 37, "t = 0, 0.55, .., 19.8 s");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_discrete_time_design_refused_at_its_period_is_advised_a_period_that_certifies() {
    let text = |h: &str| {
        msd_unlimited(&format!(
            "trigger periodic {{ every = {h}; design = discrete; }}"
        ))
    };
    let model = common::model_of("msd.tsf", &text("0.7"));
    let err = synth::synthesize(&model, &Settings::default()).expect_err("0.7 s is refused");
    let SynthError::Infeasible { achievable, .. } = &err else {
        panic!("{err}");
    };
    let advice = &achievable[0];
    let at = advice.find("every = ").expect("advised period") + "every = ".len();
    let h = advice[at..].split(';').next().expect("a number").trim();
    assert!(advice.contains("design = discrete"), "{advice}");
    let model = common::model_of("msd.tsf", &text(h));
    synth::synthesize(&model, &Settings::default())
        .expect("the advised period certifies when written");
}
