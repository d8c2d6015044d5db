//! Trigger laws: which laws a certificate covers, what a synthesized trigger
//! weight needs, and what the premise `region` needs. Synthesis keeps only
//! the guards its code needs to read the data these rules promise
//! (`synth/trigger.rs`, `synth/signal_trigger.rs`, `synth/build.rs`,
//! `synth/experimental/theorem2.rs`); the laws no certificate covers and
//! given gains with a co-designed weight are refused here only.

use super::Around;
use crate::ast::Setting;
use crate::check::gains::{gain_arg, gain_span};
use crate::check::{Checker, Draft};
use crate::diag::Diagnostic;
use crate::span::Span;
use crate::spec::{Objective, SpannedObjective, Trigger, TriggerSynthesis, Weight};

/// Where the trigger's kind and settings are written, for the refusals
/// that point at one of them.
#[derive(Debug, Clone, Default)]
pub struct TriggerSpans {
    /// The kind (`aperiodic`, `mixed`, ..).
    pub kind: Span,
    /// Each setting's key and span.
    pub settings: Vec<(String, Span)>,
}

impl TriggerSpans {
    /// The spans of a trigger item of `kind` with `settings`.
    pub fn of(kind: Span, settings: &[Setting]) -> Self {
        TriggerSpans {
            kind,
            settings: settings
                .iter()
                .map(|s| (s.key.node.clone(), s.span))
                .collect(),
        }
    }

    /// The span of setting `key`, if written.
    fn setting(&self, key: &str) -> Option<Span> {
        self.settings
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, s)| *s)
    }
}

/// The objectives the weight rules look at.
struct Found<'o> {
    linf: Option<&'o SpannedObjective>,
    saturation: Option<&'o SpannedObjective>,
    /// Whether every objective item checked (else a missing one may only have failed).
    complete: bool,
}

