//! Tuan, Apkarian, Narikiyo & Yamamoto's relaxation (*Parameterized linear
//! matrix inequality techniques in fuzzy control system design*, 2001):
//! Q_ii < 0 and 2/(r-1) Q_ii + Q_ij + Q_ji < 0 for i != j.

use crate::synth::relaxation::{DoubleSum, Family, Sink};
use tsf_lmi::LmiError;

/// Tuan's relaxation.
pub struct Tuan;

impl DoubleSum for Tuan {
    fn impose(&self, sink: &mut Sink<'_, '_>, fam: &Family<'_>) -> Result<(), LmiError> {
        let r = sink.r();
        let c = if r > 1 { 2.0 / (r as f64 - 1.0) } else { 0.0 };
        for i in 0..r {
            sink.negative(&fam.name("Q", i, i), fam.q(i, i)?)?;
        }
        let mut dropped = 0;
        for i in 0..r {
            for j in 0..r {
                if i == j {
                    continue;
                }
                if sink.pair_reduce {
                    dropped += 1;
                    continue;
                }
                let e = fam
                    .q(i, i)?
                    .scale(c)?
                    .add(fam.q(i, j)?)?
                    .add(fam.q(j, i)?)?;
                sink.negative(&fam.name("tuan", i, j), e)?;
            }
        }
        sink.dropped(fam, dropped);
        Ok(())
    }
}
