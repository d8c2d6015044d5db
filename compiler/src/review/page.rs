//! The review page's sections, in order: the design's identity, the claim
//! (what the certificate covers, the objectives, the model consistency and
//! the check's warnings), the certificate table, the gains and P, the
//! membership functions, the model-consistency map, the closed loop of the
//! scenario and the generated files.

use super::design::{Design, Origin};
use super::figures;
use super::html::{escape, figure, json_text, matrix_table, num, pairs_table};
use crate::sim::{Outcome, SimError};
use serde_json::Value;
use std::fmt::Write;

/// The run of the scenario: none in the spec, its outcome, or why it could not run.
pub enum Scenario {
    /// The spec has no `simulate` block.
    None,
    /// The run's outcome.
    Ran(Box<Outcome>),
    /// Why the run could not be made.
    Failed(String),
}

/// `(key, json_text(value))` rows of an object's fields, skipping `skip`.
fn fields(v: &Value, skip: &[&str]) -> Vec<(String, String)> {
    v.as_object().map_or_else(Vec::new, |o| {
        o.iter()
            .filter(|(k, _)| !skip.contains(&k.as_str()))
            .map(|(k, v)| (k.clone(), json_text(v)))
            .collect()
    })
}

fn identity(d: &Design) -> String {
    let r = &d.report;
    let origin = match &d.origin {
        Origin::Reused(p) => format!(
            "the certified report `{}` of `tsfc compile` (same spec sha256; nothing solved)",
            p.file_name()
                .map_or_else(String::new, |n| n.to_string_lossy().into_owned())
        ),
        Origin::Compiled(_) => "compiled for this page (no usable report of `tsfc compile`)".into(),
    };
    let rows = vec![
        ("spec".to_string(), d.spec_name.clone()),
        ("spec sha256".into(), d.sha256.clone()),
        ("tsfc".into(), json_text(&r["tsfc_version"])),
        ("design".into(), origin),
        ("status".into(), json_text(&r["status"])),
        ("mode".into(), json_text(&r["mode"])),
        ("relaxation".into(), json_text(&r["relaxation"])),
    ];
    format!(
        "<h1>Design review: controller <code>{}</code></h1>\n{}",
        escape(&json_text(&r["controller"])),
        pairs_table("Design", &rows)
    )
}

fn claim(d: &Design) -> String {
    let r = &d.report;
    let model = &d.prepared.model;
    let mut s = String::from("<h2 id=\"claim\">Plant model and claim</h2>\n");
    let premises: Vec<String> = model
        .premises
        .slots
        .iter()
        .map(|p| format!("{} in [{}, {}]", p.name, p.range.0, p.range.1))
        .collect();
    let _ = writeln!(
        s,
        "<p>The certificate is about the Takagi-Sugeno model the rules blend, x' = sum_i h_i(z) (A_i x + B_i u + D_i w), for premise values z inside their declared ranges ({}), with the gains below; it covers the plant A(x), B(x) only as far as that blend equals it (model consistency below).</p>",
        escape(&premises.join(", "))
    );
    let mut rows = vec![(
        "model".to_string(),
        format!(
            "n = {}, m = {}, q = {}, {} rules",
            json_text(&r["n"]),
            json_text(&r["m"]),
            json_text(&r["q"]),
            json_text(&r["rules"])
        ),
    )];
    rows.extend(fields(&r["objectives"], &[]));
    for v in r["verdicts"].as_array().map_or(&[][..], |a| a.as_slice()) {
        rows.push(("verdict".into(), json_text(v)));
    }
    for (key, part) in [
        ("region of attraction", &r["region_of_attraction"]),
        ("membership mismatch", &r["membership_mismatch"]),
        ("sampled loop", &r["sampled_loop"]),
        ("trigger", &r["trigger"]),
    ] {
        if !part.is_null() {
            let skip = ["U", "P", "Y", "weight", "modes"];
            let shown: Vec<String> = fields(part, &skip)
                .into_iter()
                .map(|(k, v)| format!("{k}: {v}"))
                .collect();
            rows.push((key.into(), shown.join("; ")));
        }
    }
    for key in ["reductions", "notes"] {
        for v in r[key].as_array().map_or(&[][..], |a| a.as_slice()) {
            rows.push((key.trim_end_matches('s').into(), json_text(v)));
        }
    }
    s.push_str(&pairs_table("What is certified", &rows));
    let mc = &r["model_consistency"];
    if mc.is_null() {
        s.push_str("<p>Model consistency: A and B do not depend on the state (or no rule has an operating point), so the blend is the model.</p>\n");
    } else {
        s.push_str(&pairs_table(
            "Model consistency (blended model against A(x), B(x))",
            &fields(mc, &[]),
        ));
    }
    for w in &d.warnings {
        let _ = writeln!(s, "<p class=\"warning\">warning: {}</p>", escape(w));
    }
    s
}

