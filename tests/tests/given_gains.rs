//! Given gains (`F = ...` in every rule): tsfc analyzes them instead of
//! synthesizing, and every answer is checked against one computed here
//! without LMIs: the eigenvalues of A + B F (stability, and the decay rate
//! of a single linear loop, where the quadratic Lyapunov bound is exact), a
//! frequency sweep of the closed loop's H-inf norm, and a synthesized design
//! of a shipped spec analyzed again, whose gains reach the generated code
//! bit for bit.

use crate::common;

use common::{model_of, spec_path};
use nalgebra::{Complex, DMatrix};
use tsf_lang::spec::Emit;
use tsfc::driver::compile::{compile, Compiled, Status};
use tsfc::report::SpecInfo;
use tsfc::synth::{Quantity, Settings};

/// The plant x' = A x + B u + D w, z = x, of every linear case here.
const A: [f64; 4] = [0.0, 1.0, 2.0, -1.0];
const B: [f64; 2] = [0.0, 1.0];

/// A one-rule (linear) spec with the gain `f` and `objectives`.
fn linear(f: [f64; 2], objectives: &str) -> String {
    format!(
        "tsf 1; controller lin;\nstate x1, x2; input u; disturbance w;\noutput z = [x1; x2];\n\
         A = [{}, {}; {}, {}]; B = [{}; {}]; D = [0; 1];\n\
         premise x1 range -1 .. 1 {{ all = trap(-1, -1, 1, 1); }}\n\
         rule R: x1 is all => at(x1 = 0), F = [{:?}, {:?}];\n{objectives}\nrelaxation basic;\n",
        A[0], A[1], A[2], A[3], B[0], B[1], f[0], f[1]
    )
}

/// A + B F.
fn closed_loop(f: [f64; 2]) -> DMatrix<f64> {
    DMatrix::from_row_slice(2, 2, &A)
        + DMatrix::from_column_slice(2, 1, &B) * DMatrix::from_row_slice(1, 2, &f)
}

/// Largest real part of the eigenvalues of A + B F.
fn abscissa(f: [f64; 2]) -> f64 {
    closed_loop(f)
        .complex_eigenvalues()
        .iter()
        .map(|l| l.re)
        .fold(f64::NEG_INFINITY, f64::max)
}

/// sigma_max((j w I - A_cl)^-1 E) (C = I, E = D = [0; 1]).
fn gain_at(acl: &DMatrix<f64>, w: f64) -> f64 {
    let n = acl.nrows();
    let m = DMatrix::from_fn(n, n, |i, j| {
        Complex::new(-acl[(i, j)], if i == j { w } else { 0.0 })
    });
    let e = DMatrix::from_column_slice(n, 1, &[Complex::new(0.0, 0.0), Complex::new(1.0, 0.0)]);
    let g = m
        .lu()
        .solve(&e)
        .expect("j w is not an eigenvalue of a Hurwitz matrix");
    g.svd(false, false).singular_values.max()
}

/// The H-inf norm of the closed loop from w to z: the peak of a log sweep
/// over w in [1e-4, 1e4] (4001 points), refined by golden section between
/// the sweep's neighbours of the peak (to a relative width of 1e-10 in w).
fn hinf_by_sweep(f: [f64; 2]) -> f64 {
    let acl = closed_loop(f);
    let grid: Vec<f64> = (0..=4000)
        .map(|k| 10f64.powf(-4.0 + 8.0 * k as f64 / 4000.0))
        .collect();
    let (k, _) = grid.iter().map(|&w| gain_at(&acl, w)).enumerate().fold(
        (0, f64::NEG_INFINITY),
        |b, (k, g)| if g > b.1 { (k, g) } else { b },
    );
    let (mut a, mut b) = (grid[k.saturating_sub(1)], grid[(k + 1).min(grid.len() - 1)]);
    let r = 0.5 * (5f64.sqrt() - 1.0);
    while b - a > 1e-10 * b {
        let (c, d) = (b - r * (b - a), a + r * (b - a));
        if gain_at(&acl, c) > gain_at(&acl, d) {
            b = d;
        } else {
            a = c;
        }
    }
    // The static gain (w = 0) can be the peak: the sweep's lowest point covers it.
    gain_at(&acl, 0.5 * (a + b)).max(gain_at(&acl, 0.0))
}

fn info() -> SpecInfo {
    SpecInfo {
        path: "lin.tsf".into(),
        sha256: String::new(),
    }
}

fn analyze(src: &str) -> Compiled {
    let model = model_of("lin.tsf", src);
    compile(&model, info(), &Settings::default(), Default::default())
}

