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
        self.model
            .coverage
            .overlap
            .get(i)
            .and_then(|row| row.get(j))
            .copied()
            .unwrap_or(true)
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

/// A double-sum relaxation.
pub trait DoubleSum {
    /// Adds sufficient conditions for sum_ij h_i h_j Q_ij < 0 to the sink.
    fn impose(&self, sink: &mut Sink<'_, '_>, fam: &Family<'_>) -> Result<(), LmiError>;
}
