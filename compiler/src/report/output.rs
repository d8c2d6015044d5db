//! The report's model and output-feedback sections: `local_models` (every
//! report: each rule's A, B, D, so that anyone can re-check a design),
//! `observer` (observer-based designs: C, the gains L_i, P2 and the augmented
//! certificate's P) and `static_output` (C and the gains K_j).

use crate::model::TsModel;
use crate::synth::observer::bounded::BoundedDesign;
use crate::synth::observer::{ObserverDesign, OutputFeedback, PremiseSource, StaticOutputDesign};
use crate::util::matrix::rows;
use serde::Serialize;
use tsf_lang::spec::InitialSet;

/// One rule's local model x' = A x + B u + D w.
#[derive(Debug, Serialize, schemars::JsonSchema)]
pub struct LocalModelReport {
    /// Rule name.
    pub rule: String,
    /// A (n x n rows).
    #[serde(rename = "A")]
    pub a: Vec<Vec<f64>>,
    /// B (n x m rows).
    #[serde(rename = "B")]
    pub b: Vec<Vec<f64>>,
    /// D (n x q rows; empty rows when q = 0).
    #[serde(rename = "D")]
    pub d: Vec<Vec<f64>>,
}

/// Every rule's local model, in rule order.
pub fn local_models(model: &TsModel) -> Vec<LocalModelReport> {
    model
        .rules
        .iter()
        .map(|r| LocalModelReport {
            rule: r.name.clone(),
            a: rows(&r.a),
            b: rows(&r.b),
            d: rows(&r.d),
        })
        .collect()
}

/// One rule's observer gain.
#[derive(Debug, Serialize, schemars::JsonSchema)]
pub struct ObserverGain {
    /// Rule name.
    pub rule: String,
    /// L_i (n x p rows).
    #[serde(rename = "L")]
    pub l: Vec<Vec<f64>>,
}

/// The augmented loop's certificate.
#[derive(Debug, Serialize, schemars::JsonSchema)]
pub struct AugmentedReport {
    /// The decay rate certified for (x, e).
    pub decay_rate: f64,
    /// P_aug (2n x 2n rows): V = [x; e]' P_aug [x; e]; diag(P1, Pe), or
    /// full (P_aug = X^-1) with `bounds`.
    #[serde(rename = "P")]
    pub p: Vec<Vec<f64>>,
    /// The input bound and saturation region certified on (x, e), if asked for.
    pub bounds: Option<AugmentedBoundsReport>,
}

/// The input bound and saturation region of an observer-based loop: what
/// re-checking them needs (module `synth/observer/bounded.rs`).
#[derive(Debug, Serialize, schemars::JsonSchema)]
pub struct AugmentedBoundsReport {
    /// The initial estimate the initial sets assume (0, the generated
    /// code's `INIT`): xi(0) = (x0, x0 - xhat0).
    pub xhat0: Vec<f64>,
    /// X = P_aug^-1 as solved (2n x 2n rows); the conditions are linear in X.
    #[serde(rename = "X")]
    pub x: Vec<Vec<f64>>,
    /// Initial points x0 whose (x0, x0) E(P_aug, 1) contains.
    pub initial_points: Vec<Vec<f64>>,
    /// Matrices R of initial ellipsoids {x0' R x0 <= 1} whose image (x0, x0)
    /// E(P_aug, 1) contains.
    pub initial_ellipsoids: Vec<Vec<Vec<f64>>>,
    /// The certified bound mu: ||u(t)|| <= mu on E(P_aug, 1), with
    /// [P_aug, K_j'; K_j, mu^2 I] >= 0, K_j = [F_j, -F_j].
    pub input_norm_bound: Option<f64>,
    /// The output bound lambda: ||C_z x|| <= lambda on E(P_aug, 1).
    pub output_norm_bound: Option<f64>,
    /// The generalized sector condition, with the saturation region.
    pub saturation: Option<AugmentedSectorReport>,
}

/// The sector condition's data on (x, e): psi' T (psi - H_j xi) <= 0 where
/// |(K_j - H_j)_s xi| <= u_s.
#[derive(Debug, Serialize, schemars::JsonSchema)]
pub struct AugmentedSectorReport {
    /// The saturation levels u_s.
    pub levels: Vec<f64>,
    /// The diagonal of T (T = S^-1).
    #[serde(rename = "T")]
    pub t: Vec<f64>,
    /// H_j = Z_j X^-1 (m x 2n rows), by controller rule.
    #[serde(rename = "H")]
    pub h: Vec<Vec<Vec<f64>>>,
}

