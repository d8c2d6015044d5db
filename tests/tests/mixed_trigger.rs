//! The mixed trigger on a named signal (`signal s = ..; trigger mixed { on = s; .. }`):
//! its certificate against closed forms of a scalar loop, the refusals, the
//! sensor's decisions in the runtime, the generated Rust and C, and the
//! simulator's transmission count replayed from its CSV trace.

use crate::common;

use common::model_of;
use std::cmp::Ordering;
use std::path::{Path, PathBuf};
use std::process::Command;
use tsf_runtime::SignalTrigger;
use tsfc::codegen::c::{c_sensor_file_names, emit_c_signal_sensor, runtime};
use tsfc::codegen::rust::emit_rust_signal_sensor;
use tsfc::driver::compile::{compile, Compiled};
use tsfc::report::SpecInfo;
use tsfc::synth::signal_trigger::SignalTrigger as Cert;
use tsfc::synth::Settings;
use tsfc::tables::sym::Sym;
use tsfc::tables::Tables;

/// A two-rule loop whose command is u = -2 s with s = w + 0.2 p + 0.2 p^3
/// (rule weights 1 - p^2 and p^2 on the premise region |p| <= 1).
const TWO_RULES: &str = "tsf 1; controller am;\nstate p, w; input u;\n\
    A = [0, 0.5; 0, 0]; B = [0; 1];\n\
    premise q = p * p range 0 .. 1 { lo = trap(-1, -1, 0, 1); hi = trap(0, 1, 2, 2); }\n\
    rule R1: q is lo => at(p = 0), F = [-0.4, -2];\n\
    rule R2: q is hi => at(p = 1), F = [-0.8, -2];\n\
    signal s = w + 0.2 * p + 0.2 * (p * p) * p;\n";

/// x' = a x + b u, u = f x, monitored signal s = x (so G = 1/f).
fn scalar(a: f64, b: f64, f: f64, beta: f64, rho: f64) -> String {
    format!(
        "tsf 1; controller sc;\nstate y; input u;\nA = {a:?}; B = {b:?};\n\
         premise y range -1 .. 1 {{ all = trap(-2, -1, 1, 2); }}\n\
         rule R: y is all => at(y = 0), F = {f:?};\n\
         signal s = y;\n\
         trigger mixed {{ on = s; beta = {beta:?}; rho = {rho:?}; monitor = continuous; }}\n"
    )
}

fn compiled(name: &str, text: &str) -> Compiled {
    let model = model_of(name, text);
    compile(
        &model,
        SpecInfo {
            path: name.into(),
            sha256: "0".repeat(64),
        },
        &Settings::default(),
        Default::default(),
    )
}

fn certificate(c: &Compiled) -> Cert {
    let (design, cert) = c.outcome.as_ref().expect("certified");
    assert!(cert.ok, "{}", cert.worst);
    design
        .loop_design
        .mixed()
        .cloned()
        .expect("a mixed-trigger certificate")
}

#[test]
fn scalar_decay_rate_meets_the_worst_case_error() {
    // x' = (a + b f) x + b e, |e| <= b1 |f x|: the worst admissible e gives
    // V = p x^2 the rate 2 (-(a + b f) - |b| b1 |f|), which no certificate can beat,
    // and for one constraint the S-procedure is lossless: the bisection gets close.
    let (a, b, f, beta) = (0.5, 2.0, -1.5, 0.3);
    let c = compiled("sc.tsf", &scalar(a, b, f, beta, 0.0));
    let cert = certificate(&c);
    let sup = 2.0 * (-(a + b * f) - b.abs() * beta * f.abs());
    assert!((cert.b1 - beta).abs() < 1e-12, "b1 = {}", cert.b1);
    assert!(cert.lambda <= sup * (1.0 + 1e-9), "{} > {sup}", cert.lambda);
    assert!(cert.lambda >= 0.97 * sup, "{} << {sup}", cert.lambda);
    assert_eq!((cert.v_inf, cert.x_bound), (0.0, 0.0));
    // The scalar LMI by its minors: M11 <= 0, M22 < 0, det >= 0.
    let p = cert.p[0][0];
    let m11 = 2.0 * p * (a + b * f)
        + cert.lambda * p
        + cert.tau * (1.0 + cert.eps) * cert.b1.powi(2) * f * f;
    let (m12, m22) = (p * b, -cert.tau);
    assert!(m11 < 0.0 && m22 < 0.0 && m11 * m22 - m12 * m12 >= 0.0);
}

