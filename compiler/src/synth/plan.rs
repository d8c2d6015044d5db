//! A plan: the objectives of a spec with every free parameter fixed to a
//! number, except at most one quantity the SDP minimizes.

use tsf_lang::spec::{InitialSet, Objective, Spec, Target};

/// A bound that is fixed, or minimized by the SDP.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Bound {
    /// The SDP minimizes it.
    Minimize,
    /// A free variable: the objective's constraints stay, its value is not minimized.
    Free,
    /// Fixed value.
    Fixed(f64),
}

/// H-inf gain from a disturbance to an output.
#[derive(Debug, Clone, PartialEq)]
pub struct HinfPlan {
    /// Disturbance index.
    pub from: usize,
    /// Output index.
    pub to: usize,
    /// gamma (fixed) or minimized.
    pub bound: Bound,
}

/// Peak-to-peak gain for a fixed phi.
#[derive(Debug, Clone, PartialEq)]
pub struct LinfPlan {
    /// Disturbance index.
    pub from: usize,
    /// Output index.
    pub to: usize,
    /// gamma (fixed) or minimized.
    pub bound: Bound,
    /// phi > 0 (the line search fixes it).
    pub phi: f64,
    /// xi fixed by the spec, or a variable.
    pub xi: Option<f64>,
}

/// Input-norm bound ||u(t)|| <= mu.
#[derive(Debug, Clone, PartialEq)]
pub struct InputNormPlan {
    /// mu (fixed) or minimized.
    pub bound: Bound,
    /// The initial set.
    pub initial: InitialSet,
}

/// Output-norm bound ||y(t)|| <= lambda.
#[derive(Debug, Clone, PartialEq)]
pub struct OutputNormPlan {
    /// Output index.
    pub output: usize,
    /// lambda (fixed) or minimized.
    pub bound: Bound,
    /// The initial set.
    pub initial: InitialSet,
}

/// All objectives with numbers.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Plan {
    /// Decay rate alpha (None: plain stability).
    pub decay: Option<f64>,
    /// H-inf.
    pub hinf: Option<HinfPlan>,
    /// L-inf.
    pub linf: Option<LinfPlan>,
    /// Input norm.
    pub input_norm: Option<InputNormPlan>,
    /// Output norm.
    pub output_norm: Option<OutputNormPlan>,
    /// Actuator saturation (generalized sector condition), if the spec asks
    /// for the saturation region.
    pub saturation: Option<SaturationPlan>,
}

/// Actuator saturation: levels and the disturbance bound that shrinks them.
#[derive(Debug, Clone, PartialEq)]
pub struct SaturationPlan {
    /// u_bar_s per channel.
    pub levels: Vec<f64>,
    /// Bound on ||w(t)||, if declared.
    pub disturbance_bound: Option<f64>,
    /// Initial states the region E(P, 1) must contain.
    pub contain: Option<InitialSet>,
}

/// What the spec asks to optimize, if anything.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Goal {
    /// Feasibility only.
    Feasibility,
    /// Maximize the decay rate (bisection).
    MaxDecay,
    /// Minimize inside the SDP (hinf, linf, input/output norm).
    InSdp,
}

fn bound(t: Target) -> Bound {
    match t {
        Target::Optimize => Bound::Minimize,
        Target::Fixed(v) => Bound::Fixed(v),
    }
}

