//! What `objective finite_time` needs from the rest of the spec: a `modes`
//! block (one mode for a plant without faults) and, when the plant has
//! disturbances, their energy bound (`disturbance d energy w2;`).

use crate::check::Checker;
use crate::diag::Diagnostic;
use crate::span::Span;
use crate::spec::{Objective, SpannedObjective};

impl Checker<'_> {
    /// A `finite_time` objective needs a `modes` block (`modes_span`) and,
    /// with `q` > 0 disturbance components, their energy bound.
    pub(in crate::check) fn finite_time_fits(
        &mut self,
        objectives: &[SpannedObjective],
        modes_span: Option<Span>,
        q: usize,
        energy: Option<f64>,
        energy_broken: bool,
    ) {
        let Some(o) = objectives
            .iter()
            .find(|o| matches!(o.node, Objective::FiniteTime(_)))
        else {
            return;
        };
        if modes_span.is_none() {
            self.err(
                Diagnostic::error(o.span, "objective `finite_time` needs a `modes` block")
                    .with_help("for a plant without faults, one mode: `modes { mode nominal { } rates = [0]; }`")
                    .with_note("tsfc designs finite-time boundedness for Markov jump systems; one mode is the deterministic case"),
            );
        }
        if q > 0 && energy.is_none() && !energy_broken {
            self.err(
                Diagnostic::error(o.span, "objective `finite_time` needs the disturbance energy bound")
                    .with_help("declare it: `disturbance d energy w2;` (the integral of w'w over [0, T] is at most w2)"),
            );
        }
    }
}