#[test]
fn scalar_ultimate_bound_covers_the_worst_case_equilibrium() {
    // With rho > 0 the worst admissible error e = sign(b x) (b1 |f x| + b0) drives x to
    // |x*| = |b| b0 / (-(a + b f) - |b| b1 |f|); the certified bound must contain it.
    let (a, b, f, beta, rho) = (0.0, 1.0, -2.0, 0.2, 1e-2);
    let c = compiled("sc.tsf", &scalar(a, b, f, beta, rho));
    let cert = certificate(&c);
    let b0 = rho * (1.0 / f).abs().recip();
    assert!(
        (cert.b0 - b0).abs() < 1e-12 * b0,
        "b0 = {} vs {b0}",
        cert.b0
    );
    let x_star = b.abs() * b0 / (-(a + b * f) - b.abs() * beta * f.abs());
    // Integrate the worst case from far away: it settles at x*.
    let mut x = 1.0f64;
    for _ in 0..200_000 {
        let e = (b * x).signum() * (beta * (f * x).abs() + b0);
        x += 1e-4 * ((a + b * f) * x + b * e);
    }
    assert!((x - x_star).abs() < 1e-6, "{x} vs {x_star}");
    assert!(cert.x_bound >= x_star, "{} < {x_star}", cert.x_bound);
    assert!(
        cert.x_bound < 20.0 * x_star,
        "{} far above {x_star}",
        cert.x_bound
    );
    let v = cert.tau * (1.0 + 1.0 / cert.eps) * cert.b0.powi(2) / cert.lambda;
    assert!((cert.v_inf - v).abs() <= 1e-12 * v);
}

#[test]
fn two_rule_signal_is_the_image_of_the_pdc_command() {
    let c = compiled(
        "am.tsf",
        &format!(
            "{TWO_RULES}trigger mixed {{ on = s; beta = 0.3; rho = 1e-4; monitor = step; }}\n"
        ),
    );
    let cert = certificate(&c);
    assert!((cert.g[0][0] + 0.5).abs() < 1e-9, "G = {:?}", cert.g);
    assert!(cert.image_residual <= 1e-9);
    assert!(cert.lambda > 0.0 && cert.x_bound > 0.0);
    assert!(cert.claim.contains("continuous monitoring"));
    let report = crate::common::schema::report_json(&c.report);
    assert_eq!(report["signal_trigger"]["monitor"], "step");
}

#[test]
fn the_image_is_checked_on_the_premise_region_only() {
    // The states are sampled in [-1.5, 1.5]^2 (the operating point p = 1.5): where
    // q = p^2 > 1 rule R2 alone fires and u != -2 s, but that is outside `range 0 .. 1`.
    let text = TWO_RULES.replace("at(p = 1)", "at(p = 1.5)")
        + "trigger mixed { on = s; beta = 0.3; rho = 1e-4; monitor = step; }\n";
    let cert = certificate(&compiled("am.tsf", &text));
    assert!(cert.image_residual <= 1e-9 && cert.image_points > 100);
    // Widening the declared range brings those states in: refused.
    let wide = text.replace("range 0 .. 1", "range 0 .. 2");
    let e = compiled("am.tsf", &wide)
        .outcome
        .expect_err("refused")
        .to_string();
    assert!(e.contains("constant linear image"), "{e}");
}

#[test]
fn refusals_name_the_cause() {
    // A signal that is not a linear image of the command.
    let c = compiled(
        "am.tsf",
        &format!(
            "{}trigger mixed {{ on = s; beta = 0.3; rho = 1e-4; monitor = continuous; }}\n",
            TWO_RULES.replace("signal s = w + 0.2 * p", "signal s = w + 0.3 * p")
        ),
    );
    let e = c.outcome.expect_err("refused").to_string();
    assert!(e.contains("constant linear image"), "{e}");
    // The state (the default) is not an image of a scalar command either.
    let c = compiled(
        "am.tsf",
        &format!("{TWO_RULES}trigger mixed {{ beta = 0.3; rho = 1e-4; monitor = continuous; }}\n"),
    );
    let e = c.outcome.expect_err("refused").to_string();
    assert!(
        e.contains("full column rank") || e.contains("constant linear image"),
        "{e}"
    );
    // Saturation is not covered: a spec error at check time.
    let e = common::errors_of(
        "am.tsf",
        &format!(
            "{}trigger mixed {{ on = s; beta = 0.3; rho = 1e-4; monitor = continuous; }}\n",
            TWO_RULES.replace("input u;", "input u saturate 5;")
        ),
    );
    assert_eq!(
        e[0].message,
        "the mixed-trigger certificate does not cover input saturation"
    );
    // Negative beta is a check error.
    let source = tsfc::driver::frontend::Source {
        name: "am.tsf".into(),
        text: format!(
            "{TWO_RULES}trigger mixed {{ on = s; beta = -0.3; rho = 1e-4; monitor = step; }}\n"
        ),
        bytes: Vec::new(),
    };
    let checked = tsfc::driver::frontend::check(&source);
    assert!(checked
        .diagnostics
        .iter()
        .any(|d| d.is_error() && d.message == "`beta` must not be negative"));
}