/// The report's verdict of `objective` (certified, value).
fn verdict(c: &Compiled, objective: &str) -> (bool, Option<f64>) {
    let v = c
        .report
        .verdicts
        .iter()
        .find(|v| v.objective == objective)
        .unwrap_or_else(|| panic!("no verdict for {objective}: {:?}", c.report.verdicts));
    (v.certified, v.value)
}

/// Stable gains: real distinct, complex, and fast poles.
const STABLE: [[f64; 2]; 3] = [[-8.0, -5.0], [-12.0, -1.0], [-30.0, -11.0]];
/// Unstable gains: a real pole at +0.236, and a double pole at 0 (not in the
/// open left half plane).
const UNSTABLE: [[f64; 2]; 2] = [[-1.0, -3.0], [-2.0, 1.0]];

#[test]
fn stability_is_certified_iff_the_closed_loop_is_hurwitz() {
    for f in STABLE.into_iter().chain(UNSTABLE) {
        let c = analyze(&linear(f, "objective stability;"));
        let hurwitz = abscissa(f) < 0.0;
        assert_eq!(c.report.mode, "analysis");
        assert_eq!(
            c.status == Status::Certified,
            hurwitz,
            "F = {f:?}: {:?}",
            c.report.diagnosis
        );
        assert_eq!(verdict(&c, "stability").0, hurwitz, "F = {f:?}");
        if hurwitz {
            let (d, _) = c.outcome.as_ref().expect("certified");
            assert_eq!(
                d.gains,
                vec![DMatrix::from_row_slice(1, 2, &f)],
                "the given gain"
            );
        } else {
            assert!(c.report.gains.is_empty(), "no gains emitted");
            let diag = c.report.diagnosis.as_ref().expect("diagnosis");
            assert!(diag.message.starts_with("analysis: "), "{}", diag.message);
        }
    }
}

/// For one linear loop, sup { alpha : He(A_cl X) + 2 alpha X < 0, X > 0 } is
/// -max Re eig(A_cl) (diagonalizable A_cl). The bisection stops at a relative
/// width of 1e-3 and the LMIs carry a margin of 1e-7: the certified rate is
/// within 0.2 % below the exact one, never above it.
#[test]
fn the_analysed_decay_rate_is_the_spectral_abscissa() {
    for f in STABLE {
        let c = analyze(&linear(f, "objective decay_rate maximize;"));
        assert_eq!(c.status, Status::Certified, "F = {f:?}");
        let (d, _) = c.outcome.as_ref().expect("certified");
        let alpha = d.achieved.get(Quantity::DecayRate).expect("decay rate");
        let exact = -abscissa(f);
        assert!(
            alpha <= exact * (1.0 + 1e-9),
            "F = {f:?}: {alpha} above {exact}"
        );
        assert!(
            alpha >= exact * (1.0 - 2e-3),
            "F = {f:?}: {alpha} vs {exact}"
        );
        assert_eq!(verdict(&c, "decay_rate maximize"), (true, Some(alpha)));
    }
}

/// The bounded-real lemma for one linear loop is exact: the minimized gamma
/// equals the H-inf norm up to the solver's accuracy and the margin
/// (relative 1e-4 here), and is never below it (it is a certified bound).
#[test]
fn the_analysed_hinf_gamma_matches_a_frequency_sweep() {
    for f in STABLE {
        let c = analyze(&linear(f, "objective hinf(w -> z) minimize;"));
        assert_eq!(c.status, Status::Certified, "F = {f:?}");
        let (d, _) = c.outcome.as_ref().expect("certified");
        let gamma = d.achieved.get(Quantity::HinfGamma).expect("gamma");
        let swept = hinf_by_sweep(f);
        assert!(
            gamma >= swept * (1.0 - 1e-6),
            "F = {f:?}: {gamma} below the norm {swept}"
        );
        assert!(
            (gamma - swept).abs() <= 1e-4 * swept,
            "F = {f:?}: {gamma} vs {swept}"
        );
    }
}

/// Objectives that fail together are judged alone: the report names what
/// holds (with its value) and what fails (with the best the gains certify).
#[test]
fn a_bound_the_gains_miss_is_named_with_what_holds() {
    let f = STABLE[0];
    let c = analyze(&linear(
        f,
        "objective decay_rate >= 0.5;\nobjective hinf(w -> z) <= 0.01;",
    ));
    assert_ne!(c.status, Status::Certified);
    assert!(c.report.gains.is_empty());
    assert_eq!(c.report.mode, "analysis");
    assert_eq!(verdict(&c, "stability"), (true, None));
    assert_eq!(verdict(&c, "decay_rate >= 0.5"), (true, Some(0.5)));
    let (ok, best) = verdict(&c, "hinf <= 0.01");
    assert!(!ok);
    let best = best.expect("the best bound alone");
    let swept = hinf_by_sweep(f);
    assert!((best - swept).abs() <= 1e-4 * swept, "{best} vs {swept}");
    let diag = c.report.diagnosis.as_ref().expect("diagnosis");
    assert!(
        diag.message
            .contains("not certified even alone: hinf <= 0.01"),
        "{}",
        diag.message
    );
    assert!(
        diag.message
            .contains("certified alone: stability, decay_rate >= 0.5"),
        "{}",
        diag.message
    );
}

