//! An open document: its text, the diagnostics of `tsfc check` on it, its
//! parse and symbol index, and the T-S model of its last valid version.

use super::position::LineIndex;
use super::symbols::Index;
use crate::driver::frontend::{self, Source};
use crate::model::TsModel;
use crate::util::output::MAX_SPEC_BYTES;
use lsp_types::{DiagnosticRelatedInformation, DiagnosticSeverity, Location, NumberOrString, Uri};
use std::sync::Arc;
use tsf_lang::ast::File;
use tsf_lang::{Diagnostic, Severity, Span};

/// One open document, analysed.
pub struct Document {
    /// The text as the editor has it.
    pub text: String,
    /// Line starts of `text`.
    pub lines: LineIndex,
    /// The diagnostics `tsfc check` gives for `text`.
    pub diagnostics: Vec<Diagnostic>,
    /// The parse (empty past the size limit).
    pub file: File,
    /// Declarations and resolved identifiers (empty past the size limit).
    pub index: Index,
    /// The model of this text, when it checks clean.
    pub model: Option<Arc<TsModel>>,
    /// The model of the last version that checked clean (hover falls back to it).
    pub last_good: Option<Arc<TsModel>>,
}

impl Document {
    /// Analyses `text`; `previous` gives the last valid model of an earlier version.
    pub fn new(text: String, previous: Option<&Document>) -> Self {
        let lines = LineIndex::new(&text);
        let last = previous.and_then(|p| p.last_good.clone());
        if text.len() as u64 > MAX_SPEC_BYTES {
            let message = format!(
                "the document is larger than the limit of {} MiB: it is not checked",
                MAX_SPEC_BYTES >> 20
            );
            return Document {
                diagnostics: vec![Diagnostic::error(Span::new(0, 0), message).with_help(
                    "a spec of this size is refused by `tsfc check` too (docs/limits.md)",
                )],
                text,
                lines,
                file: File::default(),
                index: Index::default(),
                model: None,
                last_good: last,
            };
        }
        let source = Source {
            name: String::new(),
            bytes: text.as_bytes().to_vec(),
            text,
        };
        let (checked, file) = frontend::check_parsed(&source);
        let text = source.text;
        let index = Index::build(&text, &file);
        let model = checked.model.map(Arc::new);
        Document {
            last_good: model.clone().or(last),
            diagnostics: checked.diagnostics,
            text,
            lines,
            file,
            index,
            model,
        }
    }

    /// The model for hovers: this version's, else the last valid one (`true` when stale).
    pub fn hover_model(&self) -> Option<(&TsModel, bool)> {
        match (&self.model, &self.last_good) {
            (Some(m), _) => Some((m, false)),
            (None, Some(m)) => Some((m, true)),
            _ => None,
        }
    }

    /// The diagnostics in LSP form for the document `uri`.
    pub fn lsp_diagnostics(&self, uri: &Uri) -> Vec<lsp_types::Diagnostic> {
        self.diagnostics
            .iter()
            .map(|d| self.lsp_diagnostic(uri, d))
            .collect()
    }

    fn lsp_diagnostic(&self, uri: &Uri, d: &Diagnostic) -> lsp_types::Diagnostic {
        let mut message = d.message.clone();
        if !d.label.is_empty() && d.label != d.message {
            message.push_str(&format!("\n{}", d.label));
        }
        for n in &d.notes {
            message.push_str(&format!("\nnote: {n}"));
        }
        if let Some(h) = &d.help {
            message.push_str(&format!("\nhelp: {h}"));
        }
        let related: Vec<DiagnosticRelatedInformation> = d
            .secondary
            .iter()
            .map(|l| DiagnosticRelatedInformation {
                location: Location::new(uri.clone(), self.lines.range(&self.text, l.span)),
                message: l.message.clone(),
            })
            .collect();
        lsp_types::Diagnostic {
            range: self.lines.range(&self.text, d.span),
            severity: Some(match d.severity {
                Severity::Error => DiagnosticSeverity::ERROR,
                Severity::Warning => DiagnosticSeverity::WARNING,
            }),
            code: None::<NumberOrString>,
            source: Some("tsfc".into()),
            message,
            related_information: (!related.is_empty()).then_some(related),
            ..Default::default()
        }
    }

    /// The text under `span`, at most `max` bytes (cut at a char boundary, `...` added).
    pub fn snippet(&self, span: Span, max: usize) -> String {
        let end = span.end.min(self.text.len());
        let start = span.start.min(end);
        let mut cut = end.min(start + max);
        while !self.text.is_char_boundary(cut) {
            cut -= 1;
        }
        let mut s = self.text.get(start..cut).unwrap_or_default().to_string();
        if cut < end {
            s.push_str(" ...");
        }
        s
    }
}
