//! The output-feedback test seam shared by `observer_code`,
//! `observer_sampled`, `observer_drift` and `output_feedback_c`: the
//! runtime's observer built from a design's tables at its exact sizes, the
//! `tsfc` command on a spec, a spec compiled in process (the gyro-less
//! spacecraft once per process), the test oscillator spec that certifies its
//! sampled loop, seeded outputs with fault values, and RK4 of a 2-state plant
//! with the command held.

use super::runtime_eval;
use super::Rng;
use std::path::{Path, PathBuf};
use std::process::Output;
use std::sync::OnceLock;
use tsf_runtime::{FactoredController, Observer, Term};
use tsfc::tables::sym::Sym;
use tsfc::tables::{PremiseCode, Tables};

/// A two-rule unstable oscillator x1'' = x1 + 0.1 sin(x1) + u with only x1
/// measured (B the same in both rules); `PERIOD` is replaced by the
/// controller's period (0.01 s certifies).
pub const OSC_SPEC: &str = "tsf 1;
controller osc_observer;
state x1, x2;
input u;
A(x) = [0, 1; 1 + 0.1 * sinc(x1), 0];
B = [0; 1];
premise s = sinc(x1) range 0.6 .. 1 { near = tri(0.6, 1, 1); far = tri(0.6, 0.6, 1); }
rule R1: s is near => at(x1 = 0, x2 = 0);
rule R2: s is far => at(x1 = 1.4, x2 = 0);
objective decay_rate >= 0.5;
relaxation basic;
measure y = x1 noise <= 0.001;
control observer_based(decay = 2);
trigger periodic { every = PERIOD; }
emit rust, c;
simulate { x0 = [0.5, 0]; xhat0 = [0, 0.8]; time = 0 .. 8 step 0.001; integrator = rk4; }
";

/// [`OSC_SPEC`] at `period`, written to `dir/osc_observer.tsf`.
pub fn osc_spec_at(period: f64, dir: &Path) -> PathBuf {
    let path = dir.join("osc_observer.tsf");
    std::fs::write(&path, OSC_SPEC.replace("PERIOD", &period.to_string())).expect("write spec");
    path
}

/// `tsfc <args> SPEC --out OUT`.
pub fn tsfc(args: &[&str], spec: &Path, out: &Path) -> Output {
    std::process::Command::new(super::tsfc_binary())
        .args(args)
        .arg(spec)
        .arg("--out")
        .arg(out)
        .output()
        .expect("run tsfc")
}

/// `tsfc compile` of the shipped spec `name` (`<stem>.tsf`) into `dir`: exit
/// 0, the Rust and C code written, the report.
pub fn compile_code(name: &str, dir: &Path) -> serde_json::Value {
    let out = tsfc(&["compile"], &super::spec_path(name), dir);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    let stem = name.trim_end_matches(".tsf");
    for ext in ["rs", "c", "h"] {
        let f = dir.join(format!("{stem}.{ext}"));
        assert!(f.exists(), "{}: {stderr}", f.display());
    }
    let report = std::fs::read(dir.join(format!("{stem}.report.json"))).expect("report");
    serde_json::from_slice(&report).expect("JSON")
}

/// A compiled spec: the controller's name, its tables and its report (JSON).
pub struct Compiled {
    /// The controller's name.
    pub name: String,
    /// Its tables.
    pub tables: Tables,
    /// Its report (JSON).
    pub report: serde_json::Value,
}

/// Compiles `spec` as `tsfc compile` does (its `Front::compile`, then
/// `Run::generate` for the spec's `emit` targets, one synthesis) and writes
/// the generated files into `dir`; `Err(why)` when it ships no code.
pub fn compiled(spec: &Path, dir: &Path) -> Result<Compiled, String> {
    let run = tsfc::driver::pipeline::read(spec)
        .and_then(|front| front.compile(&tsfc::synth::Settings::default()))
        .map_err(|e| e.message)?;
    let files = run.generate(&run.model.spec.emit).map_err(|e| e.message)?;
    for f in files {
        std::fs::write(dir.join(&f.name), f.text).expect("write a generated file");
    }
    let tables = run.tables().map_err(|e| e.message)?;
    Ok(Compiled {
        name: run.model.spec.controller.node.clone(),
        tables,
        report: super::schema::report_json(&run.compiled.report),
    })
}

/// The shipped gyro-less spacecraft `amrr2019_gyroless.tsf`, compiled once
/// per test process (its sampled loop is the suite's slowest solve; shared
/// by `output_feedback_c` and `observer_drift`), and the folder holding its
/// generated files.
pub fn gyroless() -> &'static (Compiled, PathBuf) {
    static CELL: OnceLock<(Compiled, PathBuf)> = OnceLock::new();
    CELL.get_or_init(|| {
        let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("gyroless_shared");
        std::fs::create_dir_all(&dir).expect("dir");
        let spec = super::spec_path("amrr2019_gyroless.tsf");
        let c = compiled(&spec, &dir).unwrap_or_else(|why| panic!("gyro-less spec: {why}"));
        (c, dir)
    })
}

