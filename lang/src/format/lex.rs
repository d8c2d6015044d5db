//! The formatter's lexer: the source as tokens and comments, each with the
//! number of line ends in the whitespace before it. Whitespace is all the
//! lexer drops; every other byte belongs to exactly one piece.

use crate::split::{is_line_end, word_end};

/// What a piece of source is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// A name, keyword or number.
    Word,
    /// An operator, bracket or separator (`=>`, `..`, `.*`, `<=`, ... are one piece).
    Punct,
    /// `// ...` up to the end of the line (trailing whitespace not included).
    LineComment,
    /// `/* ... */`, possibly over several lines.
    BlockComment,
}

/// One token or comment of the source.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Piece<'a> {
    /// Token or comment.
    pub kind: Kind,
    /// Its text, as in the source.
    pub text: &'a str,
    /// Its byte offset in the source.
    pub start: usize,
    /// Line ends in the whitespace just before it (0: same line as the previous piece).
    pub newlines: usize,
}

impl Piece<'_> {
    /// Whether the piece is a comment.
    pub fn is_comment(&self) -> bool {
        matches!(self.kind, Kind::LineComment | Kind::BlockComment)
    }
}

/// Operators of two characters, tried before single characters.
const PAIRS: [&str; 6] = ["=>", "->", "<=", ">=", "..", ".*"];

/// Splits `source` (which parsed, so every comment is closed) into pieces.
/// Linear in the length of the source.
pub fn lex(source: &str) -> Vec<Piece<'_>> {
    let bytes = source.as_bytes();
    let mut out = Vec::new();
    let mut i = if source.starts_with('\u{feff}') { 3 } else { 0 };
    let mut newlines = 0;
    while i < bytes.len() {
        let b = bytes[i];
        if b.is_ascii_whitespace() {
            // `\r\n` is one line end; a lone `\r` is one too.
            if b == b'\n' || (b == b'\r' && bytes.get(i + 1) != Some(&b'\n')) {
                newlines += 1;
            }
            i += 1;
            continue;
        }
        let (kind, end) = if source[i..].starts_with("//") {
            let mut j = i;
            while j < bytes.len() && !is_line_end(bytes[j]) {
                j += 1;
            }
            (Kind::LineComment, j)
        } else if source[i..].starts_with("/*") {
            let end = source[i + 2..]
                .find("*/")
                .map_or(bytes.len(), |k| i + 2 + k + 2);
            (Kind::BlockComment, end)
        } else if let Some(end) = word_end(bytes, i) {
            (Kind::Word, end)
        } else if PAIRS.iter().any(|p| source[i..].starts_with(p)) {
            (Kind::Punct, i + 2)
        } else {
            let len = source[i..].chars().next().map_or(1, char::len_utf8);
            (Kind::Punct, i + len)
        };
        let mut text = &source[i..end];
        if kind == Kind::LineComment {
            text = text.trim_end();
        }
        out.push(Piece {
            kind,
            text,
            start: i,
            newlines,
        });
        newlines = 0;
        i = end;
    }
    out
}

/// The tokens of `source` without comments, as text: what formatting must keep.
pub fn token_texts(source: &str) -> Vec<&str> {
    lex(source)
        .into_iter()
        .filter(|p| !p.is_comment())
        .map(|p| p.text)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn operators_numbers_and_comments_are_pieces() {
        let p = lex("a=>-1.5e-3 .. .5// c \n/* b\n */x'");
        let texts: Vec<_> = p.iter().map(|p| p.text).collect();
        assert_eq!(
            texts,
            [
                "a",
                "=>",
                "-",
                "1.5e-3",
                "..",
                ".5",
                "// c",
                "/* b\n */",
                "x",
                "'"
            ]
        );
        assert_eq!(p[7].newlines, 1);
        assert_eq!(p[6].kind, Kind::LineComment);
    }

    #[test]
    fn crlf_counts_one_line_end() {
        let p = lex("a;\r\n\r\nb;");
        assert_eq!(p[2].newlines, 2);
    }
}
