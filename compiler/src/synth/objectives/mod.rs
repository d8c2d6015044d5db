//! Objective families, one file each, all behind [`Objective`]: a family
//! declares its variables, imposes its conditions (its Q_ij block through the
//! relaxation, and side constraints), says what it optimizes and reads what it
//! achieved from the solution.
//!
//! Adding a family: one new file here implementing [`Objective`], one line in
//! [`from_spec`] and its kind in [`DECLARE_ORDER`] / [`IMPOSE_ORDER`].

mod decay;
mod hinf;
mod input_norm;
mod linf;
mod output_norm;
mod saturation;

pub use decay::Decay;
pub use hinf::Hinf;
pub use input_norm::InputNorm;
pub use linf::Linf;
pub use output_norm::OutputNorm;
pub use saturation::Saturation;

use super::achieved::{Achieved, Quantity};
use super::build::{BuildError, Ctx, Lmis};
use super::plan::{Bound, Goal};
use super::reduction::Values;
use crate::model::TsModel;
use std::any::Any;
use tsf_lang::spec::{self, ObjectiveKind, Spec, Target};

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

/// Cloning and downcasting, implemented for every `Clone` objective.
pub trait ObjectiveBase {
    /// A boxed copy.
    fn clone_box(&self) -> Box<dyn Objective>;
    /// For typed access ([`super::Plan::get`]).
    fn as_any(&self) -> &dyn Any;
    /// For typed access ([`super::Plan::get_mut`]).
    fn as_any_mut(&mut self) -> &mut dyn Any;
}

impl<T: Objective + Clone + 'static> ObjectiveBase for T {
    fn clone_box(&self) -> Box<dyn Objective> {
        Box::new(self.clone())
    }
    fn as_any(&self) -> &dyn Any {
        self
    }
    fn as_any_mut(&mut self) -> &mut dyn Any {
        self
    }
}

/// One objective family with its numbers.
pub trait Objective: ObjectiveBase + std::fmt::Debug + Send + Sync {
    /// The family.
    fn kind(&self) -> ObjectiveKind;

    /// Its bound: minimized (maximized for a decay rate), free or fixed.
    fn target(&self) -> Option<Bound> {
        None
    }

    /// Changes its bound (diagnosis optimizes one bound with the others kept).
    fn set_target(&mut self, _target: Bound) {}

    /// The fixed value that can conflict with other objectives, if any.
    fn fixed(&self) -> Option<f64> {
        match self.target() {
            Some(Bound::Fixed(v)) => Some(v),
            _ => None,
        }
    }

    /// How the driver optimizes it when its target is [`Bound::Minimize`].
    fn search(&self) -> Goal {
        Goal::InSdp
    }

    /// The bound in the spec's words (`hinf <= 0.5`).
    fn describe_bound(&self, v: f64) -> String {
        format!("{} <= {v}", self.kind())
    }

    /// The achieved quantity that answers "how good can this be".
    fn headline(&self) -> Option<Quantity> {
        None
    }

    /// Whether its conditions contain the Lyapunov decrease (then plain
    /// stability need not be imposed).
    fn implies_stability(&self) -> bool {
        false
    }

    /// Declares its variables.
    fn declare(&self, _model: &TsModel, _lmis: &mut Lmis<'_>) -> Result<(), BuildError> {
        Ok(())
    }

    /// Imposes its conditions.
    fn impose(&self, ctx: &Ctx<'_>, lmis: &mut Lmis<'_>) -> Result<(), BuildError>;

    /// Reads what it achieved from the solved variables.
    fn achieved(&self, _values: &Values, _out: &mut Achieved) {}
}

impl Clone for Box<dyn Objective> {
    fn clone(&self) -> Self {
        self.clone_box()
    }
}

/// A bound of the spec as a plan bound.
pub fn bound(t: Target) -> Bound {
    match t {
        Target::Optimize => Bound::Minimize,
        Target::Fixed(v) => Bound::Fixed(v),
    }
}

/// The value of a scalar variable, by name.
pub fn scalar(values: &Values, name: &str) -> Option<f64> {
    values
        .iter()
        .find(|(n, _)| n == name)
        .map(|(_, v)| v[(0, 0)])
}

/// `value` of a bound: the fixed number, or `read()` of the solved variable.
fn bound_value(target: Bound, read: impl FnOnce() -> f64) -> f64 {
    match target {
        Bound::Fixed(v) => v,
        _ => read(),
    }
}

/// The family of a spec objective, with its numbers (`None` for plain
/// stability, which the builder imposes when nothing else implies it).
pub fn from_spec(o: &spec::Objective, spec: &Spec, default_phi: f64) -> Option<Box<dyn Objective>> {
    Some(match o {
        spec::Objective::Stability => return None,
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
        }),
    })
}
