//! Splits a source file into top-level items before parsing, so that a syntax
//! error in one item does not hide the errors in the others.
//!
//! An item ends at a `;` outside any bracket, or at the `}` that closes a block
//! opened at the top level. Comments and a leading byte-order mark are skipped.
//! Unbalanced brackets are reported with the span of the opening (or stray
//! closing) bracket. The nesting of each item is measured here, on the raw
//! text, because the parser recurses once per level: an item nested deeper
//! than [`MAX_NESTING`] is reported and not parsed.

use crate::diag::{Capped, Diagnostic};
use crate::limits::MAX_NESTING;
use crate::span::Span;

/// A top-level chunk of source: `source[span.start..span.end]`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Chunk {
    /// Where the item is.
    pub span: Span,
    /// Whether a bracket or nesting error was found in it (it is not parsed then).
    pub broken: bool,
}

fn closer(open: u8) -> u8 {
    match open {
        b'(' => b')',
        b'[' => b']',
        _ => b'}',
    }
}

/// The nesting of the current item, as the parser will recurse: one level per
/// open bracket, plus one per pending unary sign or `^` (the precedence parser
/// recurses for each; a lower-precedence operator or a separator ends them).
#[derive(Debug, Default)]
struct Nesting {
    /// Open brackets: the byte, its position, and the pending count outside it.
    open: Vec<(u8, usize, usize)>,
    /// Levels of the enclosing brackets (with the pending operators outside each).
    base: usize,
    /// Pending unary signs and `^` at the current bracket level.
    pending: usize,
    /// Whether the last token ends an operand (so a sign after it is binary).
    after_operand: bool,
    /// Whether the item already went past [`MAX_NESTING`] (reported once).
    too_deep: bool,
}

impl Nesting {
    fn depth(&self) -> usize {
        self.base + self.pending
    }

    /// Counts one level opened by the token at `at`; reports the first level past the limit.
    fn deeper(&mut self, at: Span, diags: &mut Capped) {
        if self.depth() > MAX_NESTING && !self.too_deep {
            self.too_deep = true;
            diags.push_with(|| {
                Diagnostic::error(at, format!("nesting deeper than {MAX_NESTING} levels"))
                    .with_label(format!("level {} starts here", self.depth()))
                    .with_help(format!(
                        "at most {MAX_NESTING} levels of brackets, calls, unary signs and `^` \
                         (MAX_NESTING); move inner parts into `const` or `fn` items"
                    ))
            });
        }
    }

    fn open(&mut self, b: u8, i: usize, diags: &mut Capped) {
        self.open.push((b, i, self.pending));
        self.base += self.pending + 1;
        self.pending = 0;
        self.after_operand = false;
        self.deeper(Span::new(i, i + 1), diags);
    }

    /// Closes the innermost bracket (the caller checked that it matches).
    fn close(&mut self) {
        if let Some((_, _, outside)) = self.open.pop() {
            self.base -= outside + 1;
            self.pending = outside;
        }
        self.after_operand = true;
    }

    /// A sign, `^`, another operator or a separator at `i`.
    fn operator(&mut self, b: u8, i: usize, diags: &mut Capped) {
        let unary = matches!(b, b'+' | b'-') && !self.after_operand;
        if unary || b == b'^' {
            self.pending += 1;
            self.deeper(Span::new(i, i + 1), diags);
        } else {
            self.pending = 0;
        }
        self.after_operand = false;
    }

    /// Forgets everything (a new item, or recovery after a bracket error).
    fn reset(&mut self) {
        *self = Nesting::default();
    }
}

/// The end of the identifier or number starting at `i`, if one starts there.
pub(crate) fn word_end(bytes: &[u8], i: usize) -> Option<usize> {
    let is_digit = |j: usize| bytes.get(j).is_some_and(u8::is_ascii_digit);
    let digits = |mut j: usize| {
        while is_digit(j) {
            j += 1;
        }
        j
    };
    let b = bytes[i];
    if b.is_ascii_alphabetic() || b == b'_' {
        let mut j = i;
        while bytes
            .get(j)
            .is_some_and(|c| c.is_ascii_alphanumeric() || *c == b'_')
        {
            j += 1;
        }
        return Some(j);
    }
    if !(b.is_ascii_digit() || (b == b'.' && is_digit(i + 1))) {
        return None;
    }
    let mut j = digits(i);
    if bytes.get(j) == Some(&b'.') && is_digit(j + 1) {
        j = digits(j + 1);
    }
    if matches!(bytes.get(j), Some(b'e' | b'E')) {
        let sign = usize::from(matches!(bytes.get(j + 1), Some(b'+' | b'-')));
        if is_digit(j + 1 + sign) {
            j = digits(j + 1 + sign);
        }
    }
    Some(j)
}

