//! Property test: mutated shipped specs and arbitrary text never make the
//! checker panic, and every diagnostic span lies inside the input.

use proptest::prelude::*;
use std::path::Path;
use tsfc::frontend::{self, Source};

fn corpus() -> Vec<String> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut out = Vec::new();
    for dir in [root.join("../specs"), root.join("bad")] {
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
fn tokens(s: &str) -> Vec<String> {
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

#[derive(Debug, Clone)]
enum Mutation {
    DeleteToken(usize),
    DuplicateToken(usize),
    SwapTokens(usize, usize),
    DeleteByte(usize),
    InsertByte(usize, u8),
    ReplaceByte(usize, u8),
    InsertText(usize, String),
}

fn apply(text: &str, muts: &[Mutation]) -> Vec<u8> {
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

fn mutation() -> impl Strategy<Value = Mutation> {
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
    Ok(())
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
