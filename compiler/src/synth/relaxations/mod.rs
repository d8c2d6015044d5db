//! Double-sum relaxations: sufficient LMI conditions for
//! sum_i sum_j h_i h_j Q_ij < 0 from the blocks Q_ij of one objective family.
//! One file per relaxation, each implementing [`DoubleSum`]; [`Relaxer`]
//! applies the spec's one to every family and collects what the certificate
//! and report need.

mod basic;
mod mismatch;
mod tanaka;
mod tuan;

use super::reduction::Reduction;
use crate::model::TsModel;
use tsf_lang::spec::Relaxation;
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

/// The implementation of a spec's relaxation.
fn double_sum(r: Relaxation) -> Box<dyn DoubleSum> {
    match r {
        Relaxation::Basic => Box::new(basic::Basic),
        Relaxation::Tanaka { s } => Box::new(tanaka::Tanaka { s }),
        Relaxation::Tuan => Box::new(tuan::Tuan),
        // kappa does not relax these conditions (see mismatch.rs).
        Relaxation::MembershipMismatch { .. } => Box::new(mismatch::Mismatch),
    }
}

/// Imposes objective families under one relaxation and collects what the
/// certificate and report need: the reductions applied and the names of
/// constraints that are non-strict in the theory.
pub struct Relaxer<'m> {
    model: &'m TsModel,
    relaxation: Box<dyn DoubleSum>,
    eps: f64,
    pair_reduce: bool,
    /// Reductions applied.
    pub reductions: Vec<Reduction>,
    /// Constraints non-strict in the theory.
    pub nonstrict: Vec<String>,
}

impl<'m> Relaxer<'m> {
    /// `relaxation` with margin `eps`. With `pair_reduce` (every rule shares B)
    /// the pair conditions are left out: they equal sums of vertex conditions
    /// (Q_ij + Q_ji = Q_ii + Q_jj) and so are implied.
    pub fn new(model: &'m TsModel, relaxation: Relaxation, eps: f64, pair_reduce: bool) -> Self {
        Relaxer {
            model,
            relaxation: double_sum(relaxation),
            eps,
            pair_reduce,
            reductions: Vec::new(),
            nonstrict: Vec::new(),
        }
    }

    /// Every plant/controller pair `Q_ij < 0`: the sampled-data and
    /// event-triggered families, whose controller memberships are evaluated
    /// at x(t_k).
    pub fn every_pair(model: &'m TsModel, eps: f64) -> Self {
        Relaxer::new(
            model,
            Relaxation::MembershipMismatch { kappa: 0.0 },
            eps,
            false,
        )
    }

    /// Adds the relaxed conditions of `fam` to `problem`.
    pub fn impose(&mut self, problem: &mut Problem, fam: &Family<'_>) -> Result<(), LmiError> {
        let mut sink = Sink {
            problem,
            model: self.model,
            eps: self.eps,
            pair_reduce: self.pair_reduce,
            reductions: &mut self.reductions,
            nonstrict: &mut self.nonstrict,
        };
        self.relaxation.impose(&mut sink, fam)
    }
}
