//! Synthesis against answers known from outside the code: closed forms,
//! relaxation theory, eigenvalues of the closed loops, and the papers.

use nalgebra::DMatrix;
use std::path::Path;

use crate::common;
use tsfc::driver::compile::{compile, Status};
use tsfc::model::TsModel;
use tsfc::report::SpecInfo;
use tsfc::synth::{self, Quantity, Settings, SynthError};

use common::{model_of, shipped};

fn info() -> SpecInfo {
    SpecInfo {
        path: "test.tsf".into(),
        sha256: String::new(),
    }
}

/// Largest real part of the eigenvalues of A_i + B_i F_i over all rules.
fn worst_vertex_real_part(model: &TsModel, gains: &[DMatrix<f64>]) -> f64 {
    model
        .rules
        .iter()
        .zip(gains)
        .map(|(r, f)| {
            (&r.a + &r.b * f)
                .complex_eigenvalues()
                .iter()
                .map(|l| l.re)
                .fold(f64::NEG_INFINITY, f64::max)
        })
        .fold(f64::NEG_INFINITY, f64::max)
}

/// Two decoupled stable scalar plants x_k' = a_k x_k + b_k u_k + d_k w_k with
/// z = [c_1 x_1; c_2 x_2; u_1; u_2]. The optimal state-feedback H-inf gain of
/// each is d / sqrt(a^2 / c^2 + b^2) (the Riccati equation's discriminant
/// vanishes there), and the block-diagonal plant's optimum is the larger one.
#[test]
fn lti_hinf_matches_the_riccati_closed_form() {
    let (a1, b1, c1, d1) = (-1.0f64, 1.0f64, 1.0f64, 1.0f64);
    let (a2, b2, c2, d2) = (-2.0f64, 0.5f64, 3.0f64, 2.0f64);
    let spec = format!(
        "tsf 1; controller lti;\n\
         state x1, x2; input u1, u2; disturbance w1, w2;\n\
         output z = [{c1} * x1; {c2} * x2; u1; u2];\n\
         A = [{a1}, 0; 0, {a2}]; B = [{b1}, 0; 0, {b2}]; D = [{d1}, 0; 0, {d2}];\n\
         premise x1 range -1 .. 1 {{ all = trap(-1, -1, 1, 1); }}\n\
         rule R: x1 is all => at(x1 = 0);\n\
         objective hinf(w1 -> z) minimize;"
    );
    // hinf(w1 -> z) takes only the first disturbance channel: subsystem 1.
    let model = model_of("lti.tsf", &spec);
    let d = synth::synthesize(&model, &Settings::default()).expect("feasible");
    let gamma = d.achieved.get(Quantity::HinfGamma).expect("gamma");
    let exact = d1 / (a1 * a1 / (c1 * c1) + b1 * b1).sqrt();
    assert!(
        (gamma - exact).abs() / exact < 1e-4,
        "gamma {gamma} vs closed form {exact}"
    );

    // Both channels: a two-signal disturbance over the stacked plant.
    let spec2 = spec
        .replace("disturbance w1, w2;", "disturbance w[2];")
        .replace("hinf(w1 -> z)", "hinf(w -> z)");
    let model2 = model_of("lti2.tsf", &spec2);
    let d2s = synth::synthesize(&model2, &Settings::default()).expect("feasible");
    let gamma2 = d2s.achieved.get(Quantity::HinfGamma).expect("gamma");
    let exact2 = exact.max(d2 / (a2 * a2 / (c2 * c2) + b2 * b2).sqrt());
    assert!(
        (gamma2 - exact2).abs() / exact2 < 1e-4,
        "gamma {gamma2} vs closed form {exact2}"
    );
    assert!(worst_vertex_real_part(&model2, &d2s.gains) < 0.0);
}