/// The nonlinear pendulum on a cart (g = 9.8, m = 2, M = 8, l = 0.5),
/// written out from the textbook's equation (Tanaka & Wang 2001).
pub fn pendulum(x: [f64; 2], u: f64) -> [f64; 2] {
    let (g, m, mc, l) = (9.8, 2.0, 8.0, 0.5);
    let a = 1.0 / (m + mc);
    let (th, om) = (x[0], x[1]);
    let num = g * th.sin() - a * m * l * om * om * (2.0 * th).sin() / 2.0 - a * th.cos() * u;
    [om, num / (4.0 * l / 3.0 - a * m * l * th.cos().powi(2))]
}

/// A matrix of `A` rows and `B` columns from its rows (sizes checked).
pub fn fixed<const A: usize, const B: usize>(rows: &[Vec<f64>]) -> [[f64; B]; A] {
    assert_eq!(rows.len(), A, "rows");
    std::array::from_fn(|i| {
        assert_eq!(rows[i].len(), B, "columns of row {i}");
        std::array::from_fn(|j| rows[i][j])
    })
}

/// The runtime's factored PDC controller on the tables `t` at their exact
/// sizes (`N` the tables' state, y for a static-output design; `M` inputs,
/// `P` premises, `R` rules, `D` distinct terms, all checked).
pub fn factored<
    'a,
    const N: usize,
    const M: usize,
    const P: usize,
    const R: usize,
    const D: usize,
>(
    t: &'a Tables,
    terms: &'a [Term<'a, f64>],
) -> FactoredController<'a, f64, N, M, P, R, D> {
    assert_eq!(
        (t.n, t.m, t.p, t.r, terms.len()),
        (N, M, P, R, D),
        "sizes (n, m, p, r, terms)"
    );
    FactoredController {
        premise_map: match &t.premise {
            PremiseCode::Linear(l) => fixed(l),
            PremiseCode::Exprs(_) => [[0.0; N]; P],
        },
        terms: std::array::from_fn(|k| terms[k]),
        rules: std::array::from_fn(|j| t.factored.rules[j].as_slice()),
        centres: fixed(&t.centres),
        gains: std::array::from_fn(|j| fixed(&t.gains[j])),
        u_max: std::array::from_fn(|k| t.u_max[k]),
    }
}

/// The runtime's observer on the observer tables of `t` at its exact sizes
/// (`N` states, `M` inputs, `Q` outputs, `P` premises, `R` rules, `D`
/// distinct terms, all checked); `terms` are the runtime terms of
/// `t.factored.terms`.
pub fn runtime_observer<
    'a,
    const N: usize,
    const M: usize,
    const Q: usize,
    const P: usize,
    const R: usize,
    const D: usize,
>(
    t: &'a Tables,
    terms: &'a [Term<'a, f64>],
) -> Observer<'a, f64, N, M, Q, P, R, D> {
    let o = t.observer.as_ref().expect("observer tables");
    assert_eq!(o.q, Q, "measured outputs");
    Observer {
        controller: factored(t, terms),
        output_map: o.output_map.as_deref().map(fixed),
        phi: std::array::from_fn(|j| fixed(&o.phi[j])),
        gu: std::array::from_fn(|j| fixed(&o.gu[j])),
        gy: std::array::from_fn(|j| fixed(&o.gy[j])),
    }
}

/// The runtime terms of the tables' distinct premise terms.
pub fn runtime_terms(t: &Tables) -> Vec<Term<'_, f64>> {
    t.factored.terms.iter().map(|s| s.runtime()).collect()
}

/// Seeded outputs from the stream `seed`: mostly inside +-1.5, some far
/// outside, and a few non-finite and extreme values (fault paths, estimate
/// resets).
pub fn outputs(count: usize, seed: u64) -> Vec<f64> {
    let mut rng = Rng::new(seed);
    (0..count)
        .map(|k| match k % 997 {
            13 => f64::NAN,
            101 => f64::INFINITY,
            211 => 1e308,
            // A run of the largest output: the estimate overflows.
            401..=420 => f64::MAX,
            307 => -0.0,
            _ if k % 10 == 0 => rng.uniform(-40.0, 40.0),
            _ => rng.uniform(-1.5, 1.5),
        })
        .collect()
}

/// The premises `exprs` of the runtime's premise state `v`, by [`runtime_eval`].
pub fn runtime_premises<const P: usize>(exprs: &[Sym], v: &[f64]) -> [f64; P] {
    assert_eq!(exprs.len(), P, "premise expressions");
    std::array::from_fn(|p| runtime_eval(&exprs[p], v))
}

/// A 2-state plant held over a sample period: `steps` RK4 steps of `h`.
#[derive(Clone, Copy)]
pub struct HeldPlant {
    /// Its vector field `f(x, u)`.
    pub f: fn([f64; 2], f64) -> [f64; 2],
    /// RK4 step.
    pub h: f64,
    /// RK4 steps per sample.
    pub steps: usize,
}

