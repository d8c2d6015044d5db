//! Every JSON the suite has tsfc write is validated against its published
//! schema (`docs/schema/<kind>.json`, `tsfc schema`), picked by the file
//! name as [`tsfc::driver::schema::kind_of_file`] does.

use boon::{Compiler, SchemaIndex, Schemas};
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;
use tsfc::driver::schema::{kind_of_file, KINDS};

/// The published schemas, compiled once.
struct Validator {
    schemas: Schemas,
    index: Vec<(&'static str, SchemaIndex)>,
}

/// The folder of the published schemas.
pub fn schema_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../docs/schema")
}

fn validator() -> &'static Validator {
    static V: OnceLock<Validator> = OnceLock::new();
    V.get_or_init(|| {
        let mut schemas = Schemas::new();
        let mut compiler = Compiler::new();
        let mut index = Vec::new();
        for k in KINDS {
            let path = schema_dir().join(k.file_name());
            let text = std::fs::read_to_string(&path).unwrap_or_else(|e| {
                panic!(
                    "{}: {e} (write the schemas with `tsfc schema --out docs/schema`)",
                    path.display()
                )
            });
            let doc: Value =
                serde_json::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            let id = k.id();
            compiler
                .add_resource(&id, doc)
                .unwrap_or_else(|e| panic!("{}: {e:#}", path.display()));
            let i = compiler
                .compile(&id, &mut schemas)
                .unwrap_or_else(|e| panic!("{} does not compile: {e:#}", path.display()));
            index.push((k.name, i));
        }
        Validator { schemas, index }
    })
}

/// Validates `doc` against the schema of kind `kind` (its error as text).
pub fn validate(kind: &str, doc: &Value) -> Result<(), String> {
    let v = validator();
    let (_, i) = v
        .index
        .iter()
        .find(|(n, _)| *n == kind)
        .unwrap_or_else(|| panic!("no schema kind `{kind}`"));
    v.schemas.validate(doc, *i).map_err(|e| format!("{e:#}"))
}

/// Panics unless `doc` (named `what` in the message) is valid for `kind`.
pub fn assert_valid(kind: &str, doc: &Value, what: &str) {
    if let Err(e) = validate(kind, doc) {
        panic!("{what} does not validate against docs/schema/{kind}.json: {e}");
    }
}

/// The JSON of a compile report, validated against the report's schema
/// (`failed-report` unless certified), as `tsfc compile` writes it.
pub fn report_json(report: &tsfc::report::Report) -> Value {
    let json = serde_json::to_value(report).expect("the report serializes");
    let kind = if report.status == "certified" {
        "report"
    } else {
        "failed-report"
    };
    assert_valid(
        kind,
        &json,
        &format!("the report of `{}`", report.controller),
    );
    assert_eq!(
        json["$schema"].as_str(),
        Some(tsfc::driver::schema::schema_id(kind).as_str()),
        "the report names its schema"
    );
    json
}

/// Validates every `*.json` file in `dir` against the schema its name
/// picks (panics on a JSON file no schema names); returns how many.
pub fn validate_dir(dir: &Path) -> usize {
    let mut n = 0;
    let entries = std::fs::read_dir(dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
    for e in entries.flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        if !name.ends_with(".json") {
            continue;
        }
        let kind = kind_of_file(&name).unwrap_or_else(|| {
            panic!(
                "{name}: no schema names this file (add a kind to compiler/src/driver/schema.rs)"
            )
        });
        let text = std::fs::read_to_string(e.path()).expect("read the JSON");
        let doc: Value =
            serde_json::from_str(&text).unwrap_or_else(|err| panic!("{name}: not JSON: {err}"));
        assert_valid(kind.name, &doc, &e.path().display().to_string());
        n += 1;
    }
    n
}
