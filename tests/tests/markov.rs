//! Markov-switching modes end to end: the textbook two-mode jump linear
//! system whose mean-square stabilizability has a closed form, and an
//! independent re-check, from the report JSON alone, of every coupled
//! condition He(P_a (A_i + B_ai F_aj)) + sum_b pi_ab P_b + 2 alpha P_a < 0.

use crate::common;

use nalgebra::DMatrix;
use serde_json::Value;
use tsfc::driver::compile::{compile, Status};
use tsfc::report::SpecInfo;
use tsfc::synth::Settings;

pub(crate) fn info() -> SpecInfo {
    SpecInfo {
        path: "markov.tsf".into(),
        sha256: String::new(),
    }
}

/// The report JSON of a compile, and whether it was certified.
pub(crate) fn compiled(text: &str) -> (bool, Value) {
    let model = common::model_of("markov.tsf", text);
    let c = compile(&model, info(), &Settings::default(), Default::default());
    let json = crate::common::schema::report_json(&c.report);
    (c.status == Status::Certified, json)
}

pub(crate) fn matrix(v: &Value) -> DMatrix<f64> {
    let rows: Vec<Vec<f64>> = serde_json::from_value(v.clone()).expect("rows of numbers");
    let (r, c) = (rows.len(), rows.first().map_or(0, Vec::len));
    DMatrix::from_fn(r, c, |i, j| rows[i][j])
}

fn max_eig(m: &DMatrix<f64>) -> f64 {
    let s = (m + m.transpose()) * 0.5;
    s.symmetric_eigenvalues().max()
}

/// x' = a x + b_r u with b = 1 in mode `actuated` and b = 0 in mode `failed`,
/// rates [-p, p; q, -q]. Mean-square stabilizable iff diag(2 (a + f), 2 a) + Pi'
/// is Hurwitz for some f, i.e. (f -> -inf) iff 2 a < q.
fn textbook(a: f64, p: f64, q: f64, design: &str) -> String {
    format!(
        "tsf 1; controller jump; state x1; input u; A = {a}; B = 1;\n\
         premise x1 range -1 .. 1 {{ all = trap(-2, -1, 1, 2); }}\n\
         rule R: x1 is all => A = {a};\n\
         modes {{ mode actuated {{ }} mode failed {{ effectiveness = 0; }}\n\
         rates = [-{p}, {p}; {q}, -{q}]; design = {design}; }}\n"
    )
}

#[test]
fn the_textbook_boundary_2a_equals_q_is_found_on_both_sides() {
    for (p, q) in [(1.0, 2.0), (0.5, 3.0)] {
        let boundary = q / 2.0;
        for (a, expect) in [(boundary * 0.99, true), (boundary * 1.01, false)] {
            let (ok, json) = compiled(&textbook(a, p, q, "mode_dependent"));
            assert_eq!(ok, expect, "a = {a}, q = {q}: {}", json["diagnosis"]);
            if !ok {
                continue;
            }
            // The closed form, with the certified gain of mode `actuated`:
            // diag(2 (a + f), 2 a) + Pi' is Hurwitz.
            let f = json["modes"][0]["gains"][0]["F"][0][0].as_f64().expect("F");
            let pi = matrix(&json["transition_rates"]);
            let gen =
                DMatrix::from_diagonal(&nalgebra::DVector::from_vec(vec![2.0 * (a + f), 2.0 * a]))
                    + pi.transpose();
            let worst = gen
                .complex_eigenvalues()
                .iter()
                .map(|l| l.re)
                .fold(f64::NEG_INFINITY, f64::max);
            assert!(worst < 0.0, "not mean-square stable: {worst}");
        }
    }
}

#[test]
fn fault_blind_gains_cannot_stabilize_an_unstable_plant_with_a_failed_actuator() {
    // One P and one F for both modes: mode `failed` needs 2 a < 0.
    let (ok, _) = compiled(&textbook(0.5, 1.0, 2.0, "mode_independent"));
    assert!(!ok);
    let (ok, json) = compiled(&textbook(-0.5, 1.0, 2.0, "mode_independent"));
    assert!(ok, "{}", json["diagnosis"]);
    let f0 = &json["modes"][0]["gains"][0]["F"];
    assert_eq!(f0, &json["modes"][1]["gains"][0]["F"], "one gain set");
}

