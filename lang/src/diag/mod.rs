//! Diagnostics: a message, a labelled primary span, optional secondary labels,
//! notes and a help line; rendered like rustc's or as JSON for editors.
//!
//! Every text a diagnostic carries is made safe to print when it is set
//! ([`text`]), and the source under it is shown through a [`view`], so no
//! control character of the spec reaches a terminal and no long line or
//! number is repeated in full.

mod text;
mod view;

use crate::limits::MAX_DIAGNOSTICS;
use crate::span::Span;
use codespan_reporting::diagnostic::{Diagnostic as CsDiagnostic, Label as CsLabel};
use codespan_reporting::term::{self, Config};
use serde::Serialize;
use view::{Lines, Snippet};

/// How serious a diagnostic is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, schemars::JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum Severity {
    /// The spec is invalid.
    Error,
    /// The spec is valid but probably not what was meant.
    Warning,
}

/// A secondary label: a span and what it shows.
#[derive(Debug, Clone, PartialEq, Serialize, schemars::JsonSchema)]
pub struct Label {
    /// Where.
    pub span: Span,
    /// What.
    pub message: String,
}

/// One diagnostic about a spec.
#[derive(Debug, Clone, PartialEq, Serialize, schemars::JsonSchema)]
pub struct Diagnostic {
    /// Error or warning.
    pub severity: Severity,
    /// The headline, in the reader's terms.
    pub message: String,
    /// The primary span.
    pub span: Span,
    /// Text under the primary span.
    pub label: String,
    /// Other related places.
    pub secondary: Vec<Label>,
    /// Extra facts.
    pub notes: Vec<String>,
    /// How to fix it, where there is a known way.
    pub help: Option<String>,
    /// For the summary line that stands for diagnostics left out (past
    /// [`MAX_DIAGNOSTICS`]): how many; 0 for every other diagnostic. A summary
    /// has no place in the source.
    #[serde(skip_serializing_if = "is_zero")]
    pub omitted: usize,
}

fn is_zero(n: &usize) -> bool {
    *n == 0
}

impl Diagnostic {
    /// An error at `span`.
    pub fn error(span: Span, message: impl Into<String>) -> Self {
        Diagnostic {
            severity: Severity::Error,
            message: text::clean(message.into()),
            span,
            label: String::new(),
            secondary: Vec::new(),
            notes: Vec::new(),
            help: None,
            omitted: 0,
        }
    }

    /// The summary line standing for `count` diagnostics left out.
    pub fn omitted(count: usize, all_errors: bool) -> Self {
        let what = if all_errors { "errors" } else { "diagnostics" };
        Diagnostic {
            omitted: count,
            ..Diagnostic::error(Span::default(), format!("{count} more {what} not shown"))
        }
    }

    /// A warning at `span`.
    pub fn warning(span: Span, message: impl Into<String>) -> Self {
        Diagnostic {
            severity: Severity::Warning,
            ..Diagnostic::error(span, message)
        }
    }

    /// Sets the primary label.
    pub fn with_label(mut self, label: impl Into<String>) -> Self {
        self.label = text::clean(label.into());
        self
    }

    /// Adds a secondary label.
    pub fn with_secondary(mut self, span: Span, message: impl Into<String>) -> Self {
        self.secondary.push(Label {
            span,
            message: text::clean(message.into()),
        });
        self
    }

    /// Adds a note.
    pub fn with_note(mut self, note: impl Into<String>) -> Self {
        self.notes.push(text::clean(note.into()));
        self
    }

    /// Sets the help line.
    pub fn with_help(mut self, help: impl Into<String>) -> Self {
        self.help = Some(text::clean(help.into()));
        self
    }

    /// Adds a "did you mean" help line when a candidate is close to `name`.
    pub fn with_suggestion<'a>(
        self,
        name: &str,
        candidates: impl IntoIterator<Item = &'a str>,
    ) -> Self {
        match crate::suggest::suggest(name, candidates) {
            Some(c) => self.with_help(format!("did you mean `{c}`?")),
            None => self,
        }
    }

    /// Whether this is an error.
    pub fn is_error(&self) -> bool {
        self.severity == Severity::Error
    }

    /// The same diagnostic with every span clamped into `0..=len` (and to char boundaries).
    pub fn clamped(mut self, source: &str) -> Self {
        self.span = clamp(self.span, source);
        for l in &mut self.secondary {
            l.span = clamp(l.span, source);
        }
        self
    }
}

fn clamp(span: Span, source: &str) -> Span {
    let fix = |mut i: usize| {
        i = i.min(source.len());
        while i > 0 && !source.is_char_boundary(i) {
            i -= 1;
        }
        i
    };
    Span::new(fix(span.start), fix(span.end))
}

/// Diagnostics collected in source order, keeping the first [`MAX_DIAGNOSTICS`]
/// and counting the others (which are then never built).
#[derive(Debug, Default)]
pub(crate) struct Capped {
    /// The diagnostics kept.
    pub kept: Vec<Diagnostic>,
    /// How many were left out.
    pub omitted: usize,
}

