//! Property test: mutated shipped specs and arbitrary text never make the
//! checker panic, and every diagnostic span lies inside the input. Nesting-
//! and size-heavy generators push expressions to the front end's limits and
//! past them: within a limit there is no limit error, past it there is one.

use proptest::prelude::*;
use std::path::Path;
use tsf_lang::limits::{MAX_EXPR_DEPTH, MAX_NESTING};
use tsfc::driver::frontend::{self, Source};

fn corpus() -> Vec<String> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut out = Vec::new();
    for dir in [
        root.join("../specs"),
        root.join("bad"),
        root.join("fuzz_seeds"),
    ] {
        let Ok(rd) = std::fs::read_dir(&dir) else {
            continue;
        };
        let mut paths: Vec<_> = rd
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|e| e == "tsf"))
            .collect();
        paths.sort();
        for p in paths {
            if let Ok(t) = std::fs::read_to_string(&p) {
                out.push(t);
            }
        }
    }
    assert!(out.len() >= 3, "corpus is empty");
    out
}

/// Splits text into rough tokens (words, numbers, single punctuation, spaces).
pub(crate) fn tokens(s: &str) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    let mut cur = String::new();
    for ch in s.chars() {
        if ch.is_alphanumeric() || ch == '_' || ch == '.' {
            cur.push(ch);
        } else {
            if !cur.is_empty() {
                out.push(std::mem::take(&mut cur));
            }
            out.push(ch.to_string());
        }
    }
    if !cur.is_empty() {
        out.push(cur);
    }
    out
}

/// One edit of a spec's tokens or bytes.
#[derive(Debug, Clone)]
pub(crate) enum Mutation {
    DeleteToken(usize),
    DuplicateToken(usize),
    SwapTokens(usize, usize),
    DeleteByte(usize),
    InsertByte(usize, u8),
    ReplaceByte(usize, u8),
    InsertText(usize, String),
}

/// `text` with `muts` applied: token edits first, then byte edits.
pub(crate) fn apply(text: &str, muts: &[Mutation]) -> Vec<u8> {
    let mut toks = tokens(text);
    let mut bytes: Vec<u8>;
    for m in muts {
        let n = toks.len().max(1);
        match m {
            Mutation::DeleteToken(i) if !toks.is_empty() => {
                toks.remove(i % n);
            }
            Mutation::DuplicateToken(i) if !toks.is_empty() => {
                let t = toks[i % n].clone();
                toks.insert(i % n, t);
            }
            Mutation::SwapTokens(i, j) if !toks.is_empty() => toks.swap(i % n, j % n),
            _ => {}
        }
    }
    bytes = toks.concat().into_bytes();
    for m in muts {
        let n = bytes.len().max(1);
        match m {
            Mutation::DeleteByte(i) if !bytes.is_empty() => {
                bytes.remove(i % n);
            }
            Mutation::InsertByte(i, b) => bytes.insert(i % (bytes.len() + 1), *b),
            Mutation::ReplaceByte(i, b) if !bytes.is_empty() => bytes[i % n] = *b,
            Mutation::InsertText(i, t) => {
                let at = i % (bytes.len() + 1);
                bytes.splice(at..at, t.bytes());
            }
            _ => {}
        }
    }
    bytes
}

/// A random [`Mutation`].
pub(crate) fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        any::<usize>().prop_map(Mutation::DeleteToken),
        any::<usize>().prop_map(Mutation::DuplicateToken),
        (any::<usize>(), any::<usize>()).prop_map(|(a, b)| Mutation::SwapTokens(a, b)),
        any::<usize>().prop_map(Mutation::DeleteByte),
        (any::<usize>(), any::<u8>()).prop_map(|(a, b)| Mutation::InsertByte(a, b)),
        (any::<usize>(), any::<u8>()).prop_map(|(a, b)| Mutation::ReplaceByte(a, b)),
        (
            any::<usize>(),
            prop_oneof![
                Just("{".to_string()),
                Just("}".into()),
                Just("[".into()),
                Just("/*".into()),
                Just("'".into()),
                Just("1e999".into()),
                Just("inv(".into()),
                Just(";".into()),
                Just("..".into()),
                Just("é∂".into())
            ]
        )
            .prop_map(|(a, t)| Mutation::InsertText(a, t)),
    ]
}

fn check_bytes(bytes: Vec<u8>) -> Result<(), TestCaseError> {
    check_messages(bytes).map(|_| ())
}

/// Checks `bytes` like [`check_bytes`]; the messages of the errors.
fn check_messages(bytes: Vec<u8>) -> Result<Vec<String>, TestCaseError> {
    let source = Source {
        name: "fuzz.tsf".into(),
        text: String::from_utf8_lossy(&bytes).into_owned(),
        bytes,
    };
    let checked = frontend::check(&source);
    for d in &checked.diagnostics {
        prop_assert!(
            d.span.start <= d.span.end && d.span.end <= source.text.len(),
            "span {:?} outside input of {} bytes",
            d.span,
            source.text.len()
        );
        for l in &d.secondary {
            prop_assert!(
                l.span.end <= source.text.len(),
                "secondary span {:?} outside input",
                l.span
            );
        }
        prop_assert!(!d.message.is_empty());
    }
    // Rendering must not panic either.
    let _ = tsf_lang::diag::render(&source.name, &source.text, &checked.diagnostics, false);
    Ok(checked
        .diagnostics
        .into_iter()
        .filter(|d| d.is_error())
        .map(|d| d.message)
        .collect())
}

