//! Objectives: `objective kind[(signals)] goal [for x0 ...] [with ...];`, at
//! most one of them optimized. The parts each kind asks for (goal, signal
//! pair, initial set, `with` parameters) are in [`super::objective_parts`].

use super::{unknown_choice, Checker};
use crate::ast::{Goal, Ident, Item, ItemKind, NamedArg, ObjectiveFor};
use crate::diag::Diagnostic;
use crate::span::{Span, Spanned};
use crate::spec::{Objective, ObjectiveKind, Output, SpannedObjective, Target};

/// The parts of one `objective` item.
pub(super) struct ObjectiveItem<'i> {
    /// The whole item.
    pub span: Span,
    /// The kind as written.
    pub name: &'i Ident,
    /// `(from -> to)` or `(signal)`.
    pub signals: &'i [Ident],
    /// `minimize`, `<= v`, ...
    pub goal: Option<&'i Goal>,
    /// `for x0 ...`.
    pub for_: Option<&'i ObjectiveFor>,
    /// `with k = v, ...`.
    pub with: &'i [NamedArg],
}

impl Checker<'_> {
    /// The checked objectives, and an error if more than one is optimized.
    pub(super) fn objectives(
        &mut self,
        items: &[&Item],
        n: usize,
        outputs: &[Output],
    ) -> Vec<SpannedObjective> {
        let objectives = items
            .iter()
            .filter_map(|it| {
                self.objective(it, n, outputs)
                    .map(|o| Spanned::new(o, it.span))
            })
            .collect::<Vec<_>>();
        let optimized: Vec<Span> = objectives
            .iter()
            .filter(|o| is_optimized(&o.node))
            .map(|o| o.span)
            .collect();
        if let [first, second, ..] = optimized.as_slice() {
            self.err(
                Diagnostic::error(*second, "more than one objective is optimized")
                    .with_label("second `minimize`/`maximize`")
                    .with_secondary(*first, "first one here")
                    .with_help("optimize one objective and bound the others with `<=` / `>=`"),
            );
        }
        objectives
    }

    fn objective(&mut self, it: &Item, n: usize, outputs: &[Output]) -> Option<Objective> {
        let ItemKind::Objective {
            name,
            signals,
            goal,
            for_,
            with,
        } = &it.kind
        else {
            return None;
        };
        let o = ObjectiveItem {
            span: it.span,
            name,
            signals,
            goal: goal.as_ref(),
            for_: for_.as_ref(),
            with,
        };
        if !self.with_allowed(&o) {
            return None;
        }
        let Some(kind) = ObjectiveKind::from_keyword(&name.node) else {
            let kinds = ObjectiveKind::ALL.map(ObjectiveKind::keyword);
            self.err(unknown_choice(
                name.span,
                "objective",
                "objectives",
                &name.node,
                &kinds,
            ));
            return None;
        };
        match kind {
            ObjectiveKind::Stability => {
                if goal.is_some() || for_.is_some() || !self.expect_signals(&o, 0) {
                    self.err(Diagnostic::error(
                        it.span,
                        "`objective stability;` takes no goal",
                    ));
                    return None;
                }
                Some(Objective::Stability)
            }
            ObjectiveKind::DecayRate => {
                if !self.expect_signals(&o, 0) {
                    return None;
                }
                self.goal_target(&o, "maximize", ">=")
                    .map(Objective::DecayRate)
            }
            ObjectiveKind::Hinf => {
                let (from, to) = self.signal_pair(&o, outputs)?;
                Some(Objective::Hinf {
                    from,
                    to,
                    target: self.goal_target(&o, "minimize", "<=")?,
                })
            }
            ObjectiveKind::Linf => {
                let (from, to) = self.signal_pair(&o, outputs)?;
                let t = self.goal_target(&o, "minimize", "<=")?;
                self.linf_paper = self.with_param(&o, "paper");
                Some(Objective::Linf {
                    from,
                    to,
                    target: t,
                    xi: self.with_param(&o, "xi"),
                    phi: self.with_param(&o, "phi"),
                })
            }
            ObjectiveKind::InputNorm => {
                if let Some(s) = signals.first() {
                    if !self.inputs.iter().any(|i| i.name == s.node) {
                        self.err(Diagnostic::error(
                            s.span,
                            format!("`{}` is not an input", s.node),
                        ));
                        return None;
                    }
                }
                let t = self.goal_target(&o, "minimize", "<=")?;
                Some(Objective::InputNorm {
                    target: t,
                    initial: self.initial_set(&o, n)?,
                })
            }
            ObjectiveKind::OutputNorm => {
                let Some(s) = signals.first() else {
                    self.err(Diagnostic::error(
                        it.span,
                        "`output_norm` needs an output: `output_norm(z) <= ...`",
                    ));
                    return None;
                };
                let out = self.output_ref(s, outputs)?;
                let t = self.goal_target(&o, "minimize", "<=")?;
                Some(Objective::OutputNorm {
                    output: out,
                    target: t,
                    initial: self.initial_set(&o, n)?,
                })
            }
            ObjectiveKind::SaturationRegion => {
                match goal {
                    Some(Goal::Word(w)) if w.node == "region" => {}
                    _ => {
                        self.err(Diagnostic::error(
                            it.span,
                            "write `objective saturation region;`",
                        ));
                        return None;
                    }
                }
                let contain = match for_ {
                    Some(_) => Some(self.initial_set(&o, n)?),
                    None => None,
                };
                Some(Objective::SaturationRegion { contain })
            }
            ObjectiveKind::FiniteTime => {
                if !self.expect_signals(&o, 0) {
                    return None;
                }
                let target = self.goal_target(&o, "minimize", "<=");
                let ft = self.finite_time(&o, n, target?)?;
                Some(Objective::FiniteTime(ft))
            }
        }
    }
}

