//! A plan: the objectives of a spec with every free parameter fixed to a
//! number, except at most one quantity the SDP minimizes (or the decay rate a
//! bisection maximizes).

pub use super::objective::{Bound, Goal, Objective};
use super::objective::{BuildError, PlanView};
use super::objectives::{self, Decay, Linf, Saturation};
use tsf_lang::spec::{ObjectiveKind, Spec};

/// The objectives of one SDP, with numbers.
#[derive(Debug, Clone, Default)]
pub struct Plan {
    objectives: Vec<Box<dyn Objective>>,
    /// The Finsler scalar mu of a fuzzy Lyapunov design (`None`: the default,
    /// [`super::lyapunov::fuzzy::DEFAULT_MU`]; unused with a quadratic V).
    pub mu: Option<f64>,
}

impl Plan {
    /// A plan of these objectives.
    pub fn new(objectives: Vec<Box<dyn Objective>>) -> Self {
        Plan {
            objectives,
            mu: None,
        }
    }

    /// Its objectives, in spec order.
    pub fn objectives(&self) -> impl Iterator<Item = &dyn Objective> {
        self.objectives.iter().map(|o| o.as_ref())
    }

    /// Its objectives in the order of `kinds` (kinds not listed last, in spec order).
    pub fn ordered(&self, kinds: &[ObjectiveKind]) -> Vec<&dyn Objective> {
        let rank = |o: &dyn Objective| {
            kinds
                .iter()
                .position(|k| *k == o.kind())
                .unwrap_or(kinds.len())
        };
        let mut v: Vec<&dyn Objective> = self.objectives().collect();
        v.sort_by_key(|o| rank(*o));
        v
    }

    /// The certified saturation region, if an objective declares one.
    pub fn saturation(&self) -> Option<&Saturation> {
        self.objectives().find_map(|o| o.saturation_region())
    }

    /// The saturation region, mutably.
    pub fn saturation_mut(&mut self) -> Option<&mut Saturation> {
        self.objectives
            .iter_mut()
            .find_map(|o| o.saturation_region_mut())
    }

    /// The peak-to-peak (L-inf) bound, if the plan has one.
    pub fn linf(&self) -> Option<&Linf> {
        self.objectives().find_map(|o| o.peak_bound())
    }

    /// The peak-to-peak bound, mutably.
    pub fn linf_mut(&mut self) -> Option<&mut Linf> {
        self.objectives.iter_mut().find_map(|o| o.peak_bound_mut())
    }

    /// The imposed decay rate, if the plan has one.
    pub fn decay(&self) -> Option<&Decay> {
        self.objectives().find_map(|o| o.decay_rate())
    }

    /// The objective of family `kind`.
    pub fn find(&self, kind: ObjectiveKind) -> Option<&dyn Objective> {
        self.objectives().find(|o| o.kind() == kind)
    }

    /// How the plan is solved: the search of its minimized objective, if any.
    pub fn goal(&self) -> Goal {
        self.objectives()
            .find(|o| o.target() == Some(Bound::Minimize))
            .map_or(Goal::Feasibility, |o| o.search())
    }

    /// The fixed bounds, with their values (for infeasibility reports).
    pub fn fixed_bounds(&self) -> Vec<(ObjectiveKind, f64)> {
        self.objectives()
            .filter_map(|o| o.fixed().map(|v| (o.kind(), v)))
            .collect()
    }

    /// This plan with a decay rate alpha imposed.
    pub fn with_decay(&self, alpha: f64) -> Plan {
        let mut p = self.clone();
        match p.objectives.iter_mut().find_map(|o| o.decay_rate_mut()) {
            Some(d) => d.alpha = alpha,
            None => {
                let mut d = Decay::new(tsf_lang::spec::Target::Fixed(alpha));
                d.target = Bound::Free;
                p.objectives.push(Box::new(d));
            }
        }
        p
    }

    /// This plan with `kind` bounded by `value` (a decay rate: imposed).
    pub fn bounding(&self, kind: ObjectiveKind, value: f64) -> Plan {
        let mut p = self.clone();
        for o in &mut p.objectives {
            if o.kind() == kind {
                o.set_target(Bound::Fixed(value));
            }
        }
        p
    }

    /// This plan with every minimized quantity a free variable (its
    /// constraints stay): feasibility only.
    pub fn unoptimized(&self) -> Plan {
        let mut p = self.clone();
        for o in &mut p.objectives {
            if o.target() == Some(Bound::Minimize) {
                o.set_target(Bound::Free);
            }
        }
        p
    }

    /// This plan with `kind` optimized instead of bounded: it becomes minimized
    /// (a decay rate: maximized by the caller), and every other minimized
    /// quantity becomes a free variable, so its constraints (e.g. the
    /// bounded-real lemma) still restrict the design.
    pub fn optimizing(&self, kind: ObjectiveKind) -> Plan {
        let mut p = self.clone();
        for o in &mut p.objectives {
            if o.kind() == kind {
                o.set_target(Bound::Minimize);
            } else if o.target() == Some(Bound::Minimize) {
                o.set_target(Bound::Free);
            }
        }
        p
    }
}

/// The initial plan of a spec and how to solve it. A maximized decay rate
/// starts at 0 and an L-inf phi the spec leaves free starts at `default_phi`.
///
/// Declared `saturate` levels are always inside the certificate: unless the
/// spec asks for the saturation region or bounds the input norm (which
/// [`super::synthesize`] then checks against the levels), the saturation
/// region is implied.
pub fn initial_plan(spec: &Spec, default_phi: f64) -> (Plan, Goal) {
    let mut plan = Plan::new(
        spec.objectives
            .iter()
            .filter_map(|o| objectives::from_spec(&o.node, spec, default_phi))
            .collect(),
    );
    let covered = plan.objectives().any(|o| {
        matches!(
            o.kind(),
            ObjectiveKind::SaturationRegion | ObjectiveKind::InputNorm
        )
    });
    if let (Some(levels), false) = (&spec.saturation, covered) {
        plan.objectives.push(Box::new(Saturation {
            levels: levels.clone(),
            disturbance_bound: spec.disturbance_bound,
            contain: None,
            implied: true,
        }));
    }
    let goal = plan.goal();
    (plan, goal)
}

impl PlanView for Plan {
    fn reach_level(&self, tau: f64) -> Result<Option<f64>, BuildError> {
        let mut level: Option<f64> = None;
        for o in self.objectives() {
            if let Some(k) = o.reach_level(tau) {
                let k = k?;
                level = Some(level.map_or(k, |l| l.max(k)));
            }
        }
        Ok(level)
    }

    fn without_sector(&self) -> Option<ObjectiveKind> {
        self.objectives()
            .find(|o| !o.supports_sector())
            .map(|o| o.kind())
    }
}