/// A two-rule, two-state plant (a damped nonlinear spring) with three actuator
/// modes, the last with every actuator lost (rates of Xue et al. 2024).
pub(crate) fn three_modes(design: &str, relaxation: &str) -> String {
    format!(
        "tsf 1; controller sat; state x1, x2; input u[2];\n\
         A(x) = [0, 1; -1 - x1^2, -0.5]; B = [0, 0.2; 1, 1];\n\
         premise z = x1^2 range 0 .. 1 {{ lo = tri(-1, 0, 1); hi = tri(0, 1, 2); }}\n\
         rule R1: z is lo => A = [0, 1; -1, -0.5];\n\
         rule R2: z is hi => A = [0, 1; -2, -0.5], B = [0, 0.5; 1, 1];\n\
         relaxation {relaxation};\n\
         objective decay_rate maximize;\n\
         modes {{\n\
           mode normal {{ }}\n\
           mode degraded {{ effectiveness = [0.7, 0.6]; }}\n\
           mode lost {{ bias = [0.1, 0]; B = [0, 0; 0, 0]; }}\n\
           rates = [-1.7, 0.9, 0.8; 1, -5, 4; 1.6, 1.1, -2.7];\n\
           design = {design};\n\
         }}\n"
    )
}

/// B_ai of the test's plant, written here (not taken from the compiler).
pub(crate) fn input_matrix(mode: usize, rule: usize) -> DMatrix<f64> {
    let b = if rule == 0 {
        DMatrix::from_row_slice(2, 2, &[0.0, 0.2, 1.0, 1.0])
    } else {
        DMatrix::from_row_slice(2, 2, &[0.0, 0.5, 1.0, 1.0])
    };
    match mode {
        0 => b,
        1 => b * DMatrix::from_diagonal(&nalgebra::DVector::from_vec(vec![0.7, 0.6])),
        _ => DMatrix::zeros(2, 2),
    }
}

/// Re-checks every coupled condition of the report: for each mode the
/// vertex G_aii < 0 and (basic) the pairs G_aij + G_aji < 0.
fn recheck(json: &Value, pairs: bool) -> f64 {
    let a_rules = [
        DMatrix::from_row_slice(2, 2, &[0.0, 1.0, -1.0, -0.5]),
        DMatrix::from_row_slice(2, 2, &[0.0, 1.0, -2.0, -0.5]),
    ];
    let alpha = json["objectives"]["decay_rate"]
        .as_f64()
        .expect("decay rate");
    let pi = matrix(&json["transition_rates"]);
    let modes = json["modes"].as_array().expect("modes");
    assert_eq!(modes.len(), 3);
    let p: Vec<DMatrix<f64>> = modes.iter().map(|m| matrix(&m["P"])).collect();
    let mut worst = f64::NEG_INFINITY;
    for (a, mode) in modes.iter().enumerate() {
        assert!(mode["certified"].as_bool().expect("verdict"));
        assert!(p[a].symmetric_eigenvalues().min() > 0.0);
        let f: Vec<DMatrix<f64>> = (0..2).map(|j| matrix(&mode["gains"][j]["F"])).collect();
        let coupling = (0..3).fold(DMatrix::zeros(2, 2), |s, b| s + &p[b] * pi[(a, b)]);
        let g = |i: usize, j: usize| {
            let acl = &a_rules[i] + input_matrix(a, i) * &f[j];
            let pa = &p[a] * acl;
            &pa + pa.transpose() + &coupling + &p[a] * (2.0 * alpha)
        };
        for i in 0..2 {
            worst = worst.max(max_eig(&g(i, i)));
            if pairs {
                for j in i + 1..2 {
                    worst = worst.max(max_eig(&(g(i, j) + g(j, i))));
                }
            }
        }
    }
    worst
}

#[test]
fn every_coupled_condition_holds_in_the_report_and_mode_dependent_decays_faster() {
    let (ok, dep) = compiled(&three_modes("mode_dependent", "basic"));
    assert!(ok, "{}", dep["diagnosis"]);
    assert!(recheck(&dep, true) < 0.0);
    let (ok, blind) = compiled(&three_modes("mode_independent", "basic"));
    assert!(ok, "{}", blind["diagnosis"]);
    assert!(recheck(&blind, true) < 0.0);
    let rate = |j: &Value| j["objectives"]["decay_rate"].as_f64().expect("rate");
    // The lost mode bounds what any gains achieve (finite rates).
    assert!(rate(&dep) > 0.0 && rate(&dep) < 10.0, "{}", rate(&dep));
    // Fault-blind gains are a special case of mode-dependent ones.
    assert!(
        rate(&dep) >= rate(&blind) * (1.0 - 1e-2),
        "{} < {}",
        rate(&dep),
        rate(&blind)
    );
}

#[test]
fn tanaka_and_every_pair_relaxations_certify_too() {
    for relaxation in ["tanaka(s = 2)", "membership_mismatch(kappa = 0)"] {
        let (ok, json) = compiled(&three_modes("mode_dependent", relaxation));
        assert!(ok, "{relaxation}: {}", json["diagnosis"]);
        // Vertex conditions hold under every relaxation.
        assert!(recheck(&json, false) < 0.0, "{relaxation}");
        let names: Vec<&str> = json["certificate"]["lmis"]
            .as_array()
            .expect("lmis")
            .iter()
            .filter_map(|l| l["name"].as_str())
            .collect();
        assert!(
            names.iter().any(|n| n.starts_with("mode degraded")),
            "{names:?}"
        );
    }
}
