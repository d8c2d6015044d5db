//! Analysis of given gains. When every rule gives its PDC gain `F = ...`,
//! tsfc certifies the spec's objectives for those gains instead of
//! synthesizing them: the synthesis LMIs in X = P^{-1} with F_j X put in
//! place of M_j (linear in X, so they stay LMIs: [`super::objective::GainTerm`]),
//! solved over X and the objectives' own variables. A minimized bound (H-inf
//! or L-inf gamma, input or output bound) is then minimized over P for the
//! fixed gains and a maximized decay rate bisected: the analysis values. The
//! sampled-loop and event-trigger certificates take the gains as fixed data
//! already ([`super::trigger`], [`super::sampling`]), so they apply unchanged.
//!
//! When the objectives fail together, each is judged alone (its own SDP or
//! search, then the certificate): the [`Verdict`]s say what holds, with its
//! value, and what fails, with the best value the gains certify for it alone.

use super::achieved::Quantity;
use super::design::{Design, SynthError};
use super::objective::{Bound, Objective};
use super::plan::Plan;
use super::search::Runner;
use crate::model::TsModel;
use tsf_lang::spec::ObjectiveKind;

/// One objective's verdict for the given gains.
#[derive(Debug, Clone, PartialEq)]
pub struct Verdict {
    /// The objective (or loop) in the spec's words: `hinf <= 0.5`,
    /// `decay_rate maximize`, `stability`, `sampled loop (every 0.01 s)`.
    pub objective: String,
    /// Whether the given gains are certified for it.
    pub certified: bool,
    /// The quantity `value` is, if the objective has one.
    pub quantity: Option<Quantity>,
    /// Certified: the value certified (the bound, or the analysis value of a
    /// minimized or maximized objective). Not certified: the best value the
    /// gains certify for it alone, if any.
    pub value: Option<f64>,
    /// Whether it was judged together with the other objectives (one common
    /// Lyapunov matrix P), or alone because they fail together.
    pub together: bool,
    /// Why it is not certified, when the solver or a loop certificate said more.
    pub note: Option<String>,
}

impl std::fmt::Display for Verdict {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let value = match (self.quantity, self.value) {
            (Some(q), Some(v)) => Some(format!("{q} = {v:.6}")),
            _ => None,
        };
        let alone = if self.together { "" } else { " alone" };
        write!(f, "{}: ", self.objective)?;
        if self.certified {
            write!(f, "certified{alone}")?;
            if let Some(v) = value {
                write!(f, ", {v}")?;
            }
        } else {
            write!(f, "not certified for the given gains")?;
            if !self.together {
                write!(f, ", even alone")?;
            }
            if let Some(v) = value {
                write!(f, "; alone they certify at best {v}")?;
            }
        }
        if let Some(n) = &self.note {
            write!(f, " ({n})")?;
        }
        Ok(())
    }
}

/// Whether the rules give their gains (then tsfc analyzes, not synthesizes).
pub fn analysis(model: &TsModel) -> bool {
    model.spec.given_gains().is_some()
}

/// An objective in the spec's words.
fn label(o: &dyn Objective) -> String {
    let kind = o.kind();
    match o.target() {
        Some(Bound::Fixed(v)) => o.describe_bound(v),
        Some(Bound::Minimize) if kind == ObjectiveKind::DecayRate => format!("{kind} maximize"),
        Some(Bound::Minimize) => format!("{kind} minimize"),
        _ => match o.saturation_region() {
            Some(s) if s.implied => "saturation region (implied by the `saturate` levels)".into(),
            Some(_) => "saturation region".into(),
            None => kind.to_string(),
        },
    }
}

/// The verdict of stability, which every analysis certifies or not.
const STABILITY: &str = "stability";

/// The verdicts of a design whose objectives are certified together.
pub(super) fn together(d: &Design) -> Vec<Verdict> {
    let holds = |objective: String, quantity: Option<Quantity>| Verdict {
        objective,
        certified: true,
        quantity,
        value: quantity.and_then(|q| d.achieved.get(q)),
        together: true,
        note: None,
    };
    std::iter::once(holds(STABILITY.into(), None))
        .chain(d.plan.objectives().map(|o| holds(label(o), o.headline())))
        .collect()
}

/// The name of the sampled loop with intervals `sampling`.
pub(super) fn sampled_loop((lo, hi): (f64, f64)) -> String {
    if lo == hi {
        format!("sampled loop (every {hi} s)")
    } else {
        format!("sampled loop (intervals in [{lo}, {hi}] s)")
    }
}

