//! The objective: its sense and its lowered linear form.

/// Whether the objective is minimised, maximised or absent.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ObjectiveSense {
    /// Pure feasibility problem (zero objective).
    Feasibility,
    /// Minimise the objective.
    Minimize,
    /// Maximise the objective.
    Maximize,
}

/// A linear form `constant + sum coeff · x[unknown]` with merged, sorted coefficients.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct LinearForm {
    pub(crate) coeffs: Vec<(usize, f64)>,
    pub(crate) constant: f64,
}

/// The objective of a problem as stored: sense and linear form.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Objective {
    pub(crate) sense: ObjectiveSense,
    pub(crate) form: LinearForm,
}

impl Default for Objective {
    fn default() -> Self {
        Objective {
            sense: ObjectiveSense::Feasibility,
            form: LinearForm::default(),
        }
    }
}

impl Objective {
    /// `+1` when the cone program minimises the form itself, `-1` when it
    /// minimises its negation (maximisation).
    fn sign(&self) -> f64 {
        if self.sense == ObjectiveSense::Maximize {
            -1.0
        } else {
            1.0
        }
    }

    /// The cost vector `q` over `unknowns` unknowns that the cone program minimises.
    pub(crate) fn cost(&self, unknowns: usize) -> Vec<f64> {
        let mut q = vec![0.0; unknowns];
        for &(u, c) in &self.form.coeffs {
            // ok: unknowns are only ever added, so every coefficient's index is in range.
            q[u] = self.sign() * c;
        }
        q
    }

    /// The objective in the problem's own sense from the cone program's value
    /// `q'x` (0 for feasibility problems: their cost vector is zero).
    pub(crate) fn in_own_sense(&self, value: f64) -> f64 {
        match self.sense {
            ObjectiveSense::Feasibility => value,
            ObjectiveSense::Minimize | ObjectiveSense::Maximize => {
                self.sign() * value + self.form.constant
            }
        }
    }
}
