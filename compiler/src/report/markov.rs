//! The report sections of a design with modes: `modes` (per mode P, gains
//! and the verdict of its conditions) and `transition_rates`.

use super::{rows, Gain, SampledReport};
use crate::certify::Certificate;
use crate::model::TsModel;
use crate::synth::markov::ModesDesign;
use crate::synth::Design;
use serde::Serialize;
use tsf_lang::modes::ModeDesign;
use tsf_lang::spec::{Objective, Target};

/// One mode in the report.
#[derive(Debug, Serialize, schemars::JsonSchema)]
pub struct ModeReport {
    /// The mode's name.
    pub name: String,
    /// P_a (n x n rows).
    #[serde(rename = "P")]
    pub p: Vec<Vec<f64>>,
    /// F_aj per rule (empty unless certified).
    pub gains: Vec<Gain>,
    /// Whether every condition of this mode passes the certificate.
    pub certified: bool,
    /// Least margin over this mode's strict conditions.
    pub min_margin: f64,
    /// Conditions of this mode in the certificate.
    pub conditions: usize,
}

/// The `modes` and `transition_rates` sections (both `None` without modes).
pub fn sections(
    model: &TsModel,
    design: Option<&Design>,
    cert: Option<&Certificate>,
    certified: bool,
) -> (Option<Vec<ModeReport>>, Option<Vec<Vec<f64>>>) {
    let Some(modes) = &model.spec.modes else {
        return (None, None);
    };
    let rates = Some(rows(&modes.rates));
    let Some(md) = design.and_then(|d| d.modes.as_ref()) else {
        return (None, rates);
    };
    let reports = modes
        .modes
        .iter()
        .enumerate()
        .map(|(a, mode)| {
            let prefix = format!("mode {} ", mode.name);
            let own = format!("P_{} > 0", mode.name);
            let lmis: Vec<_> = cert
                .map(|c| {
                    c.lmis
                        .iter()
                        .filter(|l| l.name.starts_with(&prefix) || l.name == own)
                        .collect()
                })
                .unwrap_or_default();
            ModeReport {
                name: mode.name.clone(),
                p: rows(&md.p[a]),
                gains: if certified {
                    Gain::of_rules(model, &md.gains[a])
                } else {
                    Vec::new()
                },
                certified: !lmis.is_empty() && lmis.iter().all(|l| l.ok),
                min_margin: lmis
                    .iter()
                    .filter(|l| l.strict)
                    .map(|l| l.margin)
                    .fold(f64::INFINITY, f64::min),
                conditions: lmis.len(),
            }
        })
        .collect();
    (Some(reports), rates)
}

/// The `objectives.finite_time` section: c1, c2 (the bound the design's P_a
/// prove), T, alpha, w2, lambda1..3, the weight R, and the bound asked for
/// (`c2_bound`) when c2 was bounded rather than minimized.
pub fn finite_time(model: &TsModel, md: &ModesDesign) -> Option<FiniteTimeReport> {
    let (f, numbers) = md.finite_time()?;
    let c2_bound = model.spec.objectives.iter().find_map(|o| match &o.node {
        Objective::FiniteTime(ft) => match ft.target {
            Target::Fixed(c2) => Some(c2),
            Target::Optimize => None,
        },
        _ => None,
    });
    Some(FiniteTimeReport {
        r: rows(&f.r),
        t: f.horizon,
        alpha: f.alpha,
        c1: f.c1,
        c2: numbers.c2,
        c2_bound,
        lambda1: numbers.lambda1,
        lambda2: numbers.lambda2,
        lambda3: numbers.lambda3,
        sense: match md.design {
            ModeDesign::Dependent => "mean square (E x' R x), under the Markov chain",
            ModeDesign::Independent => "along every switching path (a mode-independent V)",
        },
        w2: f.w2,
    })
}

/// Finite-time boundedness of a mode design (fields in name order).
#[derive(Debug, Serialize, schemars::JsonSchema)]
pub struct FiniteTimeReport {
    /// The weight R of x' R x (n x n rows).
    #[serde(rename = "R")]
    pub r: Vec<Vec<f64>>,
    /// The horizon T (s).
    #[serde(rename = "T")]
    pub t: f64,
    /// The growth rate alpha of the conditions.
    pub alpha: f64,
    /// The initial bound c1 (x0' R x0 <= c1).
    pub c1: f64,
    /// The bound c2 the design's P_a prove (x' R x < c2 on [0, T]).
    pub c2: f64,
    /// The bound c2 asked for (absent when c2 was minimized).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub c2_bound: Option<f64>,
    /// lambda1 of the conditions.
    pub lambda1: f64,
    /// lambda2 of the conditions.
    pub lambda2: f64,
    /// lambda3 of the conditions.
    pub lambda3: f64,
    /// In what sense the bound holds.
    pub sense: &'static str,
    /// The disturbance energy bound w2.
    pub w2: f64,
}

/// One mode's matrices of the sampled loop's functional.
#[derive(Debug, Serialize, schemars::JsonSchema)]
pub struct ModeSampledReport {
    /// The mode's name.
    pub name: String,
    /// P_a (n x n rows).
    #[serde(rename = "P")]
    pub p: Vec<Vec<f64>>,
    /// The free matrix L1_a.
    #[serde(rename = "L1")]
    pub l1: Vec<Vec<f64>>,
    /// The free matrix L2_a.
    #[serde(rename = "L2")]
    pub l2: Vec<Vec<f64>>,
}

/// The `sampled_loop` section of a mode design with a sampled loop.
pub fn sampled_loop(model: &TsModel, design: &Design) -> Option<SampledReport> {
    let s = design.loop_design.sampled_modes()?;
    let modes = model.spec.modes.as_ref()?;
    Some(SampledReport {
        sampling: [s.sampling.0, s.sampling.1],
        decay_rate: 0.0,
        covers: crate::synth::markov::sampled::covers(s.sampling),
        p: rows(s.p.first()?),
        y: Some(rows(&s.y)),
        l: None,
        drift: None,
        bounds: None,
        hinf_gamma: None,
        modes: Some(
            modes
                .modes
                .iter()
                .enumerate()
                .map(|(a, m)| ModeSampledReport {
                    name: m.name.clone(),
                    p: rows(&s.p[a]),
                    l1: rows(&s.l1[a]),
                    l2: rows(&s.l2[a]),
                })
                .collect(),
        ),
    })
}
