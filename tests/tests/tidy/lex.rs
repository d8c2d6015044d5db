//! A small lexer of Rust source text: identifiers, punctuation, literals
//! (strings raw, byte and C, chars, numbers), lifetimes and outer doc
//! comments; other comments are dropped. Enough to find paths, items and
//! matching braces, never fooled by a brace or a path in a string.

/// What a token is; comments other than outer doc comments are dropped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Kind {
    Ident,
    /// `::`
    PathSep,
    /// Any other single punctuation character.
    Punct,
    /// A string, char or number literal (its text is not kept).
    Literal,
    Lifetime,
    /// An outer doc comment (`///` or `/** */`).
    Doc,
}

/// One token and the line (1-based) it starts on.
#[derive(Clone, Debug)]
pub(super) struct Token {
    pub(super) kind: Kind,
    pub(super) text: String,
    pub(super) line: usize,
}

impl Token {
    fn is(&self, kind: Kind, text: &str) -> bool {
        self.kind == kind && self.text == text
    }

    /// Whether this is the punctuation `c`.
    pub(super) fn is_punct(&self, c: char) -> bool {
        self.kind == Kind::Punct && self.text.len() == 1 && self.text.starts_with(c)
    }

    /// Whether this is the identifier `text`.
    pub(super) fn is_ident(&self, text: &str) -> bool {
        self.is(Kind::Ident, text)
    }
}

fn ident_start(c: char) -> bool {
    c == '_' || c.is_alphabetic()
}

fn ident_continue(c: char) -> bool {
    c == '_' || c.is_alphanumeric()
}

/// A cursor over the characters of one source file.
struct Lexer {
    chars: Vec<char>,
    pos: usize,
    line: usize,
    out: Vec<Token>,
}

impl Lexer {
    fn at(&self, k: usize) -> char {
        self.chars.get(self.pos + k).copied().unwrap_or('\0')
    }

    fn done(&self) -> bool {
        self.pos >= self.chars.len()
    }

    /// Moves one character on, counting lines.
    fn bump(&mut self) {
        if self.at(0) == '\n' {
            self.line += 1;
        }
        self.pos += 1;
    }

    fn push(&mut self, kind: Kind, text: String, line: usize) {
        self.out.push(Token { kind, text, line });
    }

    fn line_comment(&mut self) {
        let line = self.line;
        let doc = self.at(2) == '/' && self.at(3) != '/';
        while !self.done() && self.at(0) != '\n' {
            self.bump();
        }
        if doc {
            self.push(Kind::Doc, String::new(), line);
        }
    }

    /// A block comment; they nest.
    fn block_comment(&mut self) {
        let line = self.line;
        let doc = self.at(2) == '*' && !matches!(self.at(3), '*' | '/');
        let mut depth = 0usize;
        while !self.done() {
            if self.at(0) == '/' && self.at(1) == '*' {
                depth += 1;
                self.pos += 2;
            } else if self.at(0) == '*' && self.at(1) == '/' {
                depth -= 1;
                self.pos += 2;
                if depth == 0 {
                    break;
                }
            } else {
                self.bump();
            }
        }
        if doc {
            self.push(Kind::Doc, String::new(), line);
        }
    }

    /// A quoted string from its opening `"`, escapes included.
    fn string(&mut self, line: usize) {
        self.bump();
        while !self.done() {
            match self.at(0) {
                '\\' => {
                    self.bump();
                    self.bump();
                }
                '"' => {
                    self.bump();
                    break;
                }
                _ => self.bump(),
            }
        }
        self.push(Kind::Literal, String::new(), line);
    }

    /// A raw string from its `#`s or opening `"`: ends at `"` and as many `#`.
    fn raw_string(&mut self, line: usize) {
        let mut hashes = 0;
        while self.at(0) == '#' {
            hashes += 1;
            self.bump();
        }
        self.bump(); // the opening quote
        while !self.done() {
            if self.at(0) == '"' && (1..=hashes).all(|k| self.at(k) == '#') {
                self.pos += 1 + hashes;
                break;
            }
            self.bump();
        }
        self.push(Kind::Literal, String::new(), line);
    }

    /// A char literal or a lifetime (or label), from its `'`.
    fn quote(&mut self, line: usize) {
        if self.at(1) == '\\' {
            self.pos += 3; // quote, backslash, escaped char
            while !self.done() && self.at(0) != '\'' {
                self.bump();
            }
            self.pos += 1;
            self.push(Kind::Literal, String::new(), line);
        } else if self.at(2) == '\'' {
            self.pos += 3;
            self.push(Kind::Literal, String::new(), line);
        } else {
            let start = self.pos;
            self.pos += 1;
            while ident_continue(self.at(0)) {
                self.pos += 1;
            }
            let text = self.chars[start..self.pos].iter().collect();
            self.push(Kind::Lifetime, text, line);
        }
    }

    fn number(&mut self, line: usize) {
        while ident_continue(self.at(0)) || (self.at(0) == '.' && self.at(1).is_ascii_digit()) {
            self.pos += 1;
        }
        self.push(Kind::Literal, String::new(), line);
    }

