//! Model consistency: the T-S model the rules blend, sum_i h_i(z(x)) A_i,
//! compared with the state-dependent A(x) and B(x) it stands for, on a grid
//! of states spanning the rules' operating points. An exact sector model
//! gives 0; a rule whose local model is attached to the wrong sets does not.
//! Above [`MISMATCH_TOLERANCE`] the model stage warns, naming the rules that
//! fire where the mismatch is worst. Only the premise region counts (states
//! whose premise values leave the declared ranges are skipped).

use super::premise::{premise_values, rule_weight, PremiseLayout, TermSpec};
use super::LocalModel;
use nalgebra::DMatrix;
use tsf_lang::eval::Mode;
use tsf_lang::spec::{ModelMatrix, Spec};
use tsf_lang::Diagnostic;

/// Relative mismatch above which the model stage warns (25 %): the worst
/// `||sum_i h_i M_i - M(x)||_F / max_i ||M_i||_F` over the grid, M = A, B.
pub const MISMATCH_TOLERANCE: f64 = 0.25;

/// Most states evaluated (the grid per varying component shrinks to fit).
pub const MAX_POINTS: usize = 20_000;

/// Points per varying state component, at most.
const MAX_PER_AXIS: usize = 33;

/// Where the blended model and A(x), B(x) differ most.
#[derive(Debug, Clone, PartialEq)]
pub struct Consistency {
    /// States compared (inside the premise region).
    pub points: usize,
    /// Worst relative mismatch (Frobenius norm, relative to the largest local model).
    pub worst: f64,
    /// The matrix it is in (`A` or `B`).
    pub matrix: &'static str,
    /// The state where it is.
    pub at: Vec<f64>,
    /// Rules firing there, with their normalized weights h_i > 1 %.
    pub firing: Vec<(String, f64)>,
}

/// Grid bounds: from the smallest to the largest operating-point coordinate,
/// or the box a sector model was fitted on (its rules have no operating point).
fn bounds(spec: &Spec, rules: &[LocalModel], n: usize) -> Vec<(f64, f64)> {
    if let Some(s) = &spec.sector {
        return s.sample_box.clone();
    }
    (0..n)
        .map(|k| {
            rules
                .iter()
                .filter_map(|r| r.at.as_ref().and_then(|x| x.get(k).copied()))
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
                    (lo.min(v), hi.max(v))
                })
        })
        .collect()
}

/// Grid axes over `bounds`, at most [`MAX_POINTS`] points in all.
fn axes(bounds: &[(f64, f64)]) -> Vec<Vec<f64>> {
    let varying = bounds.iter().filter(|(lo, hi)| hi > lo).count().max(1);
    let per_axis =
        ((MAX_POINTS as f64).powf(1.0 / varying as f64).floor() as usize).clamp(2, MAX_PER_AXIS);
    bounds
        .iter()
        .map(|&(lo, hi)| {
            if !(lo.is_finite() && hi.is_finite()) {
                vec![0.0]
            } else if hi > lo {
                (0..per_axis)
                    .map(|i| lo + (hi - lo) * i as f64 / (per_axis - 1) as f64)
                    .collect()
            } else {
                vec![lo]
            }
        })
        .collect()
}

