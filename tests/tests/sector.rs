//! `rules sector;`: the compiler builds the exact sector-nonlinearity T-S
//! model. The generated rules are compared with the textbook vertex matrices
//! written out here in closed form, the blend with A(x) at states the test
//! draws itself, and bad specs with the error each must give.

use crate::common;

use nalgebra::DMatrix;
use tsfc::driver::frontend::{self, Source};
use tsfc::driver::prepare;
use tsfc::model::{rule_weight, TsModel};
use tsfc::sim::{simulate, Options};

/// Lorenz: sigma = 10, r = 28, b = 8/3, d = 25 (Tanaka & Wang 2001, Section 2.2).
fn lorenz_a(x1: f64) -> DMatrix<f64> {
    DMatrix::from_row_slice(
        3,
        3,
        &[-10.0, 10.0, 0.0, 28.0, -1.0, -x1, 0.0, x1, -8.0 / 3.0],
    )
}

/// The errors of a source text (messages), empty when it checks clean.
fn errors(text: &str) -> Vec<String> {
    let source = Source {
        name: "t.tsf".into(),
        text: text.into(),
        bytes: text.as_bytes().to_vec(),
    };
    frontend::check(&source)
        .diagnostics
        .iter()
        .filter(|d| d.is_error())
        .map(|d| match &d.help {
            Some(h) => format!("{} (help: {h})", d.message),
            None => d.message.clone(),
        })
        .collect()
}

/// The normalized firing strengths of `model`'s rules at premise values `z`.
fn strengths(model: &TsModel, z: &[f64]) -> Vec<f64> {
    let w: Vec<f64> = model.terms.iter().map(|t| rule_weight(t, z)).collect();
    let s: f64 = w.iter().sum();
    w.iter().map(|v| v / s).collect()
}

fn close(a: &DMatrix<f64>, b: &DMatrix<f64>, tol: f64) -> bool {
    (a - b).amax() <= tol * (1.0 + b.amax())
}

#[test]
fn lorenz_sector_rules_are_the_textbook_vertices() {
    let m = common::shipped("lorenz_sector.tsf");
    assert_eq!(m.r(), 2);
    assert_eq!(m.spec.rules[0].name, "x1_max");
    assert_eq!(m.spec.rules[1].name, "x1_min");
    assert!(
        close(&m.rules[0].a, &lorenz_a(25.0), 1e-12),
        "{}",
        m.rules[0].a
    );
    assert!(
        close(&m.rules[1].a, &lorenz_a(-25.0), 1e-12),
        "{}",
        m.rules[1].a
    );
    // Memberships (1 +- x1/d)/2 and the blend equal to A(x) on the range.
    for x1 in [-25.0, -17.3, -0.4, 0.0, 3.9, 24.99, 25.0] {
        let h = strengths(&m, &[x1]);
        let hmax = 0.5 * (1.0 + x1 / 25.0);
        assert!((h[0] - hmax).abs() < 1e-12, "x1 = {x1}: {h:?}");
        let blend = &m.rules[0].a * h[0] + &m.rules[1].a * h[1];
        assert!(close(&blend, &lorenz_a(x1), 1e-12), "x1 = {x1}");
    }
    let c = m.consistency.as_ref().expect("A depends on x");
    assert!(c.points > 1000 && c.worst < 1e-12, "{c:?}");
    let s = m.spec.sector.as_ref().expect("a sector model");
    assert!(s.residual < 1e-12 && s.samples >= 64, "{s:?}");
}

#[test]
fn truck_trailer_sector_rules_are_the_textbook_vertices() {
    let m = common::shipped("truck_trailer_sector.tsf");
    let (l, big_l, v, t, t0) = (2.8, 5.5, -1.0, 2.0, 0.5);
    let g = 0.01 / std::f64::consts::PI;
    let a = v * t / (big_l * t0);
    let vertex = |s: f64| {
        DMatrix::from_row_slice(
            3,
            3,
            &[
                -a,
                0.0,
                0.0,
                a,
                0.0,
                0.0,
                s * v * v * t * t / (2.0 * big_l * t0),
                s * v * t / t0,
                0.0,
            ],
        )
    };
    assert_eq!(m.r(), 2);
    assert!(
        close(&m.rules[0].a, &vertex(1.0), 1e-12),
        "{}",
        m.rules[0].a
    );
    assert!(close(&m.rules[1].a, &vertex(g), 1e-12), "{}", m.rules[1].a);
    let b = DMatrix::from_row_slice(3, 1, &[v * t / (l * t0), 0.0, 0.0]);
    assert!(close(&m.rules[1].b, &b, 1e-12));
    let c = m.consistency.as_ref().expect("A depends on x");
    assert!(c.worst < 1e-12, "{c:?}");
}

