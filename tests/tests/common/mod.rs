//! Helpers shared by the end-to-end tests.
#![allow(dead_code)] // each test crate uses a subset

pub mod looped;
pub mod observer;
pub mod plant;
pub mod schema;

use std::path::{Path, PathBuf};
use tsf_runtime::math;
use tsfc::driver::frontend::{self, Source};
use tsfc::model::TsModel;
use tsfc::tables::sym::{Func, Sym};

/// Path of a shipped spec.
pub fn spec_path(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../specs")
        .join(name)
}

/// The model of a source text; panics with the errors if it does not check clean.
pub fn model_of(name: &str, text: &str) -> TsModel {
    let source = Source {
        name: name.into(),
        text: text.into(),
        bytes: text.as_bytes().to_vec(),
    };
    let checked = frontend::check(&source);
    let errors: Vec<_> = checked
        .diagnostics
        .iter()
        .filter(|d| d.is_error())
        .map(|d| d.message.clone())
        .collect();
    assert!(errors.is_empty(), "{name}: {errors:?}");
    checked.model.expect("a model for a clean spec")
}

/// The errors of a source text that does not check clean (check and model stage).
pub fn errors_of(name: &str, text: &str) -> Vec<tsf_lang::Diagnostic> {
    let source = Source {
        name: name.into(),
        text: text.into(),
        bytes: text.as_bytes().to_vec(),
    };
    let errors: Vec<_> = frontend::check(&source)
        .diagnostics
        .into_iter()
        .filter(|d| d.is_error())
        .collect();
    assert!(!errors.is_empty(), "{name} checks clean");
    errors
}

