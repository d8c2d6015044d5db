//! The spec's text, kept with a prepared design so that simulate-time errors
//! caused by a spec item point at it (`file:line:col` and the line, rendered
//! like the checker's diagnostics).

use super::SimError;
use tsf_lang::{Diagnostic, Severity, Span};

/// The spec file's name (as given) and text.
#[derive(Debug, Clone, Default)]
pub struct SpecSource {
    /// The path as given (used in messages).
    pub name: String,
    /// The text.
    pub text: String,
}

impl SpecSource {
    /// A spec error rendered at the diagnostic's span; without a text (a
    /// design built by hand) the bare message.
    pub fn error(&self, d: Diagnostic) -> SimError {
        if self.text.is_empty() {
            return SimError::spec(format!("error: {}", d.message));
        }
        SimError::spec(tsf_lang::diag::render(&self.name, &self.text, &[d], false))
    }

    /// A spec error with `message` at `span` and a `help` line.
    pub fn error_at(&self, span: Span, message: String, help: &str) -> SimError {
        self.error(Diagnostic::error(span, message).with_help(help))
    }

    /// A spec error raised while evaluating `what` at time `t`.
    pub fn eval_error(&self, what: &str, t: f64, d: Diagnostic) -> SimError {
        let message = format!("{what} at t = {t}: {}", d.message);
        self.error(Diagnostic {
            message,
            severity: Severity::Error,
            ..d
        })
    }
}

/// The first `len` bytes of `span`, so a long block is shown by its first line.
pub fn head(span: Span, len: usize) -> Span {
    Span::new(span.start, span.end.min(span.start + len))
}
