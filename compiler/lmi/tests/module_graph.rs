//! The crate's modules form no circle: every `crate::`, `super::` and
//! `self::` path in `src/` is resolved to the module (file) it names, and the
//! resulting graph must be acyclic. Doc comments do not count; inline test
//! modules do.

use std::collections::{BTreeMap, BTreeSet};
use std::fs;
use std::path::Path;

type Graph = BTreeMap<String, BTreeSet<String>>;

/// Every source file's module path (`""` for `lib.rs`, `"solve::settings"`, ...) and text.
fn sources(dir: &Path, prefix: &str, out: &mut BTreeMap<String, String>) -> std::io::Result<()> {
    let mut entries: Vec<_> = fs::read_dir(dir)?.collect::<Result<_, _>>()?;
    entries.sort_by_key(|e| e.path());
    for entry in entries {
        let path = entry.path();
        let stem = path
            .file_stem()
            .and_then(|s| s.to_str())
            .unwrap_or_default();
        let child = if prefix.is_empty() {
            stem.to_owned()
        } else {
            format!("{prefix}::{stem}")
        };
        if path.is_dir() {
            sources(&path, &child, out)?;
        } else if path.extension().is_some_and(|e| e == "rs") {
            let module = if matches!(stem, "lib" | "mod") {
                prefix.to_owned()
            } else {
                child
            };
            out.insert(module, fs::read_to_string(&path)?);
        }
    }
    Ok(())
}

/// The paths of a use tree at the start of `s` (`a::b`, `a::{b, c::d}`), as
/// segments, and the text after it.
fn use_tree(s: &str) -> (Vec<Vec<String>>, &str) {
    let s = s.trim_start();
    if let Some(mut rest) = s.strip_prefix('{') {
        let mut paths = Vec::new();
        loop {
            rest = rest.trim_start();
            if let Some(after) = rest.strip_prefix('}') {
                return (paths, after);
            }
            let (inner, after) = use_tree(rest);
            if after.len() == rest.len() {
                return (paths, after);
            }
            paths.extend(inner);
            rest = after.trim_start();
            rest = rest.strip_prefix(',').unwrap_or(rest);
        }
    }
    let end = s
        .find(|c: char| !(c.is_alphanumeric() || c == '_' || c == '*'))
        .unwrap_or(s.len());
    let (ident, rest) = s.split_at(end);
    if ident.is_empty() {
        return (vec![vec![]], rest);
    }
    match rest.strip_prefix("::") {
        Some(tail) => {
            let (inner, after) = use_tree(tail);
            let paths = inner
                .into_iter()
                .map(|p| std::iter::once(ident.to_owned()).chain(p).collect())
                .collect();
            (paths, after)
        }
        None => (vec![vec![ident.to_owned()]], rest),
    }
}

/// The text without comment lines, and where its first inline module starts.
fn code(text: &str) -> (String, usize) {
    let mut code = String::new();
    let mut inline_start = usize::MAX;
    for line in text.lines().map(str::trim_start) {
        if line.starts_with("//") {
            continue;
        }
        if line.starts_with("mod ") && line.ends_with('{') {
            inline_start = inline_start.min(code.len());
        }
        code.push_str(line);
        code.push('\n');
    }
    (code, inline_start)
}

/// Start offsets of `prefix` where it begins a path (not the tail of an identifier).
fn path_starts<'a>(code: &'a str, prefix: &'a str) -> impl Iterator<Item = usize> + 'a {
    code.match_indices(prefix)
        .map(|(at, _)| at)
        .filter(move |&at| !code[..at].ends_with(|c: char| c.is_alphanumeric() || c == '_'))
}

/// The deepest module named by `segments` below `base`, through `reexports` at the root.
fn resolve(
    modules: &BTreeSet<String>,
    reexports: &BTreeMap<String, String>,
    base: &str,
    segments: &[String],
) -> Option<String> {
    let mut current = base.to_owned();
    for seg in segments {
        let next = if current.is_empty() {
            seg.clone()
        } else {
            format!("{current}::{seg}")
        };
        if modules.contains(&next) {
            current = next;
        } else if current.is_empty() {
            return reexports.get(seg).cloned();
        } else {
            break;
        }
    }
    Some(current)
}

