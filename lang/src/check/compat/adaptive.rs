//! What an adaptive controller (`adaptive { .. }`, docs/adaptive.md) cannot
//! be combined with: LMI objectives, given gains, triggers, modes, input
//! saturation, relaxations, and generated code in f32 (the law is emitted
//! in f64 only).

use crate::ast::{Item, ItemKind};
use crate::check::{Checker, Draft};
use crate::diag::Diagnostic;
use crate::span::Span;
use crate::spec::{Precision, RuleSpec, SpannedObjective};

impl Checker<'_> {
    /// What an adaptive controller cannot be combined with.
    pub(in crate::check) fn adaptive_alone(
        &mut self,
        span: Span,
        items: &[Item],
        draft: &Draft,
        objectives: &[SpannedObjective],
        rules: &[RuleSpec],
    ) -> bool {
        let refuse = |this: &mut Self, at: Span, what: &str, help: &str| {
            this.err(
                Diagnostic::error(
                    at,
                    format!("{what} cannot be used with an adaptive controller"),
                )
                .with_secondary(span, "the adaptive controller is declared here")
                .with_help(help.to_string()),
            );
        };
        let mut ok = true;
        if let Some(o) = objectives.first() {
            refuse(self, o.span, "an LMI objective", "the adaptive law needs no LMI design: remove the `objective` items (docs/adaptive.md)");
            ok = false;
        }
        if let Some(r) = rules.iter().find(|r| r.gain.is_some()) {
            refuse(
                self,
                r.span,
                "a given PDC gain",
                "the adaptive law computes the feedback from its estimates: remove `F = ...`",
            );
            ok = false;
        }
        if let Some(t) = &draft.trigger {
            refuse(
                self,
                t.span,
                "a triggering law",
                "the adaptive law runs at the simulation step; remove the `trigger` item",
            );
            ok = false;
        }
        if let (Some(at), Some(Precision::F32)) = (draft.precision_seen, draft.precision) {
            refuse(
                self,
                at,
                "`precision f32`",
                "the adaptive law is generated in f64 only (docs/limits.md): remove `precision f32`",
            );
            ok = false;
        }
        for it in items {
            let what = match &it.kind {
                ItemKind::Modes(_) => "a `modes` block",
                ItemKind::Input(_, Some(_)) => "input saturation",
                ItemKind::Relaxation(..) => "a relaxation",
                _ => continue,
            };
            refuse(self, it.span, what, "the adaptive design covers the unsaturated, single-mode loop only (docs/adaptive.md)");
            ok = false;
        }
        ok
    }
}
