//! The coverage check: over the product of the premise ranges, some rule must
//! fire (sum of weights > 0). A hole is an error with an example point.
//!
//! Candidate points per component are the range ends, every set breakpoint and
//! `about` coordinate inside the range, and the midpoints between consecutive
//! candidates. For `tri`/`trap` sets the weights are products of functions that
//! are linear between breakpoints, so a rule that is zero somewhere inside a
//! grid cell is zero at that cell's midpoint too: checking the cell midpoints
//! and vertices is exact for them. Gaussian, sigmoid and `about` sets are
//! positive everywhere in exact arithmetic; the check catches underflow.

use super::premise::{rule_weight, PremiseLayout, TermSpec};
use tsf_lang::spec::{ClauseSet, Spec};
use tsf_lang::{Diagnostic, Span};

/// Most grid points evaluated exhaustively; larger grids are sampled.
pub const MAX_GRID_POINTS: usize = 2_000_000;

/// Outcome of the coverage check.
#[derive(Debug, Clone, PartialEq)]
pub struct Coverage {
    /// Whether every point checked is covered.
    pub covered: bool,
    /// Points evaluated.
    pub points: usize,
    /// Whether the grid was exhaustive (else sampled).
    pub exhaustive: bool,
    /// Smallest total firing weight seen.
    pub min_total_weight: f64,
    /// The weakest point.
    pub weakest: Vec<f64>,
    /// `overlap[i][j]`: rules i and j fire together somewhere on the grid.
    /// Exact for tri/trap premises (their products are positive at the
    /// midpoint of any grid cell where they are positive at all).
    pub overlap: Vec<Vec<bool>>,
    /// The most rules seen firing at one point.
    pub max_firing: usize,
}

/// Uniform points per axis added to the breakpoints when the grid stays small.
const UNIFORM_POINTS: usize = 17;

fn candidates(spec: &Spec, layout: &PremiseLayout, k: usize, uniform: bool) -> Vec<f64> {
    let Some((pi, slot)) = layout
        .slots
        .iter()
        .enumerate()
        .find(|(_, s)| k >= s.first && k < s.first + s.dim)
    else {
        return vec![0.0];
    };
    let (lo, hi) = slot.range;
    let mut v = vec![lo, hi];
    if uniform {
        v.extend(
            (1..UNIFORM_POINTS - 1)
                .map(|i| lo + (hi - lo) * i as f64 / (UNIFORM_POINTS - 1) as f64),
        );
    }
    if let Some(p) = spec.premises.get(pi) {
        v.extend(p.sets.iter().flat_map(|s| s.shape.breakpoints()));
    }
    for r in &spec.rules {
        for c in r.clauses.iter().filter(|c| c.premise == pi) {
            if let ClauseSet::About(pt) = &c.set {
                v.extend(pt.get(k - slot.first).copied());
            }
        }
    }
    v.retain(|x| x.is_finite() && *x >= lo && *x <= hi);
    v.sort_by(f64::total_cmp);
    v.dedup();
    let mids: Vec<f64> = v.windows(2).map(|w| 0.5 * (w[0] + w[1])).collect();
    v.extend(mids);
    v.sort_by(f64::total_cmp);
    v
}

/// Runs the coverage check; a hole becomes an error diagnostic.
pub fn check_coverage(
    spec: &Spec,
    layout: &PremiseLayout,
    terms: &[Vec<TermSpec>],
    diags: &mut Vec<Diagnostic>,
) -> Coverage {
    let p = layout.len();
    let grid = |uniform: bool| -> Vec<Vec<f64>> {
        (0..p)
            .map(|k| candidates(spec, layout, k, uniform))
            .collect()
    };
    let size = |axes: &[Vec<f64>]| -> f64 { axes.iter().map(|a| a.len() as f64).product() };
    let mut axes = grid(true);
    if size(&axes) > MAX_GRID_POINTS as f64 {
        axes = grid(false);
    }
    let total = size(&axes);
    let exhaustive = total <= MAX_GRID_POINTS as f64;
    let count = if exhaustive {
        total as usize
    } else {
        MAX_GRID_POINTS
    };
    let mut z = vec![0.0; p];
    let mut min_w = f64::INFINITY;
    let mut weakest = z.clone();
    let mut rng = 0x9E37_79B9_7F4A_7C15u64;
    let r = terms.len();
    let mut overlap = vec![vec![false; r]; r];
    let mut max_firing = 0;
    let mut weights = vec![0.0; r];
    for idx in 0..count {
        let mut rem = idx;
        for (k, axis) in axes.iter().enumerate() {
            let i = if exhaustive {
                let i = rem % axis.len();
                rem /= axis.len();
                i
            } else {
                // xorshift: a reproducible sample of grid points.
                rng ^= rng << 13;
                rng ^= rng >> 7;
                rng ^= rng << 17;
                (rng % axis.len() as u64) as usize
            };
            z[k] = axis[i];
        }
        for (wi, t) in weights.iter_mut().zip(terms) {
            *wi = rule_weight(t, &z);
        }
        let firing: Vec<usize> = (0..r).filter(|&i| weights[i] > 0.0).collect();
        max_firing = max_firing.max(firing.len());
        for &i in &firing {
            for &j in &firing {
                overlap[i][j] = true;
            }
        }
        let w: f64 = weights.iter().sum();
        if w < min_w {
            min_w = w;
            weakest.clone_from(&z);
            if w <= 0.0 {
                break;
            }
        }
    }
    let covered = min_w > 0.0;
    if !covered {
        let point = weakest
            .iter()
            .enumerate()
            .map(|(k, v)| format!("{} = {}", layout.component_name(k), fmt_num(*v)))
            .collect::<Vec<_>>()
            .join(", ");
        let span = spec.rules.first().map_or(Span::new(0, 0), |r| r.span);
        diags.push(
            Diagnostic::error(span, "the rules do not cover the operating region")
                .with_label("these rules")
                .with_note(format!("no rule fires at {point}"))
                .with_help("add a rule for this region, widen the fuzzy sets, or choose premise variables that partition the region (e.g. `about` sets, or a premise on a function of the state)"),
        );
    } else if min_w < 1e-9 {
        let span = spec.rules.first().map_or(Span::new(0, 0), |r| r.span);
        diags.push(
            Diagnostic::warning(span, format!("the rules barely cover part of the operating region (total firing weight {min_w:.1e})"))
                .with_note("normalised strengths are numerically fragile there; consider wider sets"),
        );
    }
    Coverage {
        covered,
        points: count,
        exhaustive,
        min_total_weight: min_w,
        weakest,
        overlap,
        max_firing,
    }
}

/// Formats a number compactly for messages.
pub fn fmt_num(v: f64) -> String {
    let s = format!("{v:.6}");
    let s = s.trim_end_matches('0').trim_end_matches('.').to_string();
    if s == "-0" {
        "0".into()
    } else {
        s
    }
}