/// What [`independent_loop`] saw.
pub struct LoopRun {
    /// Largest gap to the simulator's samples: states absolute, the command
    /// relative to `1 + |u|`.
    pub worst: f64,
    /// The plant state after the last sample.
    pub x: [f64; 2],
    /// The estimate after the last sample.
    pub xhat: [f64; 2],
    /// Largest `|x1|` at a sample.
    pub max_abs_x1: f64,
    /// Largest `|u|`.
    pub max_abs_u: f64,
}

/// The loop of a 2-state, single-output observer design rebuilt outside the
/// simulator: per sample (state, command) of the simulator, y = x1, the
/// runtime observer's premise state, its premises by [`runtime_eval`],
/// `step_with_premises`, the gap to the sample, then the plant held over the
/// period. Starts from the plant state `x` and the estimate `xhat`.
pub fn independent_loop<'s, const P: usize, const R: usize, const D: usize>(
    obs: &Observer<'_, f64, 2, 1, 1, P, R, D>,
    exprs: &[Sym],
    samples: impl IntoIterator<Item = (&'s [f64], f64)>,
    plant: HeldPlant,
    (mut x, mut xhat): ([f64; 2], [f64; 2]),
) -> LoopRun {
    let (mut worst, mut max_abs_x1, mut max_abs_u): (f64, f64, f64) = (0.0, 0.0, 0.0);
    for (xs, us) in samples {
        let y = [x[0]];
        let v = obs.premise_state(&xhat, &y);
        let z = runtime_premises::<P>(exprs, &v);
        let u = obs.step_with_premises(&mut xhat, &y, &z).u[0];
        worst = worst
            .max((xs[0] - x[0]).abs())
            .max((xs[1] - x[1]).abs())
            .max((us - u).abs() / (1.0 + u.abs()));
        max_abs_x1 = max_abs_x1.max(x[0].abs());
        max_abs_u = max_abs_u.max(u.abs());
        rk4_held(&mut x, u, plant.h, plant.steps, plant.f);
    }
    LoopRun {
        worst,
        x,
        xhat,
        max_abs_x1,
        max_abs_u,
    }
}

/// `steps` RK4 steps of `h` of the 2-state plant `f(x, u)` with `u` held.
pub fn rk4_held(x: &mut [f64; 2], u: f64, h: f64, steps: usize, f: fn([f64; 2], f64) -> [f64; 2]) {
    for _ in 0..steps {
        let k1 = f(*x, u);
        let k2 = f([x[0] + h / 2.0 * k1[0], x[1] + h / 2.0 * k1[1]], u);
        let k3 = f([x[0] + h / 2.0 * k2[0], x[1] + h / 2.0 * k2[1]], u);
        let k4 = f([x[0] + h * k3[0], x[1] + h * k3[1]], u);
        for i in 0..2 {
            x[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
        }
    }
}

/// The bits of `v` in hex.
pub fn hex(v: f64) -> String {
    format!("{:x}", v.to_bits())
}

/// Compiles `driver.c` in `dir` (which includes the generated C and the
/// runtime header) with the runtime's source by the system C compiler
/// (`$CC`, else `cc`; C99, warnings as errors, no FMA contraction), runs it
/// with `input` on stdin and returns its output lines.
pub fn run_c_driver(dir: &Path, driver: &str, input: &str) -> Vec<String> {
    use tsfc::codegen::c::runtime;
    for f in runtime::files() {
        std::fs::write(dir.join(&f.name), &f.text).expect("write runtime");
    }
    std::fs::write(dir.join("driver.c"), driver).expect("write driver");
    let cc = std::env::var("CC").unwrap_or_else(|_| "cc".into());
    let exe = dir.join("driver");
    let built = std::process::Command::new(&cc)
        .args([
            "-std=c99",
            "-Wall",
            "-Wextra",
            "-Werror",
            "-pedantic",
            "-O2",
        ])
        .arg("-ffp-contract=off")
        .arg(format!("-I{}", dir.display()))
        .arg(dir.join("driver.c"))
        .arg(dir.join(runtime::SOURCE_NAME))
        .arg("-o")
        .arg(&exe)
        .arg("-lm")
        .output()
        .expect("run the C compiler");
    assert!(
        built.status.success(),
        "{}",
        String::from_utf8_lossy(&built.stderr)
    );
    let input_path = dir.join("cases.txt");
    std::fs::write(&input_path, input).expect("write cases");
    let out = std::process::Command::new(&exe)
        .stdin(std::fs::File::open(&input_path).expect("cases"))
        .stdout(std::process::Stdio::piped())
        .output()
        .expect("run the driver");
    assert!(out.status.success(), "the driver failed");
    let text = String::from_utf8(out.stdout).expect("utf-8");
    text.lines().map(str::to_string).collect()
}

/// The C helpers of a test driver: `bits` (a double's bits) and `real`
/// (a double from its bits).
pub const C_BITS: &str = r#"#include <stdio.h>
#include <string.h>

static unsigned long long bits(double v) {
    unsigned long long b;
    memcpy(&b, &v, sizeof b);
    return b;
}

static double real(unsigned long long b) {
    double v;
    memcpy(&v, &b, sizeof v);
    return v;
}
"#;
