//! The source as shown under one diagnostic: only the lines it marks, with
//! unsafe characters escaped, a leading byte-order mark dropped, every line
//! break (`\n`, `\r\n` or a lone `\r`) shown as one, and lines longer than
//! [`MAX_SHOWN_LINE`] shortened around the marked places. Line and column
//! numbers stay those of the original text.

use super::text::{is_unsafe, push_shown, shown_len};
use crate::limits::MAX_SHOWN_LINE;
use crate::span::Span;
use codespan_reporting::files::{Error, Files};
use std::cell::Cell;
use std::ops::Range;

/// Whether `b` ends a line (a lone `\r` does too).
fn is_line_end(b: u8) -> bool {
    b == b'\n' || b == b'\r'
}

/// Line breaks in `bytes` (`\r\n` counts once).
fn breaks(bytes: &[u8]) -> usize {
    let lf = bytes.iter().filter(|&&b| b == b'\n').count();
    let cr = bytes.iter().filter(|&&b| b == b'\r').count();
    let crlf = if cr == 0 {
        0
    } else {
        bytes.windows(2).filter(|w| w == b"\r\n").count()
    };
    lf + cr - crlf
}

/// Line and column lookups in the original source. Each lookup starts from
/// the last one where it can, so that many diagnostics on one long line (or
/// far down a long file) cost one pass over it, not one each.
pub(crate) struct Lines<'s> {
    src: &'s str,
    /// The last position counted, with the line breaks before it.
    counted: Cell<(usize, usize)>,
    /// The start and content end of the last line looked up.
    line: Cell<(usize, usize)>,
    /// The last position whose column was counted, with that column.
    columned: Cell<(usize, usize)>,
}

impl<'s> Lines<'s> {
    pub(crate) fn new(src: &'s str) -> Self {
        Lines {
            src,
            counted: Cell::new((0, 0)),
            line: Cell::new((usize::MAX, 0)),
            columned: Cell::new((usize::MAX, 0)),
        }
    }

    /// The start and content end of the line holding `at` (normalized).
    fn bounds(&self, at: usize) -> (usize, usize) {
        let (s, e) = self.line.get();
        if s <= at && at <= e {
            return (s, e);
        }
        let b = self.src.as_bytes();
        let mut s = at;
        while s > 0 && !is_line_end(b[s - 1]) {
            s -= 1;
        }
        let mut e = at;
        while e < b.len() && !is_line_end(b[e]) {
            e += 1;
        }
        self.line.set((s, e));
        (s, e)
    }

    /// `at` clamped into the text, onto a char boundary, and out of a `\r\n` pair.
    pub(crate) fn norm(&self, at: usize) -> usize {
        let b = self.src.as_bytes();
        let mut i = at.min(b.len());
        while i > 0 && !self.src.is_char_boundary(i) {
            i -= 1;
        }
        if i > 0 && b[i - 1] == b'\r' && b.get(i) == Some(&b'\n') {
            i -= 1;
        }
        i
    }

    /// Start of the line holding `at` (normalized).
    fn start(&self, at: usize) -> usize {
        self.bounds(at).0
    }

    /// End of the content of the line holding `at` (before its line break).
    fn end(&self, at: usize) -> usize {
        self.bounds(at).1
    }

    /// Start of the line after the one holding `at`, if there is one.
    fn next(&self, at: usize) -> Option<usize> {
        let b = self.src.as_bytes();
        let e = self.end(at);
        match (b.get(e), b.get(e + 1)) {
            (Some(b'\r'), Some(b'\n')) => Some(e + 2),
            (Some(_), _) => Some(e + 1),
            _ => None,
        }
    }

    /// Start of the line before the one starting at `start`, if there is one.
    fn prev(&self, start: usize) -> Option<usize> {
        let b = self.src.as_bytes();
        let before = match start {
            0 => return None,
            s if s >= 2 && b[s - 2] == b'\r' && b[s - 1] == b'\n' => s - 2,
            s => s - 1,
        };
        Some(self.start(before))
    }

    /// 1-based line of `at` (normalized).
    fn number(&self, at: usize) -> usize {
        let (from, before) = self.counted.get();
        let counted = if at >= from {
            before + breaks(&self.src.as_bytes()[from..at])
        } else {
            breaks(&self.src.as_bytes()[..at])
        };
        self.counted.set((at, counted));
        counted + 1
    }

    /// 1-based column (in characters) of `at` (normalized); a leading
    /// byte-order mark takes no column.
    fn column(&self, at: usize) -> usize {
        let s = self.start(at);
        let bom = usize::from(s == 0 && at >= 3 && self.src.starts_with('\u{feff}'));
        let (from, chars) = match self.columned.get() {
            (p, c) if s <= p && p <= at => (p, c),
            _ => (s, 0),
        };
        let chars = chars + self.src[from..at].chars().count();
        self.columned.set((at, chars));
        chars + 1 - bom
    }

    /// 1-based line and column of byte `at`.
    pub(crate) fn line_col(&self, at: usize) -> (usize, usize) {
        let at = self.norm(at);
        (self.number(at), self.column(at))
    }
}

