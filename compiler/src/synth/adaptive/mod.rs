//! Adaptive model-reference T-S controllers (`adaptive { ... }`, issue 15;
//! Wang, Gao & He 2013, generalized to several inputs: docs/adaptive.md).
//!
//! No SDP: the design solves the reference model's Lyapunov equation
//! ([`lyapunov`]), checks that the adaptation is well posed (the matching
//! condition C B_i diagonal with one sign per input across the rules, the
//! projection boxes against the design model's values) and reports what the
//! Lyapunov argument guarantees and what it does not. The verdict is its own
//! status, `adaptive-well-posed` (exit 0) or `adaptive-refused` (exit 3); it
//! is not an LMI certificate. The simulator (`sim/adaptive.rs`) runs the closed loop with the runtime's
//! [`tsf_runtime::AdaptiveLaw`].

pub mod lyapunov;

use crate::model::TsModel;
use nalgebra::DMatrix;
use serde::Serialize;
use tsf_lang::adaptive::Adaptive;
use tsf_runtime::Adaptation;

/// Relative size of an off-diagonal entry of C B_i that breaks matching.
pub const MATCHING_TOLERANCE: f64 = 1e-9;

/// Status word of a well-posed adaptive design.
pub const WELL_POSED: &str = "adaptive-well-posed";
/// Status word of a refused adaptive design.
pub const REFUSED: &str = "adaptive-refused";

/// The numbers of an adaptive design: what the runtime law needs.
#[derive(Debug, Clone)]
pub struct Design {
    /// States, inputs, rules.
    pub n: usize,
    /// Inputs.
    pub m: usize,
    /// Rules.
    pub rules: usize,
    /// C (m x n), row-major.
    pub c: Vec<f64>,
    /// A_m (m x m), row-major.
    pub a_m: Vec<f64>,
    /// P (m x m), row-major.
    pub p: Vec<f64>,
    /// Initial a_ik (rules x m x n).
    pub a0: Vec<f64>,
    /// Initial b_ik (rules x m).
    pub b0: Vec<f64>,
    /// Initial d.
    pub d0: f64,
    /// Adaptation of a (rate 0 when not adapted).
    pub a: Adaptation,
    /// Adaptation of b.
    pub b: Adaptation,
    /// Adaptation of d.
    pub d: Adaptation,
    /// Boundary layer.
    pub layer: f64,
}

impl Design {
    /// The runtime law over these tables.
    pub fn law(&self) -> tsf_runtime::AdaptiveLaw<'_> {
        tsf_runtime::AdaptiveLaw {
            n: self.n,
            m: self.m,
            rules: self.rules,
            c: &self.c,
            a_m: &self.a_m,
            p: &self.p,
            a: self.a,
            b: self.b,
            d: self.d,
            layer: self.layer,
        }
    }
}

/// The JSON report of an adaptive design (`<name>.adaptive.json`).
#[derive(Debug, Clone, Serialize, schemars::JsonSchema)]
pub struct Report {
    /// [`WELL_POSED`] or [`REFUSED`].
    pub status: String,
    /// Why it was refused (empty when well posed).
    pub refusals: Vec<String>,
    /// Real parts of the eigenvalues of A_m.
    pub reference_eigenvalues_re: Vec<f64>,
    /// P (row-major) with A_m' P + P A_m = -Q.
    pub p: Vec<f64>,
    /// Eigenvalues of P.
    pub p_eigenvalues: Vec<f64>,
    /// Relative residual of the Lyapunov equation.
    pub lyapunov_residual: f64,
    /// Per rule, the diagonal of C B_i (the input gains b_i of the design model).
    pub input_gains: Vec<Vec<f64>>,
    /// Largest |off-diagonal| / max |diagonal| of C B_i over the rules.
    pub matching_offdiagonal: f64,
    /// Whether the design model's a_i, b_i lie inside their projection boxes.
    pub nominal_inside_bounds: bool,
    /// Number of adapted numbers.
    pub adapted: usize,
    /// What the Lyapunov argument guarantees for this spec.
    pub guaranteed: Vec<String>,
    /// What it does not.
    pub not_guaranteed: Vec<String>,
    /// Initial-state components outside the rules' operating range
    /// (`name = value outside [lo, hi]`).
    pub x0_outside_operating_range: Vec<String>,
}

/// A design and its report (the design is `None` when refused).
#[derive(Debug, Clone)]
pub struct Outcome {
    /// The law's numbers, when well posed.
    pub design: Option<Design>,
    /// The report.
    pub report: Report,
}

impl Outcome {
    /// 0 well posed, 3 refused.
    pub fn exit_code(&self) -> u8 {
        if self.design.is_some() {
            0
        } else {
            3
        }
    }
}