/// The module graph of the crate's `src/`, with the paths that did not resolve.
fn module_graph(src: &Path) -> std::io::Result<(Graph, Vec<String>)> {
    let mut files = BTreeMap::new();
    sources(src, "", &mut files)?;
    let modules: BTreeSet<String> = files.keys().cloned().collect();
    let (root, _) = code(files.get("").map_or("", String::as_str));
    let mut reexports = BTreeMap::new();
    for at in path_starts(&root, "pub use ") {
        for path in use_tree(&root[at + "pub use ".len()..]).0 {
            if let (Some(name), Some(module)) =
                (path.last(), resolve(&modules, &BTreeMap::new(), "", &path))
            {
                reexports.insert(name.clone(), module);
            }
        }
    }
    let mut graph = Graph::new();
    let mut unresolved = Vec::new();
    for (module, text) in files.iter().filter(|(m, _)| !m.is_empty()) {
        let parent = module.rsplit_once("::").map_or("", |(p, _)| p);
        let (code, inline_start) = code(text);
        for prefix in ["crate::", "self::", "super::"] {
            for at in path_starts(&code, prefix) {
                let base = match prefix {
                    "crate::" => "",
                    // `super` inside an inline module is the file's own module.
                    "super::" if at < inline_start => parent,
                    _ => module.as_str(),
                };
                for path in use_tree(&code[at + prefix.len()..]).0 {
                    match resolve(&modules, &reexports, base, &path) {
                        Some(target) if target != *module && !target.is_empty() => {
                            graph.entry(module.clone()).or_default().insert(target);
                        }
                        Some(_) => {}
                        None => unresolved.push(format!("{module}: {prefix}{}", path.join("::"))),
                    }
                }
            }
        }
        graph.entry(module.clone()).or_default();
    }
    Ok((graph, unresolved))
}

/// A circle of the graph, if there is one (depth-first search).
fn find_cycle(graph: &Graph) -> Option<Vec<String>> {
    fn visit(
        graph: &Graph,
        node: &str,
        stack: &mut Vec<String>,
        done: &mut BTreeSet<String>,
    ) -> Option<Vec<String>> {
        if let Some(start) = stack.iter().position(|n| n == node) {
            let mut cycle = stack[start..].to_vec();
            cycle.push(node.to_owned());
            return Some(cycle);
        }
        if done.contains(node) {
            return None;
        }
        stack.push(node.to_owned());
        for next in graph.get(node).into_iter().flatten() {
            if let Some(cycle) = visit(graph, next, stack, done) {
                return Some(cycle);
            }
        }
        stack.pop();
        done.insert(node.to_owned());
        None
    }
    let mut done = BTreeSet::new();
    graph
        .keys()
        .find_map(|node| visit(graph, node, &mut Vec::new(), &mut done))
}

#[test]
fn modules_form_no_circle() -> std::io::Result<()> {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let (graph, unresolved) = module_graph(&src)?;
    for (module, targets) in &graph {
        let targets: Vec<&str> = targets.iter().map(String::as_str).collect();
        println!("{module} -> {}", targets.join(", "));
    }
    assert!(unresolved.is_empty(), "unresolved paths: {unresolved:?}");
    assert!(graph.len() > 10, "too few modules found: {graph:?}");
    assert_eq!(find_cycle(&graph), None);
    Ok(())
}

#[test]
fn the_checker_sees_grouped_imports_and_circles() {
    let (paths, rest) = use_tree("{a::{B, c::D},\n    e::F,\n};");
    assert_eq!(rest, ";");
    let expected: Vec<Vec<String>> = [&["a", "B"][..], &["a", "c", "D"], &["e", "F"]]
        .iter()
        .map(|p| p.iter().map(|s| s.to_string()).collect())
        .collect();
    assert_eq!(paths, expected);
    let mut graph = Graph::new();
    for (from, to) in [("a", "b"), ("b", "c"), ("c", "a"), ("c", "d")] {
        graph.entry(from.into()).or_default().insert(to.into());
    }
    assert_eq!(
        find_cycle(&graph),
        Some(vec!["a".into(), "b".into(), "c".into(), "a".into()])
    );
    graph.entry("c".into()).or_default().remove("a");
    assert_eq!(find_cycle(&graph), None);
}