/// x1' = -0.7 x1 is not reachable from u, so no feedback moves that pole: the
/// largest decay rate is exactly 0.7, approached by the bisection from below.
#[test]
fn decay_rate_maximization_finds_the_uncontrollable_pole() {
    let spec = "tsf 1; controller decay; state x1, x2; input u;\n\
                A = [-0.7, 0; 1, 0]; B = [0; 1];\n\
                premise x1 range -1 .. 1 { all = trap(-1, -1, 1, 1); }\n\
                rule R: x1 is all => at(x1 = 0);\n\
                objective decay_rate maximize;";
    let model = model_of("decay.tsf", spec);
    let d = synth::synthesize(&model, &Settings::default()).expect("feasible");
    let (lo, hi) = d.achieved.decay_bracket.expect("bracket");
    assert!(
        lo <= 0.7 + 1e-9 && lo > 0.7 * (1.0 - 3e-3),
        "bracket [{lo}, {hi}]"
    );
    assert!(
        hi > 0.7 - 1e-9,
        "the infeasible end {hi} must lie above the supremum"
    );
    let worst = worst_vertex_real_part(&model, &d.gains);
    assert!(
        worst <= -lo + 1e-6,
        "closed loop decays at {worst}, certified {lo}"
    );
}

fn three_rule_spec(a: f64, b: f64, relaxation: &str) -> String {
    format!(
        "tsf 1; controller tuan_bench; state x1, x2; input u;\n\
         premise z = x1 range -1 .. 1 {{ s1 = gauss(-1, 0.6); s2 = gauss(0, 0.6); s3 = gauss(1, 0.6); }}\n\
         rule R1: z is s1 => A = [1.59, -7.29; 0.01, 0], B = [1; 0];\n\
         rule R2: z is s2 => A = [0.02, -4.64; 0.35, 0.21], B = [8; 0];\n\
         rule R3: z is s3 => A = [{}, -4.33; 0, 0.05], B = [{}; -1];\n\
         objective stability; relaxation {relaxation};",
        -a,
        -b + 6.0
    )
}

fn feasible(a: f64, b: f64, relaxation: &str, eps: f64) -> Option<bool> {
    let model = model_of("grid.tsf", &three_rule_spec(a, b, relaxation));
    let settings = Settings {
        eps,
        ..Settings::default()
    };
    match synth::synthesize(&model, &settings) {
        Ok(_) => Some(true),
        Err(SynthError::Infeasible { .. }) => Some(false),
        Err(_) => None, // no verdict from the solver: not counted
    }
}

/// The classic three-rule benchmark over a grid of (a, b). Basic implies Tuan
/// (Q_ij + Q_ji < 0 and Q_ii < 0 give (2/(r-1)) Q_ii + Q_ij + Q_ji < 0), so a
/// point feasible for basic must be feasible for Tuan, and Tuan must win some
/// points. Near the boundary solvers disagree, so a point counts only when the
/// winner is feasible with margin 1e-4 and the loser infeasible with margin 1e-8.
#[test]
fn tuan_relaxation_dominates_basic_on_the_three_rule_benchmark() {
    let mut tuan_only = 0;
    let mut basic_only = 0;
    let mut points = 0;
    for ai in 0..=5 {
        for bi in 0..=6 {
            let (a, b) = (2.0 * ai as f64, -10.0 + 5.0 * bi as f64);
            points += 1;
            let basic_robust = feasible(a, b, "basic", 1e-4);
            let tuan_robust = feasible(a, b, "tuan", 1e-4);
            if tuan_robust == Some(true) && feasible(a, b, "basic", 1e-8) == Some(false) {
                tuan_only += 1;
            }
            if basic_robust == Some(true) && feasible(a, b, "tuan", 1e-8) == Some(false) {
                basic_only += 1;
            }
        }
    }
    assert_eq!(basic_only, 0, "basic was feasible where tuan was not");
    assert!(tuan_only > 0, "tuan never beat basic on {points} points");
}

