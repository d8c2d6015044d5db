//! `tsfc review`: the design review page. Its certificate rows and gains are
//! the report's numbers, every figure sits in a `<figure>` with a caption,
//! the page refers to nothing outside itself, its tags balance, text from the
//! spec is escaped, the same spec gives the same bytes, and headless Chromium
//! renders it without a console error (skipped, with a message, when the
//! `chromium` package is not installed).

use crate::common::chromium;
use std::path::{Path, PathBuf};
use std::process::Command;

const ZHANG: &str = "zhang2013_multiobjective.tsf";

/// A fresh scratch folder for `tag`.
fn scratch(tag: &str) -> PathBuf {
    crate::common::fresh_dir("review", tag)
}

fn spec(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../specs")
        .join(name)
}

/// The review page of `path` with the outputs in `out`.
fn page(path: &Path, out: &Path) -> (String, tsfc::review::Design) {
    let (html, design, failed) =
        tsfc::review::page(path, None, out).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(failed, None, "the scenario runs");
    (html, design)
}

/// The shipped spec `name` compiled as `tsfc compile` does.
fn compile(name: &str) -> tsfc::pipeline::Run {
    tsfc::pipeline::read(&spec(name))
        .unwrap_or_else(|e| panic!("{e}"))
        .compile(&tsfc::synth::Settings::default())
        .unwrap_or_else(|e| panic!("{e}"))
}

/// The report `tsfc compile` writes for the shipped spec `name`, as JSON.
fn report_of(name: &str) -> serde_json::Value {
    serde_json::to_value(&compile(name).compiled.report).expect("the report serializes")
}

/// The cells (`<td>` text) of the table whose caption is `caption`.
fn table_cells(html: &str, caption: &str) -> Vec<String> {
    let start = html
        .find(&format!("<caption>{caption}</caption>"))
        .unwrap_or_else(|| panic!("no table `{caption}`"));
    let table = &html[start..start + html[start..].find("</table>").expect("table end")];
    table
        .split("<td>")
        .skip(1)
        .map(|c| c.split("</td>").next().unwrap_or_default().to_string())
        .collect()
}

/// The page's certificate rows hold the report's conditions with its margins
/// and error bounds (the page's number format), and each gain table holds
/// the report's F (and P) entry by entry.
#[test]
fn certificate_rows_and_gains_are_the_reports() {
    let out = scratch("numbers");
    let (html, _) = page(&spec(ZHANG), &out);
    let report = report_of(ZHANG);
    let lmis = report["certificate"]["lmis"].as_array().expect("lmis");
    assert!(lmis.len() > 10);
    for l in lmis {
        let f = |k: &str| format!("{:.6e}", l[k].as_f64().expect("a number"));
        let row = format!(
            "<tr><td><code>{}</code></td><td>{}</td><td>{}</td><td class=\"mono\">{}</td><td class=\"mono\">{}</td><td class=\"ok\">yes</td></tr>",
            tsfc::review::html::escape(l["name"].as_str().expect("name")),
            l["size"],
            if l["strict"].as_bool() == Some(true) { "yes" } else { "no" },
            f("margin"),
            f("error_bound")
        );
        assert!(html.contains(&row), "no certificate row {row}");
    }
    let worst = format!(
        "{:.6e}",
        report["stored_precision"]["worst_margin"]
            .as_f64()
            .expect("worst")
    );
    assert!(
        html.contains(&format!("<td>{worst}</td>")),
        "stored precision {worst}"
    );
    let entries = |m: &serde_json::Value| -> Vec<String> {
        m.as_array()
            .expect("rows")
            .iter()
            .flat_map(|r| r.as_array().expect("row").clone())
            .map(|v| format!("{:.6e}", v.as_f64().expect("a number")))
            .collect()
    };
    for g in report["gains"].as_array().expect("gains") {
        let caption = format!("F of rule {}", g["rule"].as_str().expect("rule"));
        assert_eq!(table_cells(&html, &caption), entries(&g["F"]), "{caption}");
    }
    assert_eq!(
        table_cells(&html, "P (Lyapunov matrix, V = x&#39;Px)"),
        entries(&report["P"])
    );
    let _ = std::fs::remove_dir_all(&out);
}

