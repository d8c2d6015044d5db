//! The three-rule benchmark of Kim & Lee ("New approaches to relaxed quadratic
//! stability condition of fuzzy control systems", IEEE TFS 2000; also Tuan et
//! al. 2001, Sala & Arino 2007):
//! A1 = [1.59 -7.29; 0.01 0], A2 = [0.02 -4.64; 0.35 0.21], A3 = [-a -4.33; 0 0.05],
//! B1 = [1; 0], B2 = [8; 0], B3 = [-b + 6; -1], PDC stabilization. The map of
//! (a, b) in [0, 10] x [-10, 20] where each relaxation finds certified gains:
//! every relaxation contains the basic one, Polya's grows with its degree and
//! degree 2 certifies strictly more points than Tuan's.

use crate::common;
use common::kim_lee_rules;

use nalgebra::DMatrix;
use tsf_lmi::{Expr, Problem, SolveSettings, SolveStatus};
use tsfc::driver::compile::{compile, Status};
use tsfc::report::SpecInfo;
use tsfc::synth::Settings;

/// Gaussian sets: every rule fires everywhere, so no relaxation can drop a
/// rule pair for not overlapping (the benchmark is about the relaxations, not
/// the membership shapes).
fn spec(a: f64, b: f64, relaxation: &str) -> String {
    spec_with(a, b, relaxation, "")
}

/// [`spec`] with `extra` items appended (e.g. a `lyapunov` item).
fn spec_with(a: f64, b: f64, relaxation: &str, extra: &str) -> String {
    format!(
        "tsf 1;\ncontroller kim_lee;\nstate x1, x2;\ninput u;\n\
         premise z = x1 range -1 .. 1 {{ neg = gauss(-1, 0.6); zero = gauss(0, 0.6); pos = gauss(1, 0.6); }}\n\
         rule R1: z is neg => A = [1.59, -7.29; 0.01, 0], B = [1; 0];\n\
         rule R2: z is zero => A = [0.02, -4.64; 0.35, 0.21], B = [8; 0];\n\
         rule R3: z is pos => A = [-{a}, -4.33; 0, 0.05], B = [-{b} + 6; -1];\n\
         objective stability;\nrelaxation {relaxation};\n{extra}"
    )
}

fn certified(a: f64, b: f64, relaxation: &str) -> bool {
    certified_src(&spec(a, b, relaxation))
}

fn certified_src(src: &str) -> bool {
    let model = common::model_of("kim_lee.tsf", src);
    let info = SpecInfo {
        path: "kim_lee.tsf".into(),
        sha256: String::new(),
    };
    compile(&model, info, &Settings::default(), Default::default()).status == Status::Certified
}

/// The benchmark grid: a in 0..=10, b in -10..=20 step 2 (176 points).
fn grid() -> Vec<(f64, f64)> {
    (0..=10)
        .flat_map(|a| (0..=15).map(move |k| (a as f64, -10.0 + 2.0 * k as f64)))
        .collect()
}

/// Tuan's relaxation of the fuzzy Lyapunov conditions for the *non-PDC* law
/// u = (sum_j h_j M_j)(sum_k h_k X_k)^{-1} x, V = x' X(h)^{-1} x (Tanaka,
/// Hori & Wang 2003 in the X form): for every k,
/// Q^k_ij = sum_l phi (X_l + Y) + He(A_i X_k + B_i M_j), X_k > 0, X_k + Y >= 0.
/// Solved directly with tsf-lmi: tsfc does not emit this law (its runtime
/// blends PDC gains), so this only measures what the law would add.
fn non_pdc_feasible(rules: &[(DMatrix<f64>, DMatrix<f64>)], phi: f64) -> bool {
    let (n, r) = (2, rules.len());
    let id = DMatrix::<f64>::identity(n, n);
    let mut p = Problem::new();
    let xs: Vec<_> = (0..r)
        .map(|k| p.symmetric(&format!("X{k}"), n).expect("X"))
        .collect();
    let ms: Vec<_> = (0..r)
        .map(|j| p.full(&format!("M{j}"), 1, n).expect("M"))
        .collect();
    let y = p.symmetric("Y", n).expect("Y");
    let mut big_phi = Expr::zeros(n, n);
    for (k, &x) in xs.iter().enumerate() {
        p.psd(&format!("X{k} > I"), Expr::var(x), 1.0)
            .expect("X > I");
        p.psd(
            &format!("X{k} + Y >= 0"),
            Expr::var(x).add(Expr::var(y)).expect("+"),
            0.0,
        )
        .expect("X + Y");
        big_phi = big_phi
            .add(
                Expr::var(x)
                    .add(Expr::var(y))
                    .expect("+")
                    .scale(phi)
                    .expect("*"),
            )
            .expect("+");
    }
    let c = 2.0 / (r as f64 - 1.0);
    for (k, &xk) in xs.iter().enumerate() {
        let q = |i: usize, j: usize| {
            let (a, b) = &rules[i];
            Expr::product(a, xk, &id)
                .and_then(|ax| ax.add(Expr::product(b, ms[j], &id)?))
                .and_then(|e| e.he())
                .and_then(|e| e.add(big_phi.clone()))
                .expect("Q")
        };
        for i in 0..r {
            p.nsd(&format!("Q{k}[{i},{i}]"), q(i, i), 1e-3)
                .expect("nsd");
            for j in 0..r {
                if i != j {
                    let e = q(i, i)
                        .scale(c)
                        .and_then(|e| e.add(q(i, j)))
                        .and_then(|e| e.add(q(j, i)));
                    p.nsd(&format!("tuan{k}[{i},{j}]"), e.expect("tuan"), 1e-3)
                        .expect("nsd");
                }
            }
        }
    }
    p.feasibility();
    let s = p.solve(&SolveSettings::default()).expect("solve");
    s.status == SolveStatus::Solved
}

