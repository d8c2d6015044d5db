//! The controller side of Markov-switching modes: generated Rust and C of a
//! mode-dependent design (snapshots; the C built with the system compiler
//! and driven over random states and modes, out-of-range modes included,
//! against `tsf_runtime::ModalController` bit for bit; the generated Rust's
//! gain literals against the tables bit for bit), the seeded mode process
//! (empirical occupation against the stationary distribution of Pi solved
//! here), closed-loop runs under it, and the shipped Xue et al. (2024) spec.

use crate::common;
use common::Rng;

use nalgebra::DMatrix;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::OnceLock;
use tsf_lang::spec::CStyle;
use tsf_runtime::{Flags, ModalController, Term};
use tsfc::codegen::c::{emit_c, runtime};
use tsfc::codegen::rust::emit_rust;
use tsfc::driver::compile::{compile, Status};
use tsfc::driver::prepare;
use tsfc::report::SpecInfo;
use tsfc::sim::modes::ModeProcess;
use tsfc::sim::{simulate, simulate_csv, Options, Outcome};
use tsfc::synth::Settings;
use tsfc::tables::{PremiseCode, Tables};

/// A two-state, two-rule plant (unstable: a negative spring) with an
/// actuator that loses half its effectiveness (plus a small bias) in mode `weak`.
fn two_modes(design: &str) -> String {
    format!(
        "tsf 1; controller twomode; state x1, x2; input u;\n\
         A(x) = [0, 1; 1 + x1^2, -0.5]; B = [0; 1];\n\
         premise z = x1^2 range 0 .. 1 {{ lo = tri(-1, 0, 1); hi = tri(0, 1, 2); }}\n\
         rule R1: z is lo => A = [0, 1; 1, -0.5];\n\
         rule R2: z is hi => A = [0, 1; 2, -0.5];\n\
         objective decay_rate >= 0.2;\n\
         relaxation basic;\n\
         modes {{ mode ok {{ }} mode weak {{ effectiveness = 0.5; bias = 0.01; }}\n\
           rates = [-1, 1; 2, -2]; design = {design}; }}\n\
         emit rust, c;\n\
         simulate {{ x0 = [0.8, 0]; time = 0 .. 20 step 0.01; mode0 = ok; mode_seed = 7; }}\n"
    )
}

/// The tables of the mode-dependent two-mode design.
fn tables() -> &'static Tables {
    static T: OnceLock<Tables> = OnceLock::new();
    T.get_or_init(|| tables_of(&two_modes("mode_dependent")))
}

/// The certified tables of the spec `text` (named `twomode.tsf`).
fn tables_of(text: &str) -> Tables {
    let model = common::model_of("twomode.tsf", text);
    let c = compile(
        &model,
        SpecInfo {
            path: "twomode.tsf".into(),
            sha256: tsfc::report::sha256_hex(text.as_bytes()),
        },
        &Settings::default(),
        Default::default(),
    );
    assert_eq!(c.status, Status::Certified, "{:?}", c.report.diagnosis);
    let (design, cert) = c.outcome.expect("design");
    tsfc::tables::tables(&model, &design, &cert, "twomode.tsf", "0").expect("tables")
}

/// The sampled mode design's generated code tells the caller to step at each
/// sample and at each mode change (with the last sample), and what the
/// sampling constants mean; the fault-blind build takes no mode and says
/// nothing of mode changes.
#[test]
fn generated_sampled_modal_code_says_when_to_step() {
    let sampled = |design: &str| {
        two_modes(design).replace(
            "emit rust, c;",
            "trigger aperiodic { sampling = 0.01 .. 0.05; }\nemit rust, c;",
        )
    };
    let t = tables_of(&sampled("mode_dependent"));
    assert_eq!(t.header.sampling, Some((0.01, 0.05)));
    let rust = emit_rust(&t).expect("generates");
    syn::parse_file(&rust).expect("generated Rust parses");
    let note = "call `step` at each sample of the state AND at each mode change between samples, with the new mode and the last sample";
    // In the header comment, on SAMPLE_INTERVAL_MAX and on `step`.
    assert_eq!(rust.matches(note).count(), 3, "{rust}");
    assert!(rust.contains("/// Shortest interval in seconds between two samples of the state."));
    let c = emit_c(&t);
    assert_eq!(c.header.matches(note).count(), 1, "{}", c.header);
    assert!(c.header.contains(
        "Sampled: call it at each sample and at each mode change, with the last sample."
    ));
    insta::assert_snapshot!("twomode_sampled.h", c.header);
    // Fault-blind: one gain set, no mode argument, no mode-change calls.
    let t = tables_of(&sampled("mode_independent"));
    assert!(t.modes.is_none());
    let rust = emit_rust(&t).expect("generates");
    assert!(!rust.contains("mode change"), "{rust}");
    assert!(rust.contains("pub fn step(&mut self, x: &[f64; N]) -> [f64; M]"));
    assert!(rust.contains("pub const SAMPLE_INTERVAL_MAX: f64 = 0.05;"));
}

