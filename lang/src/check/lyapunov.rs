//! The Lyapunov function: `lyapunov quadratic;` (the default) or
//! `lyapunov fuzzy(phi = ..);`, a fuzzy Lyapunov function
//! V = x' (sum_k h_k P_k) x whose certificate assumes |dh_k/dt| <= phi_k
//! (`phi` one number for every rule, or one per rule). The fuzzy form
//! supports stability and decay-rate objectives in a continuously updated
//! loop with synthesized gains; anything else is refused with a hint in
//! `compat/lyapunov.rs`.

use super::{unknown_choice, Checker};
use crate::ast::{Ident, Item, NamedArg};
use crate::diag::Diagnostic;
use crate::eval::Mat;
use crate::limits::MAX_FUZZY_LYAPUNOV_PHI;
use crate::num::Num;
use crate::span::{Span, Spanned};
use crate::spec::{Lyapunov, Relaxation, RuleSpec, SpannedObjective, Trigger};

/// A `lyapunov` item before the rule count is known.
#[derive(Debug, Clone)]
pub(super) enum Draft {
    /// `quadratic`.
    Quadratic,
    /// `fuzzy(phi = ..)`: phi as written (a scalar or a vector), with its span.
    Fuzzy(Mat, Span),
}

/// What the fuzzy form is checked against.
pub(super) struct Around<'s> {
    /// The trigger, if any.
    pub trigger: Option<&'s Trigger>,
    /// The checked rules.
    pub rules: &'s [RuleSpec],
    /// How many rule items there were (the rules all checked when equal).
    pub rule_items: usize,
    /// The checked objectives.
    pub objectives: &'s [SpannedObjective],
    /// The relaxation in force.
    pub relaxation: &'s Spanned<Relaxation>,
    /// Whether the inputs saturate.
    pub saturated: bool,
    /// The span of a `modes` block, if any.
    pub modes: Option<Span>,
    /// Whether the spec is an adaptive controller.
    pub adaptive: bool,
}

impl Checker<'_> {
    /// A `lyapunov` item (given once).
    pub(super) fn lyapunov_item(
        &mut self,
        it: &Item,
        name: &Ident,
        args: &[NamedArg],
        draft: &mut super::Draft,
    ) {
        let mut seen = draft.lyapunov.as_ref().map(|l| l.span);
        if self.singleton(&mut seen, it.span, "the Lyapunov function") {
            if let Some(l) = self.lyapunov(name, args, it.span) {
                draft.lyapunov = Some(Spanned::new(l, it.span));
            }
        }
    }

    fn lyapunov(&mut self, name: &Ident, args: &[NamedArg], span: Span) -> Option<Draft> {
        match name.node.as_str() {
            "quadratic" => {
                self.named(args, &[], "`lyapunov quadratic`")?;
                Some(Draft::Quadratic)
            }
            "fuzzy" => {
                if let Some(a) = args.iter().find(|a| a.name.node != "phi") {
                    self.err(
                        Diagnostic::error(
                            a.name.span,
                            format!("`lyapunov fuzzy` has no parameter `{}`", a.name.node),
                        )
                        .with_label("parameters: phi"),
                    );
                    return None;
                }
                let Some(phi) = args.iter().find(|a| a.name.node == "phi") else {
                    self.err(
                        Diagnostic::error(span, "`lyapunov fuzzy` needs `phi`, the bound on |dh_k/dt|")
                            .with_help("write `lyapunov fuzzy(phi = 0.5);` (every rule) or `phi = [0.5, 1, 0.5]` (one per rule)"),
                    );
                    return None;
                };
                let v = self.eval_const(&phi.value)?;
                Some(Draft::Fuzzy(v, phi.value.span))
            }
            other => {
                self.err(unknown_choice(
                    name.span,
                    "Lyapunov function",
                    "Lyapunov functions",
                    other,
                    &["quadratic", "fuzzy"],
                ));
                None
            }
        }
    }

    /// The Lyapunov function in force (`quadratic` when none is given); the
    /// fuzzy form's phi gets one entry per rule and what it cannot be combined
    /// with is refused at its span.
    pub(super) fn settle_lyapunov(
        &mut self,
        draft: Option<Spanned<Draft>>,
        around: Around<'_>,
    ) -> Spanned<Lyapunov> {
        let quadratic = Spanned::new(Lyapunov::Quadratic, Span::new(0, 0));
        let Some(draft) = draft else {
            return quadratic;
        };
        let span = draft.span;
        let (v, vspan) = match draft.node {
            Draft::Quadratic => return Spanned::new(Lyapunov::Quadratic, span),
            Draft::Fuzzy(v, s) => (v, s),
        };
        let r = around.rules.len();
        let ok_rules = self.fuzzy_fits(span, &around);
        if around.rule_items != r {
            return quadratic;
        }
        let phi: Vec<f64> = if v.len() == 1 {
            vec![v[(0, 0)]; r]
        } else if (v.nrows() == 1 || v.ncols() == 1) && v.len() == r {
            v.iter().copied().collect()
        } else {
            self.err(
                Diagnostic::error(
                    vspan,
                    format!(
                        "`phi` must be one number or {r} numbers (one per rule), found a {} x {} value",
                        v.nrows(),
                        v.ncols()
                    ),
                )
                .with_help("phi_k bounds |dh_k/dt| of rule k, in rule order"),
            );
            return quadratic;
        };
        if let Some(bad) = phi
            .iter()
            .find(|p| !(**p > 0.0 && **p <= MAX_FUZZY_LYAPUNOV_PHI))
        {
            self.err(
                Diagnostic::error(
                    vspan,
                    format!(
                        "`phi` must be in (0, {}], found {}",
                        Num(MAX_FUZZY_LYAPUNOV_PHI),
                        Num(*bad)
                    ),
                )
                .with_help("phi_k bounds |dh_k/dt| (1/s); a smaller phi is less conservative but must hold on the closed loop"),
            );
            return quadratic;
        }
        if !ok_rules {
            return quadratic;
        }
        Spanned::new(Lyapunov::Fuzzy { phi }, span)
    }
}

