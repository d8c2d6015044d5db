//! The published JSON Schemas (`docs/schema/`, `tsfc schema`): they are what
//! the types generate now, every kind of JSON tsfc writes is produced here
//! and validates, and a report missing a required field (or carrying an
//! unknown one) does not.

use crate::common::schema::{assert_valid, report_json, schema_dir, validate, validate_dir};
use serde_json::Value;
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use tsfc::driver::schema::{self, kind_of_file, KINDS};

/// The command that rewrites the published schemas.
const REGENERATE: &str = "cargo run --release -p tsfc -- schema --out docs/schema";

/// A fresh temporary folder for `tag`.
fn fresh(tag: &str) -> PathBuf {
    crate::common::fresh_dir("schema", tag)
}

/// An unstable scalar plant stabilized by a certified gain, with a Monte
/// Carlo block and a sweep of one periodic law (every kind of run output).
fn small_spec(dir: &Path) -> PathBuf {
    let text = crate::common::scalar_campaign_spec(
        "schema_demo",
        6,
        1.5,
        "  sweep { trigger periodic { every = [0.05]; } window = 1 .. 4; columns { s = x1; } }\n",
    );
    let path = dir.join("schema_demo.tsf");
    std::fs::write(&path, text).expect("write spec");
    path
}

#[test]
fn the_published_schemas_are_what_the_types_generate() {
    let dir = schema_dir();
    for k in KINDS {
        let path = dir.join(k.file_name());
        let published = std::fs::read_to_string(&path).unwrap_or_default();
        assert!(
            published == k.text(),
            "docs/schema/{} differs from what `tsfc schema {}` generates: a field was added to, \
             removed from or changed in a type tsfc serializes. Regenerate with `{REGENERATE}`, \
             review the diff, and raise SCHEMA_VERSION (compiler/src/report/mod.rs) when a \
             field was removed, renamed or retyped.",
            k.file_name(),
            k.name
        );
        let id = k.id();
        assert!(
            id.starts_with("https://")
                && id.ends_with(&format!("/schema/v{}/{}.json", schema::VERSION, k.name)),
            "{id}"
        );
    }
    // No stale schema of a kind that is gone.
    let listed: BTreeSet<String> = std::fs::read_dir(&dir)
        .expect("docs/schema")
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".json"))
        .collect();
    let kinds: BTreeSet<String> = KINDS.iter().map(|k| k.file_name()).collect();
    assert_eq!(listed, kinds, "docs/schema holds exactly one file per kind");
    // The README lists each.
    let readme = std::fs::read_to_string(dir.join("README.md")).expect("docs/schema/README.md");
    for k in KINDS {
        assert!(
            readme.contains(&format!("`{}`", k.file_name())),
            "README lists {}",
            k.name
        );
    }
}

#[test]
fn tsfc_schema_prints_one_kind_or_writes_them_all() {
    let text = schema::run(Some("report"), None).expect("report");
    let v: Value = serde_json::from_str(&text).expect("JSON");
    assert_eq!(v["$schema"], "https://json-schema.org/draft/2020-12/schema");
    assert_eq!(
        v["$id"].as_str(),
        Some(format!("{}report.json", schema::base_url()).as_str())
    );
    let e = schema::run(Some("nope"), None).expect_err("unknown kind");
    assert_eq!(e.exit_code(), 2);
    assert!(e.message.contains("failed-report"), "{}", e.message);
    assert_eq!(schema::run(None, None).expect_err("no kind").exit_code(), 2);
    let out = fresh("out").join("nested");
    let listed = schema::run(None, Some(&out)).expect("writes");
    assert_eq!(listed.lines().count(), KINDS.len());
    for k in KINDS {
        let written = std::fs::read_to_string(out.join(k.file_name())).expect("written");
        assert_eq!(written, k.text());
    }
    // A file in the way of the folder is a clear error, not a panic.
    let blocked = fresh("blocked").join("file");
    std::fs::write(&blocked, "x").expect("write");
    assert_eq!(
        schema::run(None, Some(&blocked))
            .expect_err("not a folder")
            .exit_code(),
        2
    );
}

