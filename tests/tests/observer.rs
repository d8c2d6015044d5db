//! Output feedback (issue 36, part A): observer-based PDC with measured
//! premises and static output feedback, certified; the certificates
//! re-derived here from the report's numbers alone (local models, F_j, L_i,
//! K_j, P), with eigenvalues computed by nalgebra, at the rule vertices and
//! on a grid of the membership simplex.

use crate::common;
use nalgebra::DMatrix;
use serde_json::Value;
use tsfc::driver::compile::Status;

/// A matrix from the report's rows.
fn mat(v: &Value) -> DMatrix<f64> {
    let rows: Vec<Vec<f64>> = v
        .as_array()
        .expect("rows")
        .iter()
        .map(|r| {
            r.as_array()
                .expect("a row")
                .iter()
                .map(|x| x.as_f64().expect("a number"))
                .collect()
        })
        .collect();
    let cols = rows.first().map_or(0, Vec::len);
    DMatrix::from_fn(rows.len(), cols, |i, j| rows[i][j])
}

/// The largest eigenvalue of the symmetric part of `m`.
fn lambda_max(m: &DMatrix<f64>) -> f64 {
    let s = (m + m.transpose()) * 0.5;
    s.symmetric_eigen().eigenvalues.max()
}

/// He(P G) + 2 alpha P.
fn decrease(p: &DMatrix<f64>, g: &DMatrix<f64>, alpha: f64) -> DMatrix<f64> {
    let pg = p * g;
    &pg + pg.transpose() + p * (2.0 * alpha)
}

/// The report of a shipped spec, which must certify: its design for the
/// continuous loop (its periodic trigger removed, one line or a block, if
/// any: the sampled certificates of the shipped observer specs are tested in
/// `observer_shipped` and `observer_drift`).
fn certified(name: &str) -> Value {
    let text = std::fs::read_to_string(common::spec_path(name)).expect("the spec");
    let mut in_trigger = false;
    let continuous: String = text
        .lines()
        .filter(|l| {
            let starts = l.starts_with("trigger periodic");
            let keep = !(starts || in_trigger);
            in_trigger = (in_trigger || starts) && !l.contains('}');
            keep
        })
        .map(|l| format!("{l}\n"))
        .collect();
    let (_, c) = common::compile_text(name, &continuous);
    assert_eq!(
        c.status,
        Status::Certified,
        "{name}: {:?}",
        c.report.diagnosis
    );
    common::schema::report_json(&c.report)
}

/// Per rule (A_i, B_i) from `local_models`.
fn local_models(r: &Value) -> Vec<(DMatrix<f64>, DMatrix<f64>)> {
    r["local_models"]
        .as_array()
        .expect("local_models")
        .iter()
        .map(|m| (mat(&m["A"]), mat(&m["B"])))
        .collect()
}

/// The augmented closed loop G_ij of plant rule i under controller rule j.
fn augmented(
    models: &[(DMatrix<f64>, DMatrix<f64>)],
    f: &[DMatrix<f64>],
    l: &[DMatrix<f64>],
    c: &DMatrix<f64>,
    i: usize,
    j: usize,
) -> DMatrix<f64> {
    let (a, b) = &models[i];
    let n = a.nrows();
    let bf = b * &f[j];
    let mut g = DMatrix::zeros(2 * n, 2 * n);
    g.view_mut((0, 0), (n, n)).copy_from(&(a + &bf));
    g.view_mut((0, n), (n, n)).copy_from(&(-&bf));
    g.view_mut((n, n), (n, n)).copy_from(&(a - &l[i] * c));
    g
}

/// Memberships of two rules on a grid of the simplex (h1 = k / steps).
fn simplex_grid(steps: usize) -> Vec<[f64; 2]> {
    (0..=steps)
        .map(|k| {
            let h = k as f64 / steps as f64;
            [h, 1.0 - h]
        })
        .collect()
}

