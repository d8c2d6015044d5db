//! The JSON Schemas of every JSON document tsfc writes (`tsfc schema`),
//! derived from the Rust types that are serialized (schemars, draft 2020-12),
//! versioned by their `$id` and published under `docs/schema/`.
//!
//! Policy (docs/schema/README.md): every field a type always writes is
//! `required`; a field the writer omits when empty is optional; objects are
//! closed (`additionalProperties: false`), so a document with a field the
//! schema does not describe is invalid; a number may be `null`, which is how
//! JSON carries a non-finite value (NaN, infinity).

use crate::util::output;
use crate::Error;
use schemars::generate::SchemaSettings;
use schemars::JsonSchema;
use serde_json::{json, Value};
use std::path::{Path, PathBuf};

pub use crate::report::{schema_id, SCHEMA_VERSION as VERSION};

/// Where the schemas are published: the repository URL, `/schema/vN/`.
pub fn base_url() -> String {
    schema_id("").trim_end_matches(".json").to_string()
}

/// One kind of JSON document tsfc writes.
pub struct Kind {
    /// The kind's name (`tsfc schema NAME`; the schema file is `NAME.json`).
    pub name: &'static str,
    /// How the document's file name ends (`check` prints to stdout: none).
    pub suffix: Option<&'static str>,
    /// The command that writes it.
    pub written_by: &'static str,
    /// What it is, in a few words (the schema's title).
    pub title: &'static str,
    schema: fn() -> Value,
}

/// Every kind, those with the more specific file name suffix first.
pub const KINDS: &[Kind] = &[
    Kind {
        name: "failed-report",
        suffix: Some(".failed.report.json"),
        written_by: "tsfc compile (not certified)",
        title: "tsfc compile report of a design that is not certified",
        schema: failed_report,
    },
    Kind {
        name: "report",
        suffix: Some(".report.json"),
        written_by: "tsfc compile",
        title: "tsfc compile report",
        schema: root::<crate::report::Report>,
    },
    Kind {
        name: "adaptive-metrics",
        suffix: Some(".adaptive.metrics.json"),
        written_by: "tsfc simulate (adaptive spec)",
        title: "tsfc adaptive simulation metrics",
        schema: root::<crate::sim::adaptive::Metrics>,
    },
    Kind {
        name: "adaptive-report",
        suffix: Some(".adaptive.json"),
        written_by: "tsfc compile (adaptive spec)",
        title: "tsfc adaptive design report",
        schema: root::<crate::synth::adaptive::Report>,
    },
    Kind {
        name: "sweep-metrics",
        suffix: Some(".sweep.metrics.json"),
        written_by: "tsfc simulate --sweep",
        title: "tsfc sweep: metrics of every row's run",
        schema: root::<Vec<crate::sim::sweep::ScenarioMetrics>>,
    },
    Kind {
        name: "sweep",
        suffix: Some(".sweep.json"),
        written_by: "tsfc simulate --sweep",
        title: "tsfc sweep table",
        schema: root::<crate::sim::sweep::table::Table>,
    },
    Kind {
        name: "mc-summary",
        suffix: Some(".mc.summary.json"),
        written_by: "tsfc simulate --monte-carlo, --merge",
        title: "tsfc Monte Carlo summary",
        schema: root::<crate::sim::campaign::summary::Summary>,
    },
    Kind {
        name: "mc-runs",
        suffix: Some(".mc.runs.json"),
        written_by: "tsfc simulate --monte-carlo, --merge",
        title: "tsfc Monte Carlo runs (every run and the envelope, mergeable)",
        schema: root::<crate::sim::campaign::summary::Partial>,
    },
    Kind {
        name: "mc-shard",
        suffix: Some(".json"),
        written_by: "tsfc simulate --monte-carlo --shard k/K",
        title: "tsfc Monte Carlo shard (one shard's runs and envelope)",
        schema: root::<crate::sim::campaign::summary::Partial>,
    },
    Kind {
        name: "metrics",
        suffix: Some(".metrics.json"),
        written_by: "tsfc simulate",
        title: "tsfc simulation metrics",
        schema: root::<crate::sim::Metrics>,
    },
    Kind {
        name: "check",
        suffix: None,
        written_by: "tsfc check --format json (stdout)",
        title: "tsfc check diagnostics",
        schema: root::<super::check_json::CheckReport<'static>>,
    },
];

/// The kind named `name`.
pub fn kind(name: &str) -> Option<&'static Kind> {
    KINDS.iter().find(|k| k.name == name)
}

/// The kind of a file tsfc wrote, by its file name (None: not a tsfc JSON).
pub fn kind_of_file(file_name: &str) -> Option<&'static Kind> {
    KINDS.iter().find(|k| match (k.name, k.suffix) {
        // `<name>.mc.shard-k-of-K.json`
        ("mc-shard", Some(s)) => {
            file_name.ends_with(s)
                && file_name
                    .rsplit_once(".mc.shard-")
                    .is_some_and(|(_, tail)| tail.contains("-of-"))
        }
        (_, Some(s)) => file_name.ends_with(s),
        (_, None) => false,
    })
}

