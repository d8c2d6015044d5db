//! `relaxation membership_mismatch(kappa = ..)` in a continuous loop: the
//! bounded-mismatch LMIs (plant memberships h, controller memberships k,
//! |k_j - h_j| <= kappa). Its two ends are known relaxations (kappa = 0 is
//! `basic`, kappa = 1 is every plant/controller pair, solved here as an
//! independent SDP), a plant whose two outer rules never fire together is
//! certified with kappa = 0.1 and provably not with every pair, the certificate
//! is re-checked from the report at random (h, k) within the bound, and the
//! simulator measures the mismatch and counts the samples above kappa.

use crate::common;
use common::{kim_lee_rules, Rng};

use nalgebra::DMatrix;
use tsf_lmi::{Expr, Problem, SolveSettings, SolveStatus};
use tsfc::driver::compile::{compile, Compiled, Status};
use tsfc::report::SpecInfo;
use tsfc::synth::Settings;

fn compiled(name: &str, text: &str) -> Compiled {
    let model = common::model_of(name, text);
    let info = SpecInfo {
        path: name.into(),
        sha256: String::new(),
    };
    compile(&model, info, &Settings::default(), Default::default())
}

fn certified(name: &str, text: &str) -> bool {
    compiled(name, text).status == Status::Certified
}

fn kim_lee(a: f64, b: f64, relaxation: &str) -> String {
    format!(
        "tsf 1;\ncontroller kim_lee;\nstate x1, x2;\ninput u;\n\
         premise z = x1 range -1 .. 1 {{ neg = gauss(-1, 0.6); zero = gauss(0, 0.6); pos = gauss(1, 0.6); }}\n\
         rule R1: z is neg => A = [1.59, -7.29; 0.01, 0], B = [1; 0];\n\
         rule R2: z is zero => A = [0.02, -4.64; 0.35, 0.21], B = [8; 0];\n\
         rule R3: z is pos => A = [-{a}, -4.33; 0, 0.05], B = [-{b} + 6; -1];\n\
         objective stability;\nrelaxation {relaxation};\n"
    )
}

/// Every pair A_i X + X A_i' + B_i M_j + M_j' B_i' < 0 with X > 0, solved
/// directly with tsf-lmi (no tsfc synthesis code): the PDC condition for any
/// controller memberships.
fn every_pair_feasible(rules: &[(DMatrix<f64>, DMatrix<f64>)]) -> bool {
    let n = rules[0].0.nrows();
    let mut p = Problem::new();
    let x = p.symmetric("X", n).expect("X");
    let ms: Vec<_> = (0..rules.len())
        .map(|j| p.full(&format!("M{j}"), 1, n).expect("M"))
        .collect();
    p.psd("X > I", Expr::var(x), 1.0).expect("X > I");
    for (i, (a, b)) in rules.iter().enumerate() {
        for (j, &m) in ms.iter().enumerate() {
            let e = Expr::product(a, x, &DMatrix::identity(n, n))
                .and_then(|ax| ax.add(Expr::product(b, m, &DMatrix::identity(n, n))?))
                .and_then(|e| e.he())
                .expect("Q_ij");
            p.nsd(&format!("Q[{i},{j}]"), e, 1e-3).expect("nsd");
        }
    }
    p.feasibility();
    let s = p.solve(&SolveSettings::default()).expect("solve");
    s.status == SolveStatus::Solved
}

#[test]
fn kappa_zero_is_basic_and_kappa_one_is_every_pair_on_the_kim_lee_map() {
    let grid: Vec<(f64, f64)> = (0..=5)
        .flat_map(|a| (0..=5).map(move |k| (2.0 * a as f64, -10.0 + 6.0 * k as f64)))
        .collect();
    let mut counts = [0usize; 4];
    for &(a, b) in &grid {
        let basic = certified("kim_lee.tsf", &kim_lee(a, b, "basic"));
        let k0 = certified(
            "kim_lee.tsf",
            &kim_lee(a, b, "membership_mismatch(kappa = 0)"),
        );
        let k1 = certified(
            "kim_lee.tsf",
            &kim_lee(a, b, "membership_mismatch(kappa = 1)"),
        );
        let pairs = every_pair_feasible(&kim_lee_rules(a, b));
        assert_eq!(k0, basic, "(a, b) = ({a}, {b}): kappa = 0 vs basic");
        assert_eq!(k1, pairs, "(a, b) = ({a}, {b}): kappa = 1 vs every pair");
        for (c, v) in counts.iter_mut().zip([basic, k0, k1, pairs]) {
            *c += usize::from(v);
        }
    }
    eprintln!(
        "certified of {}: basic, kappa 0, kappa 1, every pair = {counts:?}",
        grid.len()
    );
    // The map is not trivial at either end, and every pair is the stronger condition.
    assert!(counts[0] > counts[3] && counts[3] > 0, "{counts:?}");
}

