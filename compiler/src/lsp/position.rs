//! Byte offsets of the source text and LSP positions (0-based line,
//! UTF-16 code units within the line), both ways.

use lsp_types::{Position, Range};
use tsf_lang::Span;

/// The line starts of a text, for converting between byte offsets and positions.
#[derive(Debug, Clone)]
pub struct LineIndex {
    /// Byte offset of the start of each line (the first is 0).
    starts: Vec<usize>,
}

impl LineIndex {
    /// The index of `text` (lines end at `\n`; a `\r` before it belongs to the line's end).
    pub fn new(text: &str) -> Self {
        let mut starts = vec![0];
        starts.extend(
            text.bytes()
                .enumerate()
                .filter(|&(_, b)| b == b'\n')
                .map(|(i, _)| i + 1),
        );
        LineIndex { starts }
    }

    /// The position of byte `offset` (clamped into the text and to a char boundary).
    pub fn position(&self, text: &str, offset: usize) -> Position {
        let mut offset = offset.min(text.len());
        while offset > 0 && !text.is_char_boundary(offset) {
            offset -= 1;
        }
        let line = self.starts.partition_point(|&s| s <= offset) - 1;
        let start = self.starts[line];
        let character: usize = text[start..offset].chars().map(char::len_utf16).sum();
        Position::new(to_u32(line), to_u32(character))
    }

    /// The range of `span`.
    pub fn range(&self, text: &str, span: Span) -> Range {
        Range::new(
            self.position(text, span.start),
            self.position(text, span.end),
        )
    }

    /// The byte offset of `pos` (a position past a line's end is its end; a
    /// line past the text's end is the text's end).
    pub fn offset(&self, text: &str, pos: Position) -> usize {
        let Some(&start) = self.starts.get(pos.line as usize) else {
            return text.len();
        };
        let end = self
            .starts
            .get(pos.line as usize + 1)
            .map_or(text.len(), |&s| s - 1);
        let mut units = 0usize;
        for (i, ch) in text[start..end].char_indices() {
            if units >= pos.character as usize || ch == '\r' && start + i + 1 == end {
                return start + i;
            }
            units += ch.len_utf16();
        }
        end
    }
}

fn to_u32(n: usize) -> u32 {
    u32::try_from(n).unwrap_or(u32::MAX)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn utf16_columns_both_ways() {
        // `é` is 2 bytes and 1 UTF-16 unit; `𝛼` is 4 bytes and 2 units.
        let text = "const a = 1;\n// é𝛼\r\nstate x;\n";
        let idx = LineIndex::new(text);
        let x = text.find("x;").unwrap();
        assert_eq!(idx.position(text, x), Position::new(2, 6));
        assert_eq!(idx.offset(text, Position::new(2, 6)), x);
        let after = text.find('𝛼').unwrap() + '𝛼'.len_utf8();
        assert_eq!(idx.position(text, after), Position::new(1, 6));
        assert_eq!(idx.offset(text, Position::new(1, 6)), after);
        // Past the line's end: the end of the line, before `\r\n`.
        assert_eq!(idx.offset(text, Position::new(1, 99)), after);
        assert_eq!(idx.offset(text, Position::new(9, 0)), text.len());
        assert_eq!(idx.position(text, text.len() + 5), Position::new(3, 0));
    }
}
