//! Double-sum relaxations: sufficient LMI conditions for
//! sum_i sum_j h_i h_j Q_ij < 0 from the blocks Q_ij of one objective family.
//! One file per relaxation, each implementing
//! [`super::relaxation::DoubleSum`]; [`Relaxer`] applies the spec's one to
//! every family and collects what the certificate and report need.

mod basic;
mod mismatch;
mod polya;
mod tanaka;
mod tuan;

use super::reduction::Reduction;
use super::relaxation::{DoubleSum, Family, Sink};
use crate::model::TsModel;
use tsf_lang::spec::Relaxation;
use tsf_lmi::{LmiError, Problem};

/// The implementation of a spec's relaxation.
fn double_sum(r: Relaxation) -> Box<dyn DoubleSum> {
    match r {
        Relaxation::Basic => Box::new(basic::Basic),
        Relaxation::Tanaka { s } => Box::new(tanaka::Tanaka { s }),
        Relaxation::Tuan => Box::new(tuan::Tuan),
        Relaxation::Polya { d } => Box::new(polya::Polya { d }),
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
