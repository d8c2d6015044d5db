//! The plant claim: the design made robust to the model error over a region
//! R, and R shrunk until the robust conditions hold.
//!
//! The model error comes through one seam, an [`ErrorBound`]: a function
//! that bounds ||A(x) - A_h(x)|| and ||B(x) - B_h(x)|| over a box of states.
//! With a bound, the model carries it ([`crate::model::TsModel::plant_error`]),
//! the decrease LMIs carry it as norm-bounded uncertainty
//! ([`crate::synth::objective::Ctx::with_model_error`]) and the certificate
//! re-checks them. When they fail on R, R is scaled about the origin by a
//! bisection of [`SHRINK_STEPS`] steps; the largest scale that certifies
//! gives the claim. An explicit region that fails is refused (exit 3) with
//! the largest region that certifies in the message.

use crate::driver::compile::{compile as compile_model, Compiled, Status};
use crate::model::error_bound::premise_range::{PremiseRange, MAX_PREMISE_BOXES};
use crate::model::error_bound::{self, BoundLimits};
use crate::model::plant_error::{default_region, nominal_slack, scaled, PlantError, StateBox};
use crate::model::TsModel;
use crate::report::plant::{
    not_covered, region_words, with_claim, without_claim, Claimed, SampledClaim,
};
use crate::report::{schema_id, Diagnosis, SpecInfo};
use crate::synth::Settings;
use std::time::Duration;
use tsf_lang::Diagnostic;

/// Bounds the model error of `model` over a box of states (where the
/// rigorous bound of `model::error_bound` plugs in).
pub type ErrorBound<'a> = &'a dyn Fn(&TsModel, &StateBox) -> Result<PlantError, Diagnostic>;

/// Bisection steps of the region's scale when the robust conditions fail on
/// R (the certified scale is then known to within 2^-8 of R).
pub const SHRINK_STEPS: usize = 8;

/// The note of a claim the nominal design carries ([`nominal_slack`]).
const ABSORBED: &str = "the nominal design's decrease conditions absorb the model error (margin check: no robust re-design needed)";

/// What the plant claim is asked for.
#[derive(Default, Clone, Copy)]
pub struct PlantRequest<'a> {
    /// The model-error bound (`None`: none available; the report says so).
    pub bound: Option<ErrorBound<'a>>,
    /// The region the user asks the claim for (`None`: the spec's `plant
    /// region`, else the default region, shrunk if needed). An explicit
    /// region (here or in the spec) that fails is refused.
    pub region: Option<&'a StateBox>,
}

/// The bound `tsfc compile` uses: the rigorous affine-arithmetic bound of
/// [`crate::model::error_bound::bound`] at its default work limits.
pub fn production_bound() -> Option<ErrorBound<'static>> {
    Some(&rigorous)
}

/// [`crate::model::error_bound::bound`] as an [`ErrorBound`]. A region that
/// reaches states whose premise values leave their declared ranges (where the
/// blend, hence the bound, is not defined) is no region for a claim.
fn rigorous(model: &TsModel, region: &StateBox) -> Result<PlantError, Diagnostic> {
    let b = error_bound::bound(model, &model.spec, region, &BoundLimits::default())?;
    let leaves = |why: String| {
        Err(Diagnostic::error(
            model.spec.controller.span,
            format!(
                "the region {} reaches states whose premise values leave their declared ranges ({why})",
                region_words(model, region)
            ),
        ))
    };
    match &b.premise {
        PremiseRange::Inside { .. } => {}
        PremiseRange::Leaves { premise, x, z } => {
            let slot = model
                .premises
                .slots
                .iter()
                .find(|s| (s.first..s.first + s.dim).contains(premise));
            let name = slot.map_or("a premise", |s| s.name.as_str());
            let (lo, hi) = slot.map_or((f64::NAN, f64::NAN), |s| s.range);
            return leaves(format!(
                "`{name}` = {z:.6e} at x = {x:?}, outside its range {lo} .. {hi}"
            ));
        }
        PremiseRange::Unproven { .. } => {
            return leaves(format!(
                "not proved inside after {MAX_PREMISE_BOXES} sub-boxes"
            ))
        }
    }
    Ok(PlantError {
        a: b.a_norm,
        b: b.b_norm,
        d: b.d_norm,
        boxes: b.boxes,
        converged: b.converged,
        sampled_max: b.sampled_max,
    })
}