fn certificate(d: &Design) -> String {
    let cert = &d.report["certificate"];
    let mut s = String::from("<h2 id=\"certificate\">Certificate</h2>\n");
    let _ = writeln!(
        s,
        "<p>Rule: {}. Smallest margin {} at <code>{}</code>; the certificate {}.</p>",
        escape(&json_text(&cert["rule"])),
        num(cert["min_margin"].as_f64().unwrap_or(f64::NAN)),
        escape(&json_text(&cert["worst"])),
        if cert["ok"].as_bool() == Some(true) {
            "holds"
        } else {
            "DOES NOT hold"
        }
    );
    s.push_str("<table class=\"certificate\">\n<caption>Conditions (each LMI of the certificate)</caption>\n<thead><tr><th>condition</th><th>size</th><th>strict</th><th>margin</th><th>rounding error bound</th><th>holds</th></tr></thead>\n<tbody>\n");
    for l in cert["lmis"].as_array().map_or(&[][..], |a| a.as_slice()) {
        let ok = l["ok"].as_bool() == Some(true);
        let _ = writeln!(
            s,
            "<tr><td><code>{}</code></td><td>{}</td><td>{}</td><td class=\"mono\">{}</td><td class=\"mono\">{}</td><td class=\"{}\">{}</td></tr>",
            escape(&json_text(&l["name"])),
            json_text(&l["size"]),
            json_text(&l["strict"]),
            num(l["margin"].as_f64().unwrap_or(f64::NAN)),
            num(l["error_bound"].as_f64().unwrap_or(f64::NAN)),
            if ok { "ok" } else { "bad" },
            if ok { "yes" } else { "NO" }
        );
    }
    s.push_str("</tbody>\n</table>\n");
    let sp = &d.report["stored_precision"];
    if !sp.is_null() {
        let mut rows = fields(sp, &["membership_rounding_bound"]);
        rows.extend(
            fields(&sp["membership_rounding_bound"], &[])
                .into_iter()
                .map(|(k, v)| (format!("membership rounding: {k}"), v)),
        );
        s.push_str(&pairs_table(
            "Stored precision (the certificate checked again with the gains as stored)",
            &rows,
        ));
    }
    s
}

fn gains(d: &Design) -> String {
    let t = &d.prepared.tables;
    let mut s = String::from("<h2 id=\"gains\">Gains and P</h2>\n<p>u = sum_j h_j(z) F_j x; numbers as stored in the report, printed with seven significant digits.</p>\n");
    let mut sets = vec![(String::new(), &d.report["gains"])];
    for m in d.report["modes"]
        .as_array()
        .map_or(&[][..], |a| a.as_slice())
    {
        sets.push((format!(" (mode {})", json_text(&m["name"])), &m["gains"]));
    }
    for (mode, g) in sets {
        for gain in g.as_array().map_or(&[][..], |a| a.as_slice()) {
            let caption = format!("F of rule {}{mode}", json_text(&gain["rule"]));
            s.push_str(&matrix_table(
                &caption,
                &gain["F"],
                &t.input_names,
                &t.state_names,
            ));
        }
    }
    s.push_str(&matrix_table(
        "P (Lyapunov matrix, V = x'Px)",
        &d.report["P"],
        &t.state_names,
        &t.state_names,
    ));
    s
}

