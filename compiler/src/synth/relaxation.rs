//! The relaxation seam: an objective family's blocks Q_ij ([`Family`]), where
//! a relaxation writes its conditions ([`Sink`]) and the trait every
//! relaxation in [`super::relaxations`] implements ([`DoubleSum`]).

use super::reduction::Reduction;
use crate::model::TsModel;
use tsf_lmi::{Expr, LmiError, Problem};

/// Blocks Q_ij (rule i of the plant, rule j of the controller) of one objective.
pub struct Family<'a> {
    /// Name used in constraint names (`decay`, `hinf`, ...).
    pub name: String,
    /// Q_ij as an affine expression.
    #[allow(clippy::type_complexity)]
    pub q: Box<dyn Fn(usize, usize) -> Result<Expr, LmiError> + 'a>,
}

impl Family<'_> {
    /// Q_ij.
    pub fn q(&self, i: usize, j: usize) -> Result<Expr, LmiError> {
        (self.q)(i, j)
    }

    /// The constraint name `<family> <what>[i,j]` (1-based).
    pub fn name(&self, what: &str, i: usize, j: usize) -> String {
        format!("{} {what}[{},{}]", self.name, i + 1, j + 1)
    }
}

/// Whether rules i and j of `model` can fire together.
pub fn overlap(model: &TsModel, i: usize, j: usize) -> bool {
    model
        .coverage
        .overlap
        .get(i)
        .and_then(|row| row.get(j))
        .copied()
        .unwrap_or(true)
}

/// Where a relaxation writes its conditions.
pub struct Sink<'p, 'm> {
    /// The problem.
    pub problem: &'p mut Problem,
    /// The model (rule count, overlap of rule supports).
    pub model: &'m TsModel,
    /// Margin of strict LMIs.
    pub eps: f64,
    /// Whether implied pair conditions may be left out (every rule shares B).
    pub pair_reduce: bool,
    /// Reductions applied.
    pub reductions: &'p mut Vec<Reduction>,
    /// Constraints non-strict in the theory.
    pub nonstrict: &'p mut Vec<String>,
}

impl Sink<'_, '_> {
    /// Number of rules.
    pub fn r(&self) -> usize {
        self.model.r()
    }

    /// Whether rules i and j can fire together (pairs that never do need no condition).
    pub fn overlap(&self, i: usize, j: usize) -> bool {
        overlap(self.model, i, j)
    }

    /// `e < 0` (strict, with the margin).
    pub fn negative(&mut self, name: &str, e: Expr) -> Result<(), LmiError> {
        self.problem.nsd(name, e, self.eps)?;
        Ok(())
    }

    /// Records that `count` implied pair LMIs of `fam` were left out.
    pub fn dropped(&mut self, fam: &Family<'_>, count: usize) {
        if count > 0 {
            self.reductions.push(Reduction::PairsDropped {
                family: fam.name.clone(),
                count,
            });
        }
    }
}

/// One inequality `sum_k w_k Q_{i_k j_k} + slack Y < 0` (`<= 0` when not
/// strict): a relaxation's condition as data, for problems that build their
/// blocks Q_ij themselves (the Markov modes, in X and in P variables).
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
    /// A condition on the blocks `terms` with slack coefficient `slack`.
    pub fn new(label: String, terms: Vec<(usize, usize, f64)>, slack: f64, strict: bool) -> Self {
        PairCondition {
            label,
            terms,
            slack,
            strict,
        }
    }

    /// The sum of the weights: how often a term that does not depend on
    /// (i, j) (the modes' coupling sum_b pi_ab P_b) enters the inequality.
    pub fn multiplicity(&self) -> f64 {
        self.terms.iter().map(|t| t.2).sum()
    }
}

/// A relaxation's conditions as data: the inequalities and whether they use
/// a slack Y >= 0.
#[derive(Debug, Clone, PartialEq)]
pub struct Conditions {
    /// The inequalities.
    pub list: Vec<PairCondition>,
    /// Whether a slack Y >= 0 enters them.
    pub slack: bool,
}

/// A double-sum relaxation.
pub trait DoubleSum {
    /// Adds sufficient conditions for sum_ij h_i h_j Q_ij < 0 to the sink.
    fn impose(&self, sink: &mut Sink<'_, '_>, fam: &Family<'_>) -> Result<(), LmiError>;

    /// The same conditions as data over `r` rules, leaving out pairs that
    /// never fire together (`overlap(i, j)` false); `None` when the
    /// relaxation needs variables of its own beyond one slack Y (Tuan's,
    /// Polya's, the kappa-bounded mismatch).
    fn conditions(&self, _r: usize, _overlap: &dyn Fn(usize, usize) -> bool) -> Option<Conditions> {
        None
    }
}
