//! `tsfc fmt [--check] SPEC...`: each spec rewritten in the canonical layout
//! of [`tsf_lang::format`] (atomically, only when it changes), or with
//! `--check` only the files that would change and how.

use crate::driver::frontend;
use std::io::Write;
use std::path::PathBuf;
use tsf_lang::{diag, Diagnostic, Span};

/// Exit code: every file is formatted (or, with `--check`, already was).
pub const CLEAN: u8 = 0;
/// Exit code: a file would change (`--check`) or does not parse.
pub const CHANGED_OR_SPEC: u8 = 1;
/// Exit code: a file could not be read or written.
pub const IO: u8 = 2;

/// Most changed lines a `--check` hunk shows on each side.
const MAX_HUNK_LINES: usize = 8;

/// What one `tsfc fmt` run asks.
#[derive(Debug, Clone)]
pub struct Request {
    /// The spec files.
    pub specs: Vec<PathBuf>,
    /// Write nothing; report the files that would change.
    pub check: bool,
    /// ANSI colours in the diagnostics.
    pub color: bool,
}

/// Runs `tsfc fmt`: files that change (and with `--check` their first
/// change, as a unified hunk) go to `out`, diagnostics and I/O errors to
/// `err`. Returns the exit code: the worst of the files.
pub fn run(req: &Request, out: &mut dyn Write, err: &mut dyn Write) -> u8 {
    let mut worst = CLEAN;
    for path in &req.specs {
        let code = match one(path, req, out, err) {
            Ok(code) => code,
            Err(e) => {
                let _ = writeln!(err, "error: {e}");
                IO
            }
        };
        worst = worst.max(code);
    }
    worst
}

/// Formats one file; an `Err` is an I/O error (exit code 2).
fn one(
    path: &std::path::Path,
    req: &Request,
    out: &mut dyn Write,
    err: &mut dyn Write,
) -> std::io::Result<u8> {
    let source =
        frontend::read_source(path).map_err(|e| std::io::Error::other(e.message.clone()))?;
    if let Err(e) = std::str::from_utf8(&source.bytes) {
        let at = e.valid_up_to();
        let d = Diagnostic::error(Span::new(at, at + 1), "the file is not valid UTF-8")
            .with_label("invalid byte here")
            .with_help("save the spec as UTF-8 text; it is not formatted");
        write!(
            err,
            "{}",
            diag::render(&source.name, &source.text, &[d], req.color)
        )?;
        return Ok(CHANGED_OR_SPEC);
    }
    let formatted = match tsf_lang::format::format_source(&source.text) {
        Ok(f) => f,
        Err(e) => {
            let shown = diag::render(&source.name, &source.text, &e.diagnostics, req.color);
            write!(err, "{shown}")?;
            writeln!(
                err,
                "error: `{}` is not formatted: it does not parse",
                source.name
            )?;
            return Ok(CHANGED_OR_SPEC);
        }
    };
    if formatted == source.text {
        return Ok(CLEAN);
    }
    if req.check {
        writeln!(out, "would reformat {}", source.name)?;
        write!(out, "{}", hunk(&source.text, &formatted))?;
        return Ok(CHANGED_OR_SPEC);
    }
    crate::util::output::replace_file(path, formatted.as_bytes()).map_err(|e| {
        std::io::Error::new(e.kind(), format!("cannot write `{}`: {e}", source.name))
    })?;
    writeln!(out, "formatted {}", source.name)?;
    Ok(CLEAN)
}

/// The changed region of `old` against `new` as one unified-diff hunk: the
/// lines between the common first and last lines (at most
/// [`MAX_HUNK_LINES`] of each side shown).
pub fn hunk(old: &str, new: &str) -> String {
    let a: Vec<&str> = old.lines().collect();
    let b: Vec<&str> = new.lines().collect();
    let head = a.iter().zip(&b).take_while(|(x, y)| x == y).count();
    let tail = a[head..]
        .iter()
        .rev()
        .zip(b[head..].iter().rev())
        .take_while(|(x, y)| x == y)
        .count();
    let (gone, came) = (&a[head..a.len() - tail], &b[head..b.len() - tail]);
    let mut s = format!(
        "@@ -{},{} +{},{} @@\n",
        head + 1,
        gone.len(),
        head + 1,
        came.len()
    );
    for (sign, side) in [('-', gone), ('+', came)] {
        for l in side.iter().take(MAX_HUNK_LINES) {
            s.push_str(&format!("{sign}{l}\n"));
        }
        if side.len() > MAX_HUNK_LINES {
            s.push_str(&format!(
                "{sign}... ({} more lines)\n",
                side.len() - MAX_HUNK_LINES
            ));
        }
    }
    if gone.is_empty() && came.is_empty() {
        s.push_str("(only line ends or the final newline differ)\n");
    }
    s
}
