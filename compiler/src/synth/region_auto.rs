//! `region z = auto;` in the trigger block: tsfc chooses the premise box.
//!
//! The gains are designed on the seed box (each auto premise's range times
//! [`REGION_AUTO_SEED`]); then, with the gains fixed, the box is grown: the
//! auto bounds are scaled by 2, 4, .. up to the premise's range while the
//! regional event-triggered conditions certify at the spec's threshold with
//! gamma within the goal, then the largest certified scale is refined by
//! [`REGION_AUTO_BISECTIONS`] bisections in log scale. At most
//! log2(1 / seed) + bisections trigger solves (9 for the defaults). The
//! largest certified box ships; the report gives it with the extents of
//! E(P, c).

use super::design::{SynthError, TriggerDesign};
use super::search::Runner;
use super::trigger::TriggerPlan;
use crate::model::TsModel;
use tsf_lang::limits::{REGION_AUTO_BISECTIONS, REGION_AUTO_SEED};

/// Whether the spec asks tsfc to choose the box (`region z = auto;`).
pub fn wanted(model: &TsModel) -> bool {
    model.spec.trigger_region.iter().any(|b| b.auto)
}

/// `model` with every auto bound scaled by `scale` (1: the seed box;
/// 1 / [`REGION_AUTO_SEED`]: the premise's range).
pub fn scaled(model: &TsModel, scale: f64) -> TsModel {
    let mut out = model.clone();
    for b in out.spec.trigger_region.iter_mut().filter(|b| b.auto) {
        let s = scale.min(1.0 / REGION_AUTO_SEED);
        b.range = (b.range.0 * s, b.range.1 * s);
    }
    out
}

/// One tried box, for the notes and the report.
#[derive(Debug, Clone, Copy)]
struct Tried {
    scale: f64,
    gamma: Option<f64>,
}

impl Runner<'_> {
    /// Grows the box of the certified `seed` design (gains fixed) to the
    /// largest scale of the auto bounds on which the trigger conditions
    /// certify with gamma <= `bound`; returns that design (its
    /// `region_scale` set) and a note. Without `region z = auto` the seed
    /// comes back unchanged.
    pub(super) fn grow_region(
        &mut self,
        seed: TriggerDesign,
        bound: f64,
    ) -> Result<(TriggerDesign, Option<String>), SynthError> {
        if !wanted(self.model) {
            return Ok((seed, None));
        }
        let top = 1.0 / REGION_AUTO_SEED;
        let mut tried = Vec::new();
        let mut best = (1.0, seed);
        let mut failed = None;
        let mut scale = 2.0;
        while scale <= top * (1.0 + 1e-12) {
            match self.at_scale(&best.1.plan, scale, bound, &mut tried)? {
                Some(d) => best = (scale, d),
                None => {
                    failed = Some(scale);
                    break;
                }
            }
            scale *= 2.0;
        }
        if let Some(mut hi) = failed {
            for _ in 0..REGION_AUTO_BISECTIONS {
                let mid = (best.0 * hi).sqrt();
                match self.at_scale(&best.1.plan, mid, bound, &mut tried)? {
                    Some(d) => best = (mid, d),
                    None => hi = mid,
                }
            }
        }
        let (scale, mut design) = best;
        design.region_scale = Some(scale);
        let boxes = self
            .model
            .spec
            .trigger_region
            .iter()
            .filter(|b| b.auto)
            .map(|b| {
                format!(
                    "{} in {:.6} .. {:.6}",
                    b.premise,
                    b.range.0 * scale,
                    b.range.1 * scale
                )
            })
            .collect::<Vec<_>>()
            .join(", ");
        let log = tried
            .iter()
            .map(|t| {
                format!(
                    "x{:.3}: {}",
                    t.scale,
                    t.gamma
                        .map_or("not certified".into(), |g| format!("gamma {g:.4}"))
                )
            })
            .collect::<Vec<_>>()
            .join("; ");
        let note = format!(
            "region auto: the largest certified box is {boxes} ({scale:.3} times the seed box, event-triggered gamma {:.6} <= {bound}); tried (scale of the seed box: result): {log}",
            design.gamma
        );
        Ok((design, Some(note)))
    }

    /// The trigger design of `plan`'s gains on the box at `scale`, if it
    /// certifies with gamma <= `bound`.
    fn at_scale(
        &mut self,
        plan: &TriggerPlan,
        scale: f64,
        bound: f64,
        tried: &mut Vec<Tried>,
    ) -> Result<Option<TriggerDesign>, SynthError> {
        let model = scaled(self.model, scale);
        let region = crate::model::region::premise_box(&model).map_err(SynthError::Unsupported)?;
        let plan = TriggerPlan {
            region,
            ..plan.clone()
        };
        let out = self.trigger_attempt(&plan)?.filter(|d| d.gamma <= bound);
        tried.push(Tried {
            scale,
            gamma: out.as_ref().map(|d| d.gamma),
        });
        Ok(out)
    }
}
