//! Output feedback (`control observer_based;`, `control static_output;`):
//! the plain data of the solved design that tables, code generation and the
//! simulator read, and the designs themselves.
//!
//! - Observer-based PDC with measured premises (Tanaka, Ikeda & Wang 1998,
//!   "Fuzzy regulators and fuzzy observers: relaxed stability conditions and
//!   LMI-based designs"; Tanaka & Wang 2001, ch. 5), two steps: the
//!   controller gains F_j by the core design (the spec's objectives and
//!   relaxation), then the observer gains L_i = P2^-1 N_i from
//!   He(P2 A_i - N_i C) + 2 alpha_o P2 < 0 ([`gains`]); the loop is then
//!   certified on the augmented state (x, e), e = x - x_hat, by an analysis
//!   SDP in P_aug = diag(P1, Pe) under the spec's relaxation and decay rate
//!   ([`augmented`]); with an input bound, a fixed output bound or the
//!   saturation region, by an analysis SDP in X = P_aug^-1 (full) that adds
//!   them ([`bounded`]).
//! - Static output feedback u = sum_j h_j K_j y (Crusius & Trofino 1999,
//!   "Sufficient LMI conditions for output feedback control problems"):
//!   M C = C X and M_j = N_j C added to the core problem, K_j = N_j M^-1
//!   ([`static_output`]); the core's conditions then hold for F_j = K_j C.

pub mod augmented;
pub mod bounded;
pub mod drift;
pub mod gains;
pub mod hinf;
pub mod sampled;
pub mod sampled_bounds;
pub mod static_output;

use nalgebra::DMatrix;
pub use tsf_lang::spec::ControlKind;

/// Where the premises the controller and observer blend with come from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum PremiseSource {
    /// Functions of the measured outputs y: the memberships are the plant's.
    Measured,
    /// Functions of the estimate x_hat (not certified in this build; the
    /// checker refuses them).
    Estimated,
}

/// The fuzzy observer of an observer-based design:
/// x_hat' = sum_i h_i (A_i x_hat + B_i u + L_i (y - C x_hat)), u = sum_j h_j F_j x_hat.
#[derive(Debug, Clone, PartialEq)]
pub struct ObserverDesign {
    /// The measured outputs y = C x (p x n).
    pub c: DMatrix<f64>,
    /// One name per row of C.
    pub output_names: Vec<String>,
    /// L_i (n x p), one per rule, continuous time.
    pub gains: Vec<DMatrix<f64>>,
    /// Where the premises come from.
    pub premise_source: PremiseSource,
    /// With measured premises: R = C^+ (n x p), whose x_rec = R y equals x in
    /// every state component (and every linear map) the premises read, so
    /// that z(x_rec) = z(x).
    pub premise_from_y: Option<DMatrix<f64>>,
    /// The observer's decay rate alpha_o imposed on the error dynamics.
    pub decay: f64,
    /// P2 of the observer LMIs (N_i = P2 L_i).
    pub p2: DMatrix<f64>,
    /// The augmented loop's certificate data.
    pub augmented: augmented::AugmentedDesign,
}

/// A static output-feedback design: u = sum_j h_j K_j y.
#[derive(Debug, Clone, PartialEq)]
pub struct StaticOutputDesign {
    /// The measured outputs y = C x (p x n).
    pub c: DMatrix<f64>,
    /// One name per row of C.
    pub output_names: Vec<String>,
    /// K_j (m x p), one per rule.
    pub gains: Vec<DMatrix<f64>>,
    /// With measured premises: R = C^+ (as [`ObserverDesign::premise_from_y`]).
    pub premise_from_y: Option<DMatrix<f64>>,
}

/// The output-feedback part of a design.
#[derive(Debug, Clone, PartialEq)]
pub enum OutputFeedback {
    /// An observer-based controller.
    Observer(ObserverDesign),
    /// A static output-feedback controller.
    StaticOutput(StaticOutputDesign),
}

impl OutputFeedback {
    /// The controller kind.
    pub fn kind(&self) -> ControlKind {
        match self {
            OutputFeedback::Observer(_) => ControlKind::ObserverBased,
            OutputFeedback::StaticOutput(_) => ControlKind::StaticOutput,
        }
    }
}

/// The Moore-Penrose pseudo-inverse of C (n x p), the premises' state
/// reconstruction from y; `None` if the SVD fails.
pub fn premise_from_y(c: &DMatrix<f64>) -> Option<DMatrix<f64>> {
    c.clone().pseudo_inverse(1e-12 * c.norm().max(1.0)).ok()
}

/// The observer's default decay rate: three times the controller's (the
/// estimate must settle faster than the loop it feeds), at least
/// [`MIN_OBSERVER_DECAY`].
pub fn default_observer_decay(controller: f64) -> f64 {
    (3.0 * controller).max(MIN_OBSERVER_DECAY)
}

/// The smallest default observer decay rate (1/s), used when the
/// controller's is 0 (plain stability).
pub const MIN_OBSERVER_DECAY: f64 = 0.1;