#[cfg(test)]
mod tests {
    use crate::check::testing::*;
    use crate::spec::Lyapunov;

    const THREE: &str = "tsf 1; controller c; state x1, x2; input u;\n\
        premise z = x1 range -1 .. 1 { n = tri(-2, -1, 0); o = tri(-1, 0, 1); p = tri(0, 1, 2); }\n\
        rule R1: z is n => A = [0, 1; -1, 0], B = [0; 1];\n\
        rule R2: z is o => A = [0, 1; -2, 0], B = [0; 1];\n\
        rule R3: z is p => A = [0, 1; -3, 0], B = [0; 1];\n";

    #[test]
    fn quadratic_is_the_default_and_fuzzy_broadcasts_phi() {
        assert_eq!(valid(THREE).lyapunov.node, Lyapunov::Quadratic);
        let s = valid(&format!("{THREE}lyapunov quadratic;"));
        assert_eq!(s.lyapunov.node, Lyapunov::Quadratic);
        let s = valid(&format!("{THREE}lyapunov fuzzy(phi = 0.5);"));
        assert_eq!(s.lyapunov.node, Lyapunov::Fuzzy { phi: vec![0.5; 3] });
        let s = valid(&format!(
            "{THREE}objective decay_rate maximize;\nlyapunov fuzzy(phi = [0.5, 1, 2]);"
        ));
        assert_eq!(
            s.lyapunov.node,
            Lyapunov::Fuzzy {
                phi: vec![0.5, 1.0, 2.0]
            }
        );
    }

    #[test]
    fn bad_phi_and_unsupported_combinations_have_spans() {
        let (m, at) = only_error_of(&format!("{THREE}lyapunov fuzzy(phi = [1, 2]);"));
        assert_eq!(
            m,
            "`phi` must be one number or 3 numbers (one per rule), found a 1 x 2 value"
        );
        assert_eq!(at, "[1, 2]");
        let (m, _) = only_error_of(&format!("{THREE}lyapunov fuzzy(phi = 0);"));
        assert_eq!(m, "`phi` must be in (0, 1000], found 0");
        let (m, _) = only_error_of(&format!("{THREE}lyapunov fuzzy;"));
        assert_eq!(m, "`lyapunov fuzzy` needs `phi`, the bound on |dh_k/dt|");
        let (m, _) = only_error_of(&format!("{THREE}lyapunov fuzzy(rho = 1);"));
        assert_eq!(m, "`lyapunov fuzzy` has no parameter `rho`");
        let (m, at) = only_error_of(&format!("{THREE}lyapunov cubic;"));
        assert_eq!(m, "unknown Lyapunov function `cubic`");
        assert_eq!(at, "cubic");
        let (m, at) = only_error_of(&format!(
            "{THREE}output y = x1;\nobjective input_norm(u) <= 3 for x0 = [1; 0];\nlyapunov fuzzy(phi = 1);"
        ));
        assert!(
            m.starts_with("objective `input_norm` is not supported with `lyapunov fuzzy`"),
            "{m}"
        );
        assert!(at.starts_with("objective input_norm"), "{at}");
        let (m, _) = only_error_of(&format!(
            "{THREE}trigger periodic {{ every = 0.01; }}\nlyapunov fuzzy(phi = 1);"
        ));
        assert!(m.contains("continuously updated controller"), "{m}");
        let (m, _) = only_error_of(&format!(
            "{THREE}lyapunov fuzzy(phi = 1);\nlyapunov quadratic;"
        ));
        assert_eq!(m, "the Lyapunov function is given twice");
    }
}
