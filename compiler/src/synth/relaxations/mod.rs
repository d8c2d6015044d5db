//! Double-sum relaxations: sufficient LMI conditions for
//! sum_i sum_j h_i h_j Q_ij < 0 from the blocks Q_ij of one objective family.
//! One file per relaxation, each implementing
//! [`super::relaxation::DoubleSum`]; [`Relaxer`] applies the spec's one to
//! every family and collects what the certificate and report need.

mod basic;
mod mismatch;
mod mismatch_bounded;
mod polya;
mod tanaka;
mod tuan;

use super::reduction::Reduction;
use super::relaxation::{Conditions, DoubleSum, Family, Sink};
use crate::model::TsModel;
use tsf_lang::spec::{Relaxation, Trigger};
use tsf_lmi::{LmiError, Problem};

/// The implementation of a spec's relaxation for `model`.
fn double_sum(model: &TsModel, r: Relaxation) -> Box<dyn DoubleSum> {
    match r {
        Relaxation::Basic => Box::new(basic::Basic),
        Relaxation::Tanaka { s } => Box::new(tanaka::Tanaka { s }),
        Relaxation::Tuan => Box::new(tuan::Tuan),
        Relaxation::Polya { d } => Box::new(polya::Polya { d }),
        Relaxation::MembershipMismatch { kappa } if relies(model, kappa) => {
            Box::new(mismatch_bounded::MismatchBounded { kappa })
        }
        Relaxation::MembershipMismatch { .. } => Box::new(mismatch::Mismatch),
    }
}

/// The conditions of the spec's `relaxation` over the rules of `model` as
/// data ([`DoubleSum::conditions`]), for problems that build their blocks
/// themselves (the Markov modes); `None` for a relaxation without that form
/// (the checker refuses those with modes).
pub fn conditions(model: &TsModel, relaxation: Relaxation) -> Option<Conditions> {
    let overlap = |i: usize, j: usize| super::relaxation::overlap(model, i, j);
    double_sum(model, relaxation).conditions(model.r(), &overlap)
}

/// The mismatch bound kappa the certificate relies on: the spec's
/// `membership_mismatch(kappa = ..)` in a continuous loop without modes. A sampled or
/// event-triggered loop holds the controller's memberships from the last
/// transmitted sample, so no kappa bounds its mismatch: every plant/controller
/// pair is imposed there (`None`), and kappa is not used; nor with kappa = 1.
pub fn kappa_relied_on(model: &TsModel) -> Option<f64> {
    match model.spec.relaxation.node {
        Relaxation::MembershipMismatch { kappa } if relies(model, kappa) => Some(kappa),
        _ => None,
    }
}

/// Whether the bounded-mismatch LMIs are used: a continuous loop (below) and
/// kappa < 1. kappa = 1 bounds nothing: it is the every-pair condition, imposed
/// as such (the same feasible set without the 2 r^2 slacks per objective).
fn relies(model: &TsModel, kappa: f64) -> bool {
    kappa < 1.0 && continuous(model)
}

/// Whether the bounded-mismatch LMIs apply: the controller is updated
/// continuously (no trigger, or `trigger continuous`) and there are no Markov
/// modes (whose conditions, `synth/markov/pairs.rs`, impose every pair).
fn continuous(model: &TsModel) -> bool {
    model.spec.modes.is_none()
        && matches!(
            model.spec.trigger.as_ref().map(|t| &t.node),
            None | Some(Trigger::Continuous)
        )
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
        Relaxer::with(model, double_sum(model, relaxation), eps, pair_reduce)
    }

    fn with(
        model: &'m TsModel,
        relaxation: Box<dyn DoubleSum>,
        eps: f64,
        pair_reduce: bool,
    ) -> Self {
        Relaxer {
            model,
            relaxation,
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
        Relaxer::with(model, Box::new(mismatch::Mismatch), eps, false)
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
