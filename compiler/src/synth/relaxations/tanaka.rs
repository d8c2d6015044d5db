//! Tanaka, Ikeda & Wang's relaxation for at most `s` rules firing at once
//! (*Robust stabilization of a class of uncertain nonlinear systems via fuzzy
//! control*, 1996): a slack Y >= 0 with Q_ii + (s - 1) Y < 0 and
//! (Q_ij + Q_ji)/2 - Y <= 0.

use crate::synth::blocks::nonstrict_psd;
use crate::synth::reduction::Reduction;
use crate::synth::relaxation::{Conditions, DoubleSum, Family, PairCondition, Sink};
use tsf_lmi::{Expr, LmiError};

/// The relaxation with `s` simultaneously firing rules.
pub struct Tanaka {
    /// s.
    pub s: usize,
}

impl DoubleSum for Tanaka {
    fn impose(&self, sink: &mut Sink<'_, '_>, fam: &Family<'_>) -> Result<(), LmiError> {
        let r = sink.r();
        if sink.pair_reduce {
            // Every pair LMI is implied and Y = 0 is then optimal: the vertex
            // LMIs Q_ii < 0 are equivalent. Y is left out of the solved problem
            // (the certificate inverts the reduction: Y = 0).
            for i in 0..r {
                sink.negative(&fam.name("Q+(s-1)Y", i, i), fam.q(i, i)?)?;
            }
            let pairs = (0..r)
                .flat_map(|i| (i + 1..r).map(move |j| (i, j)))
                .filter(|&(i, j)| sink.overlap(i, j))
                .count();
            sink.reductions.push(Reduction::TanakaSlackZero {
                family: fam.name.clone(),
                pairs,
                var: slack_name(fam),
                size: fam.q(0, 0)?.shape().0,
            });
            return Ok(());
        }
        let size = fam.q(0, 0)?.shape().0;
        let y = sink.problem.symmetric(&slack_name(fam), size)?;
        nonstrict_psd(
            sink.problem,
            sink.nonstrict,
            &format!("{} Y >= 0", fam.name),
            Expr::var(y),
            sink.eps,
        )?;
        for i in 0..r {
            let e = fam
                .q(i, i)?
                .add(Expr::var(y).scale((self.s as f64 - 1.0).max(0.0))?)?;
            sink.negative(&fam.name("Q+(s-1)Y", i, i), e)?;
            for j in i + 1..r {
                if !sink.overlap(i, j) {
                    continue;
                }
                let e = fam
                    .q(i, j)?
                    .add(fam.q(j, i)?)?
                    .scale(0.5)?
                    .sub(Expr::var(y))?;
                let n = fam.name("(Q+Q')/2-Y", i, j);
                sink.negative(&n, e)?;
                sink.nonstrict.push(n);
            }
        }
        Ok(())
    }

    fn conditions(&self, r: usize, overlap: &dyn Fn(usize, usize) -> bool) -> Option<Conditions> {
        let k = (self.s as f64 - 1.0).max(0.0);
        let mut list = Vec::new();
        for i in 0..r {
            let label = format!("Q+(s-1)Y[{0},{0}]", i + 1);
            list.push(PairCondition::new(label, vec![(i, i, 1.0)], k, true));
            for j in (i + 1..r).filter(|j| overlap(i, *j)) {
                let label = format!("(Q+Q')/2-Y[{},{}]", i + 1, j + 1);
                list.push(PairCondition::new(
                    label,
                    vec![(i, j, 0.5), (j, i, 0.5)],
                    -1.0,
                    false,
                ));
            }
        }
        Some(Conditions { list, slack: true })
    }
}

/// The slack's variable name in the full problem.
fn slack_name(fam: &Family<'_>) -> String {
    format!("Y_{}", fam.name)
}