/// Whether the objective is minimized or maximized (rather than bounded).
fn is_optimized(o: &Objective) -> bool {
    matches!(
        o,
        Objective::DecayRate(Target::Optimize)
            | Objective::Hinf {
                target: Target::Optimize,
                ..
            }
            | Objective::Linf {
                target: Target::Optimize,
                ..
            }
            | Objective::InputNorm {
                target: Target::Optimize,
                ..
            }
            | Objective::OutputNorm {
                target: Target::Optimize,
                ..
            }
            | Objective::FiniteTime(crate::spec::FiniteTime {
                target: Target::Optimize,
                ..
            })
    )
}

#[cfg(test)]
mod tests {
    use crate::check::testing::*;
    use crate::spec::{Objective, Target};

    const SIGNALS: &str = "disturbance d; D = 1;\noutput z = x1;\n";

    #[test]
    fn each_kind_gives_its_objective() {
        let spec = spec_with(&format!(
            "{SIGNALS}objective stability;\nobjective decay_rate >= 0.5;\nobjective hinf(d -> z) minimize;\n\
             objective input_norm <= 3 for x0 = 1;\nobjective output_norm(z) <= 2 for x0 in ellipsoid(4);"
        ));
        let kinds: Vec<_> = spec.objectives.iter().map(|o| o.node.clone()).collect();
        assert_eq!(kinds[0], Objective::Stability);
        assert_eq!(kinds[1], Objective::DecayRate(Target::Fixed(0.5)));
        assert_eq!(
            kinds[2],
            Objective::Hinf {
                from: 0,
                to: 0,
                target: Target::Optimize
            }
        );
        assert!(
            matches!(kinds[3], Objective::InputNorm { target: Target::Fixed(b), .. } if b == 3.0)
        );
        assert!(matches!(kinds[4], Objective::OutputNorm { output: 0, .. }));
    }

    #[test]
    fn only_one_objective_is_optimized() {
        let (m, at) = only_error(&format!(
            "{SIGNALS}objective decay_rate maximize;\nobjective hinf(d -> z) minimize;"
        ));
        assert_eq!(m, "more than one objective is optimized");
        assert_eq!(at, "objective hinf(d -> z) minimize;");
    }

    #[test]
    fn unknown_kinds_and_misused_forms_are_reported() {
        let (m, at) = only_error("objective decay maximize;");
        assert_eq!(m, "unknown objective `decay`");
        assert_eq!(at, "decay");
        let (m, _) = only_error("objective stability <= 1;");
        assert_eq!(m, "`objective stability;` takes no goal");
        let (m, _) = only_error("objective saturation;");
        assert_eq!(m, "write `objective saturation region;`");
        let (m, at) = only_error("objective input_norm(v) <= 1 for x0 = 1;");
        assert_eq!(m, "`v` is not an input");
        assert_eq!(at, "v");
    }
}
