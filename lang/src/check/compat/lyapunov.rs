//! What a fuzzy Lyapunov function (`lyapunov fuzzy(phi = ..)`) cannot be
//! combined with: its conditions cover stability and decay rate of
//! synthesized gains in a continuously updated, unsaturated, single-mode loop.

use crate::check::lyapunov::Around;
use crate::check::Checker;
use crate::diag::Diagnostic;
use crate::limits::MAX_FUZZY_LYAPUNOV_RULES;
use crate::span::Span;
use crate::spec::{ObjectiveKind, Relaxation, Trigger};

impl Checker<'_> {
    /// Refuses what a fuzzy Lyapunov function cannot be combined with;
    /// whether it fits.
    pub(in crate::check) fn fuzzy_fits(&mut self, span: Span, around: &Around<'_>) -> bool {
        let refuse = |c: &mut Self, at: Span, what: String, help: &str| {
            c.err(
                Diagnostic::error(at, what)
                    .with_secondary(span, "fuzzy Lyapunov function asked for here")
                    .with_help(help.to_string()),
            );
        };
        let before = self.diags.len();
        let r = around.rules.len();
        if r > MAX_FUZZY_LYAPUNOV_RULES {
            refuse(
                self,
                span,
                format!("`lyapunov fuzzy` with {r} rules: at most {MAX_FUZZY_LYAPUNOV_RULES} rules (one relaxed double sum per P_k)"),
                "use `lyapunov quadratic;` with a stronger relaxation (`polya(d = ..)`)",
            );
        }
        for o in around.objectives {
            let k = o.node.kind();
            if !matches!(k, ObjectiveKind::Stability | ObjectiveKind::DecayRate) {
                refuse(
                    self,
                    o.span,
                    format!("objective `{k}` is not supported with `lyapunov fuzzy`: its conditions use one quadratic V = x' P x"),
                    "with a fuzzy Lyapunov function use `objective stability;` or `objective decay_rate ...;`, or write `lyapunov quadratic;`",
                );
            }
        }
        if !matches!(around.trigger, None | Some(Trigger::Continuous)) {
            refuse(
                self,
                span,
                "`lyapunov fuzzy` needs a continuously updated controller: a sampled or event-triggered loop holds memberships between samples".into(),
                "remove the trigger (or write `trigger continuous;`), or use `lyapunov quadratic;`",
            );
        }
        if around.rules.iter().any(|r| r.gain.is_some()) {
            refuse(
                self,
                span,
                "`lyapunov fuzzy` designs the gains: rules that give `F = ..` are analyzed with a quadratic V only".into(),
                "remove the given gains, or use `lyapunov quadratic;`",
            );
        }
        if around.saturated {
            refuse(
                self,
                span,
                "`lyapunov fuzzy` with input saturation is not supported: the saturation region is a level set of one quadratic V".into(),
                "remove `saturate` from the input, or use `lyapunov quadratic;`",
            );
        }
        if let Some(m) = around.modes {
            refuse(
                self,
                m,
                "a `modes` block with `lyapunov fuzzy` is not supported".into(),
                "use `lyapunov quadratic;` with modes",
            );
        }
        if around.adaptive {
            refuse(
                self,
                span,
                "an adaptive controller has no fuzzy Lyapunov function".into(),
                "remove the `lyapunov` item",
            );
        }
        if matches!(
            around.relaxation.node,
            Relaxation::MembershipMismatch { .. }
        ) {
            refuse(
                self,
                around.relaxation.span,
                "`membership_mismatch` with `lyapunov fuzzy` is not supported".into(),
                "use `basic`, `tanaka(s = ..)`, `tuan` or `polya(d = ..)`",
            );
        }
        self.diags.len() == before
    }
}
