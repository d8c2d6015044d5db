//! Splits a source file into top-level items before parsing, so that a syntax
//! error in one item does not hide the errors in the others.
//!
//! An item ends at a `;` outside any bracket, or at the `}` that closes a block
//! opened at the top level. Comments are skipped. Unbalanced brackets are
//! reported with the span of the opening (or stray closing) bracket.

use crate::diag::Diagnostic;
use crate::span::Span;

/// A top-level chunk of source: `source[span.start..span.end]`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Chunk {
    /// Where the item is.
    pub span: Span,
    /// Whether a bracket error was found in it (it is not parsed then).
    pub broken: bool,
}

fn closer(open: u8) -> u8 {
    match open {
        b'(' => b')',
        b'[' => b']',
        _ => b'}',
    }
}

/// Splits `source` into item chunks; bracket errors go to `diags`.
pub fn split_items(source: &str, diags: &mut Vec<Diagnostic>) -> Vec<Chunk> {
    let bytes = source.as_bytes();
    let mut chunks = Vec::new();
    let mut stack: Vec<(u8, usize)> = Vec::new();
    let mut start: Option<usize> = None;
    let mut i = 0;
    while i < bytes.len() {
        let b = bytes[i];
        if b == b'/' && bytes.get(i + 1) == Some(&b'/') {
            while i < bytes.len() && bytes[i] != b'\n' {
                i += 1;
            }
            continue;
        }
        if b == b'/' && bytes.get(i + 1) == Some(&b'*') {
            let open = i;
            i += 2;
            loop {
                if i + 1 >= bytes.len() {
                    diags.push(
                        Diagnostic::error(Span::new(open, open + 2), "unterminated comment")
                            .with_label("this comment is never closed")
                            .with_help("close it with `*/`"),
                    );
                    i = bytes.len();
                    break;
                }
                if bytes[i] == b'*' && bytes[i + 1] == b'/' {
                    i += 2;
                    break;
                }
                i += 1;
            }
            continue;
        }
        if b.is_ascii_whitespace() {
            i += 1;
            continue;
        }
        let item_start = *start.get_or_insert(i);
        match b {
            b'(' | b'[' | b'{' => stack.push((b, i)),
            b')' | b']' | b'}' => match stack.last() {
                Some(&(open, _)) if closer(open) == b => {
                    stack.pop();
                    if b == b'}' && stack.is_empty() {
                        chunks.push(Chunk {
                            span: Span::new(item_start, i + 1),
                            broken: false,
                        });
                        start = None;
                    }
                }
                Some(&(open, at)) => {
                    diags.push(
                        Diagnostic::error(
                            Span::new(i, i + 1),
                            format!("mismatched `{}`", b as char),
                        )
                        .with_label(format!("expected `{}` here", closer(open) as char))
                        .with_secondary(Span::new(at, at + 1), "unclosed bracket opened here"),
                    );
                    // Recover: drop the rest of this item.
                    stack.clear();
                    i = skip_broken_item(bytes, i, item_start, &mut chunks);
                    start = None;
                    continue;
                }
                None => {
                    diags.push(
                        Diagnostic::error(
                            Span::new(i, i + 1),
                            format!("unexpected `{}`", b as char),
                        )
                        .with_label("nothing opened this bracket"),
                    );
                    i = skip_broken_item(bytes, i, item_start, &mut chunks);
                    start = None;
                    continue;
                }
            },
            b';' if stack.is_empty() => {
                chunks.push(Chunk {
                    span: Span::new(item_start, i + 1),
                    broken: false,
                });
                start = None;
            }
            _ => {}
        }
        i += 1;
    }
    if let Some(&(open, at)) = stack.first() {
        if let Some(s) = start {
            chunks.push(Chunk {
                span: Span::new(s, bytes.len()),
                broken: true,
            });
        }
        let what = if open == b'{' { "block" } else { "bracket" };
        diags.push(
            Diagnostic::error(Span::new(at, at + 1), format!("unterminated {what}"))
                .with_label(format!("this `{}` is never closed", open as char))
                .with_help(format!("add the matching `{}`", closer(open) as char)),
        );
    } else if let Some(s) = start {
        // Trailing text without a terminating `;`: parse it anyway so the
        // parser can say what is missing.
        chunks.push(Chunk {
            span: Span::new(s, bytes.len()),
            broken: false,
        });
    }
    chunks
}

/// After a bracket error at `i`: records the item from `item_start` as broken
/// up to the next `;` and returns the index after it.
fn skip_broken_item(bytes: &[u8], i: usize, item_start: usize, chunks: &mut Vec<Chunk>) -> usize {
    let end = skip_to_item_end(bytes, i + 1);
    chunks.push(Chunk {
        span: Span::new(item_start, end),
        broken: true,
    });
    end
}

/// After a bracket error: the index after the next top-level `;` (or the end).
fn skip_to_item_end(bytes: &[u8], mut i: usize) -> usize {
    while i < bytes.len() {
        if bytes[i] == b';' {
            return i + 1;
        }
        i += 1;
    }
    i
}

#[cfg(test)]
mod tests {
    use super::*;

    fn texts(src: &str) -> (Vec<&str>, usize) {
        let mut d = Vec::new();
        let c = split_items(src, &mut d);
        (
            c.iter()
                .filter(|c| !c.broken)
                .map(|c| &src[c.span.start..c.span.end])
                .collect(),
            d.len(),
        )
    }

    #[test]
    fn splits_statements_and_blocks() {
        let (t, e) =
            texts("tsf 1; // c;\n premise a { x = tri(0, 1, 2); } rule R: a is x => A = [1; 2];");
        assert_eq!(
            t,
            vec![
                "tsf 1;",
                "premise a { x = tri(0, 1, 2); }",
                "rule R: a is x => A = [1; 2];"
            ]
        );
        assert_eq!(e, 0);
    }

    #[test]
    fn unterminated_block_is_reported() {
        let (_, e) = texts("tsf 1; premise a { x = tri(0,1,2);");
        assert_eq!(e, 1);
    }

    #[test]
    fn mismatched_bracket_recovers() {
        let (t, e) = texts("const a = [1, 2); const b = 2;");
        assert_eq!(e, 1);
        assert_eq!(t, vec!["const b = 2;"]);
    }
}
