//! Completion: after `premise is`, the premise's sets; elsewhere the
//! language's keywords and the document's declared names.

use super::document::Document;
use super::symbols::Kind;
use lsp_types::{CompletionItem, CompletionItemKind};
use std::collections::BTreeSet;

/// The keywords of the grammar (`lang/src/tsf.pest`).
pub const KEYWORDS: &[&str] = &[
    "tsf",
    "controller",
    "const",
    "fn",
    "state",
    "input",
    "saturate",
    "disturbance",
    "bound",
    "energy",
    "output",
    "signal",
    "premise",
    "range",
    "sigma",
    "rules",
    "rule",
    "is",
    "and",
    "about",
    "at",
    "objective",
    "for",
    "in",
    "with",
    "relaxation",
    "lyapunov",
    "plant",
    "trigger",
    "emit",
    "precision",
    "simulate",
    "dynamics",
    "monte_carlo",
    "scale",
    "offset",
    "converged",
    "by",
    "sweep",
    "columns",
    "modes",
    "mode",
    "adaptive",
    "estimate",
    "robust",
    "rate",
    "bounds",
    "init",
    "layer",
    "step",
    "minimize",
    "maximize",
    "region",
];

/// The completion items at byte `offset`.
pub fn complete(doc: &Document, offset: usize) -> Vec<CompletionItem> {
    if let Some(premise) = premise_before(&doc.text, offset) {
        return doc
            .index
            .decls
            .iter()
            .filter(|d| d.kind == Kind::Set && d.premise.iter().any(|p| p == premise))
            .map(|d| item(&d.name, CompletionItemKind::ENUM_MEMBER, "fuzzy set"))
            .collect();
    }
    let mut seen = BTreeSet::new();
    let mut out: Vec<CompletionItem> = doc
        .index
        .decls
        .iter()
        .filter(|d| !matches!(d.kind, Kind::Set | Kind::Param) && seen.insert(d.name.as_str()))
        .map(|d| item(&d.name, kind_of(d.kind), d.kind.word()))
        .collect();
    out.extend(
        KEYWORDS
            .iter()
            .filter(|k| !seen.contains(*k))
            .map(|k| item(k, CompletionItemKind::KEYWORD, "keyword")),
    );
    out
}

/// For a cursor after `name is ` (and a partial word), the premise `name`.
fn premise_before(text: &str, offset: usize) -> Option<&str> {
    let before = text.get(..offset.min(text.len()))?;
    let word = |s: &str| {
        s.len()
            - s.trim_end_matches(|c: char| c.is_ascii_alphanumeric() || c == '_')
                .len()
    };
    let rest = &before[..before.len() - word(before)];
    let rest = rest.trim_end();
    let rest = rest.strip_suffix("is")?;
    if rest.len() == rest.trim_end().len() {
        return None; // `...xis`, not the keyword `is`
    }
    let rest = rest.trim_end();
    let n = word(rest);
    (n > 0).then(|| &rest[rest.len() - n..])
}

fn item(label: &str, kind: CompletionItemKind, detail: &str) -> CompletionItem {
    CompletionItem {
        label: label.to_string(),
        kind: Some(kind),
        detail: Some(detail.to_string()),
        ..Default::default()
    }
}

fn kind_of(k: Kind) -> CompletionItemKind {
    match k {
        Kind::Const => CompletionItemKind::CONSTANT,
        Kind::Fn => CompletionItemKind::FUNCTION,
        Kind::Rule | Kind::Mode | Kind::Controller => CompletionItemKind::MODULE,
        _ => CompletionItemKind::VARIABLE,
    }
}

#[cfg(test)]
mod tests {
    use super::premise_before;

    #[test]
    fn finds_the_premise_of_a_clause() {
        assert_eq!(premise_before("rule R1: s is ne", 16), Some("s"));
        assert_eq!(premise_before("rule R1: zeta is ", 17), Some("zeta"));
        assert_eq!(premise_before("rule R1: s is near and q  is", 28), None);
        assert_eq!(premise_before("this", 4), None);
    }
}
