//! Text that reaches a terminal: control and invisible formatting characters
//! are escaped (`\u{1b}`), and long runs echoed from the source are shortened.

use crate::limits::MAX_ECHO_CHARS;
use std::borrow::Cow;
use std::fmt::Write as _;

/// Whether `c` must not reach a terminal as is: control characters other
/// than tab and newline, and the invisible formatting characters that can
/// make text read differently from what it is (bidirectional overrides,
/// zero-width characters, the byte-order mark).
pub(crate) fn is_unsafe(c: char) -> bool {
    (c.is_control() && c != '\t' && c != '\n')
        || matches!(c, '\u{200B}'..='\u{200F}' | '\u{202A}'..='\u{202E}' | '\u{2060}'..='\u{2064}'
            | '\u{2066}'..='\u{2069}' | '\u{FEFF}')
}

/// Appends `c` to `out`, escaped as `\u{..}` when it is unsafe.
pub(crate) fn push_shown(out: &mut String, c: char) {
    if is_unsafe(c) {
        let _ = write!(out, "\\u{{{:x}}}", c as u32); // ok: writing to a String cannot fail
    } else {
        out.push(c);
    }
}

/// How many characters `c` takes once shown.
pub(crate) fn shown_len(c: char) -> usize {
    if is_unsafe(c) {
        format!("{:x}", c as u32).len() + 4
    } else {
        1
    }
}

/// A message, label or help line made safe to print: unsafe characters
/// escaped, and every run of more than [`MAX_ECHO_CHARS`] non-space characters
/// (a long number or name echoed from the source) shortened around `...`.
pub(crate) fn clean(text: String) -> String {
    let long_run = || {
        let mut run = 0;
        text.chars().any(|c| {
            run = if c.is_whitespace() { 0 } else { run + 1 };
            run > MAX_ECHO_CHARS
        })
    };
    if !text.chars().any(is_unsafe) && !long_run() {
        return text;
    }
    let mut out = String::with_capacity(text.len().min(4 * MAX_ECHO_CHARS));
    let mut rest = text.as_str();
    while let Some(c) = rest.chars().next() {
        if c.is_whitespace() {
            push_shown(&mut out, c);
            rest = &rest[c.len_utf8()..];
            continue;
        }
        let end = rest.find(char::is_whitespace).unwrap_or(rest.len());
        out.push_str(&excerpt(&rest[..end]));
        rest = &rest[end..];
    }
    out
}

/// `text` escaped, and shortened to about [`MAX_ECHO_CHARS`] characters
/// (its start and end around `...`) when longer.
pub(crate) fn excerpt(text: &str) -> Cow<'_, str> {
    let count = text.chars().count();
    if count <= MAX_ECHO_CHARS && !text.chars().any(is_unsafe) {
        return Cow::Borrowed(text);
    }
    let mut out = String::new();
    if count <= MAX_ECHO_CHARS {
        text.chars().for_each(|c| push_shown(&mut out, c));
        return Cow::Owned(out);
    }
    let head = MAX_ECHO_CHARS * 2 / 3;
    let tail = MAX_ECHO_CHARS - head - 3;
    text.chars()
        .take(head)
        .for_each(|c| push_shown(&mut out, c));
    out.push_str("...");
    text.chars()
        .skip(count - tail)
        .for_each(|c| push_shown(&mut out, c));
    Cow::Owned(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn control_and_invisible_characters_are_escaped() {
        assert_eq!(clean("a\u{1b}[31mb\0".into()), "a\\u{1b}[31mb\\u{0}");
        assert_eq!(clean("x\u{202e}y\u{feff}".into()), "x\\u{202e}y\\u{feff}");
        assert_eq!(clean("tab\tand\nnewline".into()), "tab\tand\nnewline");
    }

    #[test]
    fn long_runs_are_shortened_to_the_echo_limit() {
        let digits = "1".repeat(10_000);
        let m = clean(format!("number `{digits}` is out of range"));
        assert!(m.starts_with("number `111"), "{m}");
        assert!(m.ends_with("111` is out of range"), "{m}");
        assert!(m.contains("..."));
        let word = m.split(' ').nth(1).unwrap_or_default();
        assert_eq!(word.chars().count(), MAX_ECHO_CHARS);
        // Short messages are left alone.
        assert_eq!(clean("unknown name `k`".into()), "unknown name `k`");
    }
}
