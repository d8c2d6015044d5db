//! The three-rule benchmark of Kim & Lee ("New approaches to relaxed quadratic
//! stability condition of fuzzy control systems", IEEE TFS 2000; also Tuan et
//! al. 2001, Sala & Arino 2007):
//! A1 = [1.59 -7.29; 0.01 0], A2 = [0.02 -4.64; 0.35 0.21], A3 = [-a -4.33; 0 0.05],
//! B1 = [1; 0], B2 = [8; 0], B3 = [-b + 6; -1], PDC stabilization. The map of
//! (a, b) in [0, 10] x [-10, 20] where each relaxation finds certified gains:
//! every relaxation contains the basic one, Polya's grows with its degree and
//! degree 2 certifies strictly more points than Tuan's.

use crate::common;

use tsfc::compile::{compile, Status};
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

#[test]
fn fuzzy_lyapunov_maps_against_the_quadratic_ones() {
    let grid = grid();
    let cases = [
        ("tuan", ""),
        ("tuan", "lyapunov fuzzy(phi = 0.01);"),
        ("tuan", "lyapunov fuzzy(phi = 0.1);"),
        ("polya(d = 2)", ""),
        ("polya(d = 2)", "lyapunov fuzzy(phi = 0.01);"),
    ];
    let maps: Vec<Vec<bool>> = cases
        .iter()
        .map(|(r, extra)| {
            grid.iter()
                .map(|&(a, b)| certified_src(&spec_with(a, b, r, extra)))
                .collect()
        })
        .collect();
    let counts: Vec<usize> = maps
        .iter()
        .map(|m| m.iter().filter(|v| **v).count())
        .collect();
    eprintln!(
        "certified points of {}: {cases:?} -> {counts:?}",
        grid.len()
    );
    for (k, p) in grid.iter().enumerate() {
        for (c, m) in maps.iter().enumerate() {
            if m[k] != maps[0][k] {
                eprintln!("{p:?}: {:?} {} vs tuan {}", cases[c], m[k], maps[0][k]);
            }
        }
    }
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