/// The notes of a bounded augmented certificate; its input bound replaces
/// the state-feedback one in the report's objectives (the loop that ships
/// reads x_hat).
fn bounded_notes(d: &mut crate::synth::Design, b: &bounded::BoundedDesign) {
    if let Some(mu) = b.mu {
        d.achieved
            .set(crate::synth::achieved::Quantity::InputNormBound, mu);
        d.notes.push(format!(
            "observer-based input bound: ||u(t)|| <= {mu:.6} for t >= 0 from the initial set with x_hat(0) = 0, certified on the augmented loop (x, e) with the shipped F_j, L_i (E(P_aug, 1) invariant, P_aug full)"
        ));
    }
    if let Some(o) = &b.bounds.output {
        d.notes.push(format!(
            "observer-based output bound: ||z(t)|| <= {} for t >= 0 on E(P_aug, 1), from the initial set with x_hat(0) = 0",
            o.lambda
        ));
    }
    if let Some(s) = &b.bounds.saturation {
        d.notes.push(format!(
            "observer-based saturation region: E(P_aug, 1) on (x, e) is invariant for the saturated loop (levels {:?}, the observer fed the saturated command) and lies where the generalized sector condition holds{}",
            s.levels,
            if s.contain.is_some() { "; it contains the initial set with x_hat(0) = 0" } else { "" }
        ));
    }
}

/// The observer step of a `control observer_based` spec, after the core
/// design `d` (its gains F_j): the observer gains at the observer's decay
/// rate, then the augmented loop's certificate at the controller's decay
/// rate (0 for plain stability). Any other kind is left as it is.
pub fn observe(
    runner: &mut crate::synth::Runner<'_>,
    d: &mut crate::synth::Design,
) -> Result<(), crate::synth::SynthError> {
    let model = runner.model;
    if model.spec.control.kind != ControlKind::ObserverBased {
        return Ok(());
    }
    let Some(measured) = &model.spec.measure else {
        return Err(crate::synth::SynthError::Unsupported(
            "`control observer_based` needs a `measure` item".into(),
        ));
    };
    let alpha_c = d.plan.decay().map_or(0.0, |dec| dec.alpha);
    let alpha_o = model
        .spec
        .control
        .observer_decay
        .unwrap_or_else(|| default_observer_decay(alpha_c));
    let observer = gains::solve(runner, &measured.c, alpha_o)?;
    // With a periodic trigger the bounds are certified on the sampled loop
    // that ships ([`sampled_bounds`]), not on the continuous one.
    let continuous = crate::synth::loops::observer::period(model).is_none();
    let aug = match bounded::Bounds::of(&model.spec).filter(|_| continuous) {
        Some(b) => bounded::solve(
            runner,
            (&d.gains, &observer.gains),
            &measured.c,
            alpha_c,
            &b,
        )?,
        None => augmented::solve(runner, &d.gains, &observer.gains, &measured.c, alpha_c)?,
    };
    d.notes.push(format!(
        "observer-based: observer gains L_i designed at decay rate {alpha_o}{}; the augmented loop (x, e) is certified at decay rate {alpha_c} with {}",
        if model.spec.control.observer_decay.is_some() { "" } else { " (default: 3 times the controller's, at least 0.1)" },
        if aug.bounded.is_some() { "V = [x; e]' P_aug [x; e], P_aug full" } else { "V = x'P1 x + e'Pe e" }
    ));
    if let Some(gamma) = aug.hinf_gamma {
        // The core design's gamma is the state-feedback loop's; the loop that
        // ships reads x_hat, and its gain is the augmented one.
        d.achieved
            .set(crate::synth::achieved::Quantity::HinfGamma, gamma);
        d.notes.push(format!(
            "observer-based H-inf: ||z||_2 < {gamma:.6} (||w||_2^2 + ||v||_2^2)^(1/2) from x(0) = x_hat(0) = 0 (w the disturbance, v the measurement noise), certified on the augmented loop with the shipped F_j, L_i"
        ));
    }
    if let Some(b) = &aug.bounded {
        bounded_notes(d, b);
    }
    d.output = Some(OutputFeedback::Observer(ObserverDesign {
        c: measured.c.clone(),
        output_names: measured.names.clone(),
        gains: observer.gains,
        premise_source: PremiseSource::Measured,
        premise_from_y: premise_from_y(&measured.c),
        decay: alpha_o,
        p2: observer.p2,
        augmented: aug,
    }));
    Ok(())
}

/// The solved values of an observer-loop problem's named unknowns.
pub(crate) struct SolvedVars(pub(crate) Vec<(String, DMatrix<f64>)>);

impl SolvedVars {
    /// Reads every unknown of `problem` from `sol`.
    pub(crate) fn read(
        problem: &tsf_lmi::Problem,
        sol: &tsf_lmi::Solution,
    ) -> Result<Self, crate::synth::SynthError> {
        problem
            .vars()
            .map(|(name, v)| {
                sol.value(v)
                    .cloned()
                    .map(|m| (name.to_string(), m))
                    .map_err(|e| crate::synth::SynthError::Internal(format!("internal error: {e}")))
            })
            .collect::<Result<Vec<_>, _>>()
            .map(Self)
    }

    /// The value of the unknown `name`.
    pub(crate) fn get(&self, name: &str) -> Result<DMatrix<f64>, crate::synth::SynthError> {
        self.0
            .iter()
            .find(|(k, _)| k == name)
            .map(|(_, v)| v.clone())
            .ok_or_else(|| {
                crate::synth::SynthError::Internal(format!("internal error: no value of {name}"))
            })
    }
}