/// Rule 1 (x1 near -1) and rule 3 (x1 near +1) never fire together and push
/// the input in opposite directions; rule 2 is stable with a weak input.
/// Every pair is infeasible: Q_13 and Q_31 need f3 < -1 and f1 > 1 in the
/// x1 direction, Q_11 needs f1 < -1. With controller memberships within 0.1
/// of the plant's, F1 = [-3, 0], F3 = [3, 0] stabilize the loop. A(x), B(x)
/// are the exact blend on the premise range (the simulator's plant).
fn opposite(relaxation: &str) -> String {
    format!(
        "tsf 1;\ncontroller opposite;\nstate x1, x2;\ninput u;\n\
         A(x) = [3 * abs(x1) - 2, 0; 0, -1];\nB(x) = [0.1 * (1 - abs(x1)) - x1; 0];\n\
         premise z = x1 range -1 .. 1 {{ neg = tri(-1, -1, 0); zero = tri(-1, 0, 1); pos = tri(0, 1, 1); }}\n\
         rule R1: z is neg => A = [1, 0; 0, -1], B = [1; 0];\n\
         rule R2: z is zero => A = [-2, 0; 0, -1], B = [0.1; 0];\n\
         rule R3: z is pos => A = [1, 0; 0, -1], B = [-1; 0];\n\
         objective stability;\nrelaxation {relaxation};\n\
         simulate {{ x0 = [0.9, 0.5]; time = 0 .. 5 step 0.001; integrator = rk4; }}\n"
    )
}

fn opposite_rules() -> Vec<(DMatrix<f64>, DMatrix<f64>)> {
    let a = |v: f64| DMatrix::from_row_slice(2, 2, &[v, 0.0, 0.0, -1.0]);
    let b = |v: f64| DMatrix::from_row_slice(2, 1, &[v, 0.0]);
    vec![(a(1.0), b(1.0)), (a(-2.0), b(0.1)), (a(1.0), b(-1.0))]
}

#[test]
fn rules_that_never_fire_together_certify_with_kappa_but_not_with_every_pair() {
    assert!(!every_pair_feasible(&opposite_rules()));
    assert!(!certified(
        "opposite.tsf",
        &opposite("membership_mismatch(kappa = 1)")
    ));
    assert!(certified("opposite.tsf", &opposite("basic")));
    assert!(certified(
        "opposite.tsf",
        &opposite("membership_mismatch(kappa = 0)")
    ));
    let c = compiled(
        "opposite.tsf",
        &opposite("membership_mismatch(kappa = 0.1)"),
    );
    assert_eq!(c.status, Status::Certified, "{:?}", c.report.diagnosis);
    let mm = c
        .report
        .membership_mismatch
        .as_ref()
        .expect("mismatch report");
    assert!(mm.relied_on && mm.kappa == 0.1, "{mm:?}");
    assert!(
        mm.statement.contains("|k_j - h_j| <= 0.1"),
        "{}",
        mm.statement
    );
}

/// The memberships of `opposite` at x1 = z (triangles on [-1, 1]).
fn opposite_memberships(z: f64) -> [f64; 3] {
    let z = z.clamp(-1.0, 1.0);
    [(-z).max(0.0), 1.0 - z.abs(), z.max(0.0)]
}

fn matrix(rows: &serde_json::Value) -> DMatrix<f64> {
    let rows: Vec<Vec<f64>> = serde_json::from_value(rows.clone()).expect("rows");
    let (r, c) = (rows.len(), rows[0].len());
    DMatrix::from_fn(r, c, |i, j| rows[i][j])
}

