//! Why the tables of a certified design cannot be built.

use super::sym::SymError;
use std::fmt;

/// What keeps a certified design from becoming tables (and so code).
#[derive(Debug, Clone, PartialEq)]
pub enum TablesError {
    /// The certificate was refused: a design that failed it has no tables (and so no code).
    NotCertified,
    /// A premise expression has no scalar form generated code can evaluate.
    Premise {
        /// Premise name.
        name: String,
        /// Why it cannot be generated.
        reason: SymError,
    },
    /// A premise names a component its expression does not have.
    PremiseComponent {
        /// Premise name.
        name: String,
        /// The missing component.
        component: usize,
    },
    /// The premise expressions and the model disagree on the premise count.
    PremiseCount {
        /// Scalar entries of the premise expressions.
        entries: usize,
        /// Premise components of the model.
        components: usize,
    },
    /// `weight = synthesize` but the design carries no synthesized weight.
    TriggerWeightMissing,
    /// The trigger weight is not N x N.
    TriggerWeightShape {
        /// Rows of the weight.
        rows: usize,
        /// Columns of the weight.
        cols: usize,
        /// States.
        n: usize,
    },
    /// The trigger weight has a NaN or infinite entry.
    TriggerWeightNonFinite,
    /// An adaptive spec without a `simulate` step: the update laws have no
    /// controller period.
    AdaptivePeriod,
    /// An observer-based design without a periodic trigger: the observer
    /// runs at the controller's period, which the spec does not give (or
    /// which is not a positive number).
    ObserverPeriod,
    /// The observer's data have inconsistent shapes (what is wrong).
    ObserverShape(String),
    /// The discretized observer has a NaN or infinite entry.
    ObserverNonFinite,
    /// With `precision f32`, a stored number is beyond the f32 range.
    F32Range {
        /// Which table entry.
        what: String,
        /// Its value.
        value: f64,
    },
}

impl fmt::Display for TablesError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            TablesError::NotCertified => {
                f.write_str("the certificate was refused: no code is generated")
            }
            TablesError::Premise { name, reason } => write!(f, "premise `{name}`: {reason}"),
            TablesError::PremiseComponent { name, component } => {
                write!(f, "premise `{name}`: component {component} missing")
            }
            TablesError::PremiseCount {
                entries,
                components,
            } => write!(
                f,
                "internal error: {entries} premise entries for {components} components"
            ),
            TablesError::TriggerWeightMissing => f.write_str(
                "the trigger weight is `synthesize` but the design has no synthesized trigger weight: no sensor module is generated",
            ),
            TablesError::TriggerWeightShape { rows, cols, n } => write!(
                f,
                "the trigger weight is {rows}x{cols}, expected {n}x{n}"
            ),
            TablesError::TriggerWeightNonFinite => {
                f.write_str("the trigger weight has a non-finite entry")
            }
            TablesError::AdaptivePeriod => f.write_str(
                "the adaptive law is integrated at the controller period, the `simulate` block's step: add `simulate { time = t0 .. t1 step h; ... }`",
            ),
            TablesError::ObserverPeriod => f.write_str(
                "the observer runs inside the controller at its period, which the spec does not give: add `trigger periodic { every = T; }` (T in seconds, positive)",
            ),
            TablesError::ObserverShape(what) => write!(f, "observer: {what}"),
            TablesError::ObserverNonFinite => f.write_str(
                "observer: the discretized observer has a NaN or infinite entry (the period is too long for the observer's dynamics)",
            ),
            TablesError::F32Range { what, value } => write!(
                f,
                "{what} is {value:e}, beyond the largest f32 ({:e}): `precision f32` would store infinity; scale the model or write `precision f64;`",
                f32::MAX
            ),
        }
    }
}

impl std::error::Error for TablesError {}
