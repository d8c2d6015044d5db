//! The report's `plant` section: what the certificate says of the plant the
//! spec declares (A(x), B(x)), not of the rules' blend: the region R where the
//! model-error bound holds, the bound, the certified level set E(P, c) inside
//! R and one sentence of what is certified, or why no such sentence can be
//! written.

use crate::model::plant_error::{extents, level_inside, PlantError, StateBox};
use crate::model::TsModel;
use crate::report::objectives::Objectives;
use nalgebra::DMatrix;
use serde::Serialize;
use tsf_lang::spec::{Lyapunov, Objective, Trigger};

/// The `plant` section.
#[derive(Debug, Clone, Serialize, schemars::JsonSchema)]
pub struct PlantSection {
    /// The region R of the claim: per state `[lo, hi]`, null where unbounded.
    pub region: Vec<Option<(f64, f64)>>,
    /// The model-error bound over R (null: no rigorous bound available).
    pub error_bound: Option<PlantError>,
    /// P of V = x' P x (null without a certified design).
    #[serde(rename = "P")]
    pub p: Option<Vec<Vec<f64>>>,
    /// The level c of the certified set E(P, c) = {x' P x <= c}, inside R.
    pub level: Option<f64>,
    /// Per state, the extent sqrt(c (P^{-1})_kk) of E(P, c).
    pub extents: Option<Vec<f64>>,
    /// What is certified of the plant, in one sentence (null: nothing).
    pub claim: Option<String>,
    /// Why no claim is made, or how R was found.
    pub note: Option<String>,
    /// With a `dynamics` block: the claim is for the design model, the truth
    /// plant is simulated, not certified.
    pub truth_plant: Option<String>,
    /// x0' P x0 for the simulate block's initial state x0 (null without a
    /// claim or a simulate block): x0 is in the claim's E(P, c) when it is at
    /// most `level`.
    pub scenario_x0_level: Option<f64>,
}

/// The region as the report writes it (null where unbounded).
pub fn region_json(region: &StateBox) -> Vec<Option<(f64, f64)>> {
    region
        .iter()
        .map(|&(lo, hi)| (lo.is_finite() && hi.is_finite()).then_some((lo, hi)))
        .collect()
}

