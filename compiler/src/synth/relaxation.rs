//! Double-sum relaxations: sufficient LMI conditions for
//! sum_i sum_j h_i h_j Q_ij < 0 from the blocks Q_ij of one objective family.

use super::lmis::nonstrict_psd;
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

/// Imposes objective families under one relaxation and collects what the
/// certificate and report need: the reductions applied and the names of
/// constraints that are non-strict in the theory.
#[derive(Debug)]
pub struct Relaxer<'m> {
    model: &'m TsModel,
    relaxation: Relaxation,
    eps: f64,
    pair_reduce: bool,
    /// Reductions applied, one sentence each.
    pub reductions: Vec<String>,
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
            relaxation,
            eps,
            pair_reduce,
            reductions: Vec::new(),
            nonstrict: Vec::new(),
        }
    }

    /// Every plant/controller pair `Q_ij < 0` (membership mismatch with no
    /// bound used): the sampled-data and event-triggered families, whose
    /// controller memberships are evaluated at x(t_k).
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
        relax(
            problem,
            self.model,
            fam,
            self.relaxation,
            self.eps,
            self.pair_reduce,
            &mut self.reductions,
            &mut self.nonstrict,
        )
    }
}

#[allow(clippy::too_many_arguments)]
fn relax(
    problem: &mut Problem,
    model: &TsModel,
    fam: &Family<'_>,
    relaxation: Relaxation,
    eps: f64,
    pair_reduce: bool,
    reductions: &mut Vec<String>,
    nonstrict: &mut Vec<String>,
) -> Result<(), LmiError> {
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
    let name = |what: &str, i: usize, j: usize| format!("{} {what}[{},{}]", fam.name, i + 1, j + 1);
    let mut dropped = 0usize;
    match relaxation {
        Relaxation::Basic => {
            for i in 0..r {
                problem.nsd(&name("Q", i, i), (fam.q)(i, i)?, eps)?;
                for j in i + 1..r {
                    if !overlap(i, j) {
                        continue;
                    }
                    if pair_reduce {
                        dropped += 1;
                        continue;
                    }
                    problem.nsd(
                        &name("Q+Q'", i, j),
                        (fam.q)(i, j)?.add((fam.q)(j, i)?)?,
                        eps,
                    )?;
                }
            }
        }
        Relaxation::Tanaka { .. } if pair_reduce => {
            // Every pair LMI is implied and Y = 0 is then optimal: the vertex
            // LMIs Q_ii < 0 are equivalent. Y is left out of the solved problem
            // (the certificate checks the original conditions with Y = 0).
            for i in 0..r {
                problem.nsd(&name("Q+(s-1)Y", i, i), (fam.q)(i, i)?, eps)?;
            }
            let pairs = (0..r)
                .flat_map(|i| (i + 1..r).map(move |j| (i, j)))
                .filter(|&(i, j)| overlap(i, j))
                .count();
            reductions.push(format!(
                "{}: tanaka slack Y = 0 and {pairs} pair LMIs dropped: every rule shares B, so (Q_ij + Q_ji)/2 = (Q_ii + Q_jj)/2 < 0 <= Y is implied by the vertex LMIs; the certificate checks the original conditions with Y = 0",
                fam.name
            ));
        }
        Relaxation::Tanaka { s } => {
            let size = (fam.q)(0, 0)?.shape().0;
            let y = problem.symmetric(&format!("Y_{}", fam.name), size)?;
            nonstrict_psd(
                problem,
                nonstrict,
                &format!("{} Y >= 0", fam.name),
                Expr::var(y),
                eps,
            )?;
            for i in 0..r {
                let e = (fam.q)(i, i)?.add(Expr::var(y).scale((s as f64 - 1.0).max(0.0))?)?;
                problem.nsd(&name("Q+(s-1)Y", i, i), e, eps)?;
                for j in i + 1..r {
                    if !overlap(i, j) {
                        continue;
                    }
                    if pair_reduce {
                        dropped += 1;
                        continue;
                    }
                    let e = (fam.q)(i, j)?
                        .add((fam.q)(j, i)?)?
                        .scale(0.5)?
                        .sub(Expr::var(y))?;
                    let n = name("(Q+Q')/2-Y", i, j);
                    problem.nsd(&n, e, eps)?;
                    nonstrict.push(n);
                }
            }
        }
        Relaxation::Tuan => {
            let c = if r > 1 { 2.0 / (r as f64 - 1.0) } else { 0.0 };
            for i in 0..r {
                problem.nsd(&name("Q", i, i), (fam.q)(i, i)?, eps)?;
            }
            for i in 0..r {
                for j in 0..r {
                    if i == j {
                        continue;
                    }
                    if pair_reduce {
                        dropped += 1;
                        continue;
                    }
                    let e = (fam.q)(i, i)?
                        .scale(c)?
                        .add((fam.q)(i, j)?)?
                        .add((fam.q)(j, i)?)?;
                    problem.nsd(&name("tuan", i, j), e, eps)?;
                }
            }
        }
        Relaxation::MembershipMismatch { .. } => {
            // Plant and controller memberships differ: every Q_ij on its own.
            for i in 0..r {
                for j in 0..r {
                    problem.nsd(&name("Q", i, j), (fam.q)(i, j)?, eps)?;
                }
            }
        }
    }
    if dropped > 0 {
        reductions.push(format!(
            "{}: {dropped} pair LMIs dropped: every rule shares B, so each equals a sum of vertex LMIs (Q_ij + Q_ji = Q_ii + Q_jj) and is implied; the certificate still checks them",
            fam.name
        ));
    }
    Ok(())
}