#[test]
fn file_names_pick_their_schema() {
    for (file, kind) in [
        ("c.report.json", Some("report")),
        ("c.failed.report.json", Some("failed-report")),
        ("c.metrics.json", Some("metrics")),
        ("c.sweep.json", Some("sweep")),
        ("c.sweep.metrics.json", Some("sweep-metrics")),
        ("c.mc.summary.json", Some("mc-summary")),
        ("c.mc.runs.json", Some("mc-runs")),
        ("c.mc.shard-2-of-7.json", Some("mc-shard")),
        ("c.adaptive.json", Some("adaptive-report")),
        ("c.adaptive.metrics.json", Some("adaptive-metrics")),
        ("notes.json", None),
        ("c.report.json.bak", None),
    ] {
        assert_eq!(kind_of_file(file).map(|k| k.name), kind, "{file}");
    }
}

/// Compiles, simulates, sweeps, runs a Monte Carlo campaign (whole and in
/// shards), checks specs and runs an adaptive design: every kind is written
/// (or printed) at least once and validates against its published schema.
#[test]
fn every_kind_tsfc_writes_validates() {
    let mut seen: BTreeSet<&str> = BTreeSet::new();
    let dir = fresh("kinds");
    let spec = small_spec(&dir);
    // report: a certified compile.
    let front = tsfc::pipeline::read(&spec).expect("read");
    let run = front
        .compile(&tsfc::synth::Settings::default())
        .expect("compile");
    assert_eq!(run.compiled.report.status, "certified");
    report_json(&run.compiled.report);
    seen.insert("report");
    // failed-report: an unstable plant the input does not reach.
    let refused = "tsf 1; controller refused; state x1; input u; A = 1; B = 0;\n\
         premise x1 range -2 .. 2 { all = trap(-2, -2, 2, 2); }\n\
         rule R: x1 is all => A = 1;\nobjective decay_rate >= 1;\n";
    let (_, c) = crate::common::compile_text("refused.tsf", refused);
    assert_ne!(c.report.status, "certified");
    report_json(&c.report);
    seen.insert("failed-report");
    // metrics, sweep, sweep-metrics, mc-*: through the files they are written to.
    let prepared = tsfc::driver::prepare_run(&run).expect("prepared");
    let out = dir.join("out");
    tsfc::sim::simulate_to(&prepared, &tsfc::sim::Options::default(), &out).expect("simulate");
    let (table, metrics) = tsfc::sim::sweep::run_sweep(
        &prepared,
        &[],
        &tsfc::sim::Options::default(),
        &tsfc::sim::sweep::Config { jobs: Some(1) },
        &tsfc::driver::prepare::prepare_text,
    )
    .expect("sweep");
    tsfc::sim::sweep::write_sweep(&table, &metrics, &out).expect("sweep files");
    let cfg = |shard| tsfc::sim::campaign::Config {
        jobs: Some(1),
        shard,
        ..tsfc::sim::campaign::Config::default()
    };
    let opts = tsfc::sim::Options::default();
    let whole = tsfc::sim::campaign::run_campaign(&prepared, &opts, &cfg((1, 1))).expect("mc");
    tsfc::sim::campaign::write_campaign(&whole, &out).expect("mc files");
    let part = tsfc::sim::campaign::run_campaign(&prepared, &opts, &cfg((2, 3))).expect("shard");
    tsfc::sim::campaign::write_shard(&part, &out).expect("shard file");
    assert_eq!(validate_dir(&out), 6, "metrics, sweep (2), mc (2), shard");
    for e in std::fs::read_dir(&out).expect("out").flatten() {
        if let Some(k) = kind_of_file(&e.file_name().to_string_lossy()) {
            seen.insert(k.name);
        }
    }
    // check: a valid spec and bad ones (with diagnostics and labels).
    let bad = Path::new(env!("CARGO_MANIFEST_DIR")).join("bad");
    let mut checked = Vec::new();
    for p in [
        spec.clone(),
        bad.join("rule_missing_set.tsf"),
        bad.join("several_independent_errors.tsf"),
    ] {
        let source = tsfc::driver::frontend::read_source(&p).expect("read");
        let c = tsfc::driver::frontend::check(&source);
        checked.push((source, c));
    }
    let doc = tsfc::driver::check_json::CheckReport::of(&checked);
    let json: Value = serde_json::from_str(&doc.to_json().expect("json")).expect("parses");
    assert!(json["files"][2]["diagnostics"]
        .as_array()
        .is_some_and(|d| d.len() >= 2));
    assert_valid("check", &json, "check --format json");
    seen.insert("check");
    // adaptive-report and adaptive-metrics.
    let adaptive = tsfc::pipeline::read(&crate::common::spec_path("wang2013_adaptive_mrac.tsf"))
        .expect("adaptive spec");
    let aout = dir.join("adaptive");
    tsfc::driver::adaptive::compile(&adaptive, &aout, &[])
        .expect("adaptive")
        .expect("compiled");
    let short = tsfc::sim::adaptive::Options {
        horizon: Some(1.0),
        x0: None,
    };
    tsfc::driver::adaptive::simulate(&adaptive, &aout, &short)
        .expect("adaptive")
        .expect("simulated");
    assert_eq!(validate_dir(&aout), 2, "adaptive report and metrics");
    seen.extend(["adaptive-report", "adaptive-metrics"]);
    let all: BTreeSet<&str> = KINDS.iter().map(|k| k.name).collect();
    assert_eq!(seen, all, "every kind is produced and validated");
}