#[test]
fn generated_modal_code_is_snapshotted() {
    let t = tables();
    let mt = t.modes.as_ref().expect("per-mode gains");
    assert_eq!(mt.names, ["ok", "weak"]);
    assert_ne!(mt.gains[0], mt.gains[1], "mode-dependent gains differ");
    let rust = emit_rust(t).expect("generates");
    assert_eq!(rust, emit_rust(t).expect("generates"), "deterministic");
    syn::parse_file(&rust).expect("generated Rust parses");
    assert!(rust.contains("pub fn step(&mut self, mode: u8, x: &[f64; N]) -> [f64; M]"));
    insta::assert_snapshot!("twomode.rs", rust);
    let c = emit_c(t);
    assert_eq!(c, emit_c(t), "deterministic");
    insta::assert_snapshot!("twomode.h", c.header);
    insta::assert_snapshot!("twomode.c", c.source);
}

/// Every float literal of the generated Rust `TABLE.gains`, in order.
fn rust_gain_literals(text: &str) -> Vec<f64> {
    let at = text.find("gains: [").expect("gains field");
    let end = text[at..].find("u_max:").expect("u_max after gains") + at;
    let body = &text[at + "gains: ".len()..end];
    let mut out = Vec::new();
    let mut token = String::new();
    for ch in body.chars().chain(std::iter::once(',')) {
        if ch.is_ascii_digit() || ch == '.' || ch == '-' || ch == 'e' || ch == '+' {
            token.push(ch);
        } else {
            if !token.is_empty() && token != "-" {
                out.push(
                    token
                        .parse()
                        .unwrap_or_else(|_| panic!("literal `{token}`")),
                );
            }
            token.clear();
        }
    }
    out
}

#[test]
fn generated_rust_stores_every_mode_gain_bit_for_bit() {
    let t = tables();
    let rust = emit_rust(t).expect("generates");
    let stored = rust_gain_literals(&rust);
    let want: Vec<f64> = t
        .modes
        .as_ref()
        .expect("modes")
        .gains
        .iter()
        .flatten()
        .flatten()
        .flatten()
        .copied()
        .collect();
    assert_eq!(stored.len(), want.len());
    for (a, b) in stored.iter().zip(&want) {
        assert_eq!(a.to_bits(), b.to_bits(), "{a} vs {b}");
    }
    // The step passes the mode to the runtime's ModalController.
    assert!(rust.contains("TABLE.step_with_premises(mode, x, &premises(x))"));
    assert!(rust.contains("pub static TABLE: ModalController<'static, f64, N, M, P, R, D, K>"));
}

/// The C driver: reads `mode x1 x2` (x as hex bit patterns), prints the bits
/// of u, h and the flags.
fn driver() -> String {
    r#"#include "twomode.h"
#include <stdio.h>
#include <string.h>

static unsigned long long bits(double v) {
    unsigned long long b;
    memcpy(&b, &v, sizeof b);
    return b;
}

int main(void) {
    twomode_t s;
    double x[TWOMODE_N], u[TWOMODE_M];
    unsigned mode;
    twomode_init(&s);
    for (;;) {
        int k;
        unsigned long long b0, b1;
        if (scanf("%u %llx %llx", &mode, &b0, &b1) != 3) {
            return 0;
        }
        memcpy(&x[0], &b0, sizeof b0);
        memcpy(&x[1], &b1, sizeof b1);
        twomode_step(&s, (uint8_t)mode, x, u);
        printf("%llx", bits(u[0]));
        for (k = 0; k < TWOMODE_R; k++) {
            printf(" %llx", bits(twomode_strengths(&s)[k]));
        }
        printf(" %u\n", (unsigned)twomode_flags(&s));
    }
}
"#
    .to_string()
}

