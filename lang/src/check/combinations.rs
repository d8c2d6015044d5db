//! Combinations of valid items the compiler does not support, rejected here
//! with spans instead of failing after the solver ran: the saturation region
//! with a bounded disturbance and an L-inf
//! objective with neither `xi` nor `phi` fixed, and what a synthesized
//! trigger weight needs (the compiler's `synth/trigger.rs` and
//! `synth/theorem2.rs` are the other side of these rules).

use super::{Checker, Draft};
use crate::diag::Diagnostic;
use crate::span::Span;
use crate::spec::{Objective, SpannedObjective, Trigger, TriggerSynthesis, Weight};

/// The objectives the combination rules look at.
struct Found<'o> {
    linf: Option<&'o SpannedObjective>,
    saturation: Option<&'o SpannedObjective>,
    /// Whether every objective item checked (else a missing one may only have failed).
    complete: bool,
}

impl Checker<'_> {
    /// Reports the unsupported combinations among the checked items. Without
    /// saturation levels the saturation region is reported by the model stage
    /// (it needs them), so its combinations are not judged here.
    pub(super) fn combinations(
        &mut self,
        objectives: &[SpannedObjective],
        draft: &Draft,
        levels: Option<&[f64]>,
        disturbance_bound: Option<f64>,
    ) {
        let find = |f: fn(&Objective) -> bool| objectives.iter().find(|o| f(&o.node));
        let found = Found {
            linf: find(|o| matches!(o, Objective::Linf { .. })),
            saturation: find(|o| matches!(o, Objective::SaturationRegion { .. })),
            complete: objectives.len() == draft.objective_items.len(),
        };
        let region = found.saturation.filter(|_| levels.is_some());
        if let (Some(sat), Some(l), Some(_)) = (region, found.linf, disturbance_bound) {
            if matches!(
                l.node,
                Objective::Linf {
                    xi: None,
                    phi: None,
                    ..
                }
            ) {
                self.err(
                    Diagnostic::error(
                        l.span,
                        "with the saturation region and a bounded disturbance, the L-inf objective needs a fixed `phi` or `xi`",
                    )
                    .with_label("neither `phi` nor `xi` is given")
                    .with_secondary(sat.span, "saturation region here")
                    .with_note("the linear region is shrunk by 1 + xi tau^2 / phi (tau: the disturbance bound); tsfc searches one of xi, phi with the other fixed")
                    .with_help("add `with phi = 0.05` (tsfc then minimizes xi) or `with xi = ...` (tsfc then searches phi)"),
                );
            }
        }
        if let Some(at) = draft.weight_span.filter(|_| synthesized(draft)) {
            self.weight_synthesis(&found, draft, at);
        }
    }

    /// What the design method of a synthesized trigger weight (asked for at `at`) needs.
    fn weight_synthesis(&mut self, found: &Found, draft: &Draft, at: Span) {
        let theorem2_xi = match &draft.trigger_synthesis {
            Some(TriggerSynthesis::Theorem2 { xi, .. }) => Some(*xi),
            _ => None,
        };
        let method = match &draft.trigger_synthesis {
            Some(TriggerSynthesis::Theorem2 { .. }) => "Theorem 2 (`theorem2`)",
            Some(TriggerSynthesis::Codesign { .. }) => "the co-design (`codesign`)",
            _ => "the two-step method",
        };
        let (Some(linf), Some(_)) = (found.linf, found.saturation) else {
            if found.complete {
                let missing = [
                    found
                        .linf
                        .is_none()
                        .then_some("`objective linf(d -> z) ...`"),
                    found
                        .saturation
                        .is_none()
                        .then_some("`objective saturation region;`"),
                ];
                let missing: Vec<&str> = missing.into_iter().flatten().collect();
                self.err(
                    Diagnostic::error(
                        at,
                        "a synthesized trigger weight needs an L-inf objective and the saturation region",
                    )
                    .with_label(format!("synthesized by {method}"))
                    .with_note(format!("this spec has no {}", missing.join(" and no ")))
                    .with_help(format!(
                        "add {}, or give the weight as an n x n matrix: `weight = ...;`",
                        missing.join(" and ")
                    )),
                );
            }
            return;
        };
        let Objective::Linf { to, xi, .. } = linf.node else {
            return;
        };
        match theorem2_xi {
            Some(None) if xi.is_none() => self.err(
                Diagnostic::error(at, "Theorem 2 weight synthesis needs xi")
                    .with_label("no `xi` here or in the L-inf objective")
                    .with_secondary(linf.span, "L-inf objective without `with xi = ...`")
                    .with_help(
                        "write `theorem2(xi = ...)` or `objective linf(...) ... with xi = ...`",
                    ),
            ),
            Some(_) => {}
            None => {
                let Some(out) = draft.outputs.get(to) else {
                    return;
                };
                if out.e.iter().any(|v| *v != 0.0) {
                    self.err(
                        Diagnostic::error(
                            linf.span,
                            format!("a synthesized trigger weight needs an L-inf output that does not depend on the input, but `{}` does", out.name),
                        )
                        .with_label("the L-inf objective of the trigger design")
                        .with_secondary(out.span, "output declared here")
                        .with_secondary(at, "weight synthesized here")
                        .with_help(format!("drop the input terms from output `{}`, or give the weight as an n x n matrix: `weight = ...;`", out.name)),
                    );
                }
            }
        }
    }
}