fn tables(c: &Compiled, name: &str, text: &str) -> Tables {
    let (design, cert) = c.outcome.as_ref().expect("certified");
    let model = model_of(name, text);
    tsfc::tables::tables(&model, design, cert, name, &"0".repeat(64)).expect("tables")
}

/// The runtime's evaluation of a generated scalar expression.
fn eval(s: &Sym, x: &[f64]) -> f64 {
    s.eval(x)
}

/// Random trajectories: a slow walk, with a NaN and a jump now and then.
fn trajectory(seed: u64, len: usize) -> Vec<[f64; 2]> {
    let mut rng = tsfc::sim::trigger::SplitMix64::new(seed);
    let mut x = [0.5, -0.2];
    (0..len)
        .map(|k| {
            for v in &mut x {
                *v += 0.02 * (rng.next_f64() - 0.5);
            }
            if k % 97 == 50 {
                [f64::NAN, x[1]]
            } else if k % 131 == 7 {
                [x[0] + 0.5, x[1]]
            } else {
                x
            }
        })
        .collect()
}

#[test]
fn runtime_rust_and_c_sensors_decide_alike() {
    let text =
        format!("{TWO_RULES}trigger mixed {{ on = s; beta = 0.3; rho = 1e-4; monitor = step; }}\n");
    let c = compiled("am.tsf", &text);
    let t = tables(&c, "am.tsf", &text);
    let s = t.sensor.mixed().expect("signal sensor tables");
    // The generated Rust evaluates exactly these expressions with the runtime's trigger.
    let rust = emit_rust_signal_sensor(&t).expect("rust");
    assert!(rust.contains("SignalTrigger::new(BETA, RHO)"));
    assert!(rust.contains("[x[1] + 0.2 * x[0] + 0.2 * (x[0] * x[0]) * x[0]]"));
    // Independent reference: the law written out here.
    let law = |last: &Option<f64>, v: f64| match last {
        None => true,
        Some(l) => (l - v).abs().partial_cmp(&(0.3 * v.abs() + 1e-4)) != Some(Ordering::Less),
    };
    // C: the sensor module and the runtime, driven over the same trajectories.
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("mixed_trigger_c");
    std::fs::create_dir_all(&dir).expect("dir");
    let files = emit_c_signal_sensor(&t).expect("c");
    let (h, src) = c_sensor_file_names(&t);
    std::fs::write(dir.join(&h), &files.header).expect("write");
    std::fs::write(dir.join(&src), &files.source).expect("write");
    for f in runtime::files() {
        std::fs::write(dir.join(&f.name), &f.text).expect("write runtime");
    }
    let driver = format!(
        "#include <stdio.h>\n#include \"{h}\"\nint main(void) {{\n    am_sensor_t t;\n    double x[2], tx[2];\n    am_sensor_init(&t);\n    while (scanf(\"%lf %lf\", &x[0], &x[1]) == 2) {{\n        printf(\"%d\\n\", am_sensor_sample(&t, x, tx));\n    }}\n    return 0;\n}}\n"
    );
    std::fs::write(dir.join("driver.c"), driver).expect("write driver");
    let cc = std::env::var("CC").unwrap_or_else(|_| "cc".into());
    let exe = dir.join("driver");
    let o = Command::new(&cc)
        .args(["-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic"])
        .arg(dir.join("driver.c"))
        .arg(dir.join(&src))
        .arg(dir.join(runtime::SOURCE_NAME))
        .arg("-o")
        .arg(&exe)
        .arg("-lm")
        .output()
        .expect("run the C compiler");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for seed in 1..=5u64 {
        let xs = trajectory(seed, 2000);
        let input: String = xs
            .iter()
            .map(|x| format!("{:e} {:e}\n", x[0], x[1]))
            .collect();
        let inp = dir.join("input.txt");
        std::fs::write(&inp, input).expect("write input");
        let out = Command::new(&exe)
            .stdin(std::fs::File::open(&inp).expect("open"))
            .output()
            .expect("run driver");
        let c_dec: Vec<bool> = String::from_utf8_lossy(&out.stdout)
            .lines()
            .map(|l| l == "1")
            .collect();
        let mut rt = SignalTrigger::<f64, 2, 1>::new(0.3, 1e-4);
        let mut last = None;
        let mut sent = 0;
        for (k, x) in xs.iter().enumerate() {
            let sig = [eval(&s.exprs[0], x)];
            let r = rt.decide(x, &sig).is_some();
            let mine = law(&last, sig[0]);
            if mine {
                last = Some(sig[0]);
            }
            assert_eq!(r, mine, "runtime vs law at {k} (seed {seed})");
            assert_eq!(c_dec[k], r, "C vs runtime at {k} (seed {seed})");
            if r {
                let held = rt.last().map(|h| h.map(f64::to_bits));
                assert_eq!(
                    held,
                    Some(x.map(f64::to_bits)),
                    "the held value is the state"
                );
            }
            sent += usize::from(r);
        }
        assert!(sent > 20 && sent < xs.len() / 2, "{sent} transmissions");
    }
}