/// Every `<svg>` and `<img>` opens inside a `<figure>` that has a `<figcaption>`.
fn every_image_captioned(html: &str) {
    let figures: Vec<&str> = html.split("<figure").skip(1).collect();
    for f in &figures {
        let body = f.split("</figure>").next().unwrap_or_default();
        assert!(body.contains("<figcaption>"), "a figure without caption");
        let caption = body.split("<figcaption>").nth(1).unwrap_or_default();
        assert!(caption
            .split("</figcaption>")
            .next()
            .is_some_and(|c| c.len() > 20));
    }
    let outside: String = html
        .split("<figure")
        .enumerate()
        .map(|(i, part)| {
            if i == 0 {
                part
            } else {
                part.split_once("</figure>").map_or("", |p| p.1)
            }
        })
        .collect();
    assert!(
        !outside.contains("<svg") && !outside.contains("<img"),
        "an image outside a figure"
    );
    let images = html.matches("<svg").count() + html.matches("<img").count();
    assert!(
        images >= figures.len(),
        "{images} images in {} figures",
        figures.len()
    );
}

/// Nothing outside the page: no address, no script, no `src=`, no link, no `url(`.
fn self_contained(html: &str) {
    let lower = html.to_lowercase();
    for bad in [
        "http://", "https://", "<script", "src=", "<link", "url(", "@import", "//cdn",
    ] {
        assert!(!lower.contains(bad), "the page holds `{bad}`");
    }
}

/// The tags balance: every element opened is closed in order (void and
/// self-closing elements excepted).
fn balanced(html: &str) {
    const VOID: [&str; 6] = ["meta", "br", "img", "hr", "input", "link"];
    let mut stack: Vec<String> = Vec::new();
    let mut rest = html;
    while let Some(i) = rest.find('<') {
        rest = &rest[i + 1..];
        let end = rest.find('>').expect("a tag ends");
        let tag = &rest[..end];
        rest = &rest[end + 1..];
        if tag.starts_with('!') {
            continue;
        }
        let name: String = tag
            .trim_start_matches('/')
            .chars()
            .take_while(|c| c.is_ascii_alphanumeric())
            .collect();
        if let Some(closing) = tag.strip_prefix('/') {
            let open = stack
                .pop()
                .unwrap_or_else(|| panic!("`</{closing}>` closes nothing"));
            assert_eq!(open, name, "`<{open}>` closed by `</{name}>`");
        } else if !tag.ends_with('/') && !VOID.contains(&name.as_str()) {
            stack.push(name);
        }
    }
    assert!(stack.is_empty(), "unclosed: {stack:?}");
}

/// The page of the Zhang spec: one captioned figure per premise, the
/// consistency map and the run's plots, all inline; self-contained; balanced.
#[test]
fn page_is_self_contained_captioned_and_balanced() {
    let out = scratch("shape");
    let (html, design) = page(&spec(ZHANG), &out);
    let premises = &design.prepared.model.premises.slots;
    assert_eq!(premises.len(), 2);
    for (k, p) in premises.iter().enumerate() {
        let f = html
            .split(&format!("<figure id=\"premise-{k}\">"))
            .nth(1)
            .unwrap_or_else(|| panic!("no figure of premise {}", p.name));
        let f = f.split("</figure>").next().unwrap_or_default();
        assert!(f.contains("<svg"), "premise {} plotted", p.name);
        assert!(f.contains(&format!(
            "<figcaption>Membership functions of premise `{}`",
            p.name
        )));
        for set in ["neg", "zero", "pos"] {
            assert!(
                f.contains(&format!(">\n{set}\n</text>")),
                "legend entry {set}"
            );
        }
    }
    assert!(html.contains("<figure id=\"consistency\">"));
    assert!(html.contains("<figure id=\"run-0\">") && html.contains("<figure id=\"run-2\">"));
    for file in [
        "zhang_multiobjective.rs",
        "zhang_multiobjective.c",
        "tsf_runtime.h",
    ] {
        assert!(
            html.contains(&format!("<code>{file}</code>")),
            "file {file}"
        );
    }
    every_image_captioned(&html);
    self_contained(&html);
    balanced(&html);
    let _ = std::fs::remove_dir_all(&out);
}

