//! Plant and controller memberships that differ (the controller's are
//! evaluated at sampling instants): every Q_ij < 0 on its own. The mismatch
//! bound kappa is carried for the report; it does not relax the conditions
//! yet (Arino & Sala's kappa-bounded relaxation is a separate relaxation).

use crate::synth::relaxation::{Conditions, DoubleSum, Family, PairCondition, Sink};
use tsf_lmi::LmiError;

/// Every plant/controller rule pair.
pub struct Mismatch;

impl DoubleSum for Mismatch {
    fn impose(&self, sink: &mut Sink<'_, '_>, fam: &Family<'_>) -> Result<(), LmiError> {
        for i in 0..sink.r() {
            for j in 0..sink.r() {
                sink.negative(&fam.name("Q", i, j), fam.q(i, j)?)?;
            }
        }
        Ok(())
    }

    fn conditions(&self, r: usize, overlap: &dyn Fn(usize, usize) -> bool) -> Option<Conditions> {
        let list = (0..r)
            .flat_map(|i| (0..r).map(move |j| (i, j)))
            .filter(|&(i, j)| i == j || overlap(i, j))
            .map(|(i, j)| {
                let label = format!("Q[{},{}]", i + 1, j + 1);
                PairCondition::new(label, vec![(i, j, 1.0)], 0.0, true)
            })
            .collect();
        Some(Conditions { list, slack: false })
    }
}