fn bounds_report(b: &BoundedDesign, n: usize) -> AugmentedBoundsReport {
    let sets = [
        b.bounds.input.as_ref().map(|i| &i.initial),
        b.bounds
            .saturation
            .as_ref()
            .and_then(|s| s.contain.as_ref()),
    ];
    let mut initial_points = Vec::new();
    let mut initial_ellipsoids = Vec::new();
    for set in sets.into_iter().flatten() {
        match set {
            InitialSet::Point(x0) if !initial_points.contains(x0) => {
                initial_points.push(x0.clone());
            }
            InitialSet::Ellipsoid(r) if !initial_ellipsoids.contains(&rows(r)) => {
                initial_ellipsoids.push(rows(r));
            }
            _ => {}
        }
    }
    AugmentedBoundsReport {
        xhat0: vec![0.0; n],
        x: rows(&b.x),
        initial_points,
        initial_ellipsoids,
        input_norm_bound: b.mu,
        output_norm_bound: b.bounds.output.as_ref().map(|o| o.lambda),
        saturation: b.bounds.saturation.as_ref().map(|s| AugmentedSectorReport {
            levels: s.levels.clone(),
            t: b.t
                .as_ref()
                .map_or_else(Vec::new, |t| t.diagonal().iter().copied().collect()),
            h: b.h.iter().map(rows).collect(),
        }),
    }
}

/// An observer-based design.
#[derive(Debug, Serialize, schemars::JsonSchema)]
pub struct ObserverReport {
    /// The measured outputs y = C x (p x n rows).
    #[serde(rename = "C")]
    pub c: Vec<Vec<f64>>,
    /// One name per measured output.
    pub outputs: Vec<String>,
    /// Where the premises come from (`measured`: functions of y).
    pub premise_source: PremiseSource,
    /// R = C^+ (n x p rows): the premises evaluated at R y equal those at x.
    pub premise_from_y: Option<Vec<Vec<f64>>>,
    /// The observer's decay rate alpha_o.
    pub decay_rate: f64,
    /// P2 of the observer LMIs (N_i = P2 L_i).
    #[serde(rename = "P2")]
    pub p2: Vec<Vec<f64>>,
    /// The observer gains, by rule: x_hat' = sum h_i (A_i x_hat + B_i u + L_i (y - C x_hat)).
    pub gains: Vec<ObserverGain>,
    /// The certificate of the augmented loop (x, e), e = x - x_hat.
    pub augmented: AugmentedReport,
}

/// One rule's static output-feedback gain.
#[derive(Debug, Serialize, schemars::JsonSchema)]
pub struct OutputGain {
    /// Rule name.
    pub rule: String,
    /// K_j (m x p rows).
    #[serde(rename = "K")]
    pub k: Vec<Vec<f64>>,
}

/// A static output-feedback design u = sum_j h_j K_j y.
#[derive(Debug, Serialize, schemars::JsonSchema)]
pub struct StaticOutputReport {
    /// The measured outputs y = C x (p x n rows).
    #[serde(rename = "C")]
    pub c: Vec<Vec<f64>>,
    /// One name per measured output.
    pub outputs: Vec<String>,
    /// R = C^+ (n x p rows): the premises evaluated at R y equal those at x.
    pub premise_from_y: Option<Vec<Vec<f64>>>,
    /// The gains by rule (the report's `gains` are F_j = K_j C).
    pub gains: Vec<OutputGain>,
}

fn names(model: &TsModel) -> impl Iterator<Item = String> + '_ {
    model.rules.iter().map(|r| r.name.clone())
}

fn observer(model: &TsModel, o: &ObserverDesign) -> ObserverReport {
    ObserverReport {
        c: rows(&o.c),
        outputs: o.output_names.clone(),
        premise_source: o.premise_source,
        premise_from_y: o.premise_from_y.as_ref().map(rows),
        decay_rate: o.decay,
        p2: rows(&o.p2),
        gains: names(model)
            .zip(&o.gains)
            .map(|(rule, l)| ObserverGain { rule, l: rows(l) })
            .collect(),
        augmented: AugmentedReport {
            decay_rate: o.augmented.alpha,
            p: rows(&o.augmented.p),
            bounds: o
                .augmented
                .bounded
                .as_ref()
                .map(|b| bounds_report(b, model.n)),
        },
    }
}

fn static_output(model: &TsModel, s: &StaticOutputDesign) -> StaticOutputReport {
    StaticOutputReport {
        c: rows(&s.c),
        outputs: s.output_names.clone(),
        premise_from_y: s.premise_from_y.as_ref().map(rows),
        gains: names(model)
            .zip(&s.gains)
            .map(|(rule, k)| OutputGain { rule, k: rows(k) })
            .collect(),
    }
}

/// The `observer` and `static_output` sections of a design's output feedback.
pub fn sections(
    model: &TsModel,
    output: Option<&OutputFeedback>,
) -> (Option<ObserverReport>, Option<StaticOutputReport>) {
    match output {
        None => (None, None),
        Some(OutputFeedback::Observer(o)) => (Some(observer(model, o)), None),
        Some(OutputFeedback::StaticOutput(s)) => (None, Some(static_output(model, s))),
    }
}