/// The checks above can fail: a bare SVG, an external script and an
/// unbalanced tag are each caught.
#[test]
fn page_checks_catch_bad_pages() {
    let bad = ["<p><svg></svg></p>", "<figure><svg></svg></figure>"];
    for b in bad {
        assert!(
            std::panic::catch_unwind(|| every_image_captioned(b)).is_err(),
            "{b}"
        );
    }
    for b in [
        "<img src=\"a.png\">",
        "<script>x()</script>",
        "<a href=\"https://x\">",
    ] {
        assert!(
            std::panic::catch_unwind(|| self_contained(b)).is_err(),
            "{b}"
        );
    }
    for b in ["<div><p></div>", "<p>", "</p>"] {
        assert!(std::panic::catch_unwind(|| balanced(b)).is_err(), "{b}");
    }
}

/// A spec whose file name is a script tag gives a page where it is text:
/// no `<script` anywhere, the name escaped in the page and in the plots.
#[test]
fn spec_text_is_escaped() {
    let out = scratch("escape");
    let path = out.join("<script>alert(1)<.tsf");
    std::fs::copy(spec(ZHANG), &path).expect("copy the spec");
    let (html, _) = page(&path, &out);
    assert!(
        !html.to_lowercase().contains("<script"),
        "a live script tag"
    );
    assert!(
        html.contains("&lt;script&gt;alert(1)&lt;.tsf"),
        "the name, escaped"
    );
    balanced(&html);
    let _ = std::fs::remove_dir_all(&out);
}

/// The same spec gives the same page; a page from the compile's report
/// differs from a compiled one only in the row saying where the design came from.
#[test]
fn page_is_deterministic_and_reuses_the_report() {
    let (a_dir, b_dir) = (scratch("det-a"), scratch("det-b"));
    let (a, da) = page(&spec(ZHANG), &a_dir);
    let (b, _) = page(&spec(ZHANG), &b_dir);
    assert_eq!(a, b, "same spec, same bytes");
    assert!(matches!(da.origin, tsfc::review::Origin::Compiled(None)));
    // What `tsfc compile` writes: the report and the generated files.
    let run = compile(ZHANG);
    let json = serde_json::to_string_pretty(&run.compiled.report).expect("report") + "\n";
    let mut files = vec![(
        a_dir.join("zhang_multiobjective.report.json"),
        json.into_bytes(),
    )];
    for f in run
        .generate(&da.prepared.model.spec.emit)
        .expect("generate")
    {
        files.push((a_dir.join(&f.name), f.text.into_bytes()));
    }
    tsfc::util::output::write_set(&files).expect("write");
    let (r, dr) = page(&spec(ZHANG), &a_dir);
    assert!(
        matches!(dr.origin, tsfc::review::Origin::Reused(_)),
        "{:?}",
        dr.origin
    );
    let differ: Vec<(&str, &str)> = a.lines().zip(r.lines()).filter(|(x, y)| x != y).collect();
    assert_eq!(differ.len(), 1, "{differ:?}");
    assert!(differ[0].0.starts_with("<tr><th>design</th>"));
    // A generated file that is not this spec's: the report is not used.
    std::fs::write(a_dir.join("zhang_multiobjective.c"), "int x;\n").expect("write");
    let (c, dc) = page(&spec(ZHANG), &a_dir);
    assert!(
        matches!(&dc.origin, tsfc::review::Origin::Compiled(Some(w)) if w.contains("zhang_multiobjective.c"))
    );
    assert_eq!(c, a);
    for d in [a_dir, b_dir] {
        let _ = std::fs::remove_dir_all(d);
    }
}

/// `review` writes OUT/<controller>.review.html.
#[test]
fn review_writes_the_page() {
    let out = scratch("write");
    let w = tsfc::review::review(&spec(ZHANG), None, &out).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(w.path, out.join("zhang_multiobjective.review.html"));
    let bytes = std::fs::read(&w.path).expect("the page");
    assert_eq!(bytes.len(), w.bytes);
    assert!(bytes.starts_with(b"<!DOCTYPE html>"));
    let _ = std::fs::remove_dir_all(&out);
}

/// A missing spec is a usage error (exit code 2), not a panic.
#[test]
fn missing_spec_is_a_usage_error() {
    let out = scratch("missing");
    let e = tsfc::review::review(&out.join("nope.tsf"), None, &out).expect_err("no spec");
    assert_eq!(e.exit_code(), 2);
    let _ = std::fs::remove_dir_all(&out);
}

