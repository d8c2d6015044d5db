//! Tidy tests, in the style of rust-analyzer's: they read the workspace's own
//! sources as text and fail with a list of `file:line` violations, so the
//! architecture's invariants stay true without anyone remembering them.
//!
//! - `tidy_stages_flow_one_way`: the top-level modules of `compiler/src` are
//!   stages with a rank ([`RANKS`]); a stage uses only stages of a lower rank.
//! - `tidy_file_and_function_length`: no source file over [`MAX_FILE_LINES`]
//!   lines, no function over [`MAX_FN_LINES`] lines.
//!
//! Code under `#[cfg(test)]`, `tests.rs` files and `tests/` folders is left
//! out. The sources are read by a small lexer (`tidy/lex.rs`) that knows comments,
//! strings (raw, byte, C), chars and lifetimes, so a `{` or a `crate::` path
//! inside a string or a comment is never taken for code.

use std::path::{Path, PathBuf};

/// The rank of each stage (top-level module of `compiler/src`), low to high.
/// A file of rank R may use stage T only if rank(T) < R, or T is its own
/// stage; stages of the same rank (util and tape; codegen, sim and report; lsp and review) do
/// not use each other. `lib.rs`, `main.rs` and `bin/` are the top ([`TOP`]).
/// A new top-level module fails the test until it is placed here.
const RANKS: &[(&str, u8)] = &[
    // Shared utilities (RNG, hashing, atomic output) and the expression tape.
    ("util", 0),
    ("tape", 0),
    // The stages of the pipeline, in its order.
    ("model", 1),
    ("synth", 2),
    ("certify", 3),
    ("tables", 4),
    // Three consumers of a certified design, side by side.
    ("codegen", 5),
    ("sim", 5),
    ("report", 5),
    // The one driver that sequences the stages.
    ("driver", 6),
    // Tools built on the driver, side by side: the language server and the
    // design review page.
    ("lsp", 7),
    ("review", 7),
];

/// Rank of the crate root and the binaries (`lib.rs`, `main.rs`, `bin/`).
const TOP: u8 = 8;
/// Stage name of the crate root and the binaries in messages.
const TOP_STAGE: &str = "(crate root)";
/// Longest source file, in lines (the whole file, unit tests included).
const MAX_FILE_LINES: usize = 1000;
/// Longest function, from its `fn` line to its closing brace.
const MAX_FN_LINES: usize = 150;
/// Source folders whose files and functions are held to the limits.
const LENGTH_CHECKED: &[&str] = &[
    "lang/src",
    "compiler/src",
    "runtime/src",
    "compiler/lmi/src",
    "compiler/lapack/src",
];

mod checks;
mod items;
mod lex;
mod stages;

use items::{length_violations, undocumented};
use stages::stage_violations;

/// The workspace root (the parent of the `tests` crate).
fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("the tests crate lives in the workspace") // ok: fixed layout
        .to_path_buf()
}

/// Whether a path (relative, `/`-separated) is test code by its name.
fn is_test_path(rel: &str) -> bool {
    rel.split('/').any(|c| c == "tests") || rel.ends_with("tests.rs")
}

/// Every non-test `.rs` file under `dir`, as (path relative to `dir`, text),
/// sorted by path.
fn sources(dir: &Path) -> Vec<(String, String)> {
    fn walk(dir: &Path, root: &Path, out: &mut Vec<(String, String)>) {
        let entries = std::fs::read_dir(dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
        for entry in entries {
            let path = entry.expect("a directory entry").path(); // ok: test helper
            if path.is_dir() {
                walk(&path, root, out);
            } else if path.extension().is_some_and(|e| e == "rs") {
                let rel = path.strip_prefix(root).expect("under the root"); // ok: walked from root
                let rel = rel.to_string_lossy().replace('\\', "/");
                if !is_test_path(&rel) {
                    let text = std::fs::read_to_string(&path)
                        .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
                    out.push((rel, text));
                }
            }
        }
    }
    let mut out = Vec::new();
    walk(dir, dir, &mut out);
    out.sort();
    out
}

/// Panics with the numbered list of violations, if any.
fn assert_none(what: &str, violations: &[String]) {
    if violations.is_empty() {
        return;
    }
    let list: Vec<String> = violations
        .iter()
        .enumerate()
        .map(|(k, v)| format!("{:>3}. {v}", k + 1))
        .collect();
    panic!(
        "{what}: {} violations\n{}\n",
        violations.len(),
        list.join("\n")
    );
}

#[test]
fn tidy_stages_flow_one_way() {
    let files = sources(&workspace().join("compiler/src"));
    assert!(files.len() > 20, "compiler/src has {} files", files.len());
    assert_none(
        "stages of compiler/src used against the pipeline's direction \
         (rank table: RANKS in tests/tests/tidy.rs)",
        &stage_violations(&files),
    );
}

#[test]
fn tidy_file_and_function_length() {
    let mut violations = Vec::new();
    for dir in LENGTH_CHECKED {
        violations.extend(length_violations(dir, &sources(&workspace().join(dir))));
    }
    assert_none("files or functions too long", &violations);
}

#[test]
fn tidy_docs() {
    let mut violations = Vec::new();
    for (rel, src) in sources(&workspace().join("compiler/src")) {
        for (line, name) in undocumented(&src) {
            violations.push(format!(
                "compiler/src/{rel}:{line}: pub {name} has no doc comment"
            ));
        }
    }
    assert_none("public items without a doc comment", &violations);
}