/// Whether the trigger is aperiodic with `weight = synthesize`.
fn synthesized(draft: &Draft) -> bool {
    matches!(
        draft.trigger.as_ref().map(|t| &t.node),
        Some(Trigger::Aperiodic {
            weight: Weight::Synthesize,
            ..
        })
    )
}

#[cfg(test)]
mod tests {
    use crate::check::testing::*;

    /// `BASE` with saturation levels, a bounded disturbance and an output, then `extra`.
    fn spec(extra: &str) -> String {
        format!(
            "{}disturbance d bound 0.1; D = 1;\noutput z = x1;\noutput y = x1 + u;\n{extra}",
            base_with("input u;", "input u saturate 2;")
        )
    }

    const TRIGGER: &str = "trigger aperiodic { sampling = 0.01 .. 0.1; weight = synthesize; }";

    #[test]
    fn supported_combinations_are_accepted() {
        valid(&spec(&format!(
            "objective linf(d -> z) minimize with phi = 0.05;\nobjective saturation region;\n{TRIGGER}"
        )));
        valid(&spec(
            "objective linf(d -> z) minimize with xi = 0.5;\nobjective saturation region;",
        ));
        valid(&spec(
            "objective hinf(d -> z) minimize;\nobjective decay_rate >= 0.1;",
        ));
        valid(&spec(
            "objective hinf(d -> z) minimize;\nobjective saturation region;",
        ));
        valid(&spec(
            "trigger aperiodic { sampling = 0.01 .. 0.1; weight = 1; }",
        ));
    }

    #[test]
    fn without_levels_the_model_stage_reports_the_region() {
        let src = format!(
            "{BASE}disturbance d bound 0.1; D = 1;\noutput z = x1;\n\
             objective hinf(d -> z) minimize;\nobjective saturation region;"
        );
        assert!(errors(&src).is_empty());
    }

    #[test]
    fn a_bounded_disturbance_needs_a_fixed_phi_or_xi() {
        let (m, at) = only_error_of(&spec(
            "objective linf(d -> z) minimize;\nobjective saturation region;",
        ));
        assert_eq!(m, "with the saturation region and a bounded disturbance, the L-inf objective needs a fixed `phi` or `xi`");
        assert_eq!(at, "objective linf(d -> z) minimize;");
    }

    #[test]
    fn a_synthesized_weight_needs_linf_and_the_saturation_region() {
        let e = errors(&spec(&format!("objective saturation region;\n{TRIGGER}")));
        assert_eq!(e.len(), 1, "{e:#?}");
        assert_eq!(
            e[0].0.message,
            "a synthesized trigger weight needs an L-inf objective and the saturation region"
        );
        assert_eq!(e[0].1, "weight = synthesize;");
        assert_eq!(
            e[0].0.notes,
            vec!["this spec has no `objective linf(d -> z) ...`".to_string()]
        );
        // The default weight is synthesized too: the error points at the trigger kind.
        let (_, at) = only_error_of(&spec("trigger aperiodic { sampling = 0.01 .. 0.1; }"));
        assert_eq!(at, "aperiodic");
        // A failed L-inf objective is reported alone.
        let e = errors(&spec(&format!(
            "objective linf(d -> w) minimize with phi = 1;\nobjective saturation region;\n{TRIGGER}"
        )));
        assert_eq!(e.len(), 1, "{e:#?}");
        assert_eq!(e[0].0.message, "`w` is not an output");
    }

    #[test]
    fn the_two_step_linf_output_must_not_depend_on_u() {
        let (m, at) = only_error_of(&spec(&format!(
            "objective linf(d -> y) minimize with phi = 0.05;\nobjective saturation region;\n{TRIGGER}"
        )));
        assert_eq!(m, "a synthesized trigger weight needs an L-inf output that does not depend on the input, but `y` does");
        assert_eq!(at, "objective linf(d -> y) minimize with phi = 0.05;");
    }

    #[test]
    fn theorem2_needs_xi() {
        let t2 = |xi: &str| {
            format!(
                "objective linf(d -> y) minimize with phi = 0.05;\nobjective saturation region;\n\
                 trigger aperiodic {{ sampling = 0.01 .. 0.1; weight = synthesize theorem2({xi}); }}"
            )
        };
        let (m, at) = only_error_of(&spec(&t2("eps1 = 1")));
        assert_eq!(m, "Theorem 2 weight synthesis needs xi");
        assert_eq!(at, "weight = synthesize theorem2(eps1 = 1);");
        valid(&spec(&t2("xi = 0.08")));
    }
}