fn row_major(m: &DMatrix<f64>) -> Vec<f64> {
    m.transpose().as_slice().to_vec()
}

/// Per state component: (min, max) over the rules' operating points.
pub fn operating_range(model: &TsModel) -> Option<Vec<(f64, f64)>> {
    let mut range: Option<Vec<(f64, f64)>> = None;
    for at in model.rules.iter().filter_map(|r| r.at.as_ref()) {
        let r = range.get_or_insert_with(|| at.iter().map(|v| (*v, *v)).collect());
        for ((lo, hi), v) in r.iter_mut().zip(at) {
            *lo = lo.min(*v);
            *hi = hi.max(*v);
        }
    }
    range
}

/// The initial-state components outside the rules' operating range.
fn x0_outside(model: &TsModel) -> Vec<String> {
    let (Some(range), Some(sim)) = (operating_range(model), model.spec.simulate.as_ref()) else {
        return Vec::new();
    };
    let names = tsf_lang::spec::Signal::names_of(&model.spec.states);
    sim.x0
        .iter()
        .zip(&range)
        .zip(&names)
        .filter(|((v, (lo, hi)), _)| **v < *lo || **v > *hi)
        .map(|((v, (lo, hi)), name)| format!("{name} = {v} outside [{lo}, {hi}]"))
        .collect()
}

/// Designs the adaptive law of `model` (whose spec has an `adaptive` block).
pub fn design(model: &TsModel) -> Outcome {
    let ad = model
        .spec
        .adaptive
        .as_ref()
        .expect("design() is called on adaptive specs only"); // ok: its one caller, cli::outcome, returns None first when the spec has no adaptive block
    let (n, m, rules) = (model.n, model.m, model.r());
    let mut refusals = Vec::new();
    let lyap = lyapunov::solve(&ad.reference, &ad.q);
    if let Err(r) = &lyap {
        refusals.push(r.to_string());
    }
    let c = &ad.error;
    let cb: Vec<DMatrix<f64>> = model.rules.iter().map(|r| c * &r.b).collect();
    let ca: Vec<DMatrix<f64>> = model.rules.iter().map(|r| c * &r.a).collect();
    let input_gains: Vec<Vec<f64>> = cb
        .iter()
        .map(|g| g.diagonal().iter().copied().collect())
        .collect();
    let mut offdiag: f64 = 0.0;
    for (g, rule) in cb.iter().zip(&model.rules) {
        let scale = g.diagonal().amax();
        for k in 0..m {
            for l in (0..m).filter(|l| *l != k) {
                offdiag = offdiag.max(g[(k, l)].abs() / scale.max(f64::MIN_POSITIVE));
            }
            if g[(k, k)] == 0.0 {
                refusals.push(format!("rule {}: C B_i has a zero gain on input {k}: that input does not act on error component {k}", rule.name));
            }
        }
    }
    if offdiag > MATCHING_TOLERANCE {
        refusals.push(format!(
            "matching: C B_i is not diagonal (largest off-diagonal {offdiag:.3e} of the diagonal); each error component must be driven by its own input (docs/adaptive.md)"
        ));
    }
    for k in 0..m {
        let signs: Vec<f64> = input_gains.iter().map(|g| g[k].signum()).collect();
        if signs.iter().any(|s| *s != signs[0]) {
            refusals.push(format!(
                "the sign of input {k}'s gain changes between rules: the law needs a known sign"
            ));
        }
    }
    let mut nominal_inside = true;
    let (a0, a) = estimates(
        "a",
        ad.a.as_ref(),
        ca.iter().flat_map(row_major).collect(),
        &mut nominal_inside,
        &mut refusals,
    );
    let b_nominal: Vec<f64> = input_gains.iter().flatten().copied().collect();
    if let Some(e) = &ad.b {
        if b_nominal.iter().any(|v| v.signum() != e.lo.signum()) {
            refusals.push(format!(
                "the bounds {} .. {} of `b` have the other sign than the design model's input gains",
                e.lo, e.hi
            ));
        }
    }
    let (b0, b) = estimates(
        "b",
        ad.b.as_ref(),
        b_nominal,
        &mut nominal_inside,
        &mut refusals,
    );
    let (d0, d, layer) = match &ad.robust {
        Some(r) => (
            r.estimate.init.unwrap_or(r.estimate.lo),
            Adaptation {
                rate: r.estimate.rate,
                lo: r.estimate.lo,
                hi: r.estimate.hi,
            },
            r.layer,
        ),
        None => (0.0, fixed(), 1.0),
    };
    let (guaranteed, not_guaranteed) = claims(ad, nominal_inside);
    let adapted = ad.a.as_ref().map_or(0, |_| rules * m * n)
        + ad.b.as_ref().map_or(0, |_| rules * m)
        + usize::from(ad.robust.is_some());
    let (eig, p, p_eig, residual) = match &lyap {
        Ok(l) => (
            l.a_eig_re.clone(),
            row_major(&l.p),
            l.p_eig.clone(),
            l.residual,
        ),
        Err(_) => (Vec::new(), Vec::new(), Vec::new(), f64::NAN),
    };
    let report = Report {
        status: if refusals.is_empty() {
            WELL_POSED
        } else {
            REFUSED
        }
        .into(),
        refusals: refusals.clone(),
        reference_eigenvalues_re: eig,
        p: p.clone(),
        p_eigenvalues: p_eig,
        lyapunov_residual: residual,
        input_gains,
        matching_offdiagonal: offdiag,
        nominal_inside_bounds: nominal_inside,
        adapted,
        guaranteed,
        not_guaranteed,
        x0_outside_operating_range: x0_outside(model),
    };
    let design = refusals.is_empty().then(|| Design {
        n,
        m,
        rules,
        c: row_major(c),
        a_m: row_major(&ad.reference),
        p,
        a0,
        b0,
        d0,
        a,
        b,
        d,
        layer,
    });
    Outcome { design, report }
}

