//! The lines as text: trailing `//` comments of consecutive lines aligned
//! one column, two spaces past the longest code of the run.

use super::layout::Line;

/// Spaces at least between code and its trailing comment.
const COMMENT_GAP: usize = 2;

/// The text of `lines`, one line end after each, none doubled at the end.
pub fn render(lines: &[Line]) -> String {
    let mut out = String::new();
    let mut i = 0;
    while i < lines.len() {
        // A run: consecutive one-line codes with a trailing comment each.
        let alignable = |l: &Line| l.comment.is_some() && !l.code.contains('\n');
        let mut end = i;
        while end < lines.len() && alignable(&lines[end]) {
            end += 1;
        }
        if end == i {
            push_line(&mut out, &lines[i], 0);
            i += 1;
            continue;
        }
        let width = lines[i..end]
            .iter()
            .map(|l| l.code.chars().count())
            .max()
            .unwrap_or(0);
        for l in &lines[i..end] {
            push_line(&mut out, l, width + COMMENT_GAP);
        }
        i = end;
    }
    while out.ends_with("\n\n") {
        out.pop();
    }
    out
}

/// Appends one line, its comment (if any) starting at column `comment_col`
/// (or one gap after the code when the code is not aligned).
fn push_line(out: &mut String, line: &Line, comment_col: usize) {
    out.push_str(&line.code);
    if let Some(c) = &line.comment {
        let used = line.code.chars().count();
        let pad =
            comment_col
                .saturating_sub(used)
                .max(if comment_col == 0 { COMMENT_GAP } else { 1 });
        out.push_str(&" ".repeat(pad));
        out.push_str(c);
    }
    out.push('\n');
}