/// A synthesis reports its mode and no verdicts.
#[test]
fn a_synthesis_says_so() {
    let src = linear([0.0, 0.0], "objective stability;").replace(", F = [0.0, 0.0]", "");
    let c = analyze(&src);
    assert_eq!(c.status, Status::Certified);
    assert_eq!(c.report.mode, "synthesis");
    assert!(c.report.verdicts.is_empty());
}

/// The shipped pendulum's spec with `f[j]` given in rule j.
fn pendulum_with(f: &[DMatrix<f64>]) -> String {
    let text = std::fs::read_to_string(spec_path("inverted_pendulum.tsf")).expect("spec");
    let lit = |m: &DMatrix<f64>| format!("F = [{:?}, {:?}]", m[(0, 0)], m[(0, 1)]);
    let r1 = "rule R1: s is near => at(theta = 0, omega = 0)";
    let r2 = "A = [0, 1; g * sinc(pi() / 2) / den(88 * pi() / 180), 0]";
    assert!(
        text.contains(r1) && text.contains(r2),
        "the pendulum's rules changed"
    );
    text.replace(r1, &format!("{r1}, {}", lit(&f[0])))
        .replace(r2, &format!("{r2}, {}", lit(&f[1])))
        .replace(
            "controller inverted_pendulum;",
            "controller pendulum_given;",
        )
}

/// The gains of a synthesized two-rule PDC, given back to tsfc, certify the
/// same objectives, and generated Rust and C carry them exactly.
#[test]
fn a_synthesized_pendulum_design_certifies_again_as_given_gains() {
    let dir = std::env::temp_dir().join(format!("tsfc-given-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("dir");
    let synthesized = tsfc::pipeline::read(&spec_path("inverted_pendulum.tsf"))
        .expect("read")
        .compile(&Settings::default())
        .expect("compile");
    assert_eq!(synthesized.compiled.report.mode, "synthesis");
    let (d, _) = synthesized.certified().expect("certified");
    let gains = d.gains.clone();
    let path = dir.join("pendulum_given.tsf");
    std::fs::write(&path, pendulum_with(&gains)).expect("write");
    let run = tsfc::pipeline::read(&path)
        .expect("read")
        .compile(&Settings::default())
        .expect("compile");
    assert_eq!(run.exit_code(), 0, "{:?}", run.compiled.report.diagnosis);
    let report = &run.compiled.report;
    assert_eq!(report.mode, "analysis");
    assert!(
        report.verdicts.iter().all(|v| v.certified),
        "{:?}",
        report.verdicts
    );
    assert_eq!(
        verdict(&run.compiled, "decay_rate >= 0.5"),
        (true, Some(0.5))
    );
    let (analysed, cert) = run.certified().expect("certified");
    assert!(cert.ok);
    for (g, f) in analysed.gains.iter().zip(&gains) {
        let bits = |m: &DMatrix<f64>| m.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(g), bits(f), "the given gain, bit for bit");
    }
    let files = run.generate(&[Emit::Rust, Emit::C]).expect("generate");
    for suffix in [".rs", ".c"] {
        let text = &files
            .iter()
            .find(|f| f.name.ends_with(suffix))
            .unwrap_or_else(|| panic!("no {suffix}"))
            .text;
        for v in gains.iter().flat_map(|f| f.iter()) {
            assert!(text.contains(&format!("{v:?}")), "{suffix} lacks {v:?}");
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A sampled loop is certified for given gains as for synthesized ones; a
/// period they do not hold is refused naming it and what holds.
#[test]
fn the_sampled_loop_of_given_gains_is_certified_or_named() {
    let spec = |h: f64| {
        linear(
            STABLE[0],
            &format!("objective decay_rate >= 0.5;\ntrigger periodic {{ every = {h}; }}"),
        )
    };
    let c = analyze(&spec(0.05));
    assert_eq!(c.status, Status::Certified, "{:?}", c.report.diagnosis);
    assert_eq!(verdict(&c, "sampled loop (every 0.05 s)"), (true, None));
    let c = analyze(&spec(2.0));
    assert_ne!(c.status, Status::Certified);
    assert!(!verdict(&c, "sampled loop (every 2 s)").0);
    assert_eq!(verdict(&c, "decay_rate >= 0.5"), (true, Some(0.5)));
}