fn spec_file(tag: &str, text: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("mixed_trigger_sim");
    std::fs::create_dir_all(&dir).expect("dir");
    let p = dir.join(format!("{tag}.tsf"));
    std::fs::write(&p, text).expect("write spec");
    p
}

#[test]
fn per_step_monitoring_counts_replay_from_the_trace() {
    let text = format!(
        "{TWO_RULES}trigger mixed {{ on = s; beta = 0.3; rho = 1e-4; monitor = step; }}\n\
         simulate {{ time = 0 .. 20 step 0.01; x0 = [0.5, 0]; }}\n"
    );
    let prepared = tsfc::driver::prepare(&spec_file("step", &text)).expect("prepared");
    let mut csv = Vec::new();
    let o = tsfc::sim::simulate_csv(&prepared, &tsfc::sim::Options::default(), &mut csv)
        .expect("simulated");
    assert_eq!(o.metrics.monitor.as_deref(), Some("step"));
    assert_eq!(o.metrics.monitor_step, Some(0.01));
    let csv = String::from_utf8(csv).expect("utf8");
    let mut last: Option<f64> = None;
    let (mut replayed, mut rows) = (0u64, 0u64);
    for line in csv.lines().skip(1) {
        let cols: Vec<&str> = line.split(',').collect();
        let v = |i: usize| cols[i].parse::<f64>().expect("number");
        let (p, w) = (v(1), v(2));
        let sent = cols[cols.len() - 1].trim() == "1";
        let s = w + 0.2 * p + 0.2 * (p * p) * p;
        let fire = last.is_none_or(|l| {
            (l - s).abs().partial_cmp(&(0.3 * s.abs() + 1e-4)) != Some(Ordering::Less)
        });
        assert_eq!(sent, fire, "row {rows}: {line}");
        if fire {
            last = Some(s);
            replayed += 1;
        }
        rows += 1;
    }
    assert_eq!(rows, 2001);
    assert_eq!(o.metrics.transmissions, replayed);
    assert!(replayed > 5 && replayed < 500, "{replayed}");
    assert!(o.metrics.energy > 0.0 && o.metrics.mean_inter_event_s.is_some());
    // Continuous monitoring locates crossings inside the steps: at least as many events.
    let cont = tsfc::driver::prepare(&spec_file(
        "cont",
        &text.replace("monitor = step", "monitor = continuous"),
    ))
    .expect("prepared");
    let oc = tsfc::sim::simulate(&cont, &tsfc::sim::Options::default()).expect("simulated");
    assert_eq!(oc.metrics.monitor.as_deref(), Some("continuous"));
    assert!(
        oc.metrics.transmissions >= replayed * 9 / 10,
        "{} vs {replayed}",
        oc.metrics.transmissions
    );
    assert!(
        oc.metrics.final_state_norm < 0.25 * oc.metrics.initial_state_norm,
        "{} {:?}",
        oc.metrics.final_state_norm,
        oc.metrics.failures()
    );
}

#[test]
fn generated_sensor_modules_are_snapshotted() {
    let text = format!(
        "{TWO_RULES}trigger mixed {{ on = s; beta = 0.3; rho = 1e-4; monitor = continuous; }}\n"
    );
    let c = compiled("am.tsf", &text);
    let t = tables(&c, "am.tsf", &text);
    let rust = emit_rust_signal_sensor(&t).expect("rust");
    syn::parse_file(&rust).expect("the Rust sensor module parses");
    insta::assert_snapshot!("am_sensor.rs", rust);
    let files = emit_c_signal_sensor(&t).expect("c");
    insta::assert_snapshot!("am_sensor.h", files.header);
    insta::assert_snapshot!("am_sensor.c", files.source);
}
