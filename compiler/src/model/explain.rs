//! `tsfc check --explain`: the T-S model in words and numbers, as the
//! compiler built it: premises and their sets, the sector construction (when
//! `rules sector;` built the rules), each rule's premise and local model, and
//! the consistency of the blend with A(x), B(x).

use super::coverage::fmt_num;
use super::TsModel;
use nalgebra::DMatrix;
use std::fmt::Write;
use tsf_lang::spec::ClauseSet;

/// A matrix on one line per row, `[a, b; c, d]` style, indented.
pub fn matrix(name: &str, m: &DMatrix<f64>) -> String {
    let rows: Vec<String> = m
        .row_iter()
        .map(|r| r.iter().map(|v| fmt_num(*v)).collect::<Vec<_>>().join(", "))
        .collect();
    let pad = " ".repeat(name.len() + 8);
    format!("    {name} = [{}]\n", rows.join(&format!(";\n{pad}")))
}

/// The explanation of `model` (plain text, deterministic).
pub fn explain(model: &TsModel) -> String {
    let spec = &model.spec;
    let mut out = String::new();
    let _ = writeln!(out, "premises:");
    for p in &spec.premises {
        let range = p
            .range
            .map(|(lo, hi)| format!(" range {} .. {}", fmt_num(lo), fmt_num(hi)))
            .unwrap_or_default();
        let sets: Vec<String> = p
            .sets
            .iter()
            .map(|s| format!("{} = {}", s.name, s.shape))
            .collect();
        let _ = writeln!(
            out,
            "  {}{range}: {}",
            p.name,
            if sets.is_empty() {
                "(about sets)".into()
            } else {
                sets.join(", ")
            }
        );
    }
    if let Some(s) = &spec.sector {
        let names: Vec<String> = s
            .premises
            .iter()
            .map(|&k| spec.premises[k].name.clone())
            .collect();
        let _ = writeln!(
            out,
            "sector model (`rules sector;`): {} premise(s) ({}), {} rules; on [lo, hi] max = (z - lo)/(hi - lo), min = (hi - z)/(hi - lo);\n  A, B, D are affine in each premise: fitted on {} sampled states, worst relative residual {:.1e} (tolerance {:.0e})",
            names.len(),
            names.join(", "),
            spec.rules.len(),
            s.samples,
            s.residual,
            tsf_lang::sector::FIT_TOLERANCE
        );
    }
    let _ = writeln!(out, "rules:");
    for k in 0..model.rules.len() {
        out.push_str(&rule(model, k));
    }
    if let Some(c) = &model.consistency {
        let _ =
            writeln!(
            out,
            "model consistency: worst relative mismatch {:.2e} in {} over {} states (tolerance {})",
            c.worst, c.matrix, c.points, super::MISMATCH_TOLERANCE
        );
    }
    out
}

/// Rule `k` of `model` as `--explain` prints it: its premise, then its local
/// model (A_i, B_i and, with disturbances, D_i) as the checker built it.
pub fn rule(model: &TsModel, k: usize) -> String {
    let spec = &model.spec;
    let (Some(rule), Some(local)) = (spec.rules.get(k), model.rules.get(k)) else {
        return String::new();
    };
    let clauses: Vec<String> = rule
        .clauses
        .iter()
        .map(|c| {
            let p = &spec.premises[c.premise];
            match &c.set {
                ClauseSet::Named(k) => format!(
                    "{} is {}",
                    p.name,
                    p.sets.get(*k).map_or("?", |s| s.name.as_str())
                ),
                ClauseSet::About(v) => format!(
                    "{} is about [{}]",
                    p.name,
                    v.iter().map(|x| fmt_num(*x)).collect::<Vec<_>>().join(", ")
                ),
            }
        })
        .collect();
    let mut out = format!("  {}: {}\n", rule.name, clauses.join(" and "));
    out.push_str(&matrix("A", &local.a));
    out.push_str(&matrix("B", &local.b));
    if model.q > 0 {
        out.push_str(&matrix("D", &local.d));
    }
    out
}
