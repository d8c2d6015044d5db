//! The layout: pieces re-emitted with the canonical whitespace, decided by
//! the piece kinds, the parse roles and the open brackets (an explicit stack:
//! no recursion). The rules are listed in docs/language.md, "Formatting".

use super::lex::{Kind, Piece};
use super::roles::Roles;

/// Spaces per block level and per continuation.
pub const INDENT: usize = 4;

/// One output line: its code (with the indentation) and a trailing comment.
#[derive(Debug, Default)]
pub struct Line {
    /// Indentation and code (or an own-line comment).
    pub code: String,
    /// A `//` comment after the code, aligned with its neighbours when rendered.
    pub comment: Option<String>,
}

/// An open bracket.
#[derive(Debug, Clone, Copy)]
struct Open {
    /// `(`, `[` or `{`.
    ch: u8,
    /// For `{`: the block stays on one line.
    inline: bool,
    /// The column just after the bracket (where a continuation aligns).
    col: usize,
    /// The indentation of the line the bracket is on.
    line_indent: usize,
    /// The bracket ends its line: its contents are indented one level instead.
    block: bool,
}

/// The last token (or inline comment) on the current line.
#[derive(Debug, Clone, Copy)]
struct Prev {
    text_is_open: bool,
    sign: bool,
    pipe_open: bool,
    comment: bool,
}

/// The emitter's state.
struct Emitter<'r> {
    roles: &'r Roles,
    lines: Vec<Line>,
    cur: Line,
    /// Characters on the current line.
    cols: usize,
    /// Indentation of the current line.
    indent: usize,
    stack: Vec<Open>,
    /// Open non-inline blocks.
    depth: usize,
    /// The next token starts a statement.
    stmt_start: bool,
    /// The next piece must start a new line.
    need_break: bool,
    /// The last line opened a block (no blank line after it).
    after_open: bool,
    prev: Option<Prev>,
    /// Inside `| .. |` of `converged`.
    in_pipe: bool,
}