impl Kind {
    /// The schema's `$id`.
    pub fn id(&self) -> String {
        schema_id(self.name)
    }

    /// The schema file's name.
    pub fn file_name(&self) -> String {
        format!("{}.json", self.name)
    }

    /// The schema, with its `$id`, title and the policy of the module doc.
    pub fn schema(&self) -> Value {
        let mut s = (self.schema)();
        close(&mut s);
        if let Some(o) = s.as_object_mut() {
            // (serde_json's map keeps its keys in name order.)
            let by = format!("Written by `{}`.", self.written_by);
            let own = o.get("description").and_then(Value::as_str);
            let description = own.map_or(by.clone(), |d| format!("{by} {d}"));
            o.insert("description".into(), Value::String(description));
            o.insert("$id".into(), Value::String(self.id()));
            o.insert(
                "title".into(),
                Value::String(format!("{} (v{VERSION})", self.title)),
            );
        }
        s
    }

    /// The schema as published: pretty JSON with a final newline.
    pub fn text(&self) -> String {
        serde_json::to_string_pretty(&self.schema()).unwrap_or_default() + "\n"
    }
}

/// The schema of `T` as serialized (every field it always writes required).
fn root<T: JsonSchema + ?Sized>() -> Value {
    let generator = SchemaSettings::draft2020_12()
        .for_serialize()
        .into_generator();
    generator.into_root_schema_for::<T>().to_value()
}

/// The report's schema with `status` restricted to a refusal.
fn failed_report() -> Value {
    let mut s = root::<crate::report::Report>();
    if let Some(status) = s.pointer_mut("/properties/status") {
        *status = json!({
            "description": "`infeasible` or `refused`: not certified.",
            "type": "string",
            "enum": ["infeasible", "refused"]
        });
    }
    if let Some(named) = s.pointer_mut("/properties/$schema") {
        named["const"] = json!(schema_id("failed-report"));
    }
    s
}

/// Applies the policy: objects closed, numbers nullable (non-finite).
fn close(v: &mut Value) {
    match v {
        Value::Object(o) => {
            match o.get("type") {
                Some(Value::String(t)) if t == "number" => {
                    o.insert("type".into(), json!(["number", "null"]));
                }
                Some(Value::String(t)) if t == "object" => {
                    o.entry("additionalProperties").or_insert(json!(false));
                }
                _ => {}
            }
            o.values_mut().for_each(close);
        }
        Value::Array(a) => a.iter_mut().for_each(close),
        _ => {}
    }
}

/// Writes every schema into `dir` (created if missing), atomically and
/// together; returns the files written.
pub fn write_all(dir: &Path) -> Result<Vec<PathBuf>, Error> {
    write_kinds(&KINDS.iter().collect::<Vec<_>>(), dir)
}

/// Writes the schemas of `kinds` into `dir` (created if missing), atomically
/// and together; returns the files written.
fn write_kinds(kinds: &[&Kind], dir: &Path) -> Result<Vec<PathBuf>, Error> {
    std::fs::create_dir_all(dir)
        .map_err(|e| Error::usage(format!("cannot create `{}`: {e}", dir.display())))?;
    let files: Vec<(PathBuf, Vec<u8>)> = kinds
        .iter()
        .map(|k| (dir.join(k.file_name()), k.text().into_bytes()))
        .collect();
    output::write_set(&files)
        .map_err(|e| Error::usage(format!("cannot write the schemas: {e}")))?;
    Ok(files.into_iter().map(|(p, _)| p).collect())
}

/// The names of every kind, for messages.
pub fn names() -> String {
    KINDS.iter().map(|k| k.name).collect::<Vec<_>>().join(", ")
}

/// `tsfc schema [KIND] [--out DIR]`: the text to print (KIND's schema; with
/// `--out`, the files written, one line each).
pub fn run(kind_name: Option<&str>, out: Option<&Path>) -> Result<String, Error> {
    let chosen = match kind_name {
        Some(n) => Some(kind(n).ok_or_else(|| {
            Error::usage(format!(
                "unknown schema kind `{n}`; the kinds are: {}",
                names()
            ))
        })?),
        None => None,
    };
    match (chosen, out) {
        (Some(k), None) => Ok(k.text()),
        (None, None) => Err(Error::usage(format!(
            "name a kind ({}) or give --out DIR to write them all",
            names()
        ))),
        (chosen, Some(dir)) => {
            let kinds: Vec<&Kind> = match chosen {
                Some(k) => vec![k],
                None => KINDS.iter().collect(),
            };
            write_kinds(&kinds, dir).map(|files| {
                files
                    .iter()
                    .map(|f| format!("wrote {}\n", f.display()))
                    .collect()
            })
        }
    }
}
