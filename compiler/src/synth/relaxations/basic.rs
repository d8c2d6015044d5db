//! Tanaka & Wang's basic relaxation (*Fuzzy Control Systems Design and
//! Analysis*, 2001): Q_ii < 0 and Q_ij + Q_ji < 0 for i < j.

use crate::synth::relaxation::{Conditions, DoubleSum, Family, PairCondition, Sink};
use tsf_lmi::LmiError;

/// The basic relaxation.
pub struct Basic;

impl DoubleSum for Basic {
    fn impose(&self, sink: &mut Sink<'_, '_>, fam: &Family<'_>) -> Result<(), LmiError> {
        let mut dropped = 0;
        for i in 0..sink.r() {
            sink.negative(&fam.name("Q", i, i), fam.q(i, i)?)?;
            for j in i + 1..sink.r() {
                if !sink.overlap(i, j) {
                    continue;
                }
                if sink.pair_reduce {
                    dropped += 1;
                    continue;
                }
                sink.negative(&fam.name("Q+Q'", i, j), fam.q(i, j)?.add(fam.q(j, i)?)?)?;
            }
        }
        sink.dropped(fam, dropped);
        Ok(())
    }

    fn conditions(&self, r: usize, overlap: &dyn Fn(usize, usize) -> bool) -> Option<Conditions> {
        let mut list = Vec::new();
        for i in 0..r {
            list.push(PairCondition::new(
                format!("Q[{0},{0}]", i + 1),
                vec![(i, i, 1.0)],
                0.0,
                true,
            ));
            for j in (i + 1..r).filter(|j| overlap(i, *j)) {
                let label = format!("Q+Q'[{},{}]", i + 1, j + 1);
                list.push(PairCondition::new(
                    label,
                    vec![(i, j, 1.0), (j, i, 1.0)],
                    0.0,
                    true,
                ));
            }
        }
        Some(Conditions { list, slack: false })
    }
}
