//! What the compiler does not do with a `modes` block (Markov jump
//! modes): the objectives, relaxations and loops its conditions cover, given
//! gains and saturation refused at the item with the reason.

use crate::check::modes::Around;
use crate::check::{Checker, Draft};
use crate::diag::Diagnostic;
use crate::modes::Modes;
use crate::num::Num;
use crate::span::{Span, Spanned};
use crate::spec::{
    jittered_intervals, Objective, PeriodicDesign, Relaxation, SpannedObjective, Trigger, Weight,
};

impl Checker<'_> {
    /// Reports what the compiler does not do with modes: objectives other
    /// than stability, decay rate, one hinf, or finite_time alone; relaxations
    /// other than basic, tanaka (not with hinf or finite_time) and
    /// membership_mismatch (every pair), given gains, saturation,
    /// event-triggered, mixed or discrete-time loops ([`Checker::modes_trigger`]).
    pub(in crate::check) fn modes_supported(
        &mut self,
        modes: &Modes,
        draft: &Draft,
        around: &Around<'_>,
    ) -> bool {
        let before = self.diags.len();
        let note = "with `modes`, tsfc supports stability, decay-rate, hinf and finite_time objectives, relaxations basic, tanaka (stability and decay only) and membership_mismatch, and a continuous loop or a sampled one (`trigger periodic`, or `trigger aperiodic` without a threshold; stability and decay only) (docs/limits.md)";
        let unsupported = |span: Span, what: String| {
            Diagnostic::error(span, what)
                .with_secondary(modes.span, "modes here")
                .with_note(note)
        };
        for o in around.objectives {
            if !matches!(
                o.node,
                Objective::Stability
                    | Objective::DecayRate(_)
                    | Objective::Hinf { .. }
                    | Objective::FiniteTime(_)
            ) {
                self.err(
                    unsupported(
                        o.span,
                        format!(
                            "objective `{}` is not supported with `modes`",
                            o.node.kind()
                        ),
                    )
                    .with_help("remove this objective, or the `modes` block"),
                );
            }
        }
        let performance: Vec<&SpannedObjective> = around
            .objectives
            .iter()
            .filter(|o| matches!(o.node, Objective::Hinf { .. } | Objective::FiniteTime(_)))
            .collect();
        let finite_time = performance
            .iter()
            .find(|o| matches!(o.node, Objective::FiniteTime(_)));
        if let Some(ft) = finite_time {
            if let Some(other) = around
                .objectives
                .iter()
                .find(|o| o.span != ft.span && !matches!(o.node, Objective::Stability))
            {
                self.err(
                    unsupported(
                        other.span,
                        format!(
                            "objective `{}` together with `finite_time` is not supported with `modes`",
                            other.node.kind()
                        ),
                    )
                    .with_secondary(ft.span, "finite_time here")
                    .with_help("with modes `finite_time` is designed alone (with `objective stability;` at most): remove this objective"),
                );
            }
        } else if let [first, second, ..] = performance.as_slice() {
            self.err(
                unsupported(
                    second.span,
                    "more than one `hinf` objective is not supported with `modes`".into(),
                )
                .with_secondary(first.span, "first one here")
                .with_help("keep one `hinf` objective"),
            );
        }
        if let (Some(o), Relaxation::Tanaka { .. }) = (performance.first(), around.relaxation.node)
        {
            self.err(
                unsupported(
                    around.relaxation.span,
                    format!(
                        "relaxation `tanaka` with objective `{}` is not supported with `modes`",
                        o.node.kind()
                    ),
                )
                .with_help("use `relaxation basic;` or `relaxation membership_mismatch;`"),
            );
        }
        if matches!(
            around.relaxation.node,
            Relaxation::Tuan | Relaxation::Polya { .. }
        ) {
            self.err(
                unsupported(
                    around.relaxation.span,
                    "this relaxation is not supported with `modes`".into(),
                )
                .with_help("use `relaxation basic;`, `tanaka(s = ..)` or `membership_mismatch;`"),
            );
        }
        if let Some((_, span)) = around.rules.iter().find_map(|r| r.gain.as_ref()) {
            self.err(
                unsupported(*span, "given gains are not supported with `modes`".into())
                    .with_help("remove `F = ..` from the rules: the mode gains are synthesized"),
            );
        }
        if around.saturated {
            self.err(
                unsupported(
                    modes.span,
                    "`saturate` levels are not supported with `modes`".into(),
                )
                .with_help("remove `saturate` from the input, or the `modes` block"),
            );
        }
        if let Some(t) = &draft.trigger {
            self.modes_trigger(t, draft, &performance, &unsupported);
        }
        self.diags.len() == before
    }

    /// The loops supported with modes: continuous, and the sampled loop of
    /// `trigger periodic` (emulation) or a threshold-free `trigger aperiodic`
    /// with stability or decay-rate objectives (its certificate is
    /// mean-square stability, `synth/markov/sampled.rs`). Event-triggered,
    /// mixed and discrete-time designs stay refused.
    fn modes_trigger(
        &mut self,
        t: &Spanned<Trigger>,
        draft: &Draft,
        performance: &[&SpannedObjective],
        unsupported: &dyn Fn(Span, String) -> Diagnostic,
    ) {
        let sampled_help = "a sampled loop is supported with `modes`: write `trigger periodic { every = ..; }` or `trigger aperiodic { sampling = h_min .. h_max; }` (every sample transmitted)";
        match &t.node {
            Trigger::Continuous => return,
            Trigger::Periodic { .. } => {
                if let Some(d) = draft
                    .periodic_design
                    .as_ref()
                    .filter(|d| d.node == PeriodicDesign::Discrete)
                {
                    self.err(
                        unsupported(
                            d.span,
                            "the discrete-time design (`design = discrete`) is not supported with `modes`".into(),
                        )
                        .with_help("leave `design` out: the continuous mode design is then certified for the sampled loop"),
                    );
                    return;
                }
            }
            Trigger::Aperiodic {
                threshold: Some(_), ..
            } => {
                self.err(
                    unsupported(
                        t.span,
                        "an event-triggered loop (`threshold`) is not supported with `modes`"
                            .into(),
                    )
                    .with_help(sampled_help),
                );
                return;
            }
            Trigger::Aperiodic { weight, .. }
                if matches!(weight, Weight::Given(_)) || draft.trigger_synthesis.is_some() =>
            {
                self.err(
                    unsupported(
                        t.span,
                        "a trigger `weight` is not used without a threshold; with `modes` it is refused".into(),
                    )
                    .with_help("remove `weight = ..;` (every sample is transmitted)"),
                );
                return;
            }
            Trigger::Aperiodic { .. } => {}
            Trigger::Jittered { every, jitter } => {
                let (lo, hi) = jittered_intervals(*every, *jitter);
                self.err(
                    unsupported(t.span, "a jittered trigger is not supported with `modes`".into())
                        .with_help(format!("write `trigger aperiodic {{ sampling = {} .. {}; }}`: the same sampling intervals, every sample transmitted, certified with `modes`", Num(lo), Num(hi))),
                );
                return;
            }
            Trigger::Mixed { .. } => {
                self.err(
                    unsupported(
                        t.span,
                        "a mixed trigger is not supported with `modes`".into(),
                    )
                    .with_help(sampled_help),
                );
                return;
            }
        }
        if let Some(o) = performance.first() {
            self.err(
                unsupported(
                    o.span,
                    format!(
                        "objective `{}` with a sampled loop is not supported with `modes`: the sampled-loop certificate covers mean-square stability",
                        o.node.kind()
                    ),
                )
                .with_secondary(t.span, "sampled loop here")
                .with_help("use `objective stability;` or `objective decay_rate ..;` (certified for the continuous loop; the sampled loop is certified stable)"),
            );
        }
    }
}