/// Compiles `model` and makes the plant claim `request` asks for.
pub fn compile(
    model: &TsModel,
    info: SpecInfo,
    settings: &Settings,
    front: (Duration, Duration),
    request: PlantRequest<'_>,
) -> Compiled {
    let nominal = || compile_model(model, info.clone(), settings, front);
    let Some(bound) = request.bound else {
        return nominal();
    };
    if not_covered(model).is_some() {
        return nominal();
    }
    // The request's region, else the spec's `plant region`, else the default.
    let explicit = request.region.or(model.spec.plant_region.as_ref());
    let r0 = explicit.cloned().unwrap_or_else(|| default_region(model));
    // A robust re-design would trade a gain the spec minimizes for a claim
    // the spec did not ask for: only with an explicit region.
    if let (None, Some(what)) = (explicit, minimized_gain(model)) {
        let mut c = nominal();
        c.report.plant = without_claim(
            model,
            &r0,
            None,
            None,
            format!(
                "no plant claim: the spec minimizes the {what}, and a design robust to the model error would trade it for the claim; write `plant region ..;` to ask for that design (docs/language.md, \"The plant claim\"); the certificate covers the rules' blend"
            ),
        );
        return c;
    }
    let shrink_note = |s: f64| {
        (s < 1.0).then(|| {
            format!(
                "the robust conditions fail on {}; the largest region that certifies is scale {s} of it ({SHRINK_STEPS} bisection steps)",
                region_words(model, &r0)
            )
        })
    };
    let nominal_once = std::cell::OnceCell::new();
    // Err: the compile that failed (None when the bound itself failed) and why.
    let attempt = |s: f64| -> Result<Compiled, (Option<Compiled>, String)> {
        let region = scaled(&r0, s);
        let pe = match bound(model, &region) {
            Ok(pe) => pe,
            Err(d) => return Err((None, format!("no model-error bound: {}", d.message))),
        };
        // The nominal design first: when its decrease conditions absorb the
        // error (no saturation term), it ships unchanged; else a robust design.
        if margin_check_applies(model) {
            let c = nominal_once.get_or_init(nominal);
            if let Some(sec) = absorbed(model, c, &region, &pe, shrink_note(s)) {
                let mut c = compile_model(model, info.clone(), settings, front);
                c.report.plant = sec;
                return Ok(c);
            }
        }
        let mut robust = model.clone();
        robust.plant_error = Some(pe.clone());
        let mut c = compile_model(&robust, info.clone(), settings, front);
        match robust_section(model, &c, &region, &pe, shrink_note(s)) {
            Some(sec) => {
                c.report.plant = sec;
                Ok(c)
            }
            None => {
                let why = format!(
                    "the robust conditions with ||dA|| <= {:.6e}, ||dB|| <= {:.6e} fail on {}",
                    pe.a,
                    pe.b,
                    region_words(model, &region)
                );
                c.report.plant = without_claim(model, &region, Some(&pe), None, why.clone());
                Err((Some(c), why))
            }
        }
    };
    // The first failure (its compile, or none when the bound itself failed,
    // e.g. a premise leaving its range) and why: the region is shrunk either way.
    let (first, why) = match attempt(1.0) {
        Ok(c) => return c,
        Err(failed) => failed,
    };
    let (mut lo, mut hi, mut best) = (0.0f64, 1.0f64, None);
    for _ in 0..SHRINK_STEPS {
        let mid = 0.5 * (lo + hi);
        match attempt(mid) {
            Ok(c) => {
                lo = mid;
                best = Some(c);
            }
            Err(_) => hi = mid,
        }
    }
    let largest = match &best {
        Some(_) => format!(
            "the largest region that certifies is {} (scale {lo} of the region, {SHRINK_STEPS} bisection steps)",
            region_words(model, &scaled(&r0, lo))
        ),
        None => format!(
            "no region certifies down to scale 2^-{SHRINK_STEPS} of it ({SHRINK_STEPS} bisection steps)"
        ),
    };
    if explicit.is_some() {
        let failed = first.unwrap_or_else(|| {
            let mut c = nominal();
            c.report.plant = without_claim(model, &r0, None, None, why.clone());
            c
        });
        return refused(failed, format!("plant claim refused: {why}; {largest}"));
    }
    match best {
        Some(c) => c,
        None => {
            let mut c = nominal();
            let p = c.outcome.as_ref().ok().map(|(d, _)| d.p.clone());
            let pe = bound(model, &r0).ok();
            c.report.plant = without_claim(
                model,
                &r0,
                pe.as_ref(),
                p.as_ref(),
                format!(
                    "no plant claim: {why}; {largest}; the certificate covers the rules' blend"
                ),
            );
            c
        }
    }
}

/// `failed` as the refusal of an explicit region: status, failed-report
/// schema, and `message` as its diagnosis and plant note.
fn refused(mut failed: Compiled, message: String) -> Compiled {
    failed.status = Status::Refused;
    failed.report.status = "refused";
    failed.report.schema = schema_id("failed-report");
    failed.report.diagnosis = Some(Diagnosis {
        message: message.clone(),
        achievable: Vec::new(),
    });
    failed.report.plant.note = Some(message);
    failed
}

