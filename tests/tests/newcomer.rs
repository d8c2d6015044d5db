//! From a first spec to a certified design by following tsfc alone: the
//! textbook specs of tests/newcomer/ are too ambitious as written; each
//! round applies the advice the refusal prints (the first `write ...`) and
//! compiles again, at most four rounds. Also: the refused design kept in the
//! failed report, checked against eigenvalues computed here, and the
//! terminal warnings (x0 outside the certified set, large gains) against
//! levels recomputed from the report.

use crate::common;
use nalgebra::{DMatrix, DVector};
use tsfc::driver::compile::{Compiled, Status};

fn newcomer(name: &str) -> String {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("newcomer")
        .join(name);
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The refusal's text: its message and the advice lines.
fn refusal(c: &Compiled) -> String {
    let d = c
        .report
        .diagnosis
        .as_ref()
        .expect("a refusal has a diagnosis");
    std::iter::once(d.message.as_str())
        .chain(d.achievable.iter().map(String::as_str))
        .collect::<Vec<_>>()
        .join("\n")
}

/// Every spec snippet the first advice line that has one asks to write:
/// backticked after "write", separated by ", " or " and ".
fn snippets(text: &str) -> Vec<String> {
    for line in text.lines() {
        let Some(at) = line.find("write `") else {
            continue;
        };
        let mut out = Vec::new();
        let mut rest = &line[at + "write ".len()..];
        while let Some(open) = rest.strip_prefix('`') {
            let Some(end) = open.find('`') else { break };
            out.push(open[..end].trim_end_matches(';').to_string());
            rest = &open[end + 1..];
            rest = rest
                .strip_prefix(", ")
                .or_else(|| rest.strip_prefix(" and "))
                .unwrap_or("");
        }
        return out;
    }
    Vec::new()
}

/// `spec` with the advice `snippet` applied: a relaxation or trigger item
/// replaces the spec's (or is added after `rules`); `premise NAME range A ..
/// B` replaces that premise's range; an objective bound (`kind <= v` or
/// `kind >= v`) replaces the number of the objective of that kind.
fn apply(spec: &str, snippet: &str) -> String {
    let mut lines: Vec<String> = spec.lines().map(str::to_string).collect();
    let find = |lines: &[String], start: &str| {
        lines.iter().position(|l| l.trim_start().starts_with(start))
    };
    // `line` with the text from `from` to the first `stop` replaced.
    let splice = |line: &str, from: usize, stop: &[char], with: &str| {
        let to = from + line[from..].find(stop).unwrap_or(line.len() - from);
        format!("{}{with}{}", &line[..from], &line[to..])
    };
    if snippet.starts_with("relaxation") || snippet.starts_with("trigger") {
        let word = snippet.split_whitespace().next().unwrap_or_default();
        let item = if snippet.ends_with('}') {
            snippet.to_string()
        } else {
            format!("{snippet};")
        };
        match find(&lines, &format!("{word} ")) {
            Some(at) => lines[at] = item,
            None => {
                let at = find(&lines, "rules").expect("a `rules` line");
                lines.insert(at + 1, item);
            }
        }
    } else if let Some(rest) = snippet.strip_prefix("premise ") {
        let (name, range) = rest
            .split_once(" range ")
            .expect("premise NAME range A .. B");
        let at = find(&lines, &format!("premise {name} ")).expect("the premise");
        let from = lines[at].find(" range ").expect("a declared range") + " range ".len();
        let braced = lines[at].contains('{');
        let with = if braced {
            format!("{range} ")
        } else {
            range.to_string()
        };
        lines[at] = splice(&lines[at], from, &[';', '{'], &with);
    } else {
        let kind: String = snippet
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect();
        let op = if snippet.contains("<=") { "<=" } else { ">=" };
        let value = snippet.rsplit(op).next().expect("a bound").trim();
        let at = find(&lines, &format!("objective {kind}")).expect("the objective");
        let from = lines[at].find(op).expect("a bounded objective") + op.len() + 1;
        lines[at] = splice(&lines[at], from, &[';', ' '], value);
    }
    lines.join("\n") + "\n"
}

/// The advice applied as the test reads it.
#[test]
fn advice_snippets_apply_to_the_spec_text() {
    let spec = "premise q = x4 * sin(x3) range -2 .. 2;\nrules sector;\n\
                objective linf(w -> y) <= 20 with phi = 0.05;\nobjective decay_rate >= 50;\n\
                trigger periodic { every = 0.01; }\n";
    let advice = "x\ny: write `premise q range -0.5 .. 0.5`, `linf <= 20.4` and `decay_rate >= 6.17` (re-solved)";
    let mut out = spec.to_string();
    for s in snippets(advice) {
        out = apply(&out, &s);
    }
    let out = apply(&out, "relaxation membership_mismatch(kappa = 1)");
    let out = apply(&out, "trigger periodic { every = 0.00703; }");
    assert_eq!(
        out,
        "premise q = x4 * sin(x3) range -0.5 .. 0.5;\nrules sector;\n\
         relaxation membership_mismatch(kappa = 1);\n\
         objective linf(w -> y) <= 20.4 with phi = 0.05;\nobjective decay_rate >= 6.17;\n\
         trigger periodic { every = 0.00703; }\n"
    );
}

/// Compiles `spec`, applying the printed advice until it certifies (at
/// most `rounds` refusals); the refusals' texts, in order.
fn follow(name: &str, spec: &str, rounds: usize) -> (String, Vec<String>, Compiled) {
    let mut spec = spec.to_string();
    let mut seen = Vec::new();
    for _ in 0..=rounds {
        let (_, c) = common::compile_text(name, &spec);
        if c.status == Status::Certified {
            return (spec, seen, c);
        }
        let text = refusal(&c);
        assert!(
            !seen.contains(&text),
            "{name}: the same refusal twice after its advice was applied:\n{text}"
        );
        let asked = snippets(&text);
        assert!(!asked.is_empty(), "{name}: no advice to apply:\n{text}");
        for snippet in asked {
            spec = apply(&spec, &snippet);
        }
        seen.push(text);
    }
    panic!("{name}: not certified after {rounds} rounds of advice: {seen:#?}");
}

#[test]
fn the_advice_leads_from_a_first_spec_to_a_certified_design() {
    for (name, at_least) in [("duffing.tsf", 1), ("ball_beam.tsf", 2), ("tora.tsf", 1)] {
        let (spec, refusals, c) = follow(name, &newcomer(name), 4);
        assert!(
            refusals.len() >= at_least,
            "{name}: the first version was meant to be refused: {refusals:?}"
        );
        // The certified design keeps what was asked unless the advice said otherwise.
        assert!(c.report.certificate.as_ref().is_some_and(|cert| cert.ok));
        assert!(c.report.sampled_loop.is_some(), "{name}: {spec}");
        insta::assert_snapshot!(
            format!("newcomer_{}", name.trim_end_matches(".tsf")),
            refusals.join("\n---\n")
        );
    }
}

/// The Duffing refusal names the unstable pair; its eigenvalue and the kept
/// candidate's pairs agree with eigenvalues computed here from the spec's
/// A(x) at the premise's ends (z = x1^2 = 0 and 4) and the candidate's gains.
#[test]
fn the_refused_design_is_kept_and_its_unstable_pair_named() {
    let (model, c) = common::compile_text("duffing.tsf", &newcomer("duffing.tsf"));
    assert_eq!(c.status, Status::Infeasible);
    let text = refusal(&c);
    let cand = c
        .report
        .candidate
        .as_ref()
        .expect("the failed report keeps the candidate");
    assert_eq!(cand.gains.len(), 2);
    assert_eq!(cand.p.len(), 2);
    // A(x) of the spec at z: [0, 1; 1 - z, -0.3]; B = [0; 1].
    let a_at = |z: f64| DMatrix::from_row_slice(2, 2, &[0.0, 1.0, 1.0 - z, -0.3]);
    let by_rule = |rule: &str| -> f64 {
        // Rule names from `rules sector;`: z_max at z = 4, z_min at z = 0.
        match rule {
            "z_max" => 4.0,
            "z_min" => 0.0,
            other => panic!("unexpected rule {other}"),
        }
    };
    let mut worst = f64::NEG_INFINITY;
    for pair in &cand.pairs {
        let g = cand
            .gains
            .iter()
            .find(|g| g.rule == pair.controller)
            .expect("gain");
        let a = a_at(by_rule(&pair.plant));
        // Closed form of a 2x2 spectrum: lambda = tr/2 +- sqrt(tr^2/4 - det).
        let (k1, k2) = (g.f[0][0], g.f[0][1]);
        let cl = &a + DMatrix::from_row_slice(2, 2, &[0.0, 0.0, k1, k2]);
        let (tr, det) = (cl[(0, 0)] + cl[(1, 1)], cl.determinant());
        let disc = tr * tr / 4.0 - det;
        let re = if disc >= 0.0 {
            tr / 2.0 + disc.sqrt()
        } else {
            tr / 2.0
        };
        let got = pair.abscissa.expect("converged");
        assert!((got - re).abs() < 1e-9 * (1.0 + re.abs()), "{pair:?}: {re}");
        worst = worst.max(re);
    }
    assert!(worst > 0.0, "the refusal is caused by an unstable pair");
    assert!(
        text.contains(&format!("real part {worst:+.4}")) && text.contains("no sampling interval"),
        "{text}"
    );
    // The candidate is not shipped: no gains in the report proper.
    assert!(c.report.gains.is_empty());
    let _ = model;
}

/// The x0-outside warning of the compile summary, and its level recomputed
/// from the report's U.
#[test]
fn a_scenario_outside_the_certified_set_is_warned_on_the_terminal() {
    let text = newcomer("duffing.tsf")
        .replace(
            "rules sector;",
            "rules sector;\nrelaxation membership_mismatch(kappa = 1);",
        )
        .replace("x0 = [0.05, 0]", "x0 = [1.5, 0]");
    let (model, c) = common::compile_text("duffing.tsf", &text);
    assert_eq!(c.status, Status::Certified);
    let roa = c
        .report
        .region_of_attraction
        .as_ref()
        .expect("saturation region");
    let u = DMatrix::from_fn(2, 2, |i, j| roa.u[i][j]);
    let x0 = DVector::from_column_slice(&[1.5, 0.0]);
    let level = (x0.transpose() * &u * &x0)[(0, 0)];
    assert!(level > 1.0, "{level}");
    let summary = tsfc::driver::summary::summary(&model, &c, std::path::Path::new("r.json"));
    assert!(
        summary.contains(&format!("x0'Ux0 = {level:.4e} > 1")),
        "{summary}"
    );
    // Inside the set: no warning.
    let inside = text.replace("x0 = [1.5, 0]", "x0 = [0.001, 0]");
    let (model, c) = common::compile_text("duffing.tsf", &inside);
    let summary = tsfc::driver::summary::summary(&model, &c, std::path::Path::new("r.json"));
    assert!(!summary.contains("starts outside"), "{summary}");
}

/// The large-gain warning for sector rules, measured at the edge of the
/// certified set: max over x'Ux <= 1 of |F_j x| = sqrt(F_j U^-1 F_j'),
/// recomputed here from the report, against the `saturate` level.
#[test]
fn large_sector_gains_are_warned_at_the_edge_of_the_certified_set() {
    let spec = |z: &str| {
        format!(
            "tsf 1;\ncontroller duffing_hinf;\nstate x1, x2;\ninput u saturate 1;\ndisturbance w;\n\
             A(x) = [0, 1; 1 - x1^2, -0.3];\nB = [0; 1];\nD = [0; 1];\noutput z = [{z}];\n\
             premise s = x1^2 range 0 .. 4;\nrules sector;\nobjective hinf(w -> z) minimize;\n"
        )
    };
    for (z, warned) in [("100 * x1", true), ("x1", false)] {
        let (_, c) = common::compile_text("hinf.tsf", &spec(z));
        assert_eq!(c.status, Status::Certified, "{z}");
        let roa = c
            .report
            .region_of_attraction
            .as_ref()
            .expect("saturation region");
        let u_inv = DMatrix::from_fn(2, 2, |i, j| roa.u[i][j])
            .try_inverse()
            .expect("U > 0");
        let demand = c
            .report
            .gains
            .iter()
            .map(|g| {
                let f = DMatrix::from_row_slice(1, 2, &g.f[0]);
                (&f * &u_inv * f.transpose())[(0, 0)].sqrt()
            })
            .fold(0.0, f64::max);
        let note = c
            .report
            .notes
            .iter()
            .find(|n| n.contains("at the edge of the certified set"));
        assert_eq!(
            note.is_some(),
            demand > 10.0,
            "{z}: demand {demand}, notes {:?}",
            c.report.notes
        );
        assert_eq!(note.is_some(), warned, "{z}: demand {demand}");
        if let Some(n) = note {
            assert!(n.contains(&format!("{demand:.3e}")), "{n}");
        }
    }
}