/// The worst decrease of the augmented loop: the basic relaxation's vertex
/// and pair conditions, and sum_ij h_i h_j G_ij on a simplex grid.
fn worst_augmented(r: &Value, l: &[DMatrix<f64>]) -> (f64, f64) {
    let models = local_models(r);
    let f: Vec<DMatrix<f64>> = r["gains"]
        .as_array()
        .expect("gains")
        .iter()
        .map(|g| mat(&g["F"]))
        .collect();
    let o = &r["observer"];
    let c = mat(&o["C"]);
    let p = mat(&o["augmented"]["P"]);
    let alpha = o["augmented"]["decay_rate"].as_f64().expect("alpha");
    assert!(lambda_max(&(-&p)) < 0.0, "P_aug > 0");
    let g = |i, j| augmented(&models, &f, l, &c, i, j);
    let rr = models.len();
    let mut vertex = f64::NEG_INFINITY;
    for i in 0..rr {
        vertex = vertex.max(lambda_max(&decrease(&p, &g(i, i), alpha)));
        for j in i + 1..rr {
            let pair = decrease(&p, &g(i, j), alpha) + decrease(&p, &g(j, i), alpha);
            vertex = vertex.max(lambda_max(&pair));
        }
    }
    assert_eq!(rr, 2, "the grid below is for two rules");
    let mut grid = f64::NEG_INFINITY;
    for h in simplex_grid(40) {
        let mut gh = DMatrix::zeros(p.nrows(), p.ncols());
        for i in 0..2 {
            for j in 0..2 {
                gh += g(i, j) * (h[i] * h[j]);
            }
        }
        grid = grid.max(lambda_max(&decrease(&p, &gh, alpha)));
    }
    (vertex, grid)
}

fn observer_gains(r: &Value) -> Vec<DMatrix<f64>> {
    r["observer"]["gains"]
        .as_array()
        .expect("observer gains")
        .iter()
        .map(|g| mat(&g["L"]))
        .collect()
}

#[test]
fn observer_designs_are_certified_and_their_augmented_loop_rederived() {
    for (name, outputs) in [("pendulum_observer.tsf", 1), ("amrr2019_gyroless.tsf", 3)] {
        let r = certified(name);
        assert_eq!(r["control"], "observer_based");
        let o = &r["observer"];
        assert_eq!(o["premise_source"], "measured");
        assert_eq!(mat(&o["C"]).nrows(), outputs, "{name}");
        let l = observer_gains(&r);
        let (vertex, grid) = worst_augmented(&r, &l);
        assert!(vertex < 0.0, "{name}: augmented vertex conditions {vertex}");
        assert!(
            grid < 0.0,
            "{name}: augmented loop on the simplex grid {grid}"
        );
        // The observer's own conditions with the report's P2 and decay.
        let (p2, alpha_o, c) = (
            mat(&o["P2"]),
            o["decay_rate"].as_f64().expect("decay"),
            mat(&o["C"]),
        );
        for ((a, _), li) in local_models(&r).iter().zip(&l) {
            let w = lambda_max(&decrease(&p2, &(a - li * &c), alpha_o));
            assert!(w < 0.0, "{name}: observer decay condition {w}");
        }
        // The check can fail: without the observer's correction (L = 0)
        // the estimation error follows the open-loop rules, which diverge.
        let zero: Vec<_> = l.iter().map(|li| li * 0.0).collect();
        let (vertex, _) = worst_augmented(&r, &zero);
        assert!(vertex > 0.0, "{name}: L = 0 must fail ({vertex})");
    }
}

/// A two-state spec measuring x1; rule R2 hides an unstable mode in x2.
const HIDDEN: &str = "tsf 1;\ncontroller hidden;\nstate x1, x2;\ninput u;\nB = [0; 1];\n\
    premise x1 range -1 .. 1 { lo = tri(-1, -1, 1); hi = tri(-1, 1, 1); }\n\
    rule R1: x1 is lo => A = [0, 1; 1, 0];\n\
    rule R2: x1 is hi => A = [1, 0; 0, 0.5];\n\
    objective stability;\nmeasure y = x1;\ncontrol observer_based;\n";

#[test]
fn an_undetectable_rule_is_refused_at_check_time_naming_it() {
    let errors = common::errors_of("hidden.tsf", HIDDEN);
    assert_eq!(errors.len(), 1, "{errors:#?}");
    let e = &errors[0];
    assert!(
        e.message
            .starts_with("the pair (A, C) of rule R2 is not detectable"),
        "{}",
        e.message
    );
    assert!(e.message.contains("0.500000"), "{}", e.message);
    assert!(HIDDEN[e.span.start..e.span.end].starts_with("rule R2"));
    // Measuring x2 too makes every pair detectable: the spec checks clean.
    let both = HIDDEN.replace("measure y = x1;", "measure y = [x1; x2];");
    common::model_of("both.tsf", &both);
}

