//! `tsfc fmt`: the canonical layout of a `.tsf` source.
//!
//! A token-level formatter: the source is lexed into tokens and comments
//! ([`lex`]), the parser tells which signs are unary and which brackets open
//! an operand (`roles`), and the pieces are re-emitted with whitespace
//! decided by their kinds and the open brackets (`layout`); trailing
//! comments of neighbouring lines are aligned (`render`). Only whitespace
//! changes, so the tokens (and the checked spec) are the same; the author's
//! line breaks inside a statement are kept, so formatting is idempotent.
//! A source with a syntax error is refused, never rewritten.

mod layout;
pub mod lex;
mod render;
mod roles;

use crate::diag::Diagnostic;

/// Why a source was not formatted: it does not parse.
#[derive(Debug, Clone, PartialEq)]
pub struct FormatError {
    /// 1-based line of the first syntax error.
    pub line: usize,
    /// 1-based column (characters) of the first syntax error.
    pub column: usize,
    /// The syntax errors, as `tsfc check` reports them.
    pub diagnostics: Vec<Diagnostic>,
}

impl std::fmt::Display for FormatError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let message = self
            .diagnostics
            .first()
            .map_or("syntax error", |d| d.message.as_str());
        write!(
            f,
            "{}:{}: {message} (not formatted: the source does not parse)",
            self.line, self.column
        )
    }
}

impl std::error::Error for FormatError {}

/// The source in the canonical layout, or the syntax errors that stop it.
/// Nesting and size are bounded as for `tsfc check` (docs/limits.md): too
/// deep an item is a syntax error here too; the work is linear in the size.
pub fn format_source(source: &str) -> Result<String, FormatError> {
    let (_, diags, omitted) = crate::parser::parse_file(source);
    let mut errors: Vec<Diagnostic> = diags.into_iter().filter(Diagnostic::is_error).collect();
    errors.sort_by_key(|d| (d.span.start, d.span.end));
    if let Some(first) = errors.first() {
        let at = crate::diag::to_json("", source, first);
        let (line, column) = (at.line, at.column);
        let mut diagnostics = errors;
        crate::diag::cap(&mut diagnostics, omitted);
        return Err(FormatError {
            line,
            column,
            diagnostics,
        });
    }
    let pieces = lex::lex(source);
    let roles = roles::roles(source);
    let lines = layout::layout(&pieces, &roles);
    let bom = if source.starts_with('\u{feff}') {
        "\u{feff}"
    } else {
        ""
    };
    Ok(format!("{bom}{}", render::render(&lines)))
}

#[cfg(test)]
mod tests;