/// Whether the nominal design's margin check ([`absorbed`]) can carry the
/// claim: the continuous loop, no saturation term, no disturbance bound.
fn margin_check_applies(model: &TsModel) -> bool {
    continuous_loop(model) && model.spec.saturation.is_none() && !disturbance_bounds(model)
}

/// Whether the loop is continuous (`trigger continuous` or none).
fn continuous_loop(model: &TsModel) -> bool {
    matches!(
        model.spec.trigger.as_ref().map(|t| &t.node),
        None | Some(tsf_lang::spec::Trigger::Continuous)
    )
}

/// The claim of the robust compile `c` on `region` (`None`: not certified).
fn robust_section(
    model: &TsModel,
    c: &Compiled,
    region: &StateBox,
    pe: &PlantError,
    note: Option<String>,
) -> Option<crate::report::plant::PlantSection> {
    let (Status::Certified, Ok((d, _))) = (&c.status, &c.outcome) else {
        return None;
    };
    with_claim(
        model,
        &Claimed {
            region,
            bound: pe,
            p: &d.p,
            objectives: &c.report.objectives,
            saturation_level: model.spec.saturation.as_ref().map(|_| 1.0),
            note,
            sampled: sampled_claim(d),
        },
    )
}

/// The sampled or event-triggered loop's certificate as the claim reads it
/// (`None` for the continuous loop).
fn sampled_claim(d: &crate::synth::Design) -> Option<SampledClaim<'_>> {
    use crate::synth::loops::LoopDesign;
    let words = |(lo, hi): (f64, f64)| match lo == hi {
        true => format!("sampled every {hi} s, zero-order hold"),
        false => format!("sampled at any intervals in [{lo}, {hi}] s, zero-order hold"),
    };
    match &d.loop_design {
        LoopDesign::EverySample(s) => Some(SampledClaim {
            p: &s.p,
            level: match s.plan.levels.is_empty() {
                true => f64::INFINITY,
                false => s.plan.region_level(),
            },
            law: words(s.plan.sampling),
            linf: None,
        }),
        LoopDesign::Event(t) => Some(SampledClaim {
            p: &t.p,
            level: t.level(),
            law: format!(
                "{}, event-triggered with threshold nu(t_k) <= {}",
                words(t.plan.sampling),
                t.plan.nu
            ),
            linf: Some((t.gamma, t.xi, t.plan.phi)),
        }),
        _ => None,
    }
}

/// The disturbance gain the spec minimizes (H-inf or L-inf with no bound),
/// named for the report's note; `None` when it minimizes none.
fn minimized_gain(model: &TsModel) -> Option<&'static str> {
    use tsf_lang::spec::{Objective, Target};
    model.spec.objectives.iter().find_map(|o| match &o.node {
        Objective::Hinf {
            target: Target::Optimize,
            ..
        } => Some("H-infinity gain"),
        Objective::Linf {
            target: Target::Optimize,
            ..
        } => Some("L-infinity (peak-to-peak) gain"),
        _ => None,
    })
}

/// The claim the nominal design `c` makes when its decrease conditions absorb
/// the error `pe` on `region` ([`nominal_slack`]; no saturation term).
fn absorbed(
    model: &TsModel,
    c: &Compiled,
    region: &StateBox,
    pe: &PlantError,
    shrunk: Option<String>,
) -> Option<crate::report::plant::PlantSection> {
    let (Status::Certified, Ok((d, _))) = (&c.status, &c.outcome) else {
        return None;
    };
    let alpha = c.report.objectives.decay_rate.unwrap_or(0.0);
    if !nominal_slack(&model.rules, &d.p, &d.gains, alpha, pe).is_some_and(|s| s > 0.0) {
        return None;
    }
    let note = shrunk.map_or(ABSORBED.to_string(), |n| format!("{ABSORBED}; {n}"));
    with_claim(
        model,
        &Claimed {
            region,
            bound: pe,
            p: &d.p,
            objectives: &c.report.objectives,
            saturation_level: None,
            note: Some(note),
            sampled: None,
        },
    )
}

/// Whether the spec bounds a disturbance's effect (H-inf, L-inf): their
/// blocks are not in the nominal margin check, so only a robust design
/// carries them to the plant.
fn disturbance_bounds(model: &TsModel) -> bool {
    model.spec.objectives.iter().any(|o| {
        matches!(
            o.node,
            tsf_lang::spec::Objective::Hinf { .. } | tsf_lang::spec::Objective::Linf { .. }
        )
    })
}