#[test]
fn zhang2013_compiles_to_a_certified_design() {
    let model = shipped("zhang2013_multiobjective.tsf");
    let c = compile(&model, info(), &Settings::default(), Default::default());
    assert_eq!(c.status, Status::Certified, "{:?}", c.report.diagnosis);
    let (design, cert) = c.outcome.as_ref().expect("design");
    assert!(cert.ok && cert.min_margin > 0.0);
    // Every vertex closed loop decays at least at the certified rate 0.01.
    let worst = worst_vertex_real_part(&model, &design.gains);
    assert!(
        worst <= -0.01 + 1e-9,
        "vertex closed loop real part {worst}"
    );
    // The certificate checks the unreduced conditions: the 20 tanaka pair LMIs
    // per family are in it although the solved problem dropped them.
    assert!(
        cert.lmis
            .iter()
            .filter(|l| l.name.contains("(Q+Q')/2-Y"))
            .count()
            >= 40
    );
    let gamma = design.achieved.get(Quantity::HinfGamma).expect("gamma");
    let summary = format!(
        "hinf_gamma: {gamma:.4}\ndecay_rate: {}\ninput_norm_bound: {}\nconditions: {}\nstrict: {}\nmin_margin_at_least_eps: {}\n",
        design.achieved.get(Quantity::DecayRate).unwrap_or(f64::NAN),
        design.achieved.get(Quantity::InputNormBound).unwrap_or(f64::NAN),
        cert.lmis.len(),
        cert.lmis.iter().filter(|l| l.strict).count(),
        cert.min_margin >= 0.9 * design.eps
    );
    insta::assert_snapshot!(summary);
}

#[test]
fn zhang2013_paper_input_bound_is_diagnosed_infeasible() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../specs/zhang2013_multiobjective.tsf");
    let text = std::fs::read_to_string(path).expect("readable");
    let paper = text.replace(
        "objective input_norm(u) <= 5 for",
        "objective input_norm(u) <= 0.01 for",
    );
    assert_ne!(paper, text, "the spec's input-norm line changed");
    let model = model_of("zhang_paper.tsf", &paper);
    let c = compile(&model, info(), &Settings::default(), Default::default());
    assert_ne!(c.status, Status::Certified);
    assert!(c.report.gains.is_empty(), "no gains may be emitted");
    let diag = c.report.diagnosis.as_ref().expect("diagnosis");
    let line = diag
        .achievable
        .iter()
        .find(|l| l.contains("input_norm <= 0.01"))
        .expect("input-norm line");
    let value: f64 = line
        .split("other objectives is ")
        .nth(1)
        .and_then(|rest| rest.split_whitespace().next())
        // "4.563667:" when exact, "4.563664 (approximate: ...):" otherwise.
        .and_then(|v| v.trim_end_matches(':').parse().ok())
        .expect("a number");
    // The smallest input bound compatible with the other objectives; the
    // independent cvxpy check in specs/tools/lmi_sanity.py brackets it in (3, 10).
    assert!(value > 3.0 && value < 10.0, "{line}");
}

#[test]
fn pendulum_closed_loops_are_hurwitz_with_the_decay_rate() {
    let model = shipped("inverted_pendulum.tsf");
    let c = compile(&model, info(), &Settings::default(), Default::default());
    assert_eq!(c.status, Status::Certified);
    let (design, _) = c.outcome.as_ref().expect("design");
    let alpha = design.achieved.get(Quantity::DecayRate).expect("decay");
    assert!(worst_vertex_real_part(&model, &design.gains) <= -alpha + 1e-9);
}

#[test]
fn a_tampered_design_is_refused_by_the_certificate() {
    let model = shipped("inverted_pendulum.tsf");
    let mut d = synth::synthesize(&model, &Settings::default()).expect("feasible");
    let cert = tsfc::certify::certify(&model, &d).expect("certificate");
    assert!(cert.ok);
    // Flip the sign of the gains: the decay LMIs must fail.
    for (name, v) in &mut d.values {
        if name.starts_with('M') {
            *v = -v.clone();
        }
    }
    let bad = tsfc::certify::certify(&model, &d).expect("certificate");
    assert!(!bad.ok);
    assert!(bad.worst.contains("decay"), "worst: {}", bad.worst);
}

