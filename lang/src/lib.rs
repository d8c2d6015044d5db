//! The `.tsf` language: grammar (pest), typed AST with spans, name resolution,
//! shape checking, expression evaluation and rustc-style diagnostics.
//!
//! Entry point: [`check_source`], which never panics and never fails as a
//! whole: it returns the checked [`Spec`] when the file is valid, and every
//! diagnostic it found.

#![allow(clippy::result_large_err)] // diagnostics travel on the cold error path; boxing them buys nothing

pub mod adaptive;
pub mod ast;
mod check;
pub mod diag;
mod display;
pub mod eval;
pub mod format;
pub mod limits;
pub mod modes;
pub mod num;
mod parser;
pub mod sector;
pub mod span;
pub mod spec;
mod split;
mod suggest;

pub use check::GENERATABLE_FUNCTIONS;
pub use diag::{Diagnostic, Severity};
pub use span::Span;
pub use spec::Spec;

/// Parses and checks a source text: the spec (if valid) and the diagnostics,
/// sorted by position: at most [`limits::MAX_DIAGNOSTICS`], then one line
/// counting the others.
pub fn check_source(source: &str) -> (Option<Spec>, Vec<Diagnostic>) {
    let (_, spec, diags) = check_source_parsed(source);
    (spec, diags)
}

/// [`check_source`], also returning the syntax tree: the items that parsed,
/// and what the broken ones seem to declare (for editors: the outline, the
/// names and their positions).
pub fn check_source_parsed(source: &str) -> (ast::File, Option<Spec>, Vec<Diagnostic>) {
    let (file, mut diags, omitted) = parser::parse_file(source);
    let (spec, more) = check::check(&file);
    diags.extend(more);
    diags.sort_by_key(|d| (d.span.start, d.span.end));
    // The same mistake reached twice (e.g. through two uses) is reported once.
    diags.dedup_by(|a, b| a.span == b.span && a.message == b.message);
    let has_error = omitted > 0 || diags.iter().any(Diagnostic::is_error);
    diag::cap(&mut diags, omitted);
    (file, if has_error { None } else { spec }, diags)
}