/// Lays out `pieces` into lines.
pub fn layout(pieces: &[Piece<'_>], roles: &Roles) -> Vec<Line> {
    let mut e = Emitter {
        roles,
        lines: Vec::new(),
        cur: Line::default(),
        cols: 0,
        indent: 0,
        stack: Vec::new(),
        depth: 0,
        stmt_start: true,
        need_break: false,
        after_open: false,
        prev: None,
        in_pipe: false,
    };
    for (i, p) in pieces.iter().enumerate() {
        if p.is_comment() {
            e.comment(p);
        } else {
            e.token(p, pieces, i);
        }
    }
    if !e.cur.code.is_empty() {
        e.lines.push(e.cur);
    }
    e.lines
}

impl Emitter<'_> {
    fn push_text(&mut self, text: &str) {
        self.cur.code.push_str(text);
        match text.rfind('\n') {
            Some(k) => self.cols = text[k + 1..].chars().count(),
            None => self.cols += text.chars().count(),
        }
    }

    /// Ends the current line; the next one starts at `indent`, after a blank
    /// line when the source had one and one is allowed here.
    fn newline(&mut self, indent: usize, blank: bool) {
        if !self.cur.code.trim().is_empty() || self.cur.comment.is_some() {
            self.lines.push(std::mem::take(&mut self.cur));
            if blank && !self.after_open {
                self.lines.push(Line::default());
            }
        }
        self.after_open = false;
        self.cur.code = " ".repeat(indent);
        self.cols = indent;
        self.indent = indent;
        self.prev = None;
        self.need_break = false;
    }

    /// Ends the current line before a piece: at the block's indentation when
    /// a statement starts (or a block closes), else as a continuation.
    fn break_line(&mut self, statement: bool, closer: bool, blank: bool) {
        // A bracket that ends its line indents its contents one level.
        if let Some(top) = self.stack.last_mut() {
            if self.prev.is_some_and(|p| p.text_is_open) && top.ch != b'{' {
                top.block = true;
            }
        }
        let indent = if statement {
            self.depth * INDENT
        } else {
            self.continuation(closer)
        };
        self.newline(indent, blank);
    }

    /// The indentation of a line that continues a statement.
    fn continuation(&self, closer: bool) -> usize {
        match self.stack.last() {
            Some(o) if o.ch != b'{' => match (o.block, closer) {
                (true, true) => o.line_indent,
                (true, false) => o.line_indent + INDENT,
                (false, true) => o.col.saturating_sub(1),
                (false, false) => o.col,
            },
            _ => self.depth * INDENT + INDENT,
        }
    }

    fn comment(&mut self, p: &Piece<'_>) {
        let on_code_line = p.newlines == 0 && self.prev.is_some();
        if on_code_line && p.kind == Kind::LineComment {
            self.cur.comment = Some(p.text.to_string());
            self.need_break = true;
            return;
        }
        if on_code_line {
            self.push_text(" ");
        } else if self.prev.is_some() || self.need_break || p.newlines > 0 {
            self.break_line(self.stmt_start, false, p.newlines >= 2);
        }
        self.push_text(p.text);
        self.prev = Some(Prev {
            text_is_open: false,
            sign: false,
            pipe_open: false,
            comment: true,
        });
        self.need_break = p.kind == Kind::LineComment;
    }

    fn token(&mut self, p: &Piece<'_>, pieces: &[Piece<'_>], i: usize) {
        let t = p.text;
        let closes_block = t == "}" && self.stack.last().is_some_and(|o| !o.inline);
        if closes_block {
            self.depth -= 1;
        }
        // Nothing emitted on this line yet (`prev` is reset by every line end).
        let starts_line = self.prev.is_none() && self.cur.comment.is_none();
        if self.need_break || closes_block || (p.newlines > 0 && !starts_line) {
            let closer = matches!(t, ")" | "]");
            let blank = p.newlines >= 2 && !closes_block;
            self.break_line(self.stmt_start || closes_block, closer, blank);
        } else if self.space_before(p) {
            self.push_text(" ");
        }
        self.push_text(t);
        self.stmt_start = false;
        self.after_open = false;
        let mut prev = Prev {
            text_is_open: false,
            sign: self.roles.signs.contains(&p.start),
            pipe_open: false,
            comment: false,
        };
        match t {
            "(" | "[" => {
                self.open(t.as_bytes()[0], false);
                prev.text_is_open = true;
            }
            "{" => {
                let inline = inline_block(pieces, i);
                self.open(b'{', inline);
                if !inline {
                    self.depth += 1;
                    self.stmt_start = true;
                    self.need_break = true;
                    self.after_open = true;
                }
            }
            ")" | "]" => {
                self.stack.pop();
            }
            "}" => {
                self.stack.pop();
                self.stmt_start = true;
                self.need_break = true;
            }
            ";" => {
                match self.stack.last() {
                    Some(o) if o.ch == b'[' => {} // a matrix row ends
                    Some(o) if o.inline => self.stmt_start = true,
                    _ => {
                        self.stmt_start = true;
                        self.need_break = true;
                    }
                }
            }
            "|" => {
                self.in_pipe = !self.in_pipe;
                prev.pipe_open = self.in_pipe;
            }
            _ => {}
        }
        self.prev = Some(prev);
    }

    fn open(&mut self, ch: u8, inline: bool) {
        self.stack.push(Open {
            ch,
            inline,
            col: self.cols,
            line_indent: self.indent,
            block: false,
        });
    }

    /// Whether a space separates `p` from the piece before it on the line.
    fn space_before(&self, p: &Piece<'_>) -> bool {
        let Some(prev) = self.prev else {
            return false;
        };
        let t = p.text;
        if prev.comment || t == "}" {
            return true;
        }
        if matches!(t, "," | ";" | ":" | ")" | "]" | "'") {
            return false;
        }
        if prev.text_is_open || prev.sign || prev.pipe_open {
            return false;
        }
        match t {
            "|" => !self.in_pipe,
            "(" | "[" => self.roles.operands.contains(&p.start),
            _ => true,
        }
    }
}

/// Whether the block opened by `pieces[open]` stays on one line: the source
/// has it on one line, without comments or inner blocks, with at most one
/// statement. Looks no further than the first line end or inner block.
fn inline_block(pieces: &[Piece<'_>], open: usize) -> bool {
    let mut statements = 0;
    let mut nested = 0usize;
    for p in &pieces[open + 1..] {
        if p.newlines > 0 || p.is_comment() {
            return false;
        }
        match p.text {
            "{" => return false,
            "}" => return statements <= 1,
            "(" | "[" => nested += 1,
            ")" | "]" => nested = nested.saturating_sub(1),
            ";" if nested == 0 => statements += 1,
            _ => {}
        }
    }
    false
}
