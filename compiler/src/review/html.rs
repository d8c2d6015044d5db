//! HTML building blocks of the review page: escaping, the fixed number
//! format, tables of numbers, JSON values as text, figures with captions,
//! and the page's frame (inline CSS, generic fonts, no script).

use super::figures::Svg;
use std::fmt::Write;

/// Escapes text for HTML content and attribute values.
pub fn escape(text: &str) -> String {
    let mut s = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => s.push_str("&amp;"),
            '<' => s.push_str("&lt;"),
            '>' => s.push_str("&gt;"),
            '"' => s.push_str("&quot;"),
            '\'' => s.push_str("&#39;"),
            _ => s.push(c),
        }
    }
    s
}

/// The page's number format: Rust's `{:.6e}` (seven significant digits,
/// e.g. `9.998748e-8`); non-finite values as `NaN`, `inf`, `-inf`.
pub fn num(v: f64) -> String {
    format!("{v:.6e}")
}

/// A JSON value as one line of text (numbers in [`num`]'s format; integers as written).
pub fn json_text(v: &serde_json::Value) -> String {
    match v {
        serde_json::Value::Null => "-".into(),
        serde_json::Value::Bool(b) => if *b { "yes" } else { "no" }.into(),
        serde_json::Value::Number(n) if n.is_f64() => n.as_f64().map_or("-".into(), num),
        serde_json::Value::Number(n) => n.to_string(),
        serde_json::Value::String(s) => s.clone(),
        serde_json::Value::Array(a) => {
            let parts: Vec<String> = a.iter().map(json_text).collect();
            format!("[{}]", parts.join(", "))
        }
        serde_json::Value::Object(o) => {
            let parts: Vec<String> = o
                .iter()
                .map(|(k, v)| format!("{k}: {}", json_text(v)))
                .collect();
            format!("{{{}}}", parts.join(", "))
        }
    }
}

/// A matrix given as JSON rows, as a table of numbers with a caption; the
/// row and column labels are `rows[i]` and `cols[j]` when given.
pub fn matrix_table(
    caption: &str,
    m: &serde_json::Value,
    rows: &[String],
    cols: &[String],
) -> String {
    let mut s = format!(
        "<table class=\"matrix\">\n<caption>{}</caption>\n",
        escape(caption)
    );
    let data = m.as_array().map_or(&[][..], |a| a.as_slice());
    let width = data
        .iter()
        .map(|r| r.as_array().map_or(0, |a| a.len()))
        .max()
        .unwrap_or(0);
    s.push_str("<thead><tr><th></th>");
    for j in 0..width {
        let label = cols.get(j).cloned().unwrap_or_else(|| j.to_string());
        let _ = write!(s, "<th>{}</th>", escape(&label));
    }
    s.push_str("</tr></thead>\n<tbody>\n");
    for (i, row) in data.iter().enumerate() {
        let label = rows.get(i).cloned().unwrap_or_else(|| i.to_string());
        let _ = write!(s, "<tr><th>{}</th>", escape(&label));
        for v in row.as_array().map_or(&[][..], |a| a.as_slice()) {
            let _ = write!(s, "<td>{}</td>", escape(&json_text(v)));
        }
        s.push_str("</tr>\n");
    }
    s.push_str("</tbody>\n</table>\n");
    s
}

/// A table of `(key, value)` rows.
pub fn pairs_table(caption: &str, rows: &[(String, String)]) -> String {
    let mut s = format!(
        "<table class=\"pairs\">\n<caption>{}</caption>\n<tbody>\n",
        escape(caption)
    );
    for (k, v) in rows {
        let _ = writeln!(s, "<tr><th>{}</th><td>{}</td></tr>", escape(k), escape(v));
    }
    s.push_str("</tbody>\n</table>\n");
    s
}

/// A `<figure>` holding the SVG with its `<figcaption>`; `id` names it.
pub fn figure(id: &str, f: &Svg) -> String {
    format!(
        "<figure id=\"{}\">\n{}\n<figcaption>{}</figcaption>\n</figure>\n",
        escape(id),
        f.svg.trim(),
        escape(&f.caption)
    )
}

/// The page's CSS: generic font families only, SVGs scaled to the width.
const STYLE: &str = "body{font-family:sans-serif;margin:1.5em auto;max-width:1200px;padding:0 1em;color:#222;line-height:1.4}\
h1{font-size:1.6em}h2{font-size:1.25em;border-bottom:1px solid #ccc;margin-top:1.6em}\
code,.mono{font-family:monospace}\
table{border-collapse:collapse;margin:0.6em 0 1.2em;font-size:0.9em}\
caption{text-align:left;font-weight:bold;padding:0.3em 0}\
th,td{border:1px solid #ccc;padding:0.2em 0.5em;text-align:left;vertical-align:top}\
table.matrix td{text-align:right;font-family:monospace}\
td.ok{color:#1a7f37}td.bad{color:#c62828;font-weight:bold}\
.warning{background:#fff4e5;border-left:4px solid #e67e22;padding:0.4em 0.8em}\
figure{margin:1em 0;border:1px solid #ddd;padding:0.5em}\
figure svg{max-width:100%;height:auto;display:block}\
figcaption{font-size:0.9em;color:#444;margin-top:0.4em}";

/// The whole page: the HTML5 frame around `body`, titled `title`.
pub fn page(title: &str, body: &str) -> String {
    format!(
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n<title>{}</title>\n<style>{STYLE}</style>\n</head>\n<body>\n{body}</body>\n</html>\n",
        escape(title)
    )
}
