//! Objective families, one file each, all implementing
//! [`super::objective::Objective`]: a family declares its variables, imposes
//! its conditions (its Q_ij block through the relaxation, and side
//! constraints), says what it optimizes and reads what it achieved.
//!
//! Adding a family: one new file here implementing `Objective`, one arm in
//! [`from_spec`] and its kind in [`DECLARE_ORDER`] / [`IMPOSE_ORDER`].

mod decay;
pub mod discrete;
pub mod hinf;
mod input_norm;
mod linf;
mod output_norm;
mod saturation;

pub use decay::Decay;
pub use hinf::Hinf;
pub use input_norm::InputNorm;
pub use linf::{reach_level, Linf};
pub use output_norm::OutputNorm;
pub use saturation::Saturation;

use super::objective::{bound, Objective};
use tsf_lang::spec::{self, ObjectiveKind, Spec};

/// The order in which families declare their variables (the variable order
/// of the SDP, kept stable so the same spec gives the same problem).
pub const DECLARE_ORDER: &[ObjectiveKind] = &[
    ObjectiveKind::Hinf,
    ObjectiveKind::InputNorm,
    ObjectiveKind::OutputNorm,
    ObjectiveKind::Linf,
    ObjectiveKind::SaturationRegion,
    ObjectiveKind::DecayRate,
];

/// The order in which families impose their conditions.
pub const IMPOSE_ORDER: &[ObjectiveKind] = &[
    ObjectiveKind::DecayRate,
    ObjectiveKind::Hinf,
    ObjectiveKind::Linf,
    ObjectiveKind::InputNorm,
    ObjectiveKind::OutputNorm,
    ObjectiveKind::SaturationRegion,
];

/// The family of a spec objective, with its numbers (`None` for plain
/// stability, which the builder imposes when nothing else implies it).
pub fn from_spec(o: &spec::Objective, spec: &Spec, default_phi: f64) -> Option<Box<dyn Objective>> {
    Some(match o {
        // Stability is imposed by the builder; finite-time boundedness only
        // exists with `modes` (synth/markov), which does not use plans.
        spec::Objective::Stability | spec::Objective::FiniteTime(_) => return None,
        spec::Objective::DecayRate(t) => Box::new(Decay::new(*t)),
        spec::Objective::Hinf { from, to, target } => Box::new(Hinf {
            from: *from,
            to: *to,
            target: bound(*target),
        }),
        spec::Objective::Linf {
            from,
            to,
            target,
            xi,
            phi,
        } => Box::new(Linf {
            from: *from,
            to: *to,
            target: bound(*target),
            phi: phi.unwrap_or(default_phi),
            phi_fixed: phi.is_some(),
            xi: *xi,
            xi_bound: None,
            minimize_xi: false,
        }),
        spec::Objective::InputNorm { target, initial } => Box::new(InputNorm {
            target: bound(*target),
            initial: initial.clone(),
        }),
        spec::Objective::OutputNorm {
            output,
            target,
            initial,
        } => Box::new(OutputNorm {
            output: *output,
            target: bound(*target),
            initial: initial.clone(),
        }),
        spec::Objective::SaturationRegion { contain } => Box::new(Saturation {
            levels: spec.saturation.clone()?,
            disturbance_bound: spec.disturbance_bound,
            contain: contain.clone(),
            implied: false,
        }),
    })
}
