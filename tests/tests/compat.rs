//! Compatibility refusals are spec errors at check time: every fixture of a
//! combination synthesis used to refuse (exit 3, no span) is now refused by
//! `tsfc check` and by `tsfc compile` with exit 1, at the offending item,
//! before synthesis runs.

use std::path::Path;
use tsf_lang::diag;
use tsfc::driver::frontend;
use tsfc::synth::Settings;

/// Each fixture of `tests/bad/`, and the text of the line its error points at.
const REFUSED: [(&str, &str); 14] = [
    (
        "mixed_trigger_at_sampling_instants",
        "sampling = 0.001 .. 0.05;",
    ),
    ("event_trigger_given_weight", "weight = [1, 0; 0, 1];"),
    ("mixed_trigger_with_saturate", "trigger mixed {"),
    (
        "input_norm_above_saturate_level",
        "objective input_norm(u) <= 80",
    ),
    (
        "implied_saturation_linf_without_xi_or_phi",
        "objective linf(w -> z) minimize;",
    ),
    ("region_given_weight", "region theta = -0.5 .. 0.5;"),
    (
        "given_gains_with_codesign",
        "weight = synthesize codesign(rounds = 2);",
    ),
    (
        "fuzzy_lyapunov_with_given_gains",
        "lyapunov fuzzy(phi = 0.5);",
    ),
    ("region_premise_not_linear", "region z = -0.5 .. 0.5;"),
    ("region_too_many_rules", "region x1 = -0.5 .. 0.5;"),
    ("region_box_fires_no_rule", "region x1 = -0.45 .. 0.45;"),
    ("modes_relaxation_polya", "relaxation polya(d = 1);"),
    ("adaptive_precision_f32", "precision f32;"),
    ("c_reserved_controller_name", "controller tsf_pitch;"),
];

#[test]
fn combinations_synthesis_cannot_do_are_spec_errors_with_a_span() {
    for (name, line_text) in REFUSED {
        let file = format!("{name}.tsf");
        let path = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("bad")
            .join(&file);
        let source = frontend::read_source(&path).expect("fixture is readable");
        // `tsfc check`: an error (exit 1) at the offending line, with a help line.
        let checked = frontend::check(&source);
        let errors: Vec<_> = checked
            .diagnostics
            .iter()
            .filter(|d| d.is_error())
            .collect();
        assert_eq!(errors.len(), 1, "{file}: {errors:#?}");
        assert!(errors[0].help.is_some(), "{file}: no help line");
        let j = serde_json::to_value(diag::to_json(&file, &source.text, errors[0])).expect("json");
        let line = j["line"].as_u64().expect("a line") as usize;
        let at = source.text.lines().nth(line - 1).expect("the line exists");
        assert!(
            at.contains(line_text),
            "{file}:{line} is `{at}`, not `{line_text}`"
        );
        // `tsfc compile`: the same spec error (exit 1), before any synthesis.
        let front = tsfc::pipeline::read(&path).expect("readable");
        let Err(e) = front.compile(&Settings::default()) else {
            panic!("{file}: compiled");
        };
        assert_eq!(e.exit_code(), 1, "{file}: {}", e.message);
        assert!(
            e.message.contains(&format!("{file}:{line}:")),
            "{file}: {}",
            e.message
        );
    }
}