#[test]
fn sector_specs_certify_and_converge_on_the_nonlinear_plant() {
    for (name, by) in [
        ("lorenz_sector.tsf", 6.0),
        ("truck_trailer_sector.tsf", 60.0),
    ] {
        let p = prepare(&common::spec_path(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
        let o = simulate(&p, &Options::default()).unwrap_or_else(|e| panic!("{name}: {e}"));
        let mt = &o.metrics;
        assert!(mt.converged && !mt.failed, "{name}: {:?}", mt.failures());
        assert!(
            mt.final_state_norm < 1e-3 * mt.initial_state_norm,
            "{name} by {by} s: {}",
            mt.final_state_norm
        );
        assert_eq!(mt.out_of_region_samples, 0, "{name}");
    }
}

/// Two sector premises and a bilinear entry: four rules, the blend exact.
#[test]
fn two_premises_give_four_exact_vertices() {
    let text = "tsf 1;\ncontroller two;\nstate x1, x2;\ninput u;\n\
        A(x) = [x1 * x2, 1; 2 * x1 + 1, -3 + x2];\nB = [0; 1];\n\
        premise x1 range -1 .. 2;\npremise x2 range -3 .. 1;\nrules sector;\nobjective stability;\n";
    let m = common::model_of("two.tsf", text);
    let names: Vec<&str> = m.spec.rules.iter().map(|r| r.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "x1_max_x2_max",
            "x1_max_x2_min",
            "x1_min_x2_max",
            "x1_min_x2_min"
        ]
    );
    let a = |x1: f64, x2: f64| {
        DMatrix::from_row_slice(2, 2, &[x1 * x2, 1.0, 2.0 * x1 + 1.0, -3.0 + x2])
    };
    for (rule, (x1, x2)) in m
        .rules
        .iter()
        .zip([(2.0, 1.0), (2.0, -3.0), (-1.0, 1.0), (-1.0, -3.0)])
    {
        assert!(
            close(&rule.a, &a(x1, x2), 1e-10),
            "{}: {}",
            rule.name,
            rule.a
        );
    }
    // Halton-free check points of the test's own choosing.
    for (x1, x2) in [(0.3, -2.2), (-0.9, 0.7), (1.7, -0.1)] {
        let h = strengths(&m, &[x1, x2]);
        let blend = m
            .rules
            .iter()
            .zip(&h)
            .fold(DMatrix::zeros(2, 2), |acc, (r, w)| acc + &r.a * *w);
        assert!(close(&blend, &a(x1, x2), 1e-10), "({x1}, {x2})");
    }
}

/// A spec header and the Lorenz model, with `rest` appended.
fn lorenz_with(rest: &str) -> String {
    format!(
        "tsf 1;\ncontroller l;\nstate x1, x2, x3;\ninput u;\n\
         A(x) = [-10, 10, 0; 28, -1, -x1; 0, x1, -8 / 3];\nB = [1; 0; 0];\n{rest}objective stability;\n"
    )
}

#[test]
fn bad_sector_specs_are_errors_naming_the_cause() {
    let cases: [(&str, &str); 8] = [
        // x1^2 is not affine in the premise x1.
        (
            "premise x1 range -25 .. 25;\nrules sector;\n",
            "",
        ),
        ("premise x2 range -1 .. 1;\nrules sector;\n", "`A(x)[2, 1]` (0-based, as the language indexes) is not affine"),
        ("premise x1;\nrules sector;\n", "sector premise `x1` has no range"),
        (
            "premise x1 range -25 .. 25 { a = tri(-25, -25, 25); b = tri(-25, 25, 25); }\nrules sector;\n",
            "declares sets beside `rules sector;`",
        ),
        (
            "premise x1 range -25 .. 25;\nrules sector;\nrule R1: x1 is max => at(x1 = 1);\n",
            "a `rule` beside `rules sector;`",
        ),
        ("premise x1 range -25 .. 25;\nrules vertex;\n", "unknown rule construction `vertex`"),
        (
            "premise x1 range -25 .. 25;\npremise z = 2 * x1 range -50 .. 50;\nrules sector;\n",
            "not independent",
        ),
        // The advice names the premises whose removal leaves independent products.
        (
            "premise x1 range -25 .. 25;\npremise z = 2 * x1 range -50 .. 50;\nrules sector;\n",
            "`x1` or `z` is a function of the other premises",
        ),
    ];
    for (rest, want) in cases {
        let errs = errors(&lorenz_with(rest));
        if want.is_empty() {
            assert!(errs.is_empty(), "{rest}: {errs:?}");
        } else {
            assert!(
                errs.iter().any(|e| e.contains(want)),
                "{rest}: want `{want}`, got {errs:?}"
            );
        }
    }
    // A squared premise entry: A = [x1^2] is not affine in x1.
    let sq = "tsf 1;\ncontroller q;\nstate x1;\ninput u;\nA(x) = [-1 - x1 ^ 2];\nB = [1];\n\
              premise x1 range -2 .. 2;\nrules sector;\nobjective stability;\n";
    let errs = errors(sq);
    assert!(
        errs.iter()
            .any(|e| e
                .contains("entry `A(x)[0, 0]` (0-based, as the language indexes) is not affine")),
        "{errs:?}"
    );
    // Declaring the square as its own premise makes it exact.
    let fixed = sq.replace(
        "premise x1 range -2 .. 2;",
        "premise z = x1 ^ 2 range 0 .. 4;",
    );
    let m = common::model_of("fixed.tsf", &fixed);
    assert!(close(
        &m.rules[0].a,
        &DMatrix::from_element(1, 1, -5.0),
        1e-10
    ));
    assert!(close(
        &m.rules[1].a,
        &DMatrix::from_element(1, 1, -1.0),
        1e-10
    ));
}