/// The initial plan of a spec. A maximized decay rate starts at 0 and an
/// L-inf phi the spec leaves free starts at `default_phi`.
pub fn initial_plan(spec: &Spec, default_phi: f64) -> (Plan, Goal) {
    let mut plan = Plan::default();
    let mut goal = Goal::Feasibility;
    for o in &spec.objectives {
        match &o.node {
            Objective::Stability => {}
            Objective::SaturationRegion { contain } => {
                plan.saturation = spec.saturation.clone().map(|levels| SaturationPlan {
                    levels,
                    disturbance_bound: spec.disturbance_bound,
                    contain: contain.clone(),
                });
            }
            Objective::DecayRate(t) => match t {
                Target::Optimize => {
                    plan.decay = Some(0.0);
                    goal = Goal::MaxDecay;
                }
                Target::Fixed(a) => plan.decay = Some(*a),
            },
            Objective::Hinf { from, to, target } => {
                plan.hinf = Some(HinfPlan {
                    from: *from,
                    to: *to,
                    bound: bound(*target),
                });
            }
            Objective::Linf {
                from,
                to,
                target,
                xi,
                phi,
            } => {
                plan.linf = Some(LinfPlan {
                    from: *from,
                    to: *to,
                    bound: bound(*target),
                    phi: phi.unwrap_or(default_phi),
                    xi: *xi,
                });
            }
            Objective::InputNorm { target, initial } => {
                plan.input_norm = Some(InputNormPlan {
                    bound: bound(*target),
                    initial: initial.clone(),
                });
            }
            Objective::OutputNorm {
                output,
                target,
                initial,
            } => {
                plan.output_norm = Some(OutputNormPlan {
                    output: *output,
                    bound: bound(*target),
                    initial: initial.clone(),
                });
            }
        }
        if matches!(
            o.node,
            Objective::Hinf {
                target: Target::Optimize,
                ..
            } | Objective::Linf {
                target: Target::Optimize,
                ..
            } | Objective::InputNorm {
                target: Target::Optimize,
                ..
            } | Objective::OutputNorm {
                target: Target::Optimize,
                ..
            }
        ) {
            goal = Goal::InSdp;
        }
    }
    (plan, goal)
}

impl Plan {
    /// Names of the fixed bounds, with their values (for infeasibility reports).
    pub fn fixed_bounds(&self) -> Vec<(&'static str, f64)> {
        let mut out = Vec::new();
        if let Some(a) = self.decay.filter(|a| *a > 0.0) {
            out.push(("decay_rate", a));
        }
        if let Some(HinfPlan {
            bound: Bound::Fixed(g),
            ..
        }) = &self.hinf
        {
            out.push(("hinf", *g));
        }
        if let Some(LinfPlan {
            bound: Bound::Fixed(g),
            ..
        }) = &self.linf
        {
            out.push(("linf", *g));
        }
        if let Some(InputNormPlan {
            bound: Bound::Fixed(m),
            ..
        }) = &self.input_norm
        {
            out.push(("input_norm", *m));
        }
        if let Some(OutputNormPlan {
            bound: Bound::Fixed(l),
            ..
        }) = &self.output_norm
        {
            out.push(("output_norm", *l));
        }
        out
    }

    /// This plan with `name` optimized instead of bounded: it becomes minimized
    /// (or, for the decay rate, 0 = to be maximized by the caller), and every
    /// other minimized quantity becomes a free variable, so its constraints
    /// (e.g. the bounded-real lemma) still restrict the design.
    pub fn optimizing(&self, name: &str) -> Plan {
        let mut p = self.clone();
        let free = |b: &mut Bound| {
            if *b == Bound::Minimize {
                *b = Bound::Free;
            }
        };
        if let Some(h) = &mut p.hinf {
            free(&mut h.bound);
        }
        if let Some(h) = &mut p.linf {
            free(&mut h.bound);
        }
        if let Some(h) = &mut p.input_norm {
            free(&mut h.bound);
        }
        if let Some(h) = &mut p.output_norm {
            free(&mut h.bound);
        }
        match name {
            "decay_rate" => p.decay = Some(0.0),
            "hinf" => {
                if let Some(h) = &mut p.hinf {
                    h.bound = Bound::Minimize;
                }
            }
            "linf" => {
                if let Some(h) = &mut p.linf {
                    h.bound = Bound::Minimize;
                }
            }
            "input_norm" => {
                if let Some(h) = &mut p.input_norm {
                    h.bound = Bound::Minimize;
                }
            }
            "output_norm" => {
                if let Some(h) = &mut p.output_norm {
                    h.bound = Bound::Minimize;
                }
            }
            _ => {}
        }
        p
    }
}