/// A piece of a shown line: `src` in the original text shown as `dst`;
/// `exact` when byte for byte (otherwise an escape, a `...` or nothing).
#[derive(Debug, Clone, Copy)]
struct Seg {
    src: usize,
    src_end: usize,
    dst: usize,
    dst_end: usize,
    exact: bool,
}

/// One line of the snippet.
#[derive(Debug)]
struct Shown {
    /// Its range in the snippet text, line break included.
    range: Range<usize>,
    /// Its 1-based number in the original text.
    number: usize,
    /// The original line's content (None for a placeholder standing for skipped lines).
    origin: Option<Range<usize>>,
    /// Its pieces.
    segs: Vec<Seg>,
}

/// The lines of one diagnostic, as a file for codespan.
pub(crate) struct Snippet<'a> {
    name: &'a str,
    lines: &'a Lines<'a>,
    text: String,
    shown: Vec<Shown>,
}

/// A label spanning more lines than this is shown by its first
/// `LONG_LABEL_HEAD` and last two lines, as codespan shows it.
const LONG_LABEL: usize = 7;
const LONG_LABEL_HEAD: usize = 4;

impl<'a> Snippet<'a> {
    /// The snippet of the lines marked by `spans` (clamped to the text).
    pub(crate) fn new(name: &'a str, lines: &'a Lines<'a>, spans: &[Span]) -> Self {
        let marks: Vec<usize> = spans
            .iter()
            .flat_map(|s| [lines.norm(s.start), lines.norm(s.end)])
            .collect();
        let mut wanted = Vec::new();
        for pair in marks.chunks(2) {
            let (s, e) = (lines.start(pair[0]), lines.start(pair[1]));
            let (ns, ne) = (lines.number(s), lines.number(e));
            let head = if ne - ns > LONG_LABEL {
                LONG_LABEL_HEAD
            } else {
                ne - ns + 1
            };
            let mut at = Some(s);
            for k in 0..head {
                let Some(l) = at else { break };
                wanted.push((ns + k, l));
                at = lines.next(l);
            }
            if ne - ns > LONG_LABEL {
                wanted.push((ne, e));
                if let Some(p) = lines.prev(e) {
                    wanted.push((ne - 1, p));
                }
            }
        }
        wanted.sort_unstable();
        wanted.dedup();
        let mut snippet = Snippet {
            name,
            lines,
            text: String::new(),
            shown: Vec::new(),
        };
        let mut last: Option<(usize, usize)> = None;
        // Lines of the original (number, start) in order.
        for (number, start) in wanted {
            match last {
                // One line between: codespan shows it, so it is needed.
                Some((n, l)) if number == n + 2 => {
                    if let Some(mid) = lines.next(l) {
                        snippet.push_line(n + 1, mid, &marks);
                    }
                }
                Some((n, _)) if number > n + 2 => {
                    snippet.push_gap(n + 1);
                    snippet.push_gap(n + 1);
                }
                _ => {}
            }
            snippet.push_line(number, start, &marks);
            last = Some((number, start));
        }
        snippet
    }

    fn push_gap(&mut self, number: usize) {
        let at = self.text.len();
        self.text.push('\n');
        self.shown.push(Shown {
            range: at..self.text.len(),
            number,
            origin: None,
            segs: Vec::new(),
        });
    }

    /// Appends the original line starting at `start`, shortened around `marks` if long.
    fn push_line(&mut self, number: usize, start: usize, marks: &[usize]) {
        let src = self.lines.src;
        let end = self.lines.end(start);
        let begin = self.text.len();
        let mut segs = Vec::new();
        let mut from = start;
        if start == 0 && src.starts_with('\u{feff}') {
            from = 3.min(end);
            segs.push(Seg {
                src: 0,
                src_end: from,
                dst: begin,
                dst_end: begin,
                exact: false,
            });
        }
        let width: usize = src[from..end]
            .chars()
            .take(MAX_SHOWN_LINE + 1)
            .map(shown_len)
            .sum();
        if width <= MAX_SHOWN_LINE {
            self.push_text(from, end, &mut segs);
        } else {
            let windows = self.windows(from, end, marks);
            let mut at = from;
            for (a, b) in windows {
                if a > at {
                    self.push_elided(at, a, &mut segs);
                }
                self.push_text(a, b, &mut segs);
                at = b;
            }
            if at < end {
                self.push_elided(at, end, &mut segs);
            }
        }
        self.text.push('\n');
        self.shown.push(Shown {
            range: begin..self.text.len(),
            number,
            origin: Some(start..end),
            segs,
        });
    }

