//! Event triggers with a synthesized weight (`trigger aperiodic { ..
//! threshold nu = ..; weight = synthesize; }`): the sensor transmits x(t_k^l)
//! when e' Upsilon e >= nu x(t_k)' Upsilon x(t_k). Two-step: the continuous
//! design's gains, then the weight and the certified threshold
//! ([`crate::synth::trigger`]); co-design: rounds of a gain step and a
//! trigger step ([`crate::synth::codesign`]), the continuous loop then
//! re-analyzed for the co-designed gains. A premise `region` makes either
//! certificate local ([`crate::synth::vertices`]).

use super::every_sample::{looped_conditions, rebuilt_plan};
use super::{Condition, LoopCertificate, LoopDesign, LoopLaw, Rounding, Start};
use crate::model::TsModel;
use crate::synth::design::{Design, SynthError, TriggerDesign};
use crate::synth::reduction::Reduction;
use crate::synth::search::Runner;
use crate::synth::solved::Solved;
use crate::synth::{given, trigger, vertices, Quantity};
use nalgebra::DMatrix;
use serde::Serialize;

/// The two-step event trigger: the weight for the continuous design's gains.
#[derive(Debug, Clone, Copy)]
pub struct TwoStep;

impl LoopLaw for TwoStep {
    fn name(&self) -> &'static str {
        "event trigger (two-step)"
    }

    fn claims(&self, model: &TsModel) -> bool {
        trigger::wanted(model)
            && trigger::codesign_rounds(model).is_none()
            && trigger::transmission_points(model).is_none()
    }

    fn design(
        &self,
        runner: &mut Runner<'_>,
        d: &mut Design,
        _: &Start,
    ) -> Result<LoopDesign, SynthError> {
        let out = runner.trigger(d);
        let (t, notes) = given::looped(runner.model, d, given::EVENT_LOOP, out)?;
        d.notes.extend(notes);
        Ok(LoopDesign::Event(t))
    }
}

/// The co-designed event trigger: gains and weight in rounds.
#[derive(Debug, Clone, Copy)]
pub struct Codesign;

impl LoopLaw for Codesign {
    fn name(&self) -> &'static str {
        "event trigger (co-design)"
    }

    fn claims(&self, model: &TsModel) -> bool {
        trigger::codesign_rounds(model).is_some()
    }

    fn design(
        &self,
        runner: &mut Runner<'_>,
        d: &mut Design,
        start: &Start,
    ) -> Result<LoopDesign, SynthError> {
        let rounds = trigger::codesign_rounds(runner.model).unwrap_or(1);
        let (t, notes) = runner.codesign(d, rounds)?;
        reanalyzed(runner, d, start, t, notes, None)
    }
}

/// The few-transmissions design: softer gains in co-design points, the one
/// with the fewest transmissions in the spec's scenario shipped.
#[derive(Debug, Clone, Copy)]
pub struct Transmissions;

impl LoopLaw for Transmissions {
    fn name(&self) -> &'static str {
        "event trigger (few transmissions)"
    }

    fn claims(&self, model: &TsModel) -> bool {
        trigger::transmission_points(model).is_some()
    }

    fn design(
        &self,
        runner: &mut Runner<'_>,
        d: &mut Design,
        start: &Start,
    ) -> Result<LoopDesign, SynthError> {
        let (points, gamma) = trigger::transmission_points(runner.model).unwrap_or((1, None));
        let (t, notes) = runner.transmissions(d, points, gamma)?;
        let region_scale = t
            .plan
            .region
            .as_ref()
            .map(|_| t.region_scale.unwrap_or(1.0));
        reanalyzed(runner, d, start, t, notes, region_scale)
    }
}

/// The gains changed: the continuous loop is re-analyzed for the co-designed
/// ones, so every certificate speaks of them.
fn reanalyzed(
    runner: &mut Runner<'_>,
    d: &mut Design,
    start: &Start,
    t: TriggerDesign,
    notes: Vec<String>,
    region_scale: Option<f64>,
) -> Result<LoopDesign, SynthError> {
    {
        let mut again = runner.reanalyze(&start.plan, start.goal, &t.plan.gains, region_scale)?;
        again.notes.splice(0..0, d.notes.drain(..));
        again.notes.push(format!(
            "continuous design before co-design: {}",
            d.achieved
                .get(Quantity::LinfGamma)
                .map_or("-".into(), |g| format!("L-inf gamma = {g:.6}"))
        ));
        again.notes.extend(notes);
        *d = again;
        Ok(LoopDesign::Event(t))
    }
}

