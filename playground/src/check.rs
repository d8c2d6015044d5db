//! As-you-type checking: the diagnostics of one spec text with their line and
//! column spans, the document `tsfc check --format json` prints for a file.

use crate::limits;
use serde_json::{json, Value};
use tsfc::driver::check_json::CheckReport;
use tsfc::driver::frontend::{self, Source};

/// A spec text held in memory, named `name` in messages.
pub fn source(name: &str, text: &str) -> Source {
    Source {
        name: name.to_string(),
        text: text.to_string(),
        bytes: text.as_bytes().to_vec(),
    }
}

/// The check of `text`: `{ok, diagnostics: [{line, column, end_line,
/// end_column, severity, message, label, secondary, notes, help, ..}],
/// summary}` (`summary`: the model's size line when the spec is valid), or
/// `{ok: false, error}` past the size limit.
pub fn check(name: &str, text: &str) -> Value {
    if let Err(e) = limits::spec_size(text) {
        return json!({ "ok": false, "error": e, "diagnostics": [] });
    }
    let src = source(name, text);
    let checked = frontend::check(&src);
    let summary = checked.model.as_ref().map(|m| {
        format!(
            "controller `{}`: n = {}, m = {}, {} rules, {} premise components",
            m.spec.controller.node,
            m.n,
            m.m,
            m.r(),
            m.premises.len()
        )
    });
    let files = [(src, checked)];
    let doc = CheckReport::of(&files);
    let file = serde_json::to_value(&doc.files[0]).unwrap_or(Value::Null);
    json!({
        "ok": file["ok"],
        "diagnostics": file["diagnostics"],
        "summary": summary,
    })
}

#[cfg(test)]
mod tests {
    #[test]
    fn a_mistake_is_reported_at_its_line() {
        let v = super::check("t.tsf", "controller c;\nstates { x1 }\nbogus bogus;\n");
        assert_eq!(v["ok"], false);
        let d = &v["diagnostics"][0];
        assert!(d["line"].as_u64().is_some(), "{v}");
    }
}
