//! The report's `objectives` section (the achieved values) and the solver's
//! `problem` size, as typed structs: their fields are in name order, so the
//! JSON keeps the key order of the map it replaced.

use super::markov;
use crate::model::TsModel;
use crate::synth::{Design, Quantity, SolverLog};
use schemars::JsonSchema;
use serde::Serialize;

/// Achieved objective values (each present only when the design has it).
#[derive(Debug, Default, Serialize, JsonSchema)]
pub struct Objectives {
    /// Certified decay rate alpha (V decays at least like e^(-2 alpha t)).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub decay_rate: Option<f64>,
    /// [feasible, infeasible] bracket of the maximal decay rate bisection
    /// (null: no infeasible rate was found).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub decay_rate_bracket: Option<(f64, Option<f64>)>,
    /// The finite-time boundedness figures of a design with modes.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub finite_time: Option<markov::FiniteTimeReport>,
    /// Certified finite-time bound c2.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub finite_time_c2: Option<f64>,
    /// Certified H-infinity attenuation gamma.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub hinf_gamma: Option<f64>,
    /// Certified bound on ||u||.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub input_norm_bound: Option<f64>,
    /// Certified L-infinity (peak-to-peak) gamma.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub linf_gamma: Option<f64>,
    /// The L-infinity gamma of the event-triggered loop.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub linf_gamma_event_triggered: Option<f64>,
    /// The paper's L-infinity gamma the spec quotes, for comparison.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub linf_gamma_paper: Option<f64>,
    /// Parameter phi of the L-infinity conditions.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub linf_phi: Option<f64>,
    /// Parameter xi of the L-infinity conditions.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub linf_xi: Option<f64>,
    /// Certified bound on ||y||.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub output_norm_bound: Option<f64>,
}

impl Objectives {
    /// The field of quantity `q`.
    fn slot(&mut self, q: Quantity) -> &mut Option<f64> {
        match q {
            Quantity::HinfGamma => &mut self.hinf_gamma,
            Quantity::LinfGamma => &mut self.linf_gamma,
            Quantity::DecayRate => &mut self.decay_rate,
            Quantity::InputNormBound => &mut self.input_norm_bound,
            Quantity::OutputNormBound => &mut self.output_norm_bound,
            Quantity::FiniteTimeC2 => &mut self.finite_time_c2,
            Quantity::LinfPhi => &mut self.linf_phi,
            Quantity::LinfXi => &mut self.linf_xi,
        }
    }

    /// The values of `design` for `model`.
    pub fn of(model: &TsModel, design: &Design) -> Objectives {
        let a = &design.achieved;
        let mut o = Objectives::default();
        if a.get(Quantity::LinfGamma).is_some() {
            o.linf_gamma_paper = model.spec.linf_paper;
        }
        o.linf_gamma_event_triggered = design.loop_design.event().map(|t| t.gamma);
        for (q, v) in a.iter() {
            *o.slot(q) = Some(v);
        }
        o.finite_time = design
            .modes
            .as_ref()
            .and_then(|md| markov::finite_time(model, md));
        o.decay_rate_bracket = a
            .decay_bracket
            .map(|(lo, hi)| (lo, hi.is_finite().then_some(hi)));
        o
    }

    /// `(name, value)` of each value present, in name order (as in the JSON).
    pub fn entries(&self) -> Vec<(String, serde_json::Value)> {
        match serde_json::to_value(self) {
            Ok(serde_json::Value::Object(map)) => map.into_iter().collect(),
            _ => Vec::new(),
        }
    }
}

/// The size of the last solved problem (the `solver.problem` section), in
/// name order; `{}` when no problem was solved.
#[derive(Debug, Serialize, JsonSchema)]
#[serde(untagged)]
pub enum Problem {
    /// A problem was solved.
    Solved(ProblemSize),
    /// No problem was solved.
    None {},
}

/// The sizes of a solved problem.
#[derive(Debug, Serialize, JsonSchema)]
pub struct ProblemSize {
    /// The largest PSD cone's order.
    pub largest_psd_cone: usize,
    /// LMI constraints.
    pub lmis: usize,
    /// Estimated peak memory of the solves, in bytes.
    pub memory_estimate_bytes: u64,
    /// Stored non-zeros of the constraint matrix.
    pub nnz: usize,
    /// PSD cones.
    pub psd_cones: usize,
    /// Rows of the constraint matrix.
    pub rows: usize,
    /// Scalar constraints.
    pub scalar_constraints: usize,
    /// Scalar unknowns.
    pub scalar_unknowns: usize,
    /// Matrix and scalar decision variables.
    pub variables: usize,
}

impl Problem {
    /// The size of `log`'s last solved problem, and the memory estimate.
    pub fn of(log: &SolverLog) -> Problem {
        let Some(s) = &log.stats else {
            return Problem::None {};
        };
        Problem::Solved(ProblemSize {
            largest_psd_cone: s.psd_cones.iter().copied().max().unwrap_or(0),
            lmis: s.lmis,
            memory_estimate_bytes: log.memory_estimate,
            nnz: s.nnz,
            psd_cones: s.psd_cones.len(),
            rows: s.rows,
            scalar_constraints: s.scalar_constraints,
            scalar_unknowns: s.scalar_unknowns,
            variables: s.variables,
        })
    }
}