/// Renders the file `page` in headless Chromium (fresh profile, no network
/// services), with `extra` arguments; returns the console messages it logged
/// (`--enable-logging=stderr` prints each as a `:CONSOLE` line).
fn render(chromium: &Path, page: &Path, profile: &Path, extra: &[&str]) -> Vec<String> {
    let out = Command::new(chromium)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-quic",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--hide-scrollbars",
            "--enable-logging=stderr",
            "--v=0",
        ])
        .arg(format!("--user-data-dir={}", profile.display()))
        .args(extra)
        .arg(format!("file://{}", page.display()))
        .output()
        .expect("chromium runs");
    assert!(out.status.success(), "chromium failed: {out:?}");
    String::from_utf8_lossy(&out.stderr)
        .lines()
        .filter(|l| l.contains(":CONSOLE"))
        .map(str::to_string)
        .collect()
}

/// Headless Chromium renders the review page with no console message (the
/// route is proved on a page that logs a `console.error`) and takes a
/// non-empty PNG screenshot. Skipped, with a message, without `chromium`.
#[test]
fn chromium_renders_the_page_without_console_errors() {
    let Some(chromium) = chromium() else {
        eprintln!("SKIPPED chromium_renders_the_page_without_console_errors: `chromium` is not installed (apt-get install chromium)");
        return;
    };
    let dir = scratch("chromium");
    let probe = dir.join("probe.html");
    std::fs::write(
        &probe,
        "<!DOCTYPE html><html><body><p>probe</p><script>console.error(\"tsfc-probe-error\")</script></body></html>\n",
    )
    .expect("probe page");
    let caught = render(
        &chromium,
        &probe,
        &dir.join("profile-probe"),
        &["--dump-dom"],
    );
    assert!(
        caught.iter().any(|l| l.contains("tsfc-probe-error")),
        "the console route does not see a console.error: {caught:?}"
    );
    let w = tsfc::review::review(&spec(ZHANG), None, &dir).unwrap_or_else(|e| panic!("{e}"));
    let shot = dir.join("review.png");
    let console = render(
        &chromium,
        &w.path,
        &dir.join("profile-page"),
        &[
            &format!("--screenshot={}", shot.display()),
            "--window-size=1280,4000",
        ],
    );
    assert!(console.is_empty(), "console messages: {console:?}");
    let png = std::fs::read(&shot).expect("a screenshot");
    assert!(png.len() > 10_000, "screenshot of {} bytes", png.len());
    assert!(png.starts_with(b"\x89PNG\r\n\x1a\n"), "a PNG");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `about` sets (Xu & Huang's vector premises): one panel per component of
/// the premise, one curve per distinct point, the width in the caption.
#[test]
fn about_sets_are_plotted_per_component() {
    let model = crate::common::shipped("xu2020_regional.tsf");
    let f = tsfc::review::figures::membership_figure(&model, 0).unwrap_or_else(|e| panic!("{e}"));
    for c in 0..3 {
        assert!(
            f.svg.contains(&format!("degree along w[{c}]")),
            "panel w[{c}]"
        );
    }
    for p in [
        "0, 0, 0",
        "0.5, 0.5, 0.5",
        "-0.5, -0.5, -0.5",
        "1, 1, 1",
        "-1, -1, -1",
    ] {
        assert!(f.svg.contains(&format!("about [{p}]")), "curve about [{p}]");
    }
    let sigma = model.premises.slots[0].sigma;
    assert!(
        f.caption.contains(&format!("sigma = {sigma}")),
        "{}",
        f.caption
    );
}

/// The consistency map is the model stage's grid: its largest value along
/// every varying state component is the report's worst mismatch.
#[test]
fn consistency_map_peaks_at_the_worst_mismatch() {
    let model = crate::common::shipped(ZHANG);
    let c = model.consistency.as_ref().expect("a consistency check");
    let mut varying = 0;
    for (axis, profile) in c.axes.iter().zip(&c.profile) {
        assert_eq!(axis.len(), profile.len());
        if axis.len() > 1 {
            varying += 1;
            let peak = profile.iter().copied().fold(0.0, f64::max);
            assert_eq!(peak, c.worst, "the profile's peak is the worst mismatch");
        }
    }
    assert_eq!(varying, 6);
    let f = tsfc::review::figures::consistency_figure(&model, c)
        .unwrap_or_else(|e| panic!("{e}"))
        .expect("a map");
    assert!(f.svg.contains("mismatch along w") && f.svg.contains("mismatch along rho"));
    assert!(f.caption.contains(&format!("{:.1}%", 100.0 * c.worst)));
}