fn work_dir() -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join("markov_runtime_c");
    std::fs::create_dir_all(&d).expect("temp dir");
    d
}

#[test]
fn generated_modal_c_matches_the_runtime_bit_for_bit() {
    let t = tables();
    let mt = t.modes.as_ref().expect("modes");
    let PremiseCode::Exprs(exprs) = &t.premise else {
        panic!("x1^2 is a premise expression")
    };
    // The runtime's ModalController from the same tables.
    let terms: Vec<Term<'_, f64>> = t.factored.terms.iter().map(|s| s.runtime()).collect();
    assert_eq!(terms.len(), 2);
    let rules: Vec<&[usize]> = t.factored.rules.iter().map(Vec::as_slice).collect();
    let arr = |v: &[f64]| -> [f64; 2] { [v[0], v[1]] };
    let ctl: ModalController<'_, f64, 2, 1, 1, 2, 2, 2> = ModalController {
        premise_map: [[0.0, 0.0]],
        terms: [terms[0], terms[1]],
        rules: [rules[0], rules[1]],
        centres: [[t.centres[0][0]], [t.centres[1][0]]],
        gains: std::array::from_fn(|a| std::array::from_fn(|j| [arr(&mt.gains[a][j][0])])),
        u_max: [t.u_max[0]],
    };
    // Random states inside and far outside the region, edge values, and
    // modes 0, 1 and out of range (2, 7, 255).
    let mut rng = Rng::new(0x4d0d);
    let mut cases: Vec<(u8, [f64; 2])> = Vec::new();
    for k in 0..3000 {
        let scale = [0.1, 1.0, 3.0, 1e6][k % 4];
        let mode = [0u8, 1, 0, 1, 2, 7, 255][k % 7];
        cases.push((
            mode,
            [rng.uniform(-scale, scale), rng.uniform(-scale, scale)],
        ));
    }
    for e in [f64::NAN, f64::INFINITY, -0.0, 1e308, 5e-324] {
        for mode in [0u8, 1, 2] {
            cases.push((mode, [e, 0.3]));
            cases.push((mode, [0.3, e]));
        }
    }
    // Both C styles: the straight-line step and the table-driven one.
    for style in [CStyle::Straight, CStyle::Table] {
        let t = &Tables {
            c_style: style,
            ..t.clone()
        };
        let dir = work_dir().join(format!("{style:?}"));
        std::fs::create_dir_all(&dir).expect("style dir");
        let (h, c) = (emit_c(t).header, emit_c(t).source);
        assert_eq!(
            c.contains("tsf_step_with_premises)("),
            style == CStyle::Table,
            "{style:?} style expected"
        );
        std::fs::write(dir.join("twomode.h"), h).expect("write");
        std::fs::write(dir.join("twomode.c"), c).expect("write");
        for f in runtime::files() {
            std::fs::write(dir.join(&f.name), &f.text).expect("write runtime");
        }
        std::fs::write(dir.join("driver.c"), driver()).expect("write driver");
        let cc = std::env::var("CC").unwrap_or_else(|_| "cc".into());
        let exe = dir.join("driver");
        let built = Command::new(&cc)
            .args([
                "-std=c99",
                "-Wall",
                "-Wextra",
                "-Werror",
                "-pedantic",
                "-O2",
                "-ffp-contract=off",
            ])
            .arg(dir.join("twomode.c"))
            .arg(dir.join(runtime::SOURCE_NAME))
            .arg(dir.join("driver.c"))
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
        let mut input = String::new();
        for (mode, x) in &cases {
            let _ = writeln!(input, "{mode} {:x} {:x}", x[0].to_bits(), x[1].to_bits());
        }
        let input_path = dir.join("cases.txt");
        std::fs::write(&input_path, input).expect("write cases");
        let out = Command::new(&exe)
            .stdin(std::fs::File::open(&input_path).expect("cases"))
            .stdout(Stdio::piped())
            .output()
            .expect("run the driver");
        assert!(out.status.success());
        let text = String::from_utf8(out.stdout).expect("utf-8");
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines.len(), cases.len());
        let mut out_of_range = 0;
        for ((mode, x), line) in cases.iter().zip(&lines) {
            let z = [exprs[0].eval(x)];
            let s = ctl.step_with_premises(*mode, x, &z);
            let want = format!(
                "{:x} {:x} {:x} {}",
                s.u[0].to_bits(),
                s.h[0].to_bits(),
                s.h[1].to_bits(),
                s.flags.0
            );
            assert_eq!(*line, want, "mode {mode}, x = {x:?}");
            if *mode >= 2 {
                out_of_range += 1;
                assert!(s.flags.contains(Flags::MODE_OUT_OF_RANGE));
                // Mode 0's gains.
                assert_eq!(
                    s.u[0].to_bits(),
                    ctl.step_with_premises(0, x, &z).u[0].to_bits()
                );
            }
        }
        println!(
        "twomode C ({style:?} style) vs runtime: {} cases ({out_of_range} with an out-of-range mode), bit-identical",
        cases.len()
    );
    }
}

