//! The model the rules blend is compared with the state-dependent A(x) it
//! stands for: an exact sector model gives 0, swapped operating points give a
//! warning naming the rules, with the mismatch computed in closed form here.

use crate::common;

use nalgebra::DMatrix;
use tsfc::driver::frontend::{self, Source};

/// The Lorenz system by sector nonlinearity on x1 in [-25, 25]: A(x) is affine
/// in x1 and the two sets are linear in x1, so the blend equals A(x).
fn lorenz(first: &str, second: &str) -> String {
    format!(
        "tsf 1;\ncontroller lorenz;\nstate x1, x2, x3;\ninput u;\n\
         A(x) = [-10, 10, 0; 28, -1, -x1; 0, x1, -8 / 3];\nB = [1; 0; 0];\n\
         premise z = x1 range -25 .. 25 {{ neg = trap(-26, -25, -25, 25); pos = trap(-25, 25, 25, 26); }}\n\
         rule R1: z is {first} => at(x1 = -25, x2 = 0, x3 = 0);\n\
         rule R2: z is {second} => at(x1 = 25, x2 = 0, x3 = 0);\n\
         objective decay_rate >= 0.5;\nrelaxation basic;\n"
    )
}

fn lorenz_a(x1: f64) -> DMatrix<f64> {
    DMatrix::from_row_slice(
        3,
        3,
        &[-10.0, 10.0, 0.0, 28.0, -1.0, -x1, 0.0, x1, -8.0 / 3.0],
    )
}

#[test]
fn an_exact_sector_model_matches_a_of_x() {
    let model = common::model_of("lorenz.tsf", &lorenz("neg", "pos"));
    let c = model.consistency.as_ref().expect("A depends on x");
    assert!(c.points >= 30, "{}", c.points);
    assert!(c.worst < 1e-12, "worst {} at {:?}", c.worst, c.at);
}

#[test]
fn swapped_operating_points_are_a_warning_naming_the_rules() {
    let text = lorenz("pos", "neg");
    let source = Source {
        name: "swapped.tsf".into(),
        text: text.clone(),
        bytes: text.clone().into_bytes(),
    };
    let checked = frontend::check(&source);
    let warning = checked
        .diagnostics
        .iter()
        .find(|d| !d.is_error() && d.message.contains("differs from A(x)"))
        .expect("a model-consistency warning");
    let rendered = tsf_lang::diag::render("swapped.tsf", &text, &checked.diagnostics, false);
    assert!(rendered.contains("rule R"), "{rendered}");
    let model = checked
        .model
        .expect("still a model: a warning, not an error");
    let c = model.consistency.expect("compared");
    // Closed form: at x1 = -+25 only the other rule fires, so the blend is
    // A(+-25) and the difference is 50 in entries (2,3) and (3,2).
    let expected =
        (2.0f64 * 50.0 * 50.0).sqrt() / lorenz_a(25.0).norm().max(lorenz_a(-25.0).norm());
    assert!(
        (c.worst - expected).abs() < 1e-9 * expected,
        "{} vs {expected}",
        c.worst
    );
    assert_eq!(c.at[0].abs(), 25.0);
    assert_eq!(c.firing.len(), 1, "{:?}", c.firing);
    assert!(warning
        .message
        .contains(&format!("{:.0}%", 100.0 * expected)));
}