fn membership(d: &Design) -> Result<String, SimError> {
    let model = &d.prepared.model;
    let mut s = String::from("<h2 id=\"membership\">Membership functions</h2>\n");
    for k in 0..model.premises.slots.len() {
        let f = figures::membership_figure(model, k)?;
        if f.svg.is_empty() {
            let _ = writeln!(s, "<p>{}</p>", escape(&f.caption));
        } else {
            s.push_str(&figure(&format!("premise-{k}"), &f));
        }
    }
    Ok(s)
}

fn consistency(d: &Design) -> Result<String, SimError> {
    let model = &d.prepared.model;
    let mut s = String::from("<h2 id=\"consistency\">Model-consistency map</h2>\n");
    match model.consistency.as_ref() {
        Some(c) => match figures::consistency_figure(model, c)? {
            Some(f) => s.push_str(&figure("consistency", &f)),
            None => s.push_str("<p>The consistency grid has no varying state component.</p>\n"),
        },
        None => s.push_str("<p>No map: A and B do not depend on the state (or no rule has an operating point), so there is nothing to compare the blend with.</p>\n"),
    }
    Ok(s)
}

fn closed_loop(scenario: &Scenario) -> Result<String, SimError> {
    let mut s = String::from("<h2 id=\"closed-loop\">Closed loop of the scenario</h2>\n");
    match scenario {
        Scenario::None => s.push_str("<p>The spec has no <code>simulate</code> block.</p>\n"),
        Scenario::Failed(why) => {
            let _ = writeln!(
                s,
                "<p class=\"warning\">The scenario could not be run: {}</p>",
                escape(why)
            );
        }
        Scenario::Ran(o) => {
            let metrics = serde_json::to_value(&o.metrics)
                .map_err(|e| SimError::usage(format!("cannot serialize the metrics: {e}")))?;
            // The run's wall-clock time is left out: the page's bytes depend on the spec only.
            let rows: Vec<(String, String)> = fields(&metrics, &[])
                .into_iter()
                .filter(|(k, _)| !k.starts_with("wall"))
                .collect();
            s.push_str(&pairs_table(
                "Metrics of the run (tsfc simulate's metrics, without the wall-clock time)",
                &rows,
            ));
            let failures = o.metrics.failures();
            for w in o.metrics.warnings().into_iter().chain(failures) {
                let _ = writeln!(s, "<p class=\"warning\">{}</p>", escape(&w));
            }
            for (i, f) in figures::run_figures_svg(o)?.iter().enumerate() {
                s.push_str(&figure(&format!("run-{i}"), f));
            }
        }
    }
    Ok(s)
}

fn files(d: &Design) -> String {
    let mut s = String::from("<h2 id=\"files\">Generated files</h2>\n");
    if d.files.is_empty() {
        s.push_str("<p>The spec emits no code (no <code>emit</code> line).</p>\n");
        return s;
    }
    s.push_str("<table class=\"files\">\n<caption>The files <code>tsfc compile</code> writes for the spec's emit targets</caption>\n<thead><tr><th>file</th><th>sha256</th></tr></thead>\n<tbody>\n");
    for f in &d.files {
        let _ = writeln!(
            s,
            "<tr><td><code>{}</code></td><td class=\"mono\">{}</td></tr>",
            escape(&f.name),
            escape(&f.sha256)
        );
    }
    s.push_str("</tbody>\n</table>\n");
    s
}

/// The whole review page of `d` with the run of its scenario.
pub fn render(d: &Design, scenario: &Scenario) -> Result<String, SimError> {
    let mut body = identity(d);
    body.push_str(&claim(d));
    body.push_str(&certificate(d));
    body.push_str(&gains(d));
    body.push_str(&membership(d)?);
    body.push_str(&consistency(d)?);
    body.push_str(&closed_loop(scenario)?);
    body.push_str(&files(d));
    let title = format!(
        "tsfc design review: {} ({})",
        json_text(&d.report["controller"]),
        d.spec_name
    );
    Ok(super::html::page(&title, &body))
}