/// The stationary distribution of the generator `pi`: p' Pi = 0, sum p = 1,
/// solved as a linear system with one balance equation replaced by the sum.
fn stationary(pi: &DMatrix<f64>) -> Vec<f64> {
    let k = pi.nrows();
    let mut a = pi.transpose();
    let mut b = nalgebra::DVector::zeros(k);
    for j in 0..k {
        a[(k - 1, j)] = 1.0;
    }
    b[k - 1] = 1.0;
    let p = a.lu().solve(&b).expect("irreducible chain");
    p.iter().copied().collect()
}

#[test]
fn the_mode_process_occupies_modes_as_the_stationary_distribution() {
    // Xue et al.'s rates.
    let rates = [-1.7, 0.9, 0.8, 1.0, -5.0, 4.0, 1.6, 1.1, -2.7];
    let pi = DMatrix::from_row_slice(3, 3, &rates);
    let want = stationary(&pi);
    let text = format!(
        "{}modes {{ mode a {{ }} mode b {{ }} mode c {{ }} rates = [-1.7, 0.9, 0.8; 1, -5, 4; 1.6, 1.1, -2.7]; }}\n",
        "tsf 1; controller c; state x1; input u; A = -1; B = 1;\npremise x1 range -1 .. 1 { all = trap(-2, -1, 1, 2); }\nrule R: x1 is all => A = -1;\n"
    );
    let model = common::model_of("chain.tsf", &text);
    let modes = model.spec.modes.as_ref().expect("modes");
    let horizon = 20_000.0;
    let mut time = [0.0; 3];
    let mut jumps = 0u64;
    let mut p = ModeProcess::new(modes, 0, 11, 0.0);
    let mut t = 0.0;
    while p.next_jump() < horizon {
        time[p.mode()] += p.next_jump() - t;
        t = p.next_jump();
        p.jump();
        jumps += 1;
    }
    time[p.mode()] += horizon - t;
    // Expected jump rate: sum_a p_a q_a.
    let rate: f64 = (0..3).map(|a| want[a] * -rates[4 * a]).sum();
    let mut worst = 0.0f64;
    for a in 0..3 {
        let share = time[a] / horizon;
        worst = worst.max((share - want[a]).abs());
    }
    println!(
        "stationary {want:?}; empirical {:?} over {horizon} s, {jumps} jumps (expected {:.0})",
        time.map(|v| v / horizon),
        rate * horizon
    );
    assert!(worst < 0.01, "occupation off by {worst}");
    assert!(((jumps as f64) / (rate * horizon) - 1.0).abs() < 0.02);
}

/// Writes `text` as a spec file and prepares it for simulation.
fn prepared(name: &str, text: &str) -> tsfc::sim::Prepared {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("markov_runtime_specs");
    std::fs::create_dir_all(&dir).expect("dir");
    let path = dir.join(name);
    std::fs::write(&path, text).expect("write spec");
    prepare(&path).unwrap_or_else(|e| panic!("{name}: {e}"))
}

fn run(p: &tsfc::sim::Prepared) -> (Outcome, String) {
    let mut csv = Vec::new();
    let o = simulate_csv(p, &Options::default(), &mut csv).expect("runs");
    (o, String::from_utf8(csv).expect("utf-8"))
}