/// The event-triggered loop.
pub(super) const EVENT_LOOP: &str = "event-triggered loop";

/// In an analysis, the verdict of the loop `what` (sampled or
/// event-triggered) for the gains of `d`, whose continuous-loop objectives
/// are certified: added to `d`, or the analysis is refused naming what holds
/// and what fails. A synthesis passes `out` through.
pub(super) fn looped<T>(
    model: &TsModel,
    d: &mut Design,
    what: &str,
    out: Result<T, SynthError>,
) -> Result<T, SynthError> {
    if !analysis(model) {
        return out;
    }
    let note = match out {
        Ok(t) => {
            d.verdicts.push(Verdict {
                objective: what.to_string(),
                certified: true,
                quantity: None,
                value: None,
                together: true,
                note: None,
            });
            return Ok(t);
        }
        Err(SynthError::Infeasible {
            message,
            achievable,
        }) => std::iter::once(message)
            .chain(achievable)
            .collect::<Vec<_>>()
            .join("; "),
        Err(e @ SynthError::Solver { .. }) => e.to_string(),
        Err(e) => return Err(e),
    };
    let mut verdicts = d.verdicts.clone();
    verdicts.push(Verdict {
        objective: what.to_string(),
        certified: false,
        quantity: None,
        value: None,
        together: true,
        note: Some(note),
    });
    Err(SynthError::NotCertified {
        message: format!("analysis: the given gains are certified for the objectives of the continuous loop, not for the {what}"),
        verdicts,
    })
}

impl Runner<'_> {
    /// The objectives of `plan` fail together for the given gains: each is
    /// judged alone (and stability), and the analysis is refused naming what
    /// holds and what fails.
    pub(super) fn alone(&mut self, plan: &Plan) -> SynthError {
        let mut verdicts = vec![self.judge(&Plan::default(), STABILITY.into(), None)];
        for o in plan.objectives() {
            let one = Plan::new(vec![o.clone_box()]);
            verdicts.push(self.judge(&one, label(o), o.headline()));
        }
        let names = |certified: bool| {
            verdicts
                .iter()
                .filter(|v| v.certified == certified)
                .map(|v| v.objective.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        };
        let (holds, fails) = (names(true), names(false));
        let message = if fails.is_empty() {
            format!("analysis: every objective is certified alone for the given gains ({holds}), not together: they share one Lyapunov matrix P (X = P^-1); relax one of them, or analyze them in separate specs")
        } else if holds.is_empty() {
            format!("analysis: the given gains are not certified for any objective ({fails})")
        } else {
            format!("analysis: the given gains are not certified for the objectives together; not certified even alone: {fails}; certified alone: {holds}")
        };
        SynthError::NotCertified { message, verdicts }
    }

    /// The verdict of `plan` (one objective, or none: stability) alone.
    fn judge(&mut self, plan: &Plan, objective: String, quantity: Option<Quantity>) -> Verdict {
        let value_of = |d: &Design| quantity.and_then(|q| d.achieved.get(q));
        let (certified, value, note) = match self.certified(plan) {
            Ok(Some(d)) => (true, value_of(&d), None),
            Ok(None) => {
                // A bound that fails: the best value the gains certify alone.
                let best = plan
                    .objectives()
                    .find(|o| o.fixed().is_some())
                    .map(|o| plan.optimizing(o.kind()));
                let value = match best {
                    Some(p) => self.certified(&p).ok().flatten().and_then(|d| value_of(&d)),
                    None => None,
                };
                (false, value, None)
            }
            Err(e) => (false, None, Some(e.to_string())),
        };
        Verdict {
            objective,
            certified,
            quantity,
            value,
            together: false,
            note,
        }
    }

    /// The design of `plan` for the given gains if its certificate holds;
    /// `None` when infeasible, without a verdict, or not certified.
    fn certified(&mut self, plan: &Plan) -> Result<Option<Design>, SynthError> {
        let d = match self.run(plan, plan.goal()) {
            Ok(Some(d)) => d,
            Ok(None) | Err(SynthError::Solver { .. }) => return Ok(None),
            Err(e) => return Err(e),
        };
        let verify = self.settings.verifier.ok_or_else(|| {
            SynthError::Internal(
                "internal error: the analysis of given gains needs the certificate's verdict (Settings::verifier)".into(),
            )
        })?;
        Ok(verify(self.model, &d)?.then_some(d))
    }
}
