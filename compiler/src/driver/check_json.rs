//! The JSON document `tsfc check --format json` prints: per spec file its
//! name, whether it is free of errors, and its diagnostics
//! ([`tsf_lang::diag::JsonDiagnostic`]).

use super::frontend::{Checked, Source};
use schemars::JsonSchema;
use serde::Serialize;
use tsf_lang::diag::{self, JsonDiagnostic};

/// The whole document (keys of every object in name order).
#[derive(Debug, Serialize, JsonSchema)]
pub struct CheckReport<'a> {
    /// One entry per spec file read, in command-line order.
    pub files: Vec<CheckedFile<'a>>,
}

/// One spec file's result.
#[derive(Debug, Serialize, JsonSchema)]
pub struct CheckedFile<'a> {
    /// Its diagnostics (errors and warnings), by position.
    pub diagnostics: Vec<JsonDiagnostic<'a>>,
    /// The file name as given.
    pub file: &'a str,
    /// No error (warnings allowed).
    pub ok: bool,
}

impl<'a> CheckReport<'a> {
    /// The document of `files`, each a spec read and checked.
    pub fn of(files: &'a [(Source, Checked)]) -> CheckReport<'a> {
        CheckReport {
            files: files
                .iter()
                .map(|(source, checked)| CheckedFile {
                    diagnostics: checked
                        .diagnostics
                        .iter()
                        .map(|d| diag::to_json(&source.name, &source.text, d))
                        .collect(),
                    file: &source.name,
                    ok: !checked.has_errors(),
                })
                .collect(),
        }
    }

    /// The document as printed: pretty JSON whose objects (the diagnostics'
    /// too) list their keys in name order.
    pub fn to_json(&self) -> Result<String, serde_json::Error> {
        serde_json::to_string_pretty(&serde_json::to_value(self)?)
    }
}
