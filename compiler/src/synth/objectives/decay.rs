//! Stability and decay rate: He(A_i X + B_i M_j) + 2 alpha X < 0, so that
//! V = x' P x decreases at least as e^{-2 alpha t} (for a periodic loop
//! designed in discrete time, the conditions of [`super::discrete`]).

use crate::synth::achieved::{Achieved, Quantity};
use crate::synth::objective::{Bound, BuildError, Ctx, Goal, Lmis, Objective};
use crate::synth::reduction::Values;
use crate::synth::relaxation::Family;
use tsf_lang::spec::{ObjectiveKind, Target};

/// Decay rate alpha (0: plain stability).
#[derive(Debug, Clone, PartialEq)]
pub struct Decay {
    /// The rate imposed in the LMIs (the bisection moves it when maximized).
    pub alpha: f64,
    /// Fixed, or maximized by bisection ([`Bound::Minimize`]).
    pub target: Bound,
    /// Plain stability (not an objective of the spec).
    stability_only: bool,
}

impl Decay {
    /// The spec's `decay_rate` objective.
    pub fn new(t: Target) -> Self {
        let (alpha, target) = match t {
            Target::Optimize => (0.0, Bound::Minimize),
            Target::Fixed(a) => (a, Bound::Fixed(a)),
        };
        Decay {
            alpha,
            target,
            stability_only: false,
        }
    }

    /// Plain stability, imposed when no objective implies it.
    pub fn stability() -> Self {
        Decay {
            alpha: 0.0,
            target: Bound::Fixed(0.0),
            stability_only: true,
        }
    }
}

impl Objective for Decay {
    fn decay_rate(&self) -> Option<&Decay> {
        Some(self)
    }

    fn decay_rate_mut(&mut self) -> Option<&mut Decay> {
        Some(self)
    }

    fn kind(&self) -> ObjectiveKind {
        ObjectiveKind::DecayRate
    }

    fn target(&self) -> Option<Bound> {
        Some(self.target)
    }

    fn set_target(&mut self, target: Bound) {
        match target {
            Bound::Minimize => self.alpha = 0.0,
            Bound::Fixed(a) => self.alpha = a,
            Bound::Free => {}
        }
        self.target = target;
    }

    fn fixed(&self) -> Option<f64> {
        match self.target {
            Bound::Fixed(a) if a > 0.0 => Some(a),
            _ => None,
        }
    }

    fn search(&self) -> Goal {
        Goal::MaxDecay
    }

    fn describe_bound(&self, v: f64) -> String {
        format!("decay_rate >= {v}")
    }

    fn headline(&self) -> Option<Quantity> {
        Some(Quantity::DecayRate)
    }

    fn impose(&self, ctx: &Ctx<'_>, lmis: &mut Lmis<'_>) -> Result<(), BuildError> {
        let name = if self.stability_only {
            "stability"
        } else {
            "decay"
        };
        if let Some(h) = super::discrete::period(ctx.model) {
            lmis.impose(&super::discrete::family(ctx, h, self.alpha, name))?;
            return Ok(());
        }
        let shift = 2.0 * self.alpha;
        let name = if ctx.model_error.is_some() {
            format!("robust {name}")
        } else {
            name.to_string()
        };
        let fam = Family {
            name,
            q: Box::new(|i, j| {
                let q = ctx.with_sector(i, j, ctx.upsilon(i, j, shift)?, None)?;
                ctx.with_model_error(j, q)
            }),
        };
        lmis.impose(&fam)?;
        Ok(())
    }

    fn achieved(&self, _values: &Values, out: &mut Achieved) {
        if !self.stability_only {
            out.set(Quantity::DecayRate, self.alpha);
        }
    }
}