/// `linf <= g` with saturation and a bounded disturbance: xi (gamma >= xi) is
/// searched below g only. The growing bracket 1e-3 * 4^k used to jump from
/// 0.256 (infeasible) to 1.024 (> g): "infeasible" although every xi in
/// [0.2905, g) is feasible.
#[test]
fn linf_bound_with_saturation_searches_xi_below_the_bound() {
    let text =
        std::fs::read_to_string(common::spec_path("xu2020_event_triggered.tsf")).expect("readable");
    let start = text.find("trigger aperiodic {").expect("trigger block");
    let end = start + text[start..].find("\n}\n").expect("block end") + 3;
    let bounded = format!("{}{}", &text[..start], &text[end..]).replace(
        "objective linf(tau -> y) minimize with phi = 0.05",
        "objective linf(tau -> y) <= 0.5 with phi = 0.05",
    );
    // Without the trigger the loop is continuous, where kappa = 0.12 would be
    // relied on (the kappa-bounded relaxation); this test is about the xi
    // search of the every-pair problem the shipped spec solves: kappa = 1.
    let bounded = bounded.replace(
        "relaxation membership_mismatch(kappa = 0.12);",
        "relaxation membership_mismatch(kappa = 1);",
    );
    assert!(bounded.contains("<= 0.5") && !bounded.contains("trigger aperiodic"));
    let model = model_of("xu_bounded.tsf", &bounded);
    let c = compile(&model, info(), &Settings::default(), Default::default());
    assert_eq!(c.status, Status::Certified, "{:?}", c.report.diagnosis);
    let (design, _) = c.outcome.as_ref().expect("certified");
    let gamma = design.achieved.get(Quantity::LinfGamma).expect("gamma");
    let xi = design.achieved.get(Quantity::LinfXi).expect("xi");
    assert!(
        gamma <= 0.5 && xi <= gamma && xi > 0.256,
        "gamma {gamma}, xi {xi}"
    );
}

/// Polya's relaxation of degree 2 on the same benchmark and grid: wherever
/// Tuan's conditions hold so do Polya's, and Polya wins points (68 against 57
/// of 176 on the finer 11 x 16 grid, measured with the CLI). Each Polya design
/// is checked independently of the relaxation code: with its X and M_j = F_j X,
/// sum_ij h_i h_j He(A_i X + B_i M_j) is negative definite on a simplex grid.
#[test]
fn polya_dominates_tuan_and_its_designs_hold_on_the_simplex() {
    let (mut polya_only, mut tuan_only) = (0, 0);
    let mut checked = 0;
    for ai in 0..=5 {
        for bi in 0..=6 {
            let (a, b) = (2.0 * ai as f64, -10.0 + 5.0 * bi as f64);
            let polya_robust = feasible(a, b, "polya(d = 2)", 1e-4);
            if polya_robust == Some(true) && feasible(a, b, "tuan", 1e-8) == Some(false) {
                polya_only += 1;
            }
            if feasible(a, b, "tuan", 1e-4) == Some(true)
                && feasible(a, b, "polya(d = 2)", 1e-8) == Some(false)
            {
                tuan_only += 1;
            }
            if polya_robust == Some(true) {
                let model = model_of("grid.tsf", &three_rule_spec(a, b, "polya(d = 2)"));
                let d = synth::synthesize(&model, &Settings::default()).expect("feasible");
                let worst = worst_on_simplex(&model, &d.x, &d.gains);
                assert!(worst < 0.0, "a = {a}, b = {b}: max eig {worst}");
                checked += 1;
            }
        }
    }
    assert_eq!(tuan_only, 0, "tuan was feasible where polya(d = 2) was not");
    assert!(polya_only > 0, "polya never beat tuan");
    assert!(checked > 0);
}

/// Largest eigenvalue of sum_ij h_i h_j He(A_i X + B_i F_j X) over a simplex grid of step 1/20.
fn worst_on_simplex(model: &TsModel, x: &DMatrix<f64>, gains: &[DMatrix<f64>]) -> f64 {
    let r = model.r();
    assert_eq!(r, 3);
    let q = |i: usize, j: usize| {
        let m = &model.rules[i].a * x + &model.rules[i].b * &gains[j] * x;
        &m + m.transpose()
    };
    let mut worst = f64::NEG_INFINITY;
    for k1 in 0..=20 {
        for k2 in 0..=(20 - k1) {
            let h = [
                f64::from(k1) / 20.0,
                f64::from(k2) / 20.0,
                f64::from(20 - k1 - k2) / 20.0,
            ];
            let mut s = DMatrix::zeros(x.nrows(), x.ncols());
            for i in 0..r {
                for j in 0..r {
                    s += q(i, j) * (h[i] * h[j]);
                }
            }
            worst = worst.max(s.symmetric_eigen().eigenvalues.max());
        }
    }
    worst
}