/// Compares the blended model with A(x), B(x); `None` when neither depends
/// on the state (nothing to compare with) or no rule has an operating point
/// (and no sector model built them).
pub(super) fn check(
    spec: &Spec,
    rules: &[LocalModel],
    layout: &PremiseLayout,
    terms: &[Vec<TermSpec>],
    diags: &mut Vec<Diagnostic>,
) -> Option<Consistency> {
    let dependent = |m: &Option<ModelMatrix>| m.as_ref().filter(|m| m.state_dependent).cloned();
    let targets: Vec<(&'static str, ModelMatrix, Vec<&DMatrix<f64>>)> = [
        (
            "A",
            dependent(&spec.a),
            rules.iter().map(|r| &r.a).collect(),
        ),
        (
            "B",
            dependent(&spec.b),
            rules.iter().map(|r| &r.b).collect(),
        ),
    ]
    .into_iter()
    .filter_map(|(name, m, locals)| m.map(|m| (name, m, locals)))
    .collect();
    if targets.is_empty() || (rules.iter().all(|r| r.at.is_none()) && spec.sector.is_none()) {
        return None;
    }
    let ranges: Vec<(f64, f64)> = layout
        .slots
        .iter()
        .flat_map(|s| std::iter::repeat_n(s.range, s.dim))
        .collect();
    let grid = axes(&bounds(spec, rules, spec.n()));
    let mut idx = vec![0usize; grid.len()];
    let mut worst = Consistency {
        points: 0,
        worst: 0.0,
        matrix: "A",
        at: Vec::new(),
        firing: Vec::new(),
    };
    let mut worst_h = Vec::new();
    loop {
        let x: Vec<f64> = idx.iter().zip(&grid).map(|(&i, a)| a[i]).collect();
        if let Some(h) = normalized_weights(spec, &x, &ranges, terms) {
            worst.points += 1;
            let env = spec.state_env(&x, Mode::Exact);
            for (name, m, locals) in &targets {
                let Ok(exact) = env.eval(&m.expr) else {
                    continue;
                };
                let scale = locals
                    .iter()
                    .map(|l| l.norm())
                    .fold(f64::MIN_POSITIVE, f64::max);
                let mut blend = DMatrix::zeros(exact.nrows(), exact.ncols());
                for (hi, l) in h.iter().zip(locals) {
                    if l.shape() == blend.shape() {
                        blend += *l * *hi;
                    }
                }
                let rel = (blend - exact).norm() / scale;
                if rel > worst.worst {
                    worst.worst = rel;
                    worst.matrix = name;
                    worst.at = x.clone();
                    worst_h = h.clone();
                }
            }
        }
        // Odometer over the grid.
        let mut k = 0;
        while k < idx.len() {
            idx[k] += 1;
            if idx[k] < grid[k].len() {
                break;
            }
            idx[k] = 0;
            k += 1;
        }
        if k == idx.len() {
            break;
        }
    }
    worst.firing = rules
        .iter()
        .zip(&worst_h)
        .filter(|(_, h)| **h > 0.01)
        .map(|(r, h)| (r.name.clone(), *h))
        .collect();
    if worst.worst > MISMATCH_TOLERANCE {
        diags.push(warning(spec, &worst, &targets));
    }
    Some(worst)
}

/// Normalized rule weights at state `x`, if its premise values lie in the
/// declared ranges and some rule fires.
fn normalized_weights(
    spec: &Spec,
    x: &[f64],
    ranges: &[(f64, f64)],
    terms: &[Vec<TermSpec>],
) -> Option<Vec<f64>> {
    let z = premise_values(spec, x).ok()?;
    let inside = z.len() == ranges.len()
        && z.iter()
            .zip(ranges)
            .all(|(v, (lo, hi))| *v >= *lo && *v <= *hi);
    if !inside {
        return None;
    }
    let w: Vec<f64> = terms.iter().map(|t| rule_weight(t, &z)).collect();
    let total: f64 = w.iter().sum();
    (total > 0.0 && total.is_finite()).then(|| w.iter().map(|v| v / total).collect())
}

fn warning(
    spec: &Spec,
    c: &Consistency,
    targets: &[(&'static str, ModelMatrix, Vec<&DMatrix<f64>>)],
) -> Diagnostic {
    let span = targets
        .iter()
        .find(|(n, _, _)| *n == c.matrix)
        .map_or(spec.controller.span, |(_, m, _)| m.span);
    let x =
        c.at.iter()
            .map(|v| format!("{v:.4}"))
            .collect::<Vec<_>>()
            .join(", ");
    let firing = c
        .firing
        .iter()
        .map(|(r, h)| format!("{r} (h = {h:.2})"))
        .collect::<Vec<_>>()
        .join(", ");
    let mut d = Diagnostic::warning(
        span,
        format!(
            "the rules blend a model that differs from {}(x) by {:.0}% at x = [{x}]; the certificate covers the blended model, not {}(x)",
            c.matrix,
            100.0 * c.worst,
            c.matrix
        ),
    )
    .with_label(format!("{}(x) defined here", c.matrix))
    .with_help(format!(
        "rules firing there: {firing}; check that each rule's sets match its operating point (where a rule fires alone its local model should equal {}(x)); tolerance {:.0}%",
        c.matrix,
        100.0 * MISMATCH_TOLERANCE
    ));
    for (r, _) in &c.firing {
        if let Some(rule) = spec.rules.iter().find(|s| s.name == *r) {
            d = d.with_secondary(rule.span, format!("rule {r} fires here"));
        }
    }
    d
}