/// The model of a shipped spec.
pub fn shipped(name: &str) -> TsModel {
    let text = std::fs::read_to_string(spec_path(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
    model_of(name, &text)
}

/// The event-trigger design of a compile that must be certified.
pub fn event_design(c: &tsfc::driver::compile::Compiled) -> &tsfc::synth::TriggerDesign {
    assert_eq!(
        c.status,
        tsfc::driver::compile::Status::Certified,
        "{:?}",
        c.report.diagnosis
    );
    let (design, _) = c.outcome.as_ref().expect("certified");
    design.loop_design.event().expect("an event trigger")
}

/// A shipped spec's model and its compile with the default settings.
pub fn compile_shipped(name: &str) -> (TsModel, tsfc::driver::compile::Compiled) {
    compile_model(name, String::new(), shipped(name))
}

/// A source text's model and its compile with the default settings (the
/// certificate's verdict handed to synthesis, as `tsfc compile` does).
pub fn compile_text(name: &str, text: &str) -> (TsModel, tsfc::driver::compile::Compiled) {
    compile_model(name, String::new(), model_of(name, text))
}

/// The spec file at `path` checked and compiled with the default settings,
/// its report naming it `shown` with its sha256: the model, the compile and
/// the sha256; Err when it cannot be read or does not check.
pub fn compile_path(
    path: &Path,
    shown: &str,
) -> Result<(TsModel, tsfc::driver::compile::Compiled, String), String> {
    let source = frontend::read_source(path).map_err(|e| format!("{e:?}"))?;
    let sha = tsfc::report::sha256_hex(&source.bytes);
    let model = frontend::check(&source)
        .model
        .ok_or("the spec does not check")?;
    let (model, c) = compile_model(shown, sha.clone(), model);
    Ok((model, c, sha))
}

fn compile_model(
    name: &str,
    sha256: String,
    model: TsModel,
) -> (TsModel, tsfc::driver::compile::Compiled) {
    let info = tsfc::report::SpecInfo {
        path: name.into(),
        sha256,
    };
    let c = tsfc::driver::compile::compile(
        &model,
        info,
        &tsfc::synth::Settings::default(),
        Default::default(),
    );
    // Every report the suite compiles validates against its schema.
    schema::report_json(&c.report);
    (model, c)
}

/// The seeded generator of the simulator (SplitMix64), for random test points.
pub use tsfc::sim::trigger::SplitMix64 as Rng;

/// The local models (A_i, B_i) of the three-rule Kim & Lee-type benchmark
/// (Kim and Lee, "New approaches to relaxed quadratic stability condition of
/// fuzzy control systems", 2000), with the parameters a and b.
pub fn kim_lee_rules(a: f64, b: f64) -> [(nalgebra::DMatrix<f64>, nalgebra::DMatrix<f64>); 3] {
    let m = |r: &[f64]| nalgebra::DMatrix::from_row_slice(2, 2, r);
    let v = |r: &[f64]| nalgebra::DMatrix::from_row_slice(2, 1, r);
    [
        (m(&[1.59, -7.29, 0.01, 0.0]), v(&[1.0, 0.0])),
        (m(&[0.02, -4.64, 0.35, 0.21]), v(&[8.0, 0.0])),
        (m(&[-a, -4.33, 0.0, 0.05]), v(&[-b + 6.0, -1.0])),
    ]
}

/// Xu & Huang's spacecraft local model (7) at the operating point
/// w = (w, w, w), q = (q, q, q), built from the formula (not from a spec):
/// A = [-J^-1 w^x J, 0; 1/2 sqrt(1 - |q|^2) I, -1/2 w^x], B = [J^-1; 0],
/// J = [350, 3, 4; 3, 270, 10; 4, 10, 190] kg m^2.
pub fn spacecraft_local_model(w: f64, q: f64) -> (nalgebra::DMatrix<f64>, nalgebra::DMatrix<f64>) {
    use nalgebra::{DMatrix, Matrix3, Vector3};
    let jm = Matrix3::new(350.0, 3.0, 4.0, 3.0, 270.0, 10.0, 4.0, 10.0, 190.0);
    let j_inv = jm.try_inverse().expect("J invertible");
    let w = Vector3::new(w, w, w);
    let mut a = DMatrix::zeros(6, 6);
    a.view_mut((0, 0), (3, 3))
        .copy_from(&(-j_inv * w.cross_matrix() * jm));
    a.view_mut((3, 0), (3, 3))
        .copy_from(&(0.5 * (1.0 - 3.0 * q * q).sqrt() * Matrix3::identity()));
    a.view_mut((3, 3), (3, 3))
        .copy_from(&(-0.5 * w.cross_matrix()));
    let mut b = DMatrix::zeros(6, 3);
    b.view_mut((0, 0), (3, 3)).copy_from(&j_inv);
    (a, b)
}

/// Spectral abscissa max Re eig(m), by the compiler's capped Schur form
/// (nalgebra's uncapped `complex_eigenvalues` does not return on some
/// matrices with repeated eigenvalues).
pub fn abscissa(m: &nalgebra::DMatrix<f64>) -> f64 {
    tsfc::synth::adaptive::lyapunov::eigenvalue_real_parts(m)
        .and_then(|re| re.last().copied())
        .expect("the Schur form converges")
}

/// The `tsfc` binary of this build profile, built first by cargo (once per
/// test run; a no-op when it is fresh): the test binary is in
/// `<target>/<profile>/deps/`, the `tsfc` binary in `<target>/<profile>/`.
pub fn tsfc_binary() -> PathBuf {
    static BIN: std::sync::OnceLock<PathBuf> = std::sync::OnceLock::new();
    BIN.get_or_init(|| {
        let exe = std::env::current_exe().expect("the test binary's path");
        let dir = exe
            .parent()
            .and_then(Path::parent)
            .expect("the test binary is in <target>/<profile>/deps");
        let profile = dir
            .file_name()
            .and_then(|n| n.to_str())
            .unwrap_or("release");
        let profile = if profile == "debug" { "dev" } else { profile };
        let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
        let status = std::process::Command::new(cargo)
            .args([
                "build",
                "--quiet",
                "-p",
                "tsfc",
                "--bin",
                "tsfc",
                "--profile",
                profile,
            ])
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .status()
            .expect("run cargo build for the tsfc binary");
        assert!(status.success(), "cargo build -p tsfc --bin tsfc failed");
        let bin = dir.join(format!("tsfc{}", std::env::consts::EXE_SUFFIX));
        assert!(bin.is_file(), "no tsfc binary at {}", bin.display());
        bin
    })
    .clone()
}

/// The Monte Carlo demo spec: an unstable scalar plant x1' = k x1 + u + d with
/// a certified gain, a `monte_carlo` block of `runs` draws (k scaled in
/// [0.5, k_hi], x0 and d varied) and `extra` appended inside `simulate { }`
/// (e.g. a sweep).
pub fn scalar_campaign_spec(controller: &str, runs: usize, k_hi: f64, extra: &str) -> String {
    format!(
        "tsf 1;\ncontroller {controller};\nconst k = 1;\nstate x1;\ninput u;\ndisturbance d;\n\
         A = k; B = 1; D = 1;\n\
         premise x1 range -2 .. 2 {{ all = trap(-2, -2, 2, 2); }}\n\
         rule R: x1 is all => A = k;\n\
         objective decay_rate >= 1;\n\
         simulate {{\n  x0 = 0.5;\n  time = 0 .. 4 step 0.01;\n  d(t) = 0.01 * sin(t);\n\
           dynamics {{ x1' = k * x1 + u + d; }}\n\
           monte_carlo {{ runs = {runs}; k scale uniform(0.5, {k_hi}); x0 offset uniform(-0.2, 0.2);\n\
             d scale uniform(0.5, 1.5); converged |x1| <= 0.05 by 3.5; }}\n{extra}}}\n"
    )
}

/// A fresh, empty folder `tsfc-<prefix>-<tag>-<pid>` under the system's
/// temporary folder (removed first if an earlier run left it).
pub fn fresh_dir(prefix: &str, tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("tsfc-{prefix}-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("a fresh temporary folder");
    dir
}

/// The Chromium binary on PATH (`chromium`, the Debian package), if any (the review and
/// playground tests drive it; they skip without it).
pub fn chromium() -> Option<PathBuf> {
    std::env::var_os("PATH")?
        .to_str()?
        .split(':')
        .map(|d| Path::new(d).join("chromium"))
        .find(|p| p.is_file())
}

/// `e` at `v` with the Rust runtime's elementary functions (`math::sin`
/// etc.): what the generated Rust's `Real::sin` and the generated C's
/// `tsf_sin` compute, operand by operand in the generators' order.
pub fn runtime_eval(e: &Sym, v: &[f64]) -> f64 {
    match e {
        Sym::Const(c) => *c,
        Sym::X(k) => v.get(*k).copied().unwrap_or(f64::NAN),
        Sym::Add(a, b) => runtime_eval(a, v) + runtime_eval(b, v),
        Sym::Mul(a, b) => runtime_eval(a, v) * runtime_eval(b, v),
        Sym::Div(a, b) => runtime_eval(a, v) / runtime_eval(b, v),
        Sym::Neg(a) => -runtime_eval(a, v),
        Sym::Call(f, a) => {
            let a = runtime_eval(a, v);
            match f {
                Func::Sin => math::sin(a),
                Func::Cos => math::cos(a),
                Func::Exp => math::exp(a),
                Func::Sqrt => math::sqrt(a),
                Func::Atan => math::atan(a),
                Func::Abs => a.abs(),
                Func::Sinc => math::sinc(a),
                Func::Exprel => math::exprel(a),
            }
        }
    }
}
