//! Items of a source file: functions with their length, public items
//! without a doc comment.

use super::lex::{lex, matching, non_test, Kind};
use super::{MAX_FILE_LINES, MAX_FN_LINES};

/// A function: its name, the line of its `fn` and its length in lines.
#[derive(Debug, PartialEq, Eq)]
pub(super) struct Function {
    pub(super) name: String,
    pub(super) line: usize,
    pub(super) lines: usize,
}

/// Every function with a body in the code compiled outside tests.
pub(super) fn functions(src: &str) -> Vec<Function> {
    let tokens = non_test(&lex(src));
    let mut out = Vec::new();
    for i in 0..tokens.len().saturating_sub(1) {
        if !(tokens[i].is_ident("fn") && tokens[i + 1].kind == Kind::Ident) {
            continue; // `fn(u8) -> u8` is a type, `fn $name` a macro's
        }
        let mut depth = 0usize;
        for k in i + 2..tokens.len() {
            let t = &tokens[k];
            if t.is_punct('(') || t.is_punct('[') {
                depth += 1;
            } else if t.is_punct(')') || t.is_punct(']') {
                depth = depth.saturating_sub(1);
            } else if t.is_punct(';') && depth == 0 {
                break; // a declaration without a body
            } else if t.is_punct('{') && depth == 0 {
                let close = matching(&tokens, k);
                let end = tokens.get(close).map_or(tokens[k].line, |t| t.line);
                out.push(Function {
                    name: tokens[i + 1].text.clone(),
                    line: tokens[i].line,
                    lines: end - tokens[i].line + 1,
                });
                break;
            }
        }
    }
    out
}

/// Files over [`MAX_FILE_LINES`] and functions over [`MAX_FN_LINES`] among
/// `files` (relative to `dir`).
pub(super) fn length_violations(dir: &str, files: &[(String, String)]) -> Vec<String> {
    let mut out = Vec::new();
    for (rel, src) in files {
        let lines = src.lines().count();
        if lines > MAX_FILE_LINES {
            out.push(format!(
                "{dir}/{rel}: {lines} lines (limit {MAX_FILE_LINES}): split it by domain"
            ));
        }
        for f in functions(src) {
            if f.lines > MAX_FN_LINES {
                out.push(format!(
                    "{dir}/{rel}:{}: fn {} is {} lines (limit {MAX_FN_LINES})",
                    f.line, f.name, f.lines
                ));
            }
        }
    }
    out
}

/// The public functions, structs, enums and traits without a doc comment, as
/// (line, name).
pub(super) fn undocumented(src: &str) -> Vec<(usize, String)> {
    let tokens = non_test(&lex(src));
    let mut out = Vec::new();
    let mut doc = false;
    let mut k = 0;
    while k < tokens.len() {
        let t = &tokens[k];
        if t.kind == Kind::Doc {
            doc = true;
        } else if t.is_punct('#') && tokens.get(k + 1).is_some_and(|n| n.is_punct('[')) {
            doc |= tokens.get(k + 2).is_some_and(|n| n.is_ident("doc"));
            k = matching(&tokens, k + 1) + 1;
            continue; // an attribute keeps the doc comment above it
        } else if t.kind == Kind::Ident
            && tokens.get(k + 1).is_some_and(|n| n.is_punct('!'))
            && tokens
                .get(k + 2)
                .is_some_and(|n| "([{".contains(n.text.as_str()))
        {
            // A macro's body (`quote! { … }`) is generated code, not this crate's API.
            k = matching(&tokens, k + 2) + 1;
            doc = false;
            continue;
        } else if t.is_ident("pub") {
            let item = tokens[k + 1..].iter().take(4).position(|n| {
                ["fn", "struct", "enum", "trait"]
                    .iter()
                    .any(|w| n.is_ident(w))
            });
            let plain = !tokens.get(k + 1).is_some_and(|n| n.is_punct('('));
            if let (Some(p), true) = (item, plain) {
                if !doc {
                    let name = tokens.get(k + 2 + p).map_or("", |n| n.text.as_str());
                    out.push((t.line, name.to_string()));
                }
            }
            doc = false;
        } else {
            doc = false;
        }
        k += 1;
    }
    out
}