/// The region in words: `x1 in [-1, 1], w[2] in [-0.1, 0.1]` (unbounded
/// components left out; a vector state's components named `w[k]`, 0-based
/// as `plant region` writes them).
pub fn region_words(model: &TsModel, region: &StateBox) -> String {
    tsf_lang::spec::Signal::names_of(&model.spec.states)
        .into_iter()
        .zip(region)
        .filter(|(_, (lo, hi))| lo.is_finite() || hi.is_finite())
        .map(|(name, (lo, hi))| format!("{name} in [{lo:.6}, {hi:.6}]"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// What the robust conditions do not cover in this spec (`None`: covered):
/// they are built for the continuous PDC loop with a quadratic V, stability,
/// decay rate, H-inf, L-inf, input and output bounds and the saturation region.
pub fn not_covered(model: &TsModel) -> Option<String> {
    let spec = &model.spec;
    if spec.adaptive.is_some() {
        return Some("an adaptive controller".into());
    }
    if spec.modes.is_some() {
        return Some("Markov-switching modes".into());
    }
    if spec.control.kind != tsf_lang::spec::ControlKind::StateFeedback {
        return Some(format!(
            "an output-feedback controller (`control {}`: the robust conditions cover state feedback only)",
            spec.control.kind.keyword()
        ));
    }
    if let Some(t) = &spec.trigger {
        let law = crate::synth::loops::law_of(model).name();
        if !matches!(
            (&t.node, law),
            (Trigger::Continuous, _)
                | (_, "every sample" | "jittered" | "event trigger (two-step)")
        ) {
            return Some(format!("the {law} loop (the robust conditions cover the continuous loop, the sampled loops that transmit every sample and the two-step event trigger)"));
        }
    }
    if spec.periodic_design.is_some() {
        return Some("a discrete-time periodic design".into());
    }
    if !matches!(spec.lyapunov.node, Lyapunov::Quadratic) {
        return Some("a fuzzy Lyapunov function".into());
    }
    let region_objective = spec
        .objectives
        .iter()
        .any(|o| matches!(o.node, Objective::SaturationRegion { .. }));
    if spec.saturation.is_some() && !region_objective {
        return Some(
            "saturation without `objective saturation region` (its E(P, 1) sizes the claim)".into(),
        );
    }
    spec.objectives.iter().find_map(|o| match &o.node {
        Objective::FiniteTime(_) => Some("finite-time boundedness".to_string()),
        _ => None,
    })
}

/// The one line of a spec with a truth plant.
pub fn truth_plant(model: &TsModel) -> Option<String> {
    let sim = model.spec.simulate.as_ref()?;
    sim.dynamics.as_ref().map(|_| {
        "the claim is for the design model A(x), B(x); the `dynamics` block (truth plant) is simulated, not certified".to_string()
    })
}

/// The section when no claim is made: the region, the bound if there is
/// one, P of the design and the reason.
pub fn without_claim(
    model: &TsModel,
    region: &StateBox,
    bound: Option<&PlantError>,
    p: Option<&DMatrix<f64>>,
    note: String,
) -> PlantSection {
    PlantSection {
        region: region_json(region),
        error_bound: bound.cloned(),
        p: p.map(rows),
        level: None,
        extents: None,
        claim: None,
        note: Some(note),
        truth_plant: truth_plant(model),
        scenario_x0_level: None,
    }
}

/// What a certified design of the covered kind says of the plant.
pub struct Claimed<'a> {
    /// The region R.
    pub region: &'a StateBox,
    /// The model-error bound over R the design tolerates.
    pub bound: &'a PlantError,
    /// P.
    pub p: &'a DMatrix<f64>,
    /// The certified decay rate (0: stability) and bounds.
    pub objectives: &'a Objectives,
    /// The saturation objective's level of E(P, level), if any.
    pub saturation_level: Option<f64>,
    /// How R was found (shrunk from a larger one), if worth saying.
    pub note: Option<String>,
    /// The sampled or event-triggered loop's certificate, when the spec ships
    /// one: its P and level replace the continuous design's.
    pub sampled: Option<SampledClaim<'a>>,
}

/// What the robust certificate of a sampled or event-triggered loop says.
pub struct SampledClaim<'a> {
    /// P of the loop's functional (V1 = x' P x).
    pub p: &'a DMatrix<f64>,
    /// The loop's own level (E(P, c) inside its linear region and premise
    /// box; infinite when it has none).
    pub level: f64,
    /// The loop in words ("sampled every 0.01 s (zero-order hold)").
    pub law: String,
    /// The L-inf bound of the loop (gamma, xi, phi), if it certifies one.
    pub linf: Option<(f64, f64, f64)>,
}

/// The section of a claim: c the largest level with E(P, c) inside R (and
/// inside the saturation region's E(P, level)); `None` when R does not
/// contain the origin in its interior or P is singular.
pub fn with_claim(model: &TsModel, c: &Claimed<'_>) -> Option<PlantSection> {
    let p = c.sampled.as_ref().map_or(c.p, |s| s.p);
    let p_inv = p.clone().try_inverse()?;
    let mut level = level_inside(c.region, &p_inv)?;
    if let Some(s) = c.saturation_level {
        level = level.min(s);
    }
    if let Some(s) = &c.sampled {
        level = level.min(s.level);
    }
    let set = if level.is_finite() {
        format!("E(P, c) = {{x' P x <= {level:.6e}}} (inside {})", {
            let w = region_words(model, c.region);
            if w.is_empty() {
                "the state space".to_string()
            } else {
                w
            }
        })
    } else {
        "the state space".to_string()
    };
    let input = if model.spec.saturation.is_some() {
        "B(x) sat(u)"
    } else {
        "B(x) u"
    };
    let o = c.objectives;
    let rate = match o.decay_rate.filter(|a| *a > 0.0) {
        Some(alpha) => format!("decays at rate >= {alpha}"),
        None => "converges to 0 (V = x' P x decreases)".to_string(),
    };
    let with_w = if model.q > 0 { " and w = 0" } else { "" };
    let d = match c.bound.d {
        Some(d) => format!(", ||D(x) - D_h(x)|| <= {d:.6e}"),
        None => String::new(),
    };
    let (law, rate, performance) = match &c.sampled {
        None => ("continuous loop".to_string(), rate, performance(o, level)),
        Some(s) => (
            s.law.clone(),
            "is asymptotically stable".to_string(),
            s.linf.map_or_else(String::new, |(g, xi, phi)| format!(
                "; from x(0) = 0, ||y||_inf < {g} ||w||_inf for every disturbance with ||w||_inf <= {:.6e} (the state stays in E(P, c))",
                (level * phi / xi).sqrt()
            )),
        ),
    };
    let scenario = scenario_level(model, p);
    let start = match scenario {
        Some(l) if l <= level => format!(
            "; the simulate block's x(0) is in it (x0' P x0 = {l:.6e} <= c)"
        ),
        Some(l) => format!(
            "; the simulate block's x(0) is not (x0' P x0 = {l:.6e} > c: the claim covers that direction up to x0 scaled by {:.6e})",
            (level / l).sqrt()
        ),
        None => String::new(),
    };
    let claim = format!(
        "for every x(0) in {set}{with_w} the plant x' = A(x) x + {input} with this controller ({law}) {rate}{performance}, with ||A(x) - A_h(x)|| <= {:.6e} and ||B(x) - B_h(x)|| <= {:.6e}{d} on the region{start}",
        c.bound.a,
        c.bound.b
    );
    Some(PlantSection {
        region: region_json(c.region),
        error_bound: Some(c.bound.clone()),
        p: Some(rows(p)),
        level: level.is_finite().then_some(level),
        extents: level.is_finite().then(|| extents(&p_inv, level)),
        claim: Some(claim),
        note: c.note.clone(),
        truth_plant: truth_plant(model),
        scenario_x0_level: scenario,
    })
}

/// x0' P x0 for the simulate block's x0, if the spec has one.
fn scenario_level(model: &TsModel, p: &DMatrix<f64>) -> Option<f64> {
    let sim = model.spec.simulate.as_ref()?;
    let x0 = nalgebra::DVector::from_column_slice(&sim.x0);
    (x0.len() == p.nrows()).then(|| (x0.transpose() * p * &x0)[(0, 0)])
}

/// The bounds the robust conditions carry to the plant, as a clause of the
/// claim: input and output norms on E(P, min(c, 1)) (their blocks bound u, y
/// on E(P, 1), and the set is invariant inside the region); from x(0) = 0,
/// H-inf for disturbance energies gamma^2 ||w||_2^2 <= c (V <= gamma^2
/// ||w||_2^2 keeps the state in E(P, c)) and L-inf for amplitudes
/// xi ||w||_inf^2 / phi <= c (V <= xi ||w||_inf^2 / phi).
fn performance(o: &Objectives, c: f64) -> String {
    let mut parts = Vec::new();
    let inner = c.min(1.0);
    if let Some(mu) = o.input_norm_bound {
        parts.push(format!(
            "||u(t)|| <= {mu} from every x(0) in E(P, {inner:.6e})"
        ));
    }
    if let Some(l) = o.output_norm_bound {
        parts.push(format!(
            "||y(t)|| <= {l} from every x(0) in E(P, {inner:.6e})"
        ));
    }
    if let Some(g) = o.hinf_gamma {
        parts.push(format!(
            "from x(0) = 0, ||z||_2 < {g} ||w||_2 for every disturbance with ||w||_2 <= {:.6e} (the state stays in E(P, c))",
            c.sqrt() / g
        ));
    }
    if let (Some(g), Some(xi), Some(phi)) = (o.linf_gamma, o.linf_xi, o.linf_phi) {
        parts.push(format!(
            "from x(0) = 0, ||y||_inf < {g} ||w||_inf for every disturbance with ||w||_inf <= {:.6e} (the state stays in E(P, c))",
            (c * phi / xi).sqrt()
        ));
    }
    parts.iter().map(|p| format!("; {p}")).collect()
}

/// The default section of a compile without a model-error bound.
pub fn nominal(model: &TsModel, p: Option<&DMatrix<f64>>) -> PlantSection {
    let region = model
        .spec
        .plant_region
        .clone()
        .unwrap_or_else(|| crate::model::plant_error::default_region(model));
    let note = match (not_covered(model), &model.consistency) {
        (Some(what), _) => format!(
            "no plant claim: the robust conditions do not cover {what}; the certificate covers the rules' blend"
        ),
        (None, Some(c)) => format!(
            "no plant claim: no rigorous bound of the model error is available in this build, so the certificate covers the rules' blend, not A(x), B(x) (the blend differs from A(x), B(x) by up to {:.1}% on a grid of {} states, a lower bound of the true mismatch)",
            100.0 * c.worst,
            c.points
        ),
        (None, None) => "no plant claim: no rigorous bound of the model error is available in this build (the spec's A, B do not depend on the state or no rule has an operating point to compare)".to_string(),
    };
    without_claim(model, &region, None, p, note)
}

fn rows(m: &DMatrix<f64>) -> Vec<Vec<f64>> {
    m.row_iter().map(|r| r.iter().copied().collect()).collect()
}