/// The report's top-level fields that may be absent (written only when they
/// apply: `skip_serializing_if`); every other one is required.
const OPTIONAL_REPORT_FIELDS: [&str; 8] = [
    "membership_mismatch",
    "observer",
    "static_output",
    "fuzzy_lyapunov",
    "candidate",
    "signal_trigger",
    "modes",
    "transition_rates",
];

#[test]
fn a_report_missing_a_required_field_or_with_an_unknown_one_is_invalid() {
    let (_, c) = crate::common::compile_shipped("zhang2013_multiobjective.tsf");
    let report = report_json(&c.report);
    assert!(validate("report", &report).is_ok());
    // The schema lists the fields the report always writes as required.
    let text = std::fs::read_to_string(schema_dir().join("report.json")).expect("schema");
    let s: Value = serde_json::from_str(&text).expect("schema JSON");
    let required: BTreeSet<&str> = s["required"]
        .as_array()
        .expect("required")
        .iter()
        .filter_map(Value::as_str)
        .collect();
    let props: BTreeSet<&str> = s["properties"]
        .as_object()
        .expect("properties")
        .keys()
        .map(String::as_str)
        .filter(|k| !OPTIONAL_REPORT_FIELDS.contains(k))
        .collect();
    assert_eq!(required, props);
    assert_eq!(s["additionalProperties"], Value::Bool(false));
    // Each required field removed: invalid, and the error names it.
    let fields = report.as_object().expect("object");
    for key in &required {
        let mut cut = fields.clone();
        assert!(cut.remove(*key).is_some(), "the report writes `{key}`");
        let e = validate("report", &Value::Object(cut))
            .expect_err(&format!("a report without `{key}` is invalid"));
        assert!(e.contains(key), "{key}: {e}");
    }
    // A nested required field (a gain's F) and a field of the wrong type.
    let mut no_f = report.clone();
    no_f["gains"][0]
        .as_object_mut()
        .expect("a gain")
        .remove("F");
    assert!(validate("report", &no_f).is_err());
    let mut wrong = report.clone();
    wrong["n"] = Value::String("2".into());
    assert!(validate("report", &wrong).is_err());
    // An unknown field (closed objects), at the top and nested.
    let mut extra = report.clone();
    extra["gains_v2"] = Value::Bool(true);
    assert!(validate("report", &extra).is_err());
    let mut nested = report.clone();
    nested["solver"]["extra"] = Value::Null;
    assert!(validate("report", &nested).is_err());
    // A certified report is not a failed one.
    assert!(validate("failed-report", &report).is_err());
}