#[test]
fn closed_loop_under_the_seeded_mode_process_converges_deterministically() {
    for design in ["mode_dependent", "mode_independent"] {
        let p = prepared(&format!("twomode_{design}.tsf"), &two_modes(design));
        let (o, csv) = run(&p);
        let m = &o.metrics;
        let mm = m.modes.as_ref().expect("mode metrics");
        println!(
            "{design}: converged {} settle {:?} max|u| {:?} final {:.3e}; {} jumps; {:?}",
            m.converged,
            m.settle_time_s,
            m.max_abs_u,
            m.final_state_norm,
            mm.transitions,
            mm.modes
                .iter()
                .map(|s| (s.name.as_str(), s.fraction, s.entries))
                .collect::<Vec<_>>()
        );
        assert!(m.converged && !m.failed, "{design}: {:?}", m.failures());
        assert!(mm.transitions > 5, "the chain switches");
        let total: f64 = mm.modes.iter().map(|s| s.time_s).sum();
        assert!((total - 20.0).abs() < 1e-9, "time in modes {total}");
        assert_eq!(
            mm.modes.iter().map(|s| s.entries).sum::<u64>(),
            mm.transitions + 1
        );
        // CSV: a mode column; the jumps in it match the metrics.
        let mut lines = csv.lines();
        assert!(lines.next().expect("header").ends_with(",transmitted,mode"));
        let modes: Vec<u8> = lines
            .map(|l| l.rsplit(',').next().expect("mode").parse().expect("index"))
            .collect();
        let switches = modes.windows(2).filter(|w| w[0] != w[1]).count() as u64;
        assert_eq!(switches, mm.transitions);
        // Same seed, same bytes; another seed, another mode trajectory.
        assert_eq!(run(&p).1, csv, "deterministic");
        let other = prepared(
            &format!("twomode_{design}_seed8.tsf"),
            &two_modes(design).replace("mode_seed = 7", "mode_seed = 8"),
        );
        assert_ne!(run(&other).1, csv);
    }
}

#[test]
fn the_mode_plot_is_written() {
    let p = prepared("twomode_plot.tsf", &two_modes("mode_dependent"));
    let o = simulate(&p, &Options::default()).expect("runs");
    let files = tsfc::sim::plot::plots(&o).expect("plots");
    let names: Vec<&str> = files.iter().map(|f| f.0.as_str()).collect();
    assert!(names.contains(&"twomode.modes.svg") && names.contains(&"twomode.modes.png"));
    let svg = &files
        .iter()
        .find(|f| f.0 == "twomode.modes.svg")
        .expect("svg")
        .1;
    let svg = String::from_utf8_lossy(svg);
    assert!(svg.contains("0 = ok, 1 = weak"), "legend names the modes");
}

const XUE: &str = "xue2024_markov_fault_tolerant.tsf";

#[test]
fn xue2024_compiles_certified_emits_code_and_converges_under_the_mode_process() {
    let m = common::shipped(XUE);
    assert_eq!((m.n, m.m, m.r()), (6, 3, 3));
    assert!(m.coverage.covered);
    let p = prepare(&common::spec_path(XUE)).expect("certified");
    let mt = p.tables.modes.as_ref().expect("mode-dependent tables");
    assert_eq!(mt.names, ["normal", "degraded", "bias"]);
    let files = tsfc::codegen::rust::emit_rust(&p.tables).expect("rust");
    assert!(files.contains("pub const K: usize = 3;"));
    let c = emit_c(&p.tables);
    assert!(c.header.contains("#define XUE_MARKOV_K 3"));
    let o = simulate(&p, &Options::default()).expect("runs");
    let mm = o.metrics.modes.as_ref().expect("modes");
    println!(
        "xue: converged {} settle {:?} max|u| {:?} final {:.3e}; {} jumps; {:?}",
        o.metrics.converged,
        o.metrics.settle_time_s,
        o.metrics.max_abs_u,
        o.metrics.final_state_norm,
        mm.transitions,
        mm.modes
            .iter()
            .map(|s| (s.name.as_str(), s.fraction, s.max_abs_u.clone()))
            .collect::<Vec<_>>()
    );
    assert!(
        o.metrics.converged && !o.metrics.failed,
        "{:?}",
        o.metrics.failures()
    );
    assert!(mm.transitions > 50);
}