impl LoopCertificate for TriggerDesign {
    fn conditions(
        &self,
        model: &TsModel,
        eps: f64,
        gains: &[DMatrix<f64>],
        stored: Option<Rounding<'_>>,
    ) -> Result<Vec<Condition>, SynthError> {
        let plan = rebuilt_plan(&self.plan, gains, stored, true);
        let mut values = self.values.clone();
        if let Some(s) = stored {
            // The weight as the sensor module stores it.
            if let Some(v) = values.trigger_weight_mut() {
                *v = self.weight.map(s);
            }
        }
        looped_conditions(model, &plan, eps, values, &self.reductions)
    }

    fn reductions(&self) -> &[Reduction] {
        &self.reductions
    }

    fn stored_matrices(&self) -> Vec<&DMatrix<f64>> {
        vec![&self.weight]
    }

    fn region(&self) -> Option<(&DMatrix<f64>, f64)> {
        Some((&self.p, self.level()))
    }
}

/// The synthesized event trigger: transmit x(t_k^l) when
/// e' Upsilon e >= nu x(t_k)' Upsilon x(t_k), e = x(t_k^l) - x(t_k).
#[derive(Debug, Clone, Serialize, schemars::JsonSchema)]
pub struct TriggerReport {
    /// Upsilon (n x n rows).
    pub weight: Vec<Vec<f64>>,
    /// Certified threshold: the loop is certified for every nu(t_k) <= nu (the
    /// adaptive law's ceiling `max`, else the spec's nu).
    pub nu: f64,
    /// The spec's threshold (the adaptive law's lower bound and nu(0)), if any.
    pub nu_min: Option<f64>,
    /// Adaptive law (mu1, mu2, mu3), if any.
    pub adaptive: Option<[f64; 3]>,
    /// [h_min, h_max] in s.
    pub sampling: [f64; 2],
    /// Design method.
    pub method: &'static str,
    /// Certified L-inf bound of the event-triggered, sampled loop.
    pub linf_gamma: f64,
    /// Its xi.
    pub linf_xi: f64,
    /// Eigenvalues of Upsilon, ascending.
    pub weight_eigenvalues: Vec<f64>,
    /// The premise region the certificate is local to (`region z = lo .. hi;`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub region: Option<RegionReport>,
    /// The points of a few-transmissions search (`weight = synthesize transmissions;`).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub search: Vec<crate::synth::transmissions::Point>,
}

/// A local (regional) event-trigger certificate: the LMIs hold at vertices
/// enclosing the model and gains the rules blend on the premise box, and the
/// certified set E(P, c) (c = level) lies inside the box.
#[derive(Debug, Clone, Serialize, schemars::JsonSchema)]
pub struct RegionReport {
    /// The box, its memberships and the polytope of h.
    pub premise_box: crate::model::region::PremiseBox,
    /// The vertex sets (plant, controller).
    pub vertices: Option<vertices::RegionVertices>,
    /// The level c of E(P, c).
    pub level: f64,
    /// Per face, the extent max |c_k x| on E(P, c), sqrt(c c_k P^-1 c_k'),
    /// recomputed from the solved P (at most the face's bound).
    pub extents: Vec<f64>,
}

impl TriggerDesign {
    /// The report section of this event trigger (`trigger`).
    pub fn report(&self, model: &TsModel) -> TriggerReport {
        let t = self;
        let threshold = match model.spec.trigger.as_ref().map(|t| &t.node) {
            Some(tsf_lang::spec::Trigger::Aperiodic { threshold, .. }) => threshold.as_ref(),
            _ => None,
        };
        let mut eig: Vec<f64> = t
            .weight
            .clone()
            .symmetric_eigen()
            .eigenvalues
            .iter()
            .copied()
            .collect();
        eig.sort_by(f64::total_cmp);
        TriggerReport {
            weight: crate::synth::rows(&t.weight),
            nu: t.plan.nu,
            nu_min: threshold.map(|th| th.nu),
            adaptive: threshold
                .and_then(|th| th.adaptive)
                .map(|(a, b, c)| [a, b, c]),
            sampling: [t.plan.sampling.0, t.plan.sampling.1],
            method: t.method,
            linf_gamma: t.gamma,
            linf_xi: t.xi,
            weight_eigenvalues: eig,
            region: region_report(model, t),
            search: t.search.clone(),
        }
    }
}

/// The regional part of the trigger report (`None` without a region).
fn region_report(model: &TsModel, t: &TriggerDesign) -> Option<RegionReport> {
    let premise_box = t.plan.region.clone()?;
    let level = t.level();
    let p_inv = t.p.clone().try_inverse();
    let extents = premise_box
        .faces
        .iter()
        .map(|f| {
            p_inv.as_ref().map_or(f64::INFINITY, |pi| {
                (level * (&f.row * pi * f.row.transpose())[(0, 0)]).sqrt()
            })
        })
        .collect();
    Some(RegionReport {
        vertices: vertices::describe(model, &t.plan).ok().flatten(),
        premise_box,
        level,
        extents,
    })
}