impl Capped {
    /// Adds the diagnostic `make` builds, if there is room for it.
    pub fn push_with(&mut self, make: impl FnOnce() -> Diagnostic) {
        if self.kept.len() < MAX_DIAGNOSTICS {
            self.kept.push(make());
        } else {
            self.omitted += 1;
        }
    }
}

/// Keeps the first [`MAX_DIAGNOSTICS`] of `diags` (sorted by position) and
/// replaces the rest, with the `omitted` left out before, by one summary line.
pub(crate) fn cap(diags: &mut Vec<Diagnostic>, omitted: usize) {
    let cut = diags.len().saturating_sub(MAX_DIAGNOSTICS);
    let all_errors = diags[MAX_DIAGNOSTICS.min(diags.len())..]
        .iter()
        .all(Diagnostic::is_error);
    diags.truncate(MAX_DIAGNOSTICS);
    if cut + omitted > 0 {
        diags.push(Diagnostic::omitted(cut + omitted, all_errors));
    }
}

/// Renders diagnostics like rustc does (`error: ...`, `--> file:line:col`,
/// the source line, carets under the span, `= help: ...`). `color` adds ANSI colours.
pub fn render(file_name: &str, source: &str, diagnostics: &[Diagnostic], color: bool) -> String {
    let lines = Lines::new(source);
    let config = Config {
        chars: codespan_reporting::term::Chars::ascii(),
        ..Config::default()
    };
    let mut out: Vec<u8> = Vec::new();
    for d in diagnostics {
        let mut spans = vec![d.span];
        if d.omitted == 0 {
            spans.extend(d.secondary.iter().map(|l| l.span));
        }
        let file = Snippet::new(file_name, &lines, if d.omitted == 0 { &spans } else { &[] });
        let cs = to_codespan(d, &file);
        let result = if color {
            let mut w = term::termcolor::Ansi::new(&mut out);
            term::emit_to_write_style(&mut w, &config, &file, &cs)
        } else {
            let mut w = term::termcolor::NoColor::new(&mut out);
            term::emit_to_write_style(&mut w, &config, &file, &cs)
        };
        if result.is_err() {
            // Fall back to a plain line: rendering must never lose a diagnostic.
            let (l, c) = lines.line_col(d.span.start);
            out.extend_from_slice(
                format!("error: {}\n --> {file_name}:{l}:{c}\n", d.message).as_bytes(),
            );
        }
    }
    String::from_utf8_lossy(&out).into_owned()
}

fn to_codespan(d: &Diagnostic, file: &Snippet) -> CsDiagnostic<()> {
    let base = match d.severity {
        Severity::Error => CsDiagnostic::error(),
        Severity::Warning => CsDiagnostic::warning(),
    };
    let range = |s: Span| file.map(s.start)..file.map(s.end);
    let mut labels = Vec::new();
    if d.omitted == 0 {
        labels.push(CsLabel::primary((), range(d.span)).with_message(&d.label));
        for l in &d.secondary {
            labels.push(CsLabel::secondary((), range(l.span)).with_message(&l.message));
        }
    }
    let mut notes = d.notes.clone();
    if let Some(h) = &d.help {
        notes.push(format!("help: {h}"));
    }
    base.with_message(&d.message)
        .with_labels(labels)
        .with_notes(notes)
}

/// A diagnostic in the JSON form printed by `tsfc check --format json`.
#[derive(Debug, Clone, Serialize, schemars::JsonSchema)]
pub struct JsonDiagnostic<'a> {
    /// File name as given.
    pub file: &'a str,
    /// `error` or `warning`.
    pub severity: Severity,
    /// Headline.
    pub message: &'a str,
    /// 1-based start line.
    pub line: usize,
    /// 1-based start column (characters).
    pub column: usize,
    /// 1-based end line.
    pub end_line: usize,
    /// 1-based end column (characters, exclusive).
    pub end_column: usize,
    /// Byte span.
    pub span: Span,
    /// Primary label.
    pub label: &'a str,
    /// Secondary labels.
    pub secondary: &'a [Label],
    /// Notes.
    pub notes: &'a [String],
    /// Help line.
    pub help: Option<&'a str>,
}

/// The JSON view of `d` for `file`.
pub fn to_json<'a>(file: &'a str, source: &str, d: &'a Diagnostic) -> JsonDiagnostic<'a> {
    let lines = Lines::new(source);
    let (line, column) = lines.line_col(d.span.start);
    let (end_line, end_column) = lines.line_col(d.span.end);
    JsonDiagnostic {
        file,
        severity: d.severity,
        message: &d.message,
        line,
        column,
        end_line,
        end_column,
        span: d.span,
        label: &d.label,
        secondary: &d.secondary,
        notes: &d.notes,
        help: d.help.as_deref(),
    }
}
