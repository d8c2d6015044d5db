//! Bounded membership mismatch (imperfect premise matching, after Arino &
//! Sala, *Extensions to "Stability analysis of fuzzy control systems subject
//! to uncertain grades of membership"*, 2008): the plant blends its rules
//! with h (on the simplex), the controller with k (on the simplex), and
//! |k_j - h_j| <= kappa for every rule j at every instant. The condition is
//!
//!   S(h, k) = sum_i sum_j h_i k_j Q_ij < 0   for every such (h, k).
//!
//! Slacks P_ij >= 0 and G_ij >= 0 (plant rule i, controller rule j) multiply
//! the two sides of the bound, k_j - h_j + kappa >= 0 and h_j + kappa - k_j
//! >= 0, so for every i
//!
//!   sum_j k_j Q_ij <= sum_j k_j Q_ij + (k_j - h_j + kappa) P_ij + (h_j + kappa - k_j) G_ij
//!                   = sum_j k_j T_ij + sum_j h_j D_ij                    (sum_j k_j = 1)
//!
//! with D_ij = G_ij - P_ij and T_ij = Q_ij - D_ij + kappa sum_s (P_is + G_is).
//! Hence S(h, k) <= sum_ij h_i k_j T_ij + sum_ij h_i h_j D_ij, and the LMIs
//!
//!   T_ij < 0 for every (i, j);   D_ii <= 0,  D_ij + D_ji <= 0 (i < j, rules that overlap)
//!
//! imply S < 0 (the second group is the basic relaxation of the plant's own
//! double sum, non-strict). kappa = 0 is equivalent to `basic` (D_ij = Q_ij
//! up to the margin); kappa = 1 bounds nothing and is equivalent to every pair
//! Q_ij < 0 (P = G = 0 is then optimal up to the margin). A pair (i, j) whose
//! plant rules never fire together gets no D condition: its D_ij = G_ij may be
//! large, at the cost kappa G_ij in every T_is of plant rule i.
//!
//! Soundness needs the bound of the shipped loop: the controller's
//! memberships within kappa of the plant's at every instant. Only loops
//! without a trigger use this relaxation (see `relaxations::double_sum`).

use crate::synth::blocks::nonstrict_psd;
use crate::synth::relaxation::{DoubleSum, Family, Sink};
use tsf_lmi::{Expr, LmiError, Var};

/// The kappa-bounded mismatch relaxation.
pub struct MismatchBounded {
    /// Bound on |k_j - h_j| for every rule j.
    pub kappa: f64,
}

impl DoubleSum for MismatchBounded {
    fn impose(&self, sink: &mut Sink<'_, '_>, fam: &Family<'_>) -> Result<(), LmiError> {
        let r = sink.r();
        let size = fam.q(0, 0)?.shape().0;
        // p[i][j], g[i][j]: the multipliers of the lower and upper bounds.
        let mut p: Vec<Vec<Var>> = Vec::with_capacity(r);
        let mut g: Vec<Vec<Var>> = Vec::with_capacity(r);
        for i in 0..r {
            let (mut pi, mut gi) = (Vec::with_capacity(r), Vec::with_capacity(r));
            for j in 0..r {
                for (what, row) in [("Pk", &mut pi), ("Gk", &mut gi)] {
                    let v = sink.problem.symmetric(&slack_name(fam, what, i, j), size)?;
                    nonstrict_psd(
                        sink.problem,
                        sink.nonstrict,
                        &format!("{} >= 0", fam.name(what, i, j)),
                        Expr::var(v),
                        sink.eps,
                    )?;
                    row.push(v);
                }
            }
            p.push(pi);
            g.push(gi);
        }
        let d = |i: usize, j: usize| Expr::var(g[i][j]).sub(Expr::var(p[i][j]));
        for i in 0..r {
            // kappa sum_s (P_is + G_is), shared by every T_ij of plant rule i.
            let spread = Expr::sum(
                size,
                size,
                (0..r).flat_map(|s| [Expr::var(p[i][s]), Expr::var(g[i][s])]),
            )?
            .scale(self.kappa)?;
            for j in 0..r {
                let t = fam.q(i, j)?.sub(d(i, j)?)?.add(spread.clone())?;
                sink.negative(&fam.name("Q-D+kS", i, j), t)?;
            }
        }
        for i in 0..r {
            let n = fam.name("D", i, i);
            sink.negative(&n, d(i, i)?)?;
            sink.nonstrict.push(n);
            for j in i + 1..r {
                if !sink.overlap(i, j) {
                    continue;
                }
                let n = fam.name("D+D'", i, j);
                sink.negative(&n, d(i, j)?.add(d(j, i)?)?)?;
                sink.nonstrict.push(n);
            }
        }
        Ok(())
    }
}

/// A slack's variable name in the full problem.
fn slack_name(fam: &Family<'_>, what: &str, i: usize, j: usize) -> String {
    format!("{what}_{}[{},{}]", fam.name, i + 1, j + 1)
}