/// A quantity that is not adapted.
fn fixed() -> Adaptation {
    Adaptation {
        rate: 0.0,
        lo: f64::NEG_INFINITY,
        hi: f64::INFINITY,
    }
}

/// Initial values and adaptation of the estimated quantity `name` whose
/// design-model values are `nominal`. `inside` is cleared when a design-model
/// value lies outside the box; without `init` that is a refusal (the estimate
/// would start outside its bounds).
fn estimates(
    name: &str,
    e: Option<&tsf_lang::adaptive::Estimate>,
    nominal: Vec<f64>,
    inside: &mut bool,
    refusals: &mut Vec<String>,
) -> (Vec<f64>, Adaptation) {
    let Some(e) = e else {
        return (nominal, fixed());
    };
    let outside = nominal.iter().find(|v| !(e.lo..=e.hi).contains(*v));
    if let Some(v) = outside {
        *inside = false;
        if e.init.is_none() {
            refusals.push(format!(
                "`{name}` starts at the design model's values (no `init`), but {v} lies outside its bounds {} .. {}",
                e.lo, e.hi
            ));
        }
    }
    let init = match e.init {
        Some(v) => vec![v; nominal.len()],
        None => nominal,
    };
    let adaptation = Adaptation {
        rate: e.rate,
        lo: e.lo,
        hi: e.hi,
    };
    (init, adaptation)
}

/// What the Lyapunov argument of docs/adaptive.md gives for this block.
fn claims(ad: &Adaptive, nominal_inside: bool) -> (Vec<String>, Vec<String>) {
    let mut yes = vec![
        "every estimate stays inside its projection bounds at every step (projection after each update)".to_string(),
        "the input-gain blend sum_i h_i b_i keeps the sign of the bounds, so the law never divides by zero".to_string(),
    ];
    let mut no = vec![
        "convergence of the states that are not in the error signal: s -> 0 must imply x -> 0 (the spec's choice of `error`; for the spacecraft, rho' = H(rho)(s - k1 rho))".to_string(),
        "anything outside the rules' operating range: the T-S blend extrapolates there and the modelling error counts as disturbance".to_string(),
        "time-varying true parameters (e.g. J(t)): the argument assumes constant a_i, b_i".to_string(),
    ];
    let matched = "if the plant is exactly the T-S model with constant a_i, b_i inside the boxes and |d_k| <= d_max <= the robust term's upper bound: V = eps'P eps + sum(tilde^2 / rate) does not increase, so eps is bounded".to_string();
    if nominal_inside {
        yes.push(matched);
    } else {
        no.push(format!(
            "{matched} (not here: the design model's values lie outside the boxes)"
        ));
    }
    match &ad.robust {
        Some(r) => {
            yes.push(format!("with the boundary layer phi = {}: eps is ultimately bounded (|(P eps)_k| of the order of phi), not driven to 0", r.layer));
            no.push("asymptotic convergence eps -> 0 (lost to the boundary layer; a pure sign term would chatter at the controller rate)".into());
        }
        None => no.push("rejection of any disturbance or modelling error (no robust term)".into()),
    }
    no.push("parameter convergence to the true values (needs persistent excitation)".into());
    no.push("the discrete-time loop: the update laws are integrated by explicit Euler at the controller rate; the argument is for continuous time".into());
    (yes, no)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fixed_quantities_never_move() {
        let f = fixed();
        assert_eq!(f.rate, 0.0);
        assert!(f.lo < f.hi);
    }
}
