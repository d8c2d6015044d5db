//! The stage graph of `compiler/src`: every path from one stage into
//! another, checked against the rank table, and the cycles among stages.

use super::lex::{item_end, lex, matching, non_test, Kind, Token};
use super::{RANKS, TOP, TOP_STAGE};
use std::collections::{BTreeMap, BTreeSet};

/// One path from a file of one stage into another stage.
#[derive(Clone, Debug)]
struct Edge {
    /// The file, relative to `compiler/src`.
    file: String,
    line: usize,
    from: String,
    to: String,
    /// The source line, trimmed.
    code: String,
}

impl Edge {
    fn at(&self) -> String {
        format!("compiler/src/{}:{}", self.file, self.line)
    }
}

fn rank(stage: &str) -> Option<u8> {
    if stage == TOP_STAGE {
        return Some(TOP);
    }
    RANKS.iter().find(|(s, _)| *s == stage).map(|&(_, r)| r)
}

/// Whether a file (relative to `compiler/src`) belongs to a binary crate,
/// whose `crate::` paths name the binary's own modules.
fn is_binary(rel: &str) -> bool {
    rel == "main.rs" || rel.starts_with("bin/")
}

/// The stage of a file: its top-level folder or file under `compiler/src`.
fn stage_of(rel: &str) -> String {
    if rel == "lib.rs" || is_binary(rel) {
        return TOP_STAGE.into();
    }
    let first = rel.split('/').next().unwrap_or(rel);
    first.trim_end_matches(".rs").into()
}

/// The module path of a file of the library: `synth/a/b.rs` is
/// `[synth, a, b]`, `synth/a/mod.rs` is `[synth, a]`, `lib.rs` is `[]`.
fn module_path(rel: &str) -> Vec<String> {
    let mut parts: Vec<String> = rel
        .trim_end_matches(".rs")
        .split('/')
        .map(String::from)
        .collect();
    if matches!(
        parts.last().map(String::as_str),
        Some("mod" | "lib" | "main")
    ) {
        parts.pop();
    }
    parts
}

/// The first segments of the use tree starting at `at`: `x::…` gives `x`,
/// `{x::…, y, {z}}` gives `x`, `y` and `z`, each with its line.
fn heads(tokens: &[Token], at: usize) -> Vec<(String, usize)> {
    let Some(t) = tokens.get(at) else {
        return Vec::new();
    };
    if !t.is_punct('{') {
        return match t.kind {
            Kind::Ident | Kind::Punct => vec![(t.text.clone(), t.line)],
            _ => Vec::new(),
        };
    }
    let close = matching(tokens, at);
    let mut out = Vec::new();
    let mut k = at + 1;
    while k < close {
        out.extend(heads(tokens, k));
        // On to the token after the next `,` of this group.
        let mut depth = 0usize;
        while k < close {
            let t = &tokens[k];
            if t.is_punct('{') {
                depth += 1;
            } else if t.is_punct('}') {
                depth -= 1;
            } else if t.is_punct(',') && depth == 0 {
                break;
            }
            k += 1;
        }
        k += 1;
    }
    out
}

/// How the first segment of a path from the crate root resolves.
struct Root {
    /// The top-level modules.
    modules: BTreeSet<String>,
    /// Names `lib.rs` re-exports (`pub use error::Error`), with their stage.
    reexports: BTreeMap<String, String>,
}

impl Root {
    fn new(files: &[(String, String)]) -> Self {
        let modules = files
            .iter()
            .filter(|(rel, _)| rel != "lib.rs" && !is_binary(rel))
            .map(|(rel, _)| stage_of(rel))
            .collect();
        let mut reexports = BTreeMap::new();
        if let Some((_, lib)) = files.iter().find(|(rel, _)| rel == "lib.rs") {
            let tokens = non_test(&lex(lib));
            for k in 0..tokens.len().saturating_sub(2) {
                if !(tokens[k].is_ident("pub") && tokens[k + 1].is_ident("use")) {
                    continue;
                }
                // `pub use stage::…` or `pub use crate::stage::…`.
                let mut at = k + 2;
                if tokens[at].is_ident("crate") || tokens[at].is_ident("self") {
                    at += 2;
                }
                let Some(stage) = tokens.get(at).map(|t| t.text.clone()) else {
                    continue;
                };
                let end = item_end(&tokens, k);
                for w in tokens[(at + 1).min(end)..end].windows(2) {
                    let leaf = w[1].is_punct(',') || w[1].is_punct('}') || w[1].is_punct(';');
                    if w[0].kind == Kind::Ident && leaf && w[0].text != "self" {
                        reexports.insert(w[0].text.clone(), stage.clone());
                    }
                }
            }
        }
        Root { modules, reexports }
    }

    /// The stage a path `crate::<head>` lands in.
    fn resolve(&self, head: &str) -> String {
        if self.modules.contains(head) {
            head.into()
        } else if let Some(stage) = self.reexports.get(head) {
            stage.clone()
        } else {
            TOP_STAGE.into() // defined in lib.rs itself, `self` or a glob
        }
    }
}

