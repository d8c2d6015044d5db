//! The checked `modes { ... }` block: a continuous-time Markov chain over
//! named operating modes (e.g. actuator faults), each with its own input
//! matrix and an optional actuator bias.

use crate::eval::Mat;
use crate::span::Span;

/// How a mode's input matrix is obtained.
#[derive(Debug, Clone, PartialEq)]
pub enum Actuator {
    /// `effectiveness = [f_1, ..., f_m]`: every rule's B_i times diag(f).
    Effectiveness(Vec<f64>),
    /// `B = ...`: this n x m matrix for every rule.
    Given(Mat),
}

impl Actuator {
    /// The mode's input matrix for a rule whose nominal input matrix is `b`.
    pub fn input_matrix(&self, b: &Mat) -> Mat {
        match self {
            Actuator::Effectiveness(f) => {
                let mut out = b.clone();
                for (k, fk) in f.iter().enumerate() {
                    if k < out.ncols() {
                        out.column_mut(k).scale_mut(*fk);
                    }
                }
                out
            }
            Actuator::Given(m) => m.clone(),
        }
    }
}

/// One named mode of the chain.
#[derive(Debug, Clone, PartialEq)]
pub struct Mode {
    /// Its name.
    pub name: String,
    /// Its input matrix.
    pub actuator: Actuator,
    /// Actuator bias b (length m): the plant sees B_a u + B b in this mode. A
    /// disturbance for simulation; the stability and decay conditions do not
    /// depend on it.
    pub bias: Option<Vec<f64>>,
    /// Where it is defined.
    pub span: Span,
}

/// Whether the gains depend on the mode.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ModeDesign {
    /// Gains F_aj per mode a (the controller knows the active mode).
    Dependent,
    /// One gain set F_j for every mode (fault-blind).
    Independent,
}

impl ModeDesign {
    /// Its keyword (`mode_dependent`, `mode_independent`).
    pub fn keyword(self) -> &'static str {
        match self {
            ModeDesign::Dependent => "mode_dependent",
            ModeDesign::Independent => "mode_independent",
        }
    }
}

/// The `modes` block.
#[derive(Debug, Clone, PartialEq)]
pub struct Modes {
    /// The modes, in source order (their indices index `rates`).
    pub modes: Vec<Mode>,
    /// The transition-rate matrix Pi (generator): pi_ab >= 0 for a != b, rows sum to 0.
    pub rates: Mat,
    /// Mode-dependent or mode-independent gains.
    pub design: ModeDesign,
    /// Where the block is.
    pub span: Span,
}

impl Modes {
    /// Number of modes.
    pub fn len(&self) -> usize {
        self.modes.len()
    }

    /// Whether there is no mode (never true for a checked block).
    pub fn is_empty(&self) -> bool {
        self.modes.is_empty()
    }
}