    /// The parts of the long line `from..end` to show: around each mark on
    /// it (or its start when none), merged where they overlap.
    fn windows(&self, from: usize, end: usize, marks: &[usize]) -> Vec<(usize, usize)> {
        let src = self.lines.src;
        let reach = MAX_SHOWN_LINE / 4;
        let back = |m: usize| {
            src[from..m]
                .char_indices()
                .rev()
                .nth(reach - 1)
                .map_or(from, |(i, _)| from + i)
        };
        let fwd = |m: usize, n: usize| {
            src[m..end]
                .char_indices()
                .nth(n)
                .map_or(end, |(i, _)| m + i)
        };
        let mut w: Vec<(usize, usize)> = marks
            .iter()
            .filter(|&&m| from <= m && m <= end)
            .map(|&m| (back(m), fwd(m, reach)))
            .collect();
        if w.is_empty() {
            w.push((from, fwd(from, 2 * reach)));
        }
        w.sort_unstable();
        let mut merged: Vec<(usize, usize)> = Vec::new();
        for (a, b) in w {
            match merged.last_mut() {
                Some(last) if a <= last.1 => last.1 = last.1.max(b),
                _ => merged.push((a, b)),
            }
        }
        merged
    }

    /// Appends `src[a..b]`, unsafe characters escaped.
    fn push_text(&mut self, a: usize, b: usize, segs: &mut Vec<Seg>) {
        let src = self.lines.src;
        let mut run = a;
        for (i, c) in src[a..b].char_indices() {
            if !is_unsafe(c) {
                continue;
            }
            let at = a + i;
            self.push_exact(run, at, segs);
            let dst = self.text.len();
            push_shown(&mut self.text, c);
            segs.push(Seg {
                src: at,
                src_end: at + c.len_utf8(),
                dst,
                dst_end: self.text.len(),
                exact: false,
            });
            run = at + c.len_utf8();
        }
        self.push_exact(run, b, segs);
    }

    fn push_exact(&mut self, a: usize, b: usize, segs: &mut Vec<Seg>) {
        if a < b {
            let dst = self.text.len();
            self.text.push_str(&self.lines.src[a..b]);
            segs.push(Seg {
                src: a,
                src_end: b,
                dst,
                dst_end: self.text.len(),
                exact: true,
            });
        }
    }

    fn push_elided(&mut self, a: usize, b: usize, segs: &mut Vec<Seg>) {
        let dst = self.text.len();
        self.text.push_str("...");
        segs.push(Seg {
            src: a,
            src_end: b,
            dst,
            dst_end: self.text.len(),
            exact: false,
        });
    }

    /// Where byte `at` of the original text is in the snippet.
    pub(crate) fn map(&self, at: usize) -> usize {
        let at = self.lines.norm(at);
        let line = self.shown.iter().find(|l| {
            l.origin
                .as_ref()
                .is_some_and(|o| o.start <= at && at <= o.end)
        });
        let Some(line) = line else {
            return 0; // ok: every marked place is on a shown line
        };
        match line.segs.iter().rev().find(|s| s.src <= at) {
            Some(s) if s.exact => s.dst + (at - s.src).min(s.src_end - s.src),
            Some(s) if at == s.src => s.dst,
            Some(s) => s.dst_end,
            None => line.range.start,
        }
    }

    /// Where byte `at` of the snippet (on shown line `line`) is in the original.
    fn unmap(&self, line: usize, at: usize) -> Option<usize> {
        let l = self.shown.get(line)?;
        let origin = l.origin.as_ref()?;
        Some(match l.segs.iter().rev().find(|s| s.dst <= at) {
            Some(s) if s.exact => s.src + (at - s.dst).min(s.src_end - s.src),
            Some(s) if at == s.dst => s.src,
            Some(s) => s.src_end,
            None => origin.start,
        })
    }
}

impl<'f> Files<'f> for Snippet<'_> {
    type FileId = ();
    type Name = &'f str;
    type Source = &'f str;

    fn name(&'f self, (): ()) -> Result<&'f str, Error> {
        Ok(self.name)
    }

    fn source(&'f self, (): ()) -> Result<&'f str, Error> {
        Ok(&self.text)
    }

    fn line_index(&'f self, (): (), byte_index: usize) -> Result<usize, Error> {
        Ok(self
            .shown
            .iter()
            .position(|l| byte_index < l.range.end)
            .unwrap_or(self.shown.len().saturating_sub(1)))
    }

    fn line_number(&'f self, (): (), line_index: usize) -> Result<usize, Error> {
        self.shown
            .get(line_index)
            .map(|l| l.number)
            .ok_or(Error::LineTooLarge {
                given: line_index,
                max: self.shown.len(),
            })
    }

    fn column_number(
        &'f self,
        (): (),
        line_index: usize,
        byte_index: usize,
    ) -> Result<usize, Error> {
        let line = self.shown.get(line_index).ok_or(Error::LineTooLarge {
            given: line_index,
            max: self.shown.len(),
        })?;
        Ok(match self.unmap(line_index, byte_index) {
            Some(at) => self.lines.column(at),
            None => byte_index.saturating_sub(line.range.start) + 1,
        })
    }

    fn line_range(&'f self, (): (), line_index: usize) -> Result<Range<usize>, Error> {
        self.shown
            .get(line_index)
            .map(|l| l.range.clone())
            .ok_or(Error::LineTooLarge {
                given: line_index,
                max: self.shown.len(),
            })
    }
}
