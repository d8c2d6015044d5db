//! Compatibility: valid items the compiler cannot do together, refused here
//! with a span, a reason and a `help:` line, so that `tsfc check` exits 1 on
//! them and synthesis never meets them. One file per feature, holding every
//! combination that feature refuses:
//!
//! | feature | file |
//! |---|---|
//! | trigger laws: the laws a certificate covers, a synthesized weight's needs, `region` | [`trigger`] |
//! | `saturate` levels and the saturation region (explicit or implied) | [`saturation`] |
//! | `trigger periodic { design = discrete; }` | [`discrete`] |
//! | `modes` (Markov jump modes) | [`modes`] |
//! | `objective finite_time` | [`finite_time`] |
//! | `lyapunov fuzzy(..)` | [`lyapunov`] |
//! | `adaptive { .. }` | [`adaptive`] |
//! | code targets (`emit c` and the controller name) | [`targets`] |
//! | output feedback (`control observer_based`, `control static_output`) | [`output_feedback`] |
//!
//! Premises that must be linear in the state for `region` need the model
//! stage (`compiler/src/model/region.rs`, reported during `tsfc check`).
//! Synthesis keeps a typed `Unsupported` error for each of these as a last
//! line of defence, and refuses on its own only what depends on solved numbers.

mod adaptive;
mod discrete;
mod finite_time;
mod lyapunov;
mod modes;
mod output_feedback;
mod saturation;
mod targets;
mod trigger;

pub(super) use trigger::TriggerSpans;

use super::{Checker, Draft};
use crate::span::{Span, Spanned};
use crate::spec::{RegionBound, SpannedObjective};

/// The checked items the trigger and saturation rules look at.
pub(super) struct Around<'s> {
    /// The controller name.
    pub controller: Option<&'s Spanned<String>>,
    /// The checked objectives.
    pub objectives: &'s [SpannedObjective],
    /// Whether every objective item checked (else a missing one may only have failed).
    pub objectives_complete: bool,
    /// The `saturate` levels, when they evaluated.
    pub levels: Option<&'s [f64]>,
    /// Where `saturate` is written, evaluated or not.
    pub saturate: Option<Span>,
    /// Where the first input is declared.
    pub first_input: Option<Span>,
    /// The disturbance bound, if declared.
    pub disturbance_bound: Option<f64>,
    /// The checked `region` settings of the trigger.
    pub trigger_region: &'s [RegionBound],
    /// The span of a `modes` block, if any (its own rules then cover the loop).
    pub modes: Option<Span>,
}

impl Checker<'_> {
    /// Reports the unsupported combinations of the trigger law, the
    /// saturation levels and the code targets with the rest of the spec.
    pub(super) fn compatibility(&mut self, draft: &Draft, around: &Around<'_>) {
        self.saturation_fits(around);
        self.trigger_fits(draft, around);
        if let Some(name) = around.controller {
            self.targets_fit(name, draft);
        }
    }
}