/// Whether `b` ends a line (a lone `\r` does too).
pub(crate) fn is_line_end(b: u8) -> bool {
    b == b'\n' || b == b'\r'
}

/// Splits `source` into item chunks; bracket and nesting errors go to `diags`.
pub fn split_items(source: &str, diags: &mut Capped) -> Vec<Chunk> {
    let bytes = source.as_bytes();
    let mut chunks = Vec::new();
    let mut nest = Nesting::default();
    let mut start: Option<usize> = None;
    // A byte-order mark is not part of the text.
    let mut i = if source.starts_with('\u{feff}') { 3 } else { 0 };
    while i < bytes.len() {
        let b = bytes[i];
        if b == b'/' && bytes.get(i + 1) == Some(&b'/') {
            while i < bytes.len() && !is_line_end(bytes[i]) {
                i += 1;
            }
            continue;
        }
        if b == b'/' && bytes.get(i + 1) == Some(&b'*') {
            i = skip_block_comment(bytes, i, diags);
            continue;
        }
        if b.is_ascii_whitespace() {
            i += 1;
            continue;
        }
        let item_start = *start.get_or_insert(i);
        if let Some(end) = word_end(bytes, i) {
            nest.after_operand = true;
            i = end;
            continue;
        }
        match b {
            b'(' | b'[' | b'{' => nest.open(b, i, diags),
            b')' | b']' | b'}' => match nest.open.last() {
                Some(&(open, _, _)) if closer(open) == b => {
                    nest.close();
                    if b == b'}' && nest.open.is_empty() {
                        chunks.push(Chunk {
                            span: Span::new(item_start, i + 1),
                            broken: nest.too_deep,
                        });
                        nest.reset();
                        start = None;
                    }
                }
                Some(&(open, at, _)) => {
                    diags.push_with(|| {
                        Diagnostic::error(
                            Span::new(i, i + 1),
                            format!("mismatched `{}`", b as char),
                        )
                        .with_label(format!("expected `{}` here", closer(open) as char))
                        .with_secondary(Span::new(at, at + 1), "unclosed bracket opened here")
                    });
                    // Recover: drop the rest of this item.
                    nest.reset();
                    i = skip_broken_item(bytes, i, item_start, &mut chunks);
                    start = None;
                    continue;
                }
                None => {
                    diags.push_with(|| {
                        Diagnostic::error(
                            Span::new(i, i + 1),
                            format!("unexpected `{}`", b as char),
                        )
                        .with_label("nothing opened this bracket")
                    });
                    nest.reset();
                    i = skip_broken_item(bytes, i, item_start, &mut chunks);
                    start = None;
                    continue;
                }
            },
            b';' if nest.open.is_empty() => {
                chunks.push(Chunk {
                    span: Span::new(item_start, i + 1),
                    broken: nest.too_deep,
                });
                nest.reset();
                start = None;
            }
            b'\'' => nest.after_operand = true,
            _ if b.is_ascii() => nest.operator(b, i, diags),
            _ => {}
        }
        i += 1;
    }
    if let Some(&(open, at, _)) = nest.open.first() {
        if let Some(s) = start {
            chunks.push(Chunk {
                span: Span::new(s, bytes.len()),
                broken: true,
            });
        }
        let what = if open == b'{' { "block" } else { "bracket" };
        diags.push_with(|| {
            Diagnostic::error(Span::new(at, at + 1), format!("unterminated {what}"))
                .with_label(format!("this `{}` is never closed", open as char))
                .with_help(format!("add the matching `{}`", closer(open) as char))
        });
    } else if let Some(s) = start {
        // Trailing text without a terminating `;`: parse it anyway so the
        // parser can say what is missing.
        chunks.push(Chunk {
            span: Span::new(s, bytes.len()),
            broken: nest.too_deep,
        });
    }
    chunks
}

/// Skips the block comment opening at `open`; returns the index after it
/// (the end of the text, reported, if it is never closed).
fn skip_block_comment(bytes: &[u8], open: usize, diags: &mut Capped) -> usize {
    let mut i = open + 2;
    while i + 1 < bytes.len() {
        if bytes[i] == b'*' && bytes[i + 1] == b'/' {
            return i + 2;
        }
        i += 1;
    }
    diags.push_with(|| {
        Diagnostic::error(Span::new(open, open + 2), "unterminated comment")
            .with_label("this comment is never closed")
            .with_help("close it with `*/`")
    });
    bytes.len()
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
        let mut d = Capped::default();
        let c = split_items(src, &mut d);
        let d = d.kept;
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
