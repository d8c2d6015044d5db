//! Every bad spec under `tests/bad/` is rejected with readable diagnostics;
//! the rendered text of each is an insta snapshot (review with `cargo insta review`).

use std::path::Path;
use tsf_lang::diag;
use tsfc::driver::frontend;

fn render(path: &Path) -> (String, usize) {
    let mut source = frontend::read_source(path).expect("fixture is readable");
    // Snapshots name the file only, never an absolute path.
    source.name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let checked = frontend::check(&source);
    let errors = checked.diagnostics.iter().filter(|d| d.is_error()).count();
    let text = diag::render(&source.name, &source.text, &checked.diagnostics, false);
    // `tsfc check --format json` of the spec validates against its schema.
    let files = [(source, checked)];
    let doc = tsfc::driver::check_json::CheckReport::of(&files);
    let json = serde_json::to_value(&doc).expect("serializes");
    crate::common::schema::assert_valid("check", &json, &files[0].0.name);
    (text, errors)
}

#[test]
fn bad_specs_are_rejected_with_snapshotted_diagnostics() {
    let mut count = 0;
    insta::glob!("../bad", "*.tsf", |path| {
        let (text, errors) = render(path);
        assert!(errors >= 1, "{} was accepted", path.display());
        // Each fixture has one mistake (the multi-error fixture has two):
        // a cascade of follow-up errors would be a regression.
        let expected = if path.ends_with("several_independent_errors.tsf") {
            2
        } else {
            1
        };
        assert_eq!(errors, expected, "{}:\n{text}", path.display());
        insta::assert_snapshot!(text);
        count += 1;
    });
    assert!(count >= 25, "only {count} bad specs");
}

#[test]
fn json_diagnostics_have_positions_inside_the_file() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("bad/rule_missing_set.tsf");
    let source = frontend::read_source(&path).expect("readable");
    let checked = frontend::check(&source);
    let d = checked
        .diagnostics
        .iter()
        .find(|d| d.is_error())
        .expect("an error");
    let j = serde_json::to_value(diag::to_json("x.tsf", &source.text, d)).expect("serializes");
    assert_eq!(j["severity"], "error");
    let line = j["line"].as_u64().expect("line") as usize;
    let col = j["column"].as_u64().expect("column") as usize;
    let text_line = source.text.lines().nth(line - 1).expect("line exists");
    assert!(
        text_line[col - 1..].starts_with("faar"),
        "points at the set name: {text_line}"
    );
    assert_eq!(j["help"], "did you mean `far`?");
}