/// A valid spec with a vector constant `v` and a function `f`, to which one
/// generated item is appended.
const BASE: &str = "tsf 1; controller c; state x1; input u; A = -1; B = 1;\n\
    premise x1 range -1 .. 1 { all = trap(-1, -1, 1, 1); }\n\
    rule R: x1 is all => A = -2;\nconst v = [0];\nfn f(a) = a;\n";

/// Ways to wrap an expression in one more level of nesting (each counts one
/// level towards `MAX_NESTING`): an opening and a closing text.
const WRAPPERS: [(&str, &str); 8] = [
    ("(", ")"),
    ("[", "]"),
    ("abs(", ")"),
    ("f(", ")"),
    ("v[", "]"),
    ("-", ""),
    ("1 ^ ", ""),
    ("[1, ", "; 2, 3]"),
];

/// `inner` wrapped by `levels` (indices into [`WRAPPERS`], outermost first).
fn nested(levels: &[usize], inner: &str) -> String {
    let open: String = levels.iter().map(|&w| WRAPPERS[w].0).collect();
    let close: String = levels.iter().rev().map(|&w| WRAPPERS[w].1).collect();
    format!("{open}{inner}{close}")
}

/// Whether an error names the limit starting with `what`.
fn has_limit_error(errors: &[String], what: &str) -> bool {
    errors.iter().any(|m| m.starts_with(what))
}

fn cases() -> u32 {
    std::env::var("TSFC_FUZZ_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(10_000)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(cases()))]

    #[test]
    fn mutated_specs_never_panic(which in any::<usize>(), muts in proptest::collection::vec(mutation(), 1..6)) {
        let corpus = corpus();
        let text = &corpus[which % corpus.len()];
        check_bytes(apply(text, &muts))?;
    }

    #[test]
    fn arbitrary_utf8_never_panics(s in "\\PC{0,400}") {
        check_bytes(s.into_bytes())?;
    }

    #[test]
    fn arbitrary_bytes_never_panic(b in proptest::collection::vec(any::<u8>(), 0..300)) {
        check_bytes(b)?;
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(cases() / 10))]

    /// Mixed nesting of every kind, in a constant or an unused function, up
    /// to twice the limit: one nesting error exactly when it is too deep.
    #[test]
    fn deep_nesting_is_checked_or_one_error(
        levels in proptest::collection::vec(0..WRAPPERS.len(), 0..2 * MAX_NESTING),
        in_fn in any::<bool>(),
    ) {
        let item = if in_fn {
            format!("fn g(a) = {};", nested(&levels, "a"))
        } else {
            format!("const k = {};", nested(&levels, "1"))
        };
        let errors = check_messages(format!("{BASE}{item}").into_bytes())?;
        let too_deep = has_limit_error(&errors, "nesting deeper than");
        prop_assert_eq!(too_deep, levels.len() > MAX_NESTING, "{:?}", errors);
        if too_deep {
            prop_assert_eq!(errors.len(), 1, "{:?}", errors);
        }
    }

    /// Flat chains of operators, up to three times the depth limit: a chain
    /// of `+` longer than the limit is one error, a shorter chain of any
    /// operators is none.
    #[test]
    fn long_chains_are_checked_or_one_error(
        ops in proptest::collection::vec(0..5usize, 0..3 * MAX_EXPR_DEPTH),
        sums_only in any::<bool>(),
    ) {
        let mut expr = String::from("x1");
        for &op in &ops {
            expr.push_str([" + ", " - ", " * ", " .* ", " / "][if sums_only { 0 } else { op }]);
            expr.push_str(if op % 2 == 0 { "2" } else { "x1" });
        }
        let item = format!("premise z = {expr} range -1 .. 1 {{ all = trap(-1, -1, 1, 1); }}");
        let errors = check_messages(format!("{BASE}{item}").into_bytes())?;
        let too_deep = has_limit_error(&errors, "expression nested too deeply");
        if ops.len() < MAX_EXPR_DEPTH {
            prop_assert!(!too_deep, "{:?}", errors);
        } else if sums_only {
            prop_assert!(too_deep, "{:?}", errors);
            prop_assert_eq!(errors.len(), 1, "{:?}", errors);
        }
    }

    /// Many items and wide matrices: checked without a panic, every span
    /// inside the input (the diagnostics are capped).
    #[test]
    fn many_items_and_wide_matrices_never_panic(
        consts in 0..3000usize,
        width in 0..5000usize,
        broken in proptest::collection::vec(any::<usize>(), 0..400),
    ) {
        let mut src = String::from(BASE);
        for i in 0..consts {
            src.push_str(&format!("const c{i} = {};\n", i % 7));
        }
        let row = vec!["1"; width.max(1)].join(", ");
        src.push_str(&format!("const w = [{row}];\n"));
        let mut bytes = src.into_bytes();
        for b in broken {
            let at = b % (bytes.len() + 1);
            bytes.insert(at, b"@;(["[b % 4]);
        }
        check_bytes(bytes)?;
    }
}