/// Every path of one file that leaves its stage: `crate::x`, `crate::{x, y}`,
/// `tsfc::x` and `super::…` chains that climb to the crate root.
fn edges_of(rel: &str, src: &str, root: &Root) -> Vec<Edge> {
    let tokens = non_test(&lex(src));
    let lines: Vec<&str> = src.lines().collect();
    let from = stage_of(rel);
    let base = module_path(rel);
    // Inline modules (`mod x { … }`) open at a brace depth.
    let mut inline: Vec<usize> = Vec::new();
    let mut braces = 0usize;
    let mut out = Vec::new();
    for i in 0..tokens.len() {
        let t = &tokens[i];
        let prev_sep = i > 0 && tokens[i - 1].kind == Kind::PathSep;
        let next_sep = tokens.get(i + 1).is_some_and(|n| n.kind == Kind::PathSep);
        let mut targets = Vec::new();
        if t.is_punct('{') {
            if i >= 2 && tokens[i - 2].is_ident("mod") && tokens[i - 1].kind == Kind::Ident {
                inline.push(braces);
            }
            braces += 1;
        } else if t.is_punct('}') {
            braces = braces.saturating_sub(1);
            if inline.last() == Some(&braces) {
                inline.pop();
            }
        } else if prev_sep || !next_sep {
            // Not the start of a path.
        } else if t.is_ident("tsfc") || (t.is_ident("crate") && !is_binary(rel)) {
            targets = heads(&tokens, i + 2);
        } else if t.is_ident("super") && !is_binary(rel) {
            let mut k = i;
            let mut ups = 0;
            while tokens.get(k).is_some_and(|t| t.is_ident("super"))
                && tokens.get(k + 1).is_some_and(|t| t.kind == Kind::PathSep)
            {
                ups += 1;
                k += 2;
            }
            if ups == base.len() + inline.len() {
                targets = heads(&tokens, k);
            }
        }
        for (head, line) in targets {
            let to = root.resolve(&head);
            if to != from {
                let code = lines.get(line - 1).map_or("", |l| l.trim()).to_string();
                out.push(Edge {
                    file: rel.into(),
                    line,
                    from: from.clone(),
                    to,
                    code,
                });
            }
        }
    }
    out
}

/// One cycle through `start` in the stage graph, as the edges that close it.
fn cycle_through(start: &str, graph: &BTreeMap<String, Vec<Edge>>) -> Option<Vec<Edge>> {
    // Breadth first, so the cycle shown is a shortest one.
    let mut came: BTreeMap<String, Edge> = BTreeMap::new();
    let mut queue = std::collections::VecDeque::from([start.to_string()]);
    while let Some(node) = queue.pop_front() {
        for edge in graph.get(&node).into_iter().flatten() {
            if edge.to == start {
                let mut path = vec![edge.clone()];
                let mut at = node.clone();
                while at != start {
                    let e = came[&at].clone();
                    at = e.from.clone();
                    path.push(e);
                }
                path.reverse();
                return Some(path);
            }
            if !came.contains_key(&edge.to) {
                came.insert(edge.to.clone(), edge.clone());
                queue.push_back(edge.to.clone());
            }
        }
    }
    None
}

/// The cycles among stages: a shortest cycle through each stage that is on
/// one (each cycle once), each hop with one `file:line` that makes it.
fn cycles(edges: &[Edge]) -> Vec<String> {
    // One witness per stage pair: the first in file order.
    let mut graph: BTreeMap<String, Vec<Edge>> = BTreeMap::new();
    for e in edges {
        let out = graph.entry(e.from.clone()).or_default();
        if !out.iter().any(|o| o.to == e.to) {
            out.push(e.clone());
        }
    }
    let mut seen: BTreeSet<BTreeSet<(String, String)>> = BTreeSet::new();
    let mut out = Vec::new();
    for stage in graph.keys() {
        let Some(cycle) = cycle_through(stage, &graph) else {
            continue;
        };
        if !seen.insert(
            cycle
                .iter()
                .map(|e| (e.from.clone(), e.to.clone()))
                .collect(),
        ) {
            continue;
        }
        let names: Vec<&str> = cycle.iter().map(|e| e.from.as_str()).collect();
        let hops: Vec<String> = cycle
            .iter()
            .map(|e| format!("{} -> {} at {}", e.from, e.to, e.at()))
            .collect();
        out.push(format!(
            "cycle {} -> {stage}: {}",
            names.join(" -> "),
            hops.join("; ")
        ));
    }
    out
}

/// Every violation of the stage order among `files` (paths relative to
/// `compiler/src`, non-test files only): unregistered stages, paths against
/// the order (or between stages of one rank), and cycles.
pub(super) fn stage_violations(files: &[(String, String)]) -> Vec<String> {
    let root = Root::new(files);
    let mut out = Vec::new();
    for module in &root.modules {
        if rank(module).is_none() {
            let is_dir = files
                .iter()
                .any(|(r, _)| r.starts_with(&format!("{module}/")));
            let place = if is_dir { "/" } else { ".rs" };
            out.push(format!(
                "compiler/src/{module}{place}: stage `{module}` is not in the rank table: \
                 register it in the rank table (RANKS in tests/tests/tidy.rs)"
            ));
        }
    }
    let edges: Vec<Edge> = files
        .iter()
        .flat_map(|(rel, src)| edges_of(rel, src, &root))
        .collect();
    for e in &edges {
        let (Some(from), Some(to)) = (rank(&e.from), rank(&e.to)) else {
            continue;
        };
        if to >= from {
            let why = if to == from {
                "same rank"
            } else {
                "higher rank"
            };
            out.push(format!(
                "{}: {} (rank {from}) uses {} (rank {to}, {why}): `{}`",
                e.at(),
                e.from,
                e.to,
                e.code
            ));
        }
    }
    out.extend(cycles(&edges));
    out
}
