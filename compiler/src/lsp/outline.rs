//! Document symbols: the outline of the spec's declarations (a premise's
//! sets under the premise).

use super::document::Document;
use super::symbols::Kind;
use lsp_types::{DocumentSymbol, SymbolKind};
use std::collections::HashMap;

/// The outline of `doc`.
#[allow(deprecated)] // `DocumentSymbol::deprecated` must be set to build the struct
pub fn outline(doc: &Document) -> Vec<DocumentSymbol> {
    let mut out: Vec<DocumentSymbol> = Vec::new();
    // Where each premise is in `out` (the last of that name).
    let mut premises: HashMap<&str, usize> = HashMap::new();
    for d in &doc.index.decls {
        let symbol = DocumentSymbol {
            name: d.name.clone(),
            detail: Some(d.kind.word().to_string()),
            kind: symbol_kind(d.kind),
            tags: None,
            deprecated: None,
            range: doc.lines.range(&doc.text, d.item.join(d.span)),
            selection_range: doc.lines.range(&doc.text, d.span),
            children: None,
        };
        match d.kind {
            Kind::Param => {}
            Kind::Set => {
                let parent = d.premise.iter().find_map(|p| premises.get(p.as_str()));
                match parent {
                    Some(&k) => out[k].children.get_or_insert_with(Vec::new).push(symbol),
                    None => out.push(symbol),
                }
            }
            Kind::Premise => {
                premises.insert(&d.name, out.len());
                out.push(symbol);
            }
            _ => out.push(symbol),
        }
    }
    out
}

fn symbol_kind(k: Kind) -> SymbolKind {
    match k {
        Kind::Controller => SymbolKind::MODULE,
        Kind::Const => SymbolKind::CONSTANT,
        Kind::Fn => SymbolKind::FUNCTION,
        Kind::Param => SymbolKind::TYPE_PARAMETER,
        Kind::State | Kind::Input | Kind::Disturbance | Kind::Output | Kind::Signal => {
            SymbolKind::VARIABLE
        }
        Kind::Matrix => SymbolKind::ARRAY,
        Kind::Premise => SymbolKind::NAMESPACE,
        Kind::Set => SymbolKind::ENUM_MEMBER,
        Kind::Rule => SymbolKind::EVENT,
        Kind::Mode => SymbolKind::ENUM,
    }
}