    /// An identifier, or the prefix of a raw identifier or of a prefixed
    /// literal (`r"…"`, `br#"…"#`, `b"…"`, `c"…"`, `b'…'`).
    fn word(&mut self, line: usize) {
        let start = self.pos;
        while ident_continue(self.at(0)) {
            self.pos += 1;
        }
        let word: String = self.chars[start..self.pos].iter().collect();
        let raw_prefix = matches!(word.as_str(), "r" | "br" | "cr");
        if raw_prefix && matches!(self.at(0), '"' | '#') {
            let hashes = (0..).take_while(|&k| self.at(k) == '#').count();
            if self.at(hashes) == '"' {
                return self.raw_string(line);
            }
            if word == "r" && hashes == 1 && ident_start(self.at(1)) {
                self.pos += 1;
                return self.word(line); // raw identifier: r#type is `type`
            }
        }
        if matches!(word.as_str(), "b" | "c") && self.at(0) == '"' {
            return self.string(line);
        }
        if word == "b" && self.at(0) == '\'' {
            return self.quote(line);
        }
        self.push(Kind::Ident, word, line);
    }

    fn token(&mut self) {
        let c = self.at(0);
        let line = self.line;
        match c {
            _ if c.is_whitespace() => self.bump(),
            '/' if self.at(1) == '/' => self.line_comment(),
            '/' if self.at(1) == '*' => self.block_comment(),
            '"' => self.string(line),
            '\'' => self.quote(line),
            _ if c.is_ascii_digit() => self.number(line),
            _ if ident_start(c) => self.word(line),
            ':' if self.at(1) == ':' => {
                self.pos += 2;
                self.push(Kind::PathSep, "::".into(), line);
            }
            _ => {
                self.pos += 1;
                self.push(Kind::Punct, c.to_string(), line);
            }
        }
    }
}

/// The tokens of a Rust source text.
pub(super) fn lex(src: &str) -> Vec<Token> {
    let mut lexer = Lexer {
        chars: src.chars().collect(),
        pos: 0,
        line: 1,
        out: Vec::new(),
    };
    while !lexer.done() {
        lexer.token();
    }
    lexer.out
}

/// Index of the bracket that closes the one at `open` (or the end).
pub(super) fn matching(tokens: &[Token], open: usize) -> usize {
    let (o, c) = match tokens[open].text.as_str() {
        "(" => ('(', ')'),
        "[" => ('[', ']'),
        _ => ('{', '}'),
    };
    let mut depth = 0usize;
    for (k, t) in tokens.iter().enumerate().skip(open) {
        if t.is_punct(o) {
            depth += 1;
        } else if t.is_punct(c) {
            depth -= 1;
            if depth == 0 {
                return k;
            }
        }
    }
    tokens.len()
}

/// Whether the attribute between `[` and `]` is `cfg(test)` (or a `cfg`
/// that requires `test`, like `cfg(all(test, unix))`; not `any` or `not`).
fn is_cfg_test(attr: &[Token]) -> bool {
    attr.first().is_some_and(|t| t.is_ident("cfg"))
        && attr.iter().any(|t| t.is_ident("test"))
        && !attr.iter().any(|t| t.is_ident("not") || t.is_ident("any"))
}

/// Index just past the item starting at `start`: its `;`, or the brace that
/// closes its body (a `use` tree's braces are part of the path).
pub(super) fn item_end(tokens: &[Token], start: usize) -> usize {
    let is_use = tokens[start..]
        .iter()
        .find(|t| t.kind == Kind::Ident && t.text != "pub" && t.text != "crate")
        .is_some_and(|t| t.is_ident("use"));
    let mut depth = 0usize;
    let mut k = start;
    while k < tokens.len() {
        let t = &tokens[k];
        if t.is_punct('{') && depth == 0 && !is_use {
            return matching(tokens, k) + 1;
        } else if t.is_punct('(') || t.is_punct('[') || t.is_punct('{') {
            depth += 1;
        } else if t.is_punct(')') || t.is_punct(']') || t.is_punct('}') {
            depth = depth.saturating_sub(1);
        } else if t.is_punct(';') && depth == 0 {
            return k + 1;
        }
        k += 1;
    }
    tokens.len()
}

/// The tokens of the code compiled outside tests: every item under a
/// `#[cfg(test)]` attribute is dropped, and a file whose inner attribute is
/// `#![cfg(test)]` has no tokens at all.
pub(super) fn non_test(tokens: &[Token]) -> Vec<Token> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < tokens.len() {
        if !tokens[i].is_punct('#') {
            out.push(tokens[i].clone());
            i += 1;
            continue;
        }
        // A run of attributes and doc comments, then the item they apply to.
        let mut j = i;
        let mut test = false;
        let mut inner = false;
        while j < tokens.len() {
            if tokens[j].kind == Kind::Doc {
                j += 1;
                continue;
            }
            if !tokens[j].is_punct('#') {
                break;
            }
            let bang = tokens.get(j + 1).is_some_and(|t| t.is_punct('!'));
            let open = j + 1 + usize::from(bang);
            if !tokens.get(open).is_some_and(|t| t.is_punct('[')) {
                break;
            }
            let close = matching(tokens, open);
            let attr_test = is_cfg_test(&tokens[open + 1..close.min(tokens.len())]);
            test |= attr_test;
            inner |= attr_test && bang;
            j = close + 1;
        }
        if inner {
            return Vec::new();
        }
        if test {
            i = item_end(tokens, j);
        } else {
            out.extend_from_slice(&tokens[i..j.max(i + 1)]);
            i = j.max(i + 1);
        }
    }
    out
}
