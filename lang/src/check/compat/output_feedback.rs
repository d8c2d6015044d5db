//! What output feedback (`control observer_based;`, `control static_output;`)
//! needs and cannot be combined with in this build: a `measure` item;
//! premises on measured states (every state component a premise reads lies
//! in the row space of C); for `static_output` a C of full row rank; for
//! `observer_based` the objectives the augmented loop's certificate covers
//! (stability, decay rate, an input bound and saturation levels; H-inf and a
//! fixed output bound on the continuous loop only, H-inf not with the
//! bounds). Neither is combined with a trigger other than `periodic` (the
//! sampled loop), modes, an adaptive block, a fuzzy Lyapunov function, given
//! gains or a plant region.

use crate::ast::ItemKind;
use crate::check::measure::{rank, recovered, state_reads};
use crate::check::Checker;
use crate::diag::Diagnostic;
use crate::span::Span;
use crate::spec::{ControlKind, Lyapunov, ObjectiveKind, Signal, Spec, Trigger};

impl Checker<'_> {
    /// Refuses the output-feedback combinations this build cannot certify.
    pub(in crate::check) fn output_feedback_fits(&mut self, spec: &Spec) {
        let kind = spec.control.kind;
        if kind == ControlKind::StateFeedback {
            return;
        }
        let at = spec.control.span;
        let word = kind.keyword();
        let Some(measured) = &spec.measure else {
            self.err(
                Diagnostic::error(at, format!("`control {word}` needs measured outputs"))
                    .with_label("no `measure` item")
                    .with_help("declare what the controller reads, e.g. `measure y = [1, 0] * x;` (y = C x)"),
            );
            return;
        };
        let c = &measured.c;
        if kind == ControlKind::StaticOutput && rank(c) < c.nrows() {
            self.err(
                Diagnostic::error(measured.span, format!("`control static_output` needs C of full row rank, but the {} measured rows have rank {}", c.nrows(), rank(c)))
                    .with_label("these measurements repeat one another")
                    .with_help("remove the redundant `measure` rows (the design inverts M with M C = C X)"),
            );
        }
        self.premises_measured(spec, c);
        self.output_feedback_alone(spec, at, word);
        if kind == ControlKind::ObserverBased {
            self.observer_objectives(spec, at);
        }
    }

    /// The objectives the augmented loop's certificate covers: stability, a
    /// decay rate, H-inf, an input bound, a fixed output bound and the
    /// saturation region on the continuous loop (H-inf not together with the
    /// bounds); stability, a decay rate, an input bound and the saturation
    /// region (the linear region: no active saturation), or H-inf with a
    /// fixed bound (free vertices, without the bounds), on the sampled loop.
    fn observer_objectives(&mut self, spec: &Spec, at: Span) {
        let sampled = spec
            .trigger
            .as_ref()
            .is_some_and(|t| matches!(t.node, Trigger::Periodic { .. }));
        let bounded = spec.saturation.is_some()
            || spec.objectives.iter().any(|o| {
                matches!(
                    o.node.kind(),
                    ObjectiveKind::InputNorm
                        | ObjectiveKind::OutputNorm
                        | ObjectiveKind::SaturationRegion
                )
            });
        for o in &spec.objectives {
            let k = o.node.kind();
            let augmented = matches!(
                k,
                ObjectiveKind::Hinf
                    | ObjectiveKind::InputNorm
                    | ObjectiveKind::OutputNorm
                    | ObjectiveKind::SaturationRegion
            );
            let continuous_only = matches!(k, ObjectiveKind::Hinf | ObjectiveKind::OutputNorm);
            let minimized_output = matches!(
                o.node,
                crate::spec::Objective::OutputNorm {
                    target: crate::spec::Target::Optimize,
                    ..
                }
            );
            let sampled_hinf = k == ObjectiveKind::Hinf && !bounded;
            let minimized_hinf = matches!(
                o.node,
                crate::spec::Objective::Hinf {
                    target: crate::spec::Target::Optimize,
                    ..
                }
            );
            if sampled_hinf && sampled && minimized_hinf {
                self.err(
                    Diagnostic::error(o.span, "`objective hinf` needs a fixed bound for the sampled `control observer_based` loop")
                        .with_secondary(at, "the observer-based controller is declared here")
                        .with_help("write the bound, e.g. `objective hinf(d -> z) <= 20;`: the sampled loop's H-inf gain is certified against a fixed bound (the gains of a minimized continuous design are too aggressive to sample, and the sampled problem without a bound is ill-posed for the solver)"),
                );
            } else if sampled_hinf && sampled && !spec.trigger_region.is_empty() {
                self.err(
                    Diagnostic::error(o.span, "`objective hinf` is not covered for the sampled `control observer_based` loop on a region")
                        .with_secondary(spec.trigger_region[0].span, "the membership-drift region is declared here")
                        .with_help("the region's drift bound assumes the state stays in the box over a period, which an energy-bounded disturbance does not keep; remove the `region` settings (free vertices, a global certificate) or the H-inf objective"),
                );
            } else if continuous_only && sampled && !sampled_hinf {
                self.err(
                    Diagnostic::error(o.span, format!("`objective {}` is not covered for the sampled `control observer_based` loop", k.keyword()))
                        .with_secondary(at, "the observer-based controller is declared here")
                        .with_help("the sampled loop's certificate covers stability, a decay rate, an input bound and saturation levels (the actuator kept linear on the certified set), and a fixed H-inf bound without them; the output bound, and H-inf together with the bounds, are certified on the continuous augmented loop only (remove the `trigger periodic` item, or the objective)"),
                );
            } else if minimized_output {
                self.err(
                    Diagnostic::error(o.span, "`objective output_norm` needs a fixed bound for `control observer_based`")
                        .with_secondary(at, "the observer-based controller is declared here")
                        .with_help("write the bound, e.g. `objective output_norm(z) <= 1.0 for x0 = ...;` (the augmented loop's output bound keeps its certified set inside a region; it is not minimized in this build)"),
                );
            } else if k == ObjectiveKind::Hinf && bounded {
                self.err(
                    Diagnostic::error(o.span, "`objective hinf` is not combined with an input bound or saturation for `control observer_based`")
                        .with_secondary(at, "the observer-based controller is declared here")
                        .with_help("the augmented loop's input bound and saturation region are certified without a disturbance in this build: remove the H-inf objective, or the `input_norm` objective, the saturation region and the `saturate` levels"),
                );
            }
            if !augmented && !matches!(k, ObjectiveKind::Stability | ObjectiveKind::DecayRate) {
                self.err(
                    Diagnostic::error(o.span, format!("`objective {}` is not covered for `control observer_based`", k.keyword()))
                        .with_secondary(at, "the observer-based controller is declared here")
                        .with_help("the augmented loop (x, e) is certified for stability, a decay rate, an H-inf gain, input and output bounds and the saturation region in this build (docs/limits.md); use `control static_output;` or state feedback for the other objectives"),
                );
            }
        }
    }

    /// `region` settings of the sampled observer loop (the membership drift
    /// route): each names a state, and together they bound every state.
    fn drift_region(&mut self, spec: &Spec) {
        let bounds = &spec.trigger_region;
        let Some(first) = bounds.first() else {
            return;
        };
        let help = "the sampled observer certificate on a region bounds the membership drift over a period from a box on every state: write `region x = lo .. hi;` for each state (docs/language.md, The sampled loop)";
        if let Some(b) = bounds.iter().find(|b| b.state.is_none()) {
            self.err(
                Diagnostic::error(b.span, format!("`region {}` names a premise variable; the sampled observer loop's region bounds states", b.premise))
                    .with_help(help),
            );
            return;
        }
        let n = spec.n();
        let mut bounded = vec![false; n];
        for b in bounds {
            if let Some((at, len)) = b.state {
                bounded[at..at + len].iter_mut().for_each(|v| *v = true);
            }
        }
        let names = Signal::names_of(&spec.states);
        let missing: Vec<&str> = (0..n)
            .filter(|&k| !bounded[k])
            .map(|k| names[k].as_str())
            .collect();
        if !missing.is_empty() {
            self.err(
                Diagnostic::error(
                    first.span,
                    format!(
                        "the sampled observer loop's region leaves {} unbounded",
                        missing.join(", ")
                    ),
                )
                .with_help(help),
            );
        }
    }

    /// Every state component a premise reads must be recovered from y.
    fn premises_measured(&mut self, spec: &Spec, c: &crate::eval::Mat) {
        let n = spec.n();
        let names = Signal::names_of(&spec.states);
        let word = spec.control.kind.keyword();
        for p in &spec.premises {
            let reads = state_reads(&p.expr, &spec.states, n);
            let missing: Vec<&str> = (0..n)
                .filter(|&k| reads[k] && !recovered(c, k))
                .map(|k| names.get(k).map_or("?", String::as_str))
                .collect();
            if missing.is_empty() {
                continue;
            }
            let list = missing
                .iter()
                .map(|m| format!("`{m}`"))
                .collect::<Vec<_>>()
                .join(", ");
            self.err(
                Diagnostic::error(p.span, format!("premise `{}` reads {list}, which the measured outputs do not recover", p.name))
                    .with_label(format!("`control {word}` needs measured premises"))
                    .with_secondary(spec.control.span, "the output-feedback controller is declared here")
                    .with_help(format!("measure {list} (`measure y = ..;`) or write the premise on measured states; premises of the estimate would need a bound on the membership mismatch h(x) - h(x_hat), which this build does not certify")),
            );
        }
    }

    /// The items output feedback is not combined with.
    fn output_feedback_alone(&mut self, spec: &Spec, at: Span, word: &str) {
        let refuse = |this: &mut Self, span: Span, what: &str, help: &str| {
            this.err(
                Diagnostic::error(span, format!("{what} cannot be used with `control {word}`"))
                    .with_secondary(at, "the output-feedback controller is declared here")
                    .with_help(help.to_string()),
            );
        };
        if let Some(t) = &spec.trigger {
            if !matches!(t.node, Trigger::Continuous | Trigger::Periodic { .. }) {
                refuse(self, t.span, "this triggering law", "output feedback is certified for the continuous loop and for `trigger periodic { every = T; }` (the sampled loop) in this build");
            }
            let periodic = matches!(t.node, Trigger::Periodic { .. });
            if periodic && spec.control.kind == ControlKind::ObserverBased {
                self.drift_region(spec);
            }
        }
        if matches!(spec.lyapunov.node, Lyapunov::Fuzzy { .. }) {
            refuse(
                self,
                spec.lyapunov.span,
                "a fuzzy Lyapunov function",
                "use the quadratic Lyapunov function (remove the `lyapunov` item)",
            );
        }
        if let Some(r) = spec.rules.iter().find(|r| r.gain.is_some()) {
            refuse(
                self,
                r.span,
                "a given state-feedback gain",
                "the output-feedback gains are synthesized: remove `F = ...`",
            );
        }
        for it in &self.file.items {
            let what = match &it.kind {
                ItemKind::Modes(_) => "a `modes` block",
                ItemKind::Adaptive(_) => "an `adaptive` block",
                ItemKind::PlantRegion(_) => "a `plant region`",
                _ => continue,
            };
            refuse(
                self,
                it.span,
                what,
                "output feedback covers the nominal single-mode PDC loop in this build (docs/limits.md)",
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::check::testing::*;

    const PENDULUM: &str = "tsf 1; controller c; state th, om; input u;\n\
        A(x) = [0, 1; 10 * sinc(th), 0]; B = [0; 1];\n\
        premise s = sinc(th) range 0.6 .. 1 { near = tri(0.6, 1, 1); far = tri(0.6, 0.6, 1); }\n\
        rule R1: s is near => at(th = 0, om = 0);\n\
        rule R2: s is far => at(th = 1.4, om = 0);\n\
        objective decay_rate >= 0.5;\n";

    #[test]
    fn measured_premises_pass_and_unmeasured_ones_are_refused() {
        let spec = valid(&format!(
            "{PENDULUM}measure y = th;\ncontrol observer_based;\n"
        ));
        assert_eq!(spec.measure.map(|m| m.c.nrows()), Some(1));
        let (m, at) = only_error_of(&format!(
            "{PENDULUM}measure y = om;\ncontrol observer_based;\n"
        ));
        assert_eq!(
            m,
            "premise `s` reads `th`, which the measured outputs do not recover"
        );
        assert_eq!(at, "s");
    }

    #[test]
    fn output_feedback_needs_a_measure_and_full_rank_for_static_output() {
        let (m, at) = only_error_of(&format!("{PENDULUM}control static_output;\n"));
        assert_eq!(m, "`control static_output` needs measured outputs");
        assert_eq!(at, "control static_output;");
        let (m, _) = only_error_of(&format!(
            "{PENDULUM}measure y = [th; 2 * th];\ncontrol static_output;\n"
        ));
        assert!(m.contains("full row rank"), "{m}");
    }

    #[test]
    fn observer_based_refuses_uncovered_objectives_and_triggers() {
        let src = format!(
            "{PENDULUM}measure y = th;\ncontrol observer_based;\nobjective input_norm(u) <= 5 for x0 = [0.1, 0];\n"
        );
        valid(&src);
        valid(&format!("{src}trigger periodic {{ every = 0.01; }}\n"));
        valid(
            &format!("{src}objective saturation region;\ntrigger periodic {{ every = 0.01; }}\n")
                .replace("input u;", "input u saturate 50;"),
        );
        let (m, at) = only_error_of(&format!(
            "{PENDULUM}measure y = th;\ncontrol observer_based;\noutput z = th;\nobjective output_norm(z) <= 1 for x0 = [0.1, 0];\ntrigger periodic {{ every = 0.01; }}\n"
        ));
        assert_eq!(
            m,
            "`objective output_norm` is not covered for the sampled `control observer_based` loop"
        );
        assert!(at.starts_with("objective output_norm"), "{at}");
        let (m, at) = only_error_of(&format!(
            "{PENDULUM}measure y = th;\ncontrol observer_based;\ndisturbance d; D = [0; 1]; output z = th;\nobjective linf(d -> z) <= 5;\n"
        ));
        assert_eq!(
            m,
            "`objective linf` is not covered for `control observer_based`"
        );
        assert!(at.starts_with("objective linf"), "{at}");
        let (m, at) = only_error_of(&format!(
            "{PENDULUM}measure y = th;\ncontrol observer_based;\noutput z = th;\nobjective output_norm(z) minimize for x0 = [0.1, 0];\n"
        ));
        assert_eq!(
            m,
            "`objective output_norm` needs a fixed bound for `control observer_based`"
        );
        assert!(at.starts_with("objective output_norm"), "{at}");
        let (m, at) = only_error_of(&format!(
            "{PENDULUM}measure y = th;\ncontrol observer_based;\ndisturbance d; D = [0; 1]; output z = th;\nobjective hinf(d -> z) minimize;\nobjective saturation region;\n"
        ).replace("input u;", "input u saturate 50;"));
        assert!(
            m.starts_with("`objective hinf` is not combined with an input bound or saturation"),
            "{m}"
        );
        assert!(at.starts_with("objective hinf"), "{at}");
        let src = format!(
            "{PENDULUM}measure y = th;\ncontrol static_output;\ntrigger jittered {{ every = 0.01; jitter = 0.001; }}\n"
        );
        let (m, _) = only_error_of(&src);
        assert_eq!(
            m,
            "this triggering law cannot be used with `control static_output`"
        );
        for kind in ["static_output", "observer_based"] {
            valid(&format!(
                "{PENDULUM}measure y = th;\ncontrol {kind};\ntrigger periodic {{ every = 0.01; }}\n"
            ));
        }
    }
}
