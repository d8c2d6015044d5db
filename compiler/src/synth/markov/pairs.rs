//! The double-sum relaxation of the mode conditions as data: which
//! combinations of blocks Q_ij each inequality sums, with which slack. The
//! synthesis ([`super::problem`], X variables) and the certificate
//! (`certify/markov.rs`, P variables) read the same list, so they cannot
//! disagree on what is imposed.

use crate::model::TsModel;
use tsf_lang::spec::Relaxation;

/// One inequality `sum_k w_k Q_{i_k j_k} + slack Y < 0` (`<= 0` when not strict).
#[derive(Debug, Clone, PartialEq)]
pub struct PairCondition {
    /// Its label (`Q[1,1]`, `Q+Q'[1,2]`, `Q+(s-1)Y[2,2]`, ...), 1-based.
    pub label: String,
    /// (i, j, w): rule i of the plant, rule j of the controller, weight.
    pub terms: Vec<(usize, usize, f64)>,
    /// Coefficient of the relaxation's slack Y (0 without one).
    pub slack: f64,
    /// Whether the inequality is strict.
    pub strict: bool,
}

impl PairCondition {
    /// The sum of the weights: how often the coupling term sum_b pi_ab P_b
    /// (which does not depend on i, j) enters the inequality.
    pub fn multiplicity(&self) -> f64 {
        self.terms.iter().map(|t| t.2).sum()
    }
}

/// The conditions of `relaxation` over the rules of `model` and whether
/// they use a slack Y >= 0 (one per mode). Basic (Tanaka & Wang 2001):
/// Q_ii < 0, Q_ij + Q_ji < 0; membership_mismatch: every Q_ij < 0; tanaka
/// (Tanaka, Ikeda & Wang 1996): Q_ii + (s - 1) Y < 0, (Q_ij + Q_ji)/2 - Y <= 0.
/// Pairs of rules that never fire together are left out. Other relaxations
/// are refused by the checker (`None`).
pub fn conditions(model: &TsModel, relaxation: Relaxation) -> Option<(Vec<PairCondition>, bool)> {
    let r = model.r();
    let overlap = |i: usize, j: usize| {
        model
            .coverage
            .overlap
            .get(i)
            .and_then(|row| row.get(j))
            .copied()
            .unwrap_or(true)
    };
    let cond =
        |label: String, terms: Vec<(usize, usize, f64)>, slack: f64, strict: bool| PairCondition {
            label,
            terms,
            slack,
            strict,
        };
    let mut out = Vec::new();
    let uses_slack = matches!(relaxation, Relaxation::Tanaka { .. });
    for i in 0..r {
        match relaxation {
            Relaxation::Basic => {
                out.push(cond(
                    format!("Q[{0},{0}]", i + 1),
                    vec![(i, i, 1.0)],
                    0.0,
                    true,
                ));
                for j in (i + 1..r).filter(|j| overlap(i, *j)) {
                    let label = format!("Q+Q'[{},{}]", i + 1, j + 1);
                    out.push(cond(label, vec![(i, j, 1.0), (j, i, 1.0)], 0.0, true));
                }
            }
            Relaxation::MembershipMismatch { .. } => {
                for j in (0..r).filter(|j| i == *j || overlap(i, *j)) {
                    let label = format!("Q[{},{}]", i + 1, j + 1);
                    out.push(cond(label, vec![(i, j, 1.0)], 0.0, true));
                }
            }
            Relaxation::Tanaka { s } => {
                let k = (s as f64 - 1.0).max(0.0);
                let label = format!("Q+(s-1)Y[{0},{0}]", i + 1);
                out.push(cond(label, vec![(i, i, 1.0)], k, true));
                for j in (i + 1..r).filter(|j| overlap(i, *j)) {
                    let label = format!("(Q+Q')/2-Y[{},{}]", i + 1, j + 1);
                    out.push(cond(label, vec![(i, j, 0.5), (j, i, 0.5)], -1.0, false));
                }
            }
            Relaxation::Tuan | Relaxation::Polya { .. } => return None,
        }
    }
    Some((out, uses_slack))
}