/// The fuzzy Lyapunov function tsfc emits (PDC gains, Finsler form) against
/// the quadratic one under the same relaxation: never smaller, point by point
/// (it contains the quadratic conditions for small mu), and every point it
/// certifies carries a region where |dh_k/dt| <= phi_k was checked (the
/// certificate has that entry). Measured: on this grid it certifies exactly
/// the quadratic points (tuan 57, polya(d = 2) 68 of 176): the (1,1) block
/// He(A_cl G) + Phi with one slack G is a common-matrix condition. The
/// non-PDC law (not emitted; [`non_pdc_feasible`]) is measured alongside.
#[test]
fn fuzzy_lyapunov_maps_against_the_quadratic_ones() {
    let grid = grid();
    let phi = 0.1;
    let flf = format!("lyapunov fuzzy(phi = {phi});");
    let cases = [
        ("tuan", ""),
        ("tuan", flf.as_str()),
        ("polya(d = 2)", ""),
        ("polya(d = 2)", flf.as_str()),
    ];
    let maps: Vec<Vec<bool>> = cases
        .iter()
        .map(|(r, extra)| {
            grid.iter()
                .map(|&(a, b)| certified_src(&spec_with(a, b, r, extra)))
                .collect()
        })
        .collect();
    let non_pdc: Vec<Vec<bool>> = [0.01, phi, 1.0]
        .iter()
        .map(|&f| {
            grid.iter()
                .map(|&(a, b)| non_pdc_feasible(&kim_lee_rules(a, b), f))
                .collect()
        })
        .collect();
    let count = |m: &[bool]| m.iter().filter(|v| **v).count();
    let counts: Vec<usize> = maps.iter().map(|m| count(m)).collect();
    eprintln!(
        "certified points of {}: {cases:?} -> {counts:?}; non-PDC law, tuan, phi = 0.01, {phi}, 1 (not emitted): {:?}",
        grid.len(),
        non_pdc.iter().map(|m| count(m)).collect::<Vec<_>>()
    );
    for (k, p) in grid.iter().enumerate() {
        assert!(
            !maps[0][k] || maps[1][k],
            "{p:?}: tuan certified, fuzzy+tuan did not"
        );
        assert!(
            !maps[2][k] || maps[3][k],
            "{p:?}: polya certified, fuzzy+polya did not"
        );
        assert!(
            !maps[1][k] || maps[3][k],
            "{p:?}: fuzzy+tuan certified, fuzzy+polya did not"
        );
    }
    assert_eq!(counts[1], counts[0], "fuzzy+tuan vs tuan");
    assert_eq!(counts[3], counts[2], "fuzzy+polya vs polya");
    assert!(
        counts[3] > counts[0],
        "fuzzy+polya(d = 2) {} vs tuan {}",
        counts[3],
        counts[0]
    );
}

#[test]
fn the_feasibility_map_grows_from_basic_to_tuan_to_polya() {
    let relaxations = [
        "basic",
        "tuan",
        "polya(d = 1)",
        "polya(d = 2)",
        "polya(d = 3)",
    ];
    let grid = grid();
    let maps: Vec<Vec<bool>> = relaxations
        .iter()
        .map(|r| grid.iter().map(|&(a, b)| certified(a, b, r)).collect())
        .collect();
    let counts: Vec<usize> = maps
        .iter()
        .map(|m| m.iter().filter(|v| **v).count())
        .collect();
    eprintln!(
        "certified points of {}: {relaxations:?} -> {counts:?}",
        grid.len()
    );
    // Nesting, point by point: what basic certifies every other one does, and
    // Polya of degree 2 certifies whatever degree 1 does.
    for (k, p) in grid.iter().enumerate() {
        for m in &maps[1..] {
            assert!(
                !maps[0][k] || m[k],
                "{p:?}: basic certified, a weaker relaxation did not"
            );
        }
        for d in 2..4 {
            assert!(
                !maps[d][k] || maps[d + 1][k],
                "{p:?}: polya {} certified, polya {} did not",
                d - 1,
                d
            );
        }
    }
    assert!(counts[0] > 0 && counts[0] < grid.len(), "{counts:?}");
    assert!(
        counts[3] > counts[1],
        "polya(d = 2) {} vs tuan {}",
        counts[3],
        counts[1]
    );
}