impl Checker<'_> {
    /// Errors for trigger laws outside every certificate and for what a
    /// synthesized weight or a premise `region` needs. With `modes`, the
    /// loops are judged by `modes.rs` instead (`region` here).
    pub(super) fn trigger_fits(&mut self, draft: &Draft, around: &Around<'_>) {
        let Some(t) = &draft.trigger else {
            return;
        };
        self.region_fits(draft, around);
        if around.modes.is_some() {
            return;
        }
        let spans = &draft.trigger_spans;
        match &t.node {
            Trigger::Mixed { monitor, .. } => {
                if monitor.sampling().is_some() {
                    let at = spans.setting("sampling").unwrap_or(spans.kind);
                    self.err(
                        Diagnostic::error(at, "the `trigger mixed` law at aperiodic sampling instants is not covered by a certificate yet")
                            .with_label("checked at aperiodic sampling instants")
                            .with_note("the mixed-trigger certificate covers the law checked continuously (or at every step) only")
                            .with_help("write `monitor = continuous;` with `on = <signal>;` (a signal that is a linear image of the PDC command is certified), or use `trigger aperiodic { sampling = ..; threshold nu = ..; weight = synthesize; }` (certified event trigger) or `trigger periodic { every = ..; }`"),
                    );
                }
                if let Some(levels) = around.saturate {
                    self.err(
                        Diagnostic::error(spans.kind, "the mixed-trigger certificate does not cover input saturation")
                            .with_label("this law is certified for the unsaturated loop")
                            .with_secondary(levels, "input saturation declared here")
                            .with_help("remove `saturate` from the input (the certificate assumes u is applied unsaturated), or use `trigger aperiodic { ..; weight = synthesize; }` with the saturation region"),
                    );
                }
            }
            Trigger::Aperiodic {
                threshold: Some(_),
                weight: Weight::Given(_),
                ..
            } => {
                let at = spans.setting("weight").unwrap_or(spans.kind);
                let mut d = Diagnostic::error(
                    at,
                    "an event trigger with a given weight is not covered by a certificate yet",
                )
                .with_label("weight given here");
                if let Some(th) = spans.setting("threshold") {
                    d = d.with_secondary(th, "the threshold makes it an event trigger");
                }
                self.err(d.with_help("write `weight = synthesize;` (the weight is then designed and certified with the threshold), or remove the threshold (every sample is then transmitted)"));
            }
            _ => {}
        }
        if let Some(at) = draft.weight_span.filter(|_| synthesized(draft)) {
            let before = self.diags.len();
            self.gains_with_method(draft, at);
            let find = |f: fn(&Objective) -> bool| around.objectives.iter().find(|o| f(&o.node));
            let found = Found {
                linf: find(|o| matches!(o, Objective::Linf { .. })),
                saturation: find(|o| matches!(o, Objective::SaturationRegion { .. })),
                complete: around.objectives_complete,
            };
            self.weight_synthesis(&found, draft, at);
            let theorem2 = matches!(
                draft.trigger_synthesis,
                Some(TriggerSynthesis::Theorem2 { .. })
            );
            if theorem2 && self.diags.len() == before {
                self.err(
                    Diagnostic::warning(at, "Theorem 2 designs are reported, never emitted: `tsfc compile` solves them and exits 3")
                        .with_note("Xu & Huang's Theorem 2 is an experiment (docs/event_trigger.md); no certificate of it is built")
                        .with_help("write `weight = synthesize;` (or `synthesize codesign`) for a certified design"),
                );
            }
        }
    }

    /// Given gains with a weight design method that designs the gains itself.
    fn gains_with_method(&mut self, draft: &Draft, at: Span) {
        let Some(given) = draft.rule_items.iter().find_map(|it| gain_arg(it)) else {
            return;
        };
        let method = match &draft.trigger_synthesis {
            Some(TriggerSynthesis::Theorem2 { .. }) => "Theorem 2",
            Some(TriggerSynthesis::Codesign { .. }) => "co-design",
            Some(TriggerSynthesis::Transmissions { .. }) => "few-transmissions",
            _ => return,
        };
        self.err(
            Diagnostic::error(at, format!("given gains cannot be analyzed with {method} weight synthesis"))
                .with_label(format!("{method} designs the gains together with the trigger weight"))
                .with_secondary(gain_span(given), "gain given here")
                .with_help("write `weight = synthesize;` (the two-step method keeps the given gains and designs the weight for them), or remove the gains"),
        );
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
            Some(TriggerSynthesis::Transmissions { .. }) => {
                "the few-transmissions design (`transmissions`)"
            }
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

    /// `region` makes the event-triggered certificate local to a premise box:
    /// it needs an event trigger whose weight tsfc synthesizes by the
    /// two-step method or the co-design (no other certificate uses the box,
    /// and with `modes` the loop is certified on the whole premise range).
    fn region_fits(&mut self, draft: &Draft, around: &Around<'_>) {
        let Some(first) = around.trigger_region.first() else {
            return;
        };
        let event = synthesized(draft)
            && matches!(
                draft.trigger_synthesis,
                None | Some(TriggerSynthesis::TwoStep)
                    | Some(TriggerSynthesis::Codesign { .. })
                    | Some(TriggerSynthesis::Transmissions { .. })
            );
        let transmissions = matches!(
            draft.trigger_synthesis,
            Some(TriggerSynthesis::Transmissions { .. })
        );
        if let Some(auto) = around.trigger_region.iter().find(|b| b.auto) {
            if event && !transmissions {
                self.err(
                    Diagnostic::error(auto.span, "`region .. = auto` needs `weight = synthesize transmissions`")
                        .with_label("only the few-transmissions design grows the box for its gains")
                        .with_help("write the box (`region z = lo .. hi;`), or use `weight = synthesize transmissions(points = .., gamma = ..);`"),
                );
                return;
            }
        }
        // The sampled observer loop's drift route: checked with the spec
        // (`output_feedback.rs`: every state bounded, states only).
        let observer = matches!(
            draft.trigger.as_ref().map(|t| &t.node),
            Some(Trigger::Periodic { .. })
        ) && draft
            .control
            .as_ref()
            .is_some_and(|c| c.kind == crate::spec::ControlKind::ObserverBased);
        if (event || observer) && around.modes.is_none() {
            return;
        }
        let mut d = Diagnostic::error(
            first.span,
            "`region` needs an event trigger whose weight tsfc synthesizes",
        )
        .with_label("no certificate of this loop is made local to this box");
        d = match around.modes {
            Some(m) => d
                .with_secondary(m, "modes here")
                .with_note("with `modes` the loop is certified on the whole premise range"),
            None => d.with_note("the regional certificate is the two-step or co-designed event trigger's (docs/language.md, Regional certificate), or the sampled observer loop's (`control observer_based;` with `trigger periodic`)"),
        };
        self.err(d.with_help("remove `region` (the certificate then holds on the whole premise range), or use `threshold nu = ..; weight = synthesize;` (or `synthesize codesign`) with an L-inf objective and the saturation region"));
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
    fn supported_laws_are_accepted() {
        valid(&spec(&format!(
            "objective linf(d -> z) minimize with phi = 0.05;\nobjective saturation region;\n{TRIGGER}"
        )));
        valid(&spec(
            "trigger aperiodic { sampling = 0.01 .. 0.1; weight = 1; }",
        ));
        valid(&format!(
            "{BASE}signal s = x1;\ntrigger mixed {{ on = s; beta = 0.1; rho = 1e-4; monitor = continuous; }}"
        ));
    }

    #[test]
    fn laws_no_certificate_covers_are_refused_at_the_setting() {
        let (m, at) =
            only_error("trigger mixed { sampling = 0.01 .. 0.1; beta = 0.5; rho = 1e-4; }");
        assert_eq!(m, "the `trigger mixed` law at aperiodic sampling instants is not covered by a certificate yet");
        assert_eq!(at, "sampling = 0.01 .. 0.1;");
        let (m, at) = only_error(
            "trigger aperiodic { sampling = 0.01 .. 0.1; threshold nu = 0.1; weight = 1; }",
        );
        assert_eq!(
            m,
            "an event trigger with a given weight is not covered by a certificate yet"
        );
        assert_eq!(at, "weight = 1;");
        let (m, at) = only_error_of(&spec(
            "signal s = x1;\ntrigger mixed { on = s; beta = 0.1; rho = 1e-4; monitor = step; }",
        ));
        assert_eq!(
            m,
            "the mixed-trigger certificate does not cover input saturation"
        );
        assert_eq!(at, "mixed");
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
        // Accepted, with a warning that compile reports and refuses it.
        let (_, diags) = crate::check_source(&spec(&t2("xi = 0.08")));
        assert!(diags.iter().all(|d| !d.is_error()), "{diags:#?}");
        assert!(diags.iter().any(|d| d
            .message
            .starts_with("Theorem 2 designs are reported, never emitted")));
    }

    #[test]
    fn given_gains_do_not_go_with_theorem2() {
        let src = spec(
            "objective linf(d -> z) minimize with phi = 0.05, xi = 0.1;\nobjective saturation region;\n\
             trigger aperiodic { sampling = 0.01 .. 0.1; weight = synthesize theorem2(xi = 0.1); }\n",
        )
        .replace("=> A = -2;", "=> A = -2, F = -1;");
        let (m, at) = only_error_of(&src);
        assert_eq!(
            m,
            "given gains cannot be analyzed with Theorem 2 weight synthesis"
        );
        assert_eq!(at, "weight = synthesize theorem2(xi = 0.1);");
        valid(&src.replace(" theorem2(xi = 0.1)", ""));
    }

    #[test]
    fn a_region_needs_a_synthesized_event_trigger_weight() {
        let want = "`region` needs an event trigger whose weight tsfc synthesizes";
        let (m, at) = only_error(
            "trigger aperiodic { sampling = 0.01 .. 0.1; weight = 1; region x1 = -0.5 .. 0.5; }",
        );
        assert_eq!(
            (m.as_str(), at.as_str()),
            (want, "region x1 = -0.5 .. 0.5;")
        );
        let src = spec(
            "objective linf(d -> z) minimize with phi = 0.05, xi = 0.1;\nobjective saturation region;\n\
             trigger aperiodic { sampling = 0.01 .. 0.1; threshold nu = 0.1; weight = synthesize{}; region x1 = -0.5 .. 0.5; }",
        );
        valid(&src.replace("{}", ""));
        valid(&src.replace("{}", " codesign"));
        valid(&src.replace("{}", " transmissions"));
        // `auto` is the few-transmissions design's: it grows the box for its gains.
        let auto = src.replace("-0.5 .. 0.5", "auto");
        valid(&auto.replace("{}", " transmissions(points = 3)"));
        let (m, at) = only_error_of(&auto.replace("{}", " codesign"));
        assert_eq!(
            (m.as_str(), at.as_str()),
            (
                "`region .. = auto` needs `weight = synthesize transmissions`",
                "region x1 = auto;"
            )
        );
        let (m, _) = only_error_of(&src.replace("{}", " theorem2"));
        assert_eq!(m, want);
        // With modes the loop is certified on the whole range.
        let modes = "modes { mode a { } rates = [0]; }\n";
        let e = errors(&format!(
            "{BASE}{modes}trigger aperiodic {{ sampling = 0.01 .. 0.1; region x1 = -0.5 .. 0.5; }}"
        ));
        assert_eq!(e.len(), 1, "{e:#?}");
        assert_eq!(e[0].0.message, want);
    }
}