#[test]
fn the_report_certificate_holds_at_random_memberships_within_kappa() {
    let kappa = 0.1;
    let c = compiled(
        "opposite.tsf",
        &opposite(&format!("membership_mismatch(kappa = {kappa})")),
    );
    assert_eq!(c.status, Status::Certified);
    // Everything from the report's JSON: P and the gains.
    let json = crate::common::schema::report_json(&c.report);
    let p = matrix(&json["P"]);
    let gains: Vec<DMatrix<f64>> = json["gains"]
        .as_array()
        .expect("gains")
        .iter()
        .map(|g| matrix(&g["F"]))
        .collect();
    assert_eq!(gains.len(), 3);
    let rules = opposite_rules();
    let mut rng = Rng::new(0x9e37_79b9_7f4a_7c15);
    let mut worst = f64::NEG_INFINITY;
    for s in 0..4000 {
        let h = opposite_memberships(-1.0 + 2.0 * rng.next_f64());
        // k = (1 - t) h + t w, w on the simplex (a vertex every fourth sample):
        // |k_j - h_j| = t |w_j - h_j| <= t <= kappa.
        let w: [f64; 3] = if s % 4 == 0 {
            let v = (rng.next_f64() * 3.0) as usize % 3;
            std::array::from_fn(|j| f64::from(u8::from(j == v)))
        } else {
            let e: [f64; 3] = std::array::from_fn(|_| -rng.next_f64().max(1e-300).ln());
            let sum: f64 = e.iter().sum();
            e.map(|v| v / sum)
        };
        let t = if s % 2 == 0 {
            kappa
        } else {
            kappa * rng.next_f64()
        };
        let k: [f64; 3] = std::array::from_fn(|j| (1.0 - t) * h[j] + t * w[j]);
        assert!(h
            .iter()
            .zip(&k)
            .all(|(a, b)| (a - b).abs() <= kappa + 1e-12));
        let mut acl = DMatrix::zeros(2, 2);
        for (i, (a, b)) in rules.iter().enumerate() {
            for (j, f) in gains.iter().enumerate() {
                acl += (a + b * f) * (h[i] * k[j]);
            }
        }
        let lyap = acl.transpose() * &p + &p * &acl;
        let top = lyap.symmetric_eigenvalues().max();
        worst = worst.max(top / p.norm());
        assert!(top < 0.0, "h = {h:?}, k = {k:?}: lambda_max = {top:e}");
    }
    eprintln!("largest lambda_max(A'P + PA) / ||P|| over 4000 samples: {worst:.3e}");
    // Outside the bound the certificate promises nothing, and here it fails:
    // the plant in rule 1 alone, the controller in rule 3 alone.
    let acl = &rules[0].0 + &rules[0].1 * &gains[2];
    let lyap = acl.transpose() * &p + &p * &acl;
    assert!(lyap.symmetric_eigenvalues().max() > 0.0);
}

#[test]
fn the_simulation_measures_the_mismatch_and_counts_samples_above_kappa() {
    let dir = std::env::temp_dir().join(format!("tsfc-kappa-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("dir");
    let mut maxima = Vec::new();
    for kappa in ["0.1", "0"] {
        let path = dir.join(format!("opposite_{}.tsf", kappa.replace('.', "_")));
        std::fs::write(
            &path,
            opposite(&format!("membership_mismatch(kappa = {kappa})")),
        )
        .expect("write spec");
        let prepared = tsfc::driver::prepare(&path).expect("certified");
        // The generated headers state the bound the certificate relies on.
        assert!(
            prepared.tables.header.relaxation.ends_with(&format!(
                "valid while the controller's memberships are within {kappa} of the plant's"
            )),
            "{}",
            prepared.tables.header.relaxation
        );
        let o = tsfc::sim::simulate(&prepared, &Default::default()).expect("simulate");
        let m = &o.metrics;
        assert!(!m.failed, "{:?}", m.failures());
        assert_eq!(m.certified_kappa, Some(kappa.parse().expect("kappa")));
        // The controller updates every 1 ms step; x1 moves by at most |x1'| h
        // over a step, so the triangle memberships by at most that much.
        assert!(
            m.max_membership_mismatch > 0.0 && m.max_membership_mismatch < 0.01,
            "{}",
            m.max_membership_mismatch
        );
        let above = m.samples_above_kappa.expect("counted");
        if kappa == "0" {
            assert!(above > 0 && !m.warnings().is_empty());
        } else {
            assert_eq!(above, 0);
            assert!(m.warnings().is_empty());
        }
        maxima.push(m.max_membership_mismatch);
    }
    eprintln!("max membership mismatch over the runs: {maxima:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn event_triggered_loops_keep_every_pair_and_say_so() {
    let model = common::shipped("xu2020_event_triggered.tsf");
    assert_eq!(tsfc::synth::relaxations::kappa_relied_on(&model), None);
    let mm = tsfc::report::MismatchReport::of(&model).expect("mismatch relaxation");
    assert!(!mm.relied_on && mm.kappa == 0.12);
    assert!(mm.statement.contains("not used"), "{}", mm.statement);
}