#[test]
fn static_output_feedback_certifies_and_its_loop_is_rederived() {
    let r = certified("lorenz_static_output.tsf");
    assert_eq!(r["control"], "static_output");
    let s = &r["static_output"];
    let c = mat(&s["C"]);
    let k: Vec<_> = s["gains"]
        .as_array()
        .expect("K")
        .iter()
        .map(|g| mat(&g["K"]))
        .collect();
    let models = local_models(&r);
    let p = mat(&r["P"]);
    let alpha = r["objectives"]["decay_rate"].as_f64().expect("decay");
    assert!(alpha >= 0.5);
    let g = |i: usize, j: usize| &models[i].0 + &models[i].1 * &k[j] * &c;
    let mut worst = f64::NEG_INFINITY;
    for i in 0..models.len() {
        worst = worst.max(lambda_max(&decrease(&p, &g(i, i), alpha)));
        for j in i + 1..models.len() {
            let pair = decrease(&p, &g(i, j), alpha) + decrease(&p, &g(j, i), alpha);
            worst = worst.max(lambda_max(&pair));
        }
    }
    assert!(worst < 0.0, "static output loop: {worst}");
    for h in simplex_grid(40) {
        let mut gh = DMatrix::zeros(3, 3);
        for i in 0..2 {
            for j in 0..2 {
                gh += g(i, j) * (h[i] * h[j]);
            }
        }
        assert!(lambda_max(&decrease(&p, &gh, alpha)) < 0.0, "{h:?}");
    }
    // The loop reads y only: the shipped state-feedback gains are K_j C.
    for (gain, kj) in r["gains"].as_array().expect("gains").iter().zip(&k) {
        assert_eq!(mat(&gain["F"]), kj * &c);
    }
}

#[test]
fn static_output_feedback_is_refused_with_advice() {
    let text = std::fs::read_to_string(common::spec_path("pendulum_observer.tsf"))
        .expect("the pendulum spec")
        .replace(
            "control observer_based(decay = 30);\ntrigger periodic { every = 0.01; }",
            "control static_output;",
        );
    assert!(text.contains("control static_output;"));
    let (_, c) = common::compile_text("pendulum_sof.tsf", &text);
    assert_eq!(c.status, Status::Infeasible);
    let d = c.report.diagnosis.expect("a diagnosis");
    assert!(
        d.achievable
            .iter()
            .any(|a| a.contains("measure more states") && a.contains("control observer_based")),
        "{d:?}"
    );
}

#[test]
fn unmeasured_premises_are_refused_for_observer_based_control() {
    let text = std::fs::read_to_string(common::spec_path("pendulum_observer.tsf"))
        .expect("the pendulum spec")
        .replace("measure y = theta", "measure y = omega");
    let errors = common::errors_of("pendulum_rate.tsf", &text);
    assert!(
        errors
            .iter()
            .any(|e| e.message
                == "premise `s` reads `theta`, which the measured outputs do not recover"),
        "{errors:#?}"
    );
}

/// The shipped spec without its periodic trigger: the continuous loop is
/// certified, but no code is written.
#[test]
fn compile_writes_the_report_and_stops_before_code_for_output_feedback() {
    let dir = common::fresh_dir("observer", "compile");
    let text = std::fs::read_to_string(common::spec_path("pendulum_observer.tsf"))
        .expect("the pendulum spec");
    let continuous = text.replace("trigger periodic { every = 0.01; }\n", "");
    assert_ne!(continuous, text, "the shipped spec's trigger line");
    let spec = dir.join("pendulum_observer.tsf");
    std::fs::write(&spec, continuous).expect("write spec");
    let out = std::process::Command::new(common::tsfc_binary())
        .args(["compile"])
        .arg(&spec)
        .arg("--out")
        .arg(&dir)
        .output()
        .expect("run tsfc");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("its code and simulation need `trigger periodic { every = T; }`"),
        "{stderr}"
    );
    let report: Value = serde_json::from_slice(
        &std::fs::read(dir.join("pendulum_observer.report.json")).expect("the report"),
    )
    .expect("JSON");
    assert_eq!(report["status"], "certified");
    assert!(!dir.join("pendulum_observer.rs").exists());
    assert!(!dir.join("pendulum_observer.c").exists());
}
