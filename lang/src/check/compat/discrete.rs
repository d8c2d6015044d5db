//! `trigger periodic { design = discrete; }`: what the discrete-time design
//! route supports (stability and decay rate of synthesized gains, no
//! `saturate`), each refusal at the setting with the reason.

use crate::check::Checker;
use crate::diag::Diagnostic;
use crate::span::Spanned;
use crate::spec::{Objective, PeriodicDesign, RuleSpec, SpannedObjective};

impl Checker<'_> {
    /// Errors for what `design = discrete` does not cover.
    pub(in crate::check) fn discrete_design_fits(
        &mut self,
        design: Option<&Spanned<PeriodicDesign>>,
        objectives: &[SpannedObjective],
        saturated: bool,
        rules: &[RuleSpec],
    ) {
        let Some(d) = design.filter(|d| d.node == PeriodicDesign::Discrete) else {
            return;
        };
        let note = "the discrete-time route designs for stability and decay rate of the zero-order-hold model (docs/language.md, Triggering laws)";
        for o in objectives {
            if !matches!(o.node, Objective::Stability | Objective::DecayRate(_)) {
                self.err(
                    Diagnostic::error(
                        o.span,
                        "this objective is not supported with `design = discrete`",
                    )
                    .with_secondary(d.span, "discrete-time design asked here")
                    .with_note(note)
                    .with_help("use `design = emulation` (the default) for this objective"),
                );
            }
        }
        if saturated {
            self.err(
                Diagnostic::error(d.span, "`design = discrete` with `saturate` is not supported")
                    .with_note("declared input limits must be inside the certificate; the discrete route has no saturation condition yet")
                    .with_help("use `design = emulation` (the saturation region is certified for the sampled loop)"),
            );
        }
        if let Some((_, span)) = rules.iter().find_map(|r| r.gain.as_ref()) {
            self.err(
                Diagnostic::error(*span, "given gains with `design = discrete`")
                    .with_secondary(d.span, "discrete-time design asked here")
                    .with_help("given gains are analyzed, not designed: drop `design = discrete`"),
            );
        }
    }
}
