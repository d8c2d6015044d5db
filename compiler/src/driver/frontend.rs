//! Loading a spec file and running the language and model stages on it.

use crate::model::{self, TsModel};
use std::path::Path;
use std::time::{Duration, Instant};
use tsf_lang::ast::File;
use tsf_lang::{Diagnostic, Span};

/// A source file as read from disk.
#[derive(Debug, Clone)]
pub struct Source {
    /// The path as given by the user (used in messages).
    pub name: String,
    /// The text (invalid UTF-8 replaced, and reported).
    pub text: String,
    /// The raw bytes (for hashing).
    pub bytes: Vec<u8>,
}

/// Why a file could not be checked at all (exit code 2).
#[derive(Debug)]
pub struct IoFailure {
    /// What went wrong, ready to print.
    pub message: String,
}

/// Reads a spec file.
pub fn read_source(path: &Path) -> Result<Source, IoFailure> {
    let bytes = crate::util::output::read_limited(path).map_err(|e| IoFailure {
        message: format!("cannot read `{}`: {e}", path.display()),
    })?;
    let text = String::from_utf8_lossy(&bytes).into_owned();
    Ok(Source {
        name: path.display().to_string(),
        text,
        bytes,
    })
}

/// The outcome of checking one source.
#[derive(Debug)]
pub struct Checked {
    /// The model, if the spec is valid.
    pub model: Option<TsModel>,
    /// All diagnostics (errors and warnings), sorted by position.
    pub diagnostics: Vec<Diagnostic>,
    /// Time spent in the language stage.
    pub parse_time: Duration,
    /// Time spent in the model stage.
    pub model_time: Duration,
}

impl Checked {
    /// Whether any diagnostic is an error.
    pub fn has_errors(&self) -> bool {
        self.diagnostics.iter().any(Diagnostic::is_error)
    }
}

/// Parses, checks and builds the model of a source text. Never panics.
pub fn check(source: &Source) -> Checked {
    check_parsed(source).0
}

/// [`check`], also returning the syntax tree the language stage parsed (for
/// the language server's names and outline).
pub fn check_parsed(source: &Source) -> (Checked, File) {
    let t0 = Instant::now();
    let mut diagnostics = Vec::new();
    if let Err(e) = std::str::from_utf8(&source.bytes) {
        let at = e.valid_up_to();
        diagnostics.push(
            Diagnostic::error(Span::new(at, at + 1), "the file is not valid UTF-8")
                .with_label("invalid byte here")
                .with_help("save the spec as UTF-8 text"),
        );
    }
    let (file, spec, diags) = tsf_lang::check_source_parsed(&source.text);
    diagnostics.extend(diags);
    let parse_time = t0.elapsed();
    let t1 = Instant::now();
    let model = match spec {
        Some(spec) if diagnostics.iter().all(|d| !d.is_error()) => {
            model::build(spec, &mut diagnostics)
        }
        _ => None,
    };
    let model_time = t1.elapsed();
    let diagnostics = diagnostics
        .into_iter()
        .map(|d| d.clamped(&source.text))
        .collect();
    let checked = Checked {
        model,
        diagnostics,
        parse_time,
        model_time,
    };
    (checked, file)
}
