//! Premise layout (the premise vector z), rule premises as runtime terms, and
//! the `about` widths.

use tsf_lang::eval::Mode;
use tsf_lang::spec::{ClauseSet, SetShape, Spec};
use tsf_lang::Diagnostic;
use tsf_runtime::membership::Membership;
use tsf_runtime::{Rule, Term};

/// One premise variable's place in z.
#[derive(Debug, Clone, PartialEq)]
pub struct PremiseSlot {
    /// Name used in rules.
    pub name: String,
    /// Index of its first component in z.
    pub first: usize,
    /// Number of components.
    pub dim: usize,
    /// Operating range of each component.
    pub range: (f64, f64),
    /// Width of its `about` sets.
    pub sigma: f64,
}

/// All premise variables, flattened into z.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct PremiseLayout {
    /// Slots in declaration order.
    pub slots: Vec<PremiseSlot>,
}

impl PremiseLayout {
    /// Total length P of z.
    pub fn len(&self) -> usize {
        self.slots.iter().map(|s| s.dim).sum()
    }

    /// Whether there is no premise variable.
    pub fn is_empty(&self) -> bool {
        self.slots.is_empty()
    }

    /// The declared range of every component of z, in order.
    pub fn component_ranges(&self) -> Vec<(f64, f64)> {
        self.slots
            .iter()
            .flat_map(|s| std::iter::repeat_n(s.range, s.dim))
            .collect()
    }

    /// Name of component `k` of z (`w1`, or `q[2]` for vector premises).
    pub fn component_name(&self, k: usize) -> String {
        for s in &self.slots {
            if k >= s.first && k < s.first + s.dim {
                return if s.dim == 1 {
                    s.name.clone()
                } else {
                    format!("{}[{}]", s.name, k - s.first)
                };
            }
        }
        format!("z[{k}]")
    }
}

/// One conjunct of a rule premise, owning its data.
#[derive(Debug, Clone, PartialEq)]
pub enum TermSpec {
    /// `z[var] is set`.
    Is {
        /// Component of z.
        var: usize,
        /// The set.
        set: SetShape,
    },
    /// `z[first..first+point.len()] is about point`.
    About {
        /// First component.
        first: usize,
        /// The point.
        point: Vec<f64>,
        /// Width.
        sigma: f64,
    },
}

/// The runtime's membership for a set shape.
pub fn membership(s: SetShape) -> Membership<f64> {
    match s {
        SetShape::Tri(a, b, c) => Membership::Tri { a, b, c },
        SetShape::Trap(a, b, c, d) => Membership::Trap { a, b, c, d },
        SetShape::Gauss(center, sigma) => Membership::Gauss { center, sigma },
        SetShape::Sigmoid(slope, center) => Membership::Sigmoid { slope, center },
    }
}

impl TermSpec {
    /// The runtime's term for this conjunct (borrowing an `about` point).
    pub fn runtime(&self) -> Term<'_, f64> {
        match self {
            TermSpec::Is { var, set } => Term::Is {
                var: *var,
                set: membership(*set),
            },
            TermSpec::About {
                first,
                point,
                sigma,
            } => Term::About {
                first: *first,
                point,
                sigma: *sigma,
            },
        }
    }
}

/// Rule weight (product t-norm) at premise vector `z`, computed by the runtime.
pub fn rule_weight(terms: &[TermSpec], z: &[f64]) -> f64 {
    let rt: Vec<Term<'_, f64>> = terms.iter().map(TermSpec::runtime).collect();
    Rule::new(&rt).weight(z)
}

/// Every rule's terms in the runtime's form, converted once for loops over
/// many states ([`rule_weight`] converts them at each call).
pub fn runtime_terms(terms: &[Vec<TermSpec>]) -> Vec<Vec<Term<'_, f64>>> {
    terms
        .iter()
        .map(|t| t.iter().map(TermSpec::runtime).collect())
        .collect()
}

/// Lays out z and fixes each premise's range and `about` width.
pub(super) fn layout(spec: &Spec, diags: &mut Vec<Diagnostic>) -> PremiseLayout {
    let mut slots = Vec::new();
    let mut first = 0;
    for (pi, p) in spec.premises.iter().enumerate() {
        let abouts: Vec<&Vec<f64>> = spec
            .rules
            .iter()
            .flat_map(|r| r.clauses.iter())
            .filter(|c| c.premise == pi)
            .filter_map(|c| match &c.set {
                ClauseSet::About(v) => Some(v),
                ClauseSet::Named(_) => None,
            })
            .collect();
        let mut points: Vec<f64> = p.sets.iter().flat_map(|s| s.shape.breakpoints()).collect();
        points.extend(abouts.iter().flat_map(|v| v.iter().copied()));
        let range = p.range.unwrap_or_else(|| {
            let lo = points.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = points.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            if lo < hi {
                (lo, hi)
            } else {
                (lo - 1.0, lo + 1.0)
            }
        });
        let sigma = p.sigma.unwrap_or_else(|| {
            let mut min_d = f64::INFINITY;
            for (i, a) in abouts.iter().enumerate() {
                for b in abouts.iter().skip(i + 1) {
                    let d = a
                        .iter()
                        .zip(b.iter())
                        .map(|(x, y)| (x - y) * (x - y))
                        .sum::<f64>()
                        .sqrt();
                    if d > 0.0 {
                        min_d = min_d.min(d);
                    }
                }
            }
            if min_d.is_finite() {
                0.5 * min_d
            } else {
                0.5 * (range.1 - range.0).max(1e-6)
            }
        });
        if !abouts.is_empty() && !p.sets.is_empty() {
            diags.push(
                Diagnostic::warning(
                    p.span,
                    format!(
                        "premise `{}` is used both with named sets and with `about`",
                        p.name
                    ),
                )
                .with_note(
                    "the two kinds of sets are not a partition together; check the coverage",
                ),
            );
        }
        slots.push(PremiseSlot {
            name: p.name.clone(),
            first,
            dim: p.dim,
            range,
            sigma,
        });
        first += p.dim;
    }
    PremiseLayout { slots }
}

/// The runtime terms of every rule.
pub(super) fn rule_terms(spec: &Spec, layout: &PremiseLayout) -> Vec<Vec<TermSpec>> {
    spec.rules
        .iter()
        .map(|r| {
            r.clauses
                .iter()
                .filter_map(|c| {
                    let slot = layout.slots.get(c.premise)?;
                    let p = spec.premises.get(c.premise)?;
                    Some(match &c.set {
                        ClauseSet::Named(i) => TermSpec::Is {
                            var: slot.first,
                            set: p.sets.get(*i)?.shape,
                        },
                        ClauseSet::About(v) => TermSpec::About {
                            first: slot.first,
                            point: v.clone(),
                            sigma: slot.sigma,
                        },
                    })
                })
                .collect()
        })
        .collect()
}

/// Premise values z at state x (evaluating the premise expressions).
pub fn premise_values(spec: &Spec, x: &[f64]) -> Result<Vec<f64>, Diagnostic> {
    let env = spec.state_env(x, Mode::Exact);
    let mut z = Vec::new();
    for p in &spec.premises {
        let v = env.eval(&p.expr)?;
        match p.component {
            Some(k) => z.push(v.get(k).copied().unwrap_or(f64::NAN)),
            None => z.extend(v.iter().copied()),
        }
    }
    Ok(z)
}

/// Centre of each rule in premise space: the peak of each named set, the
/// `about` point, or (for a premise the rule does not mention) the premise
/// value at the rule's operating point (else the middle of the range).
pub(super) fn rule_centers(
    spec: &Spec,
    layout: &PremiseLayout,
    terms: &[Vec<TermSpec>],
) -> Vec<Vec<f64>> {
    spec.rules
        .iter()
        .zip(terms)
        .map(|(r, ts)| {
            let at_z =
                r.at.as_ref()
                    .and_then(|(x, _)| premise_values(spec, x).ok());
            let mut c: Vec<f64> = layout
                .slots
                .iter()
                .flat_map(|s| std::iter::repeat_n(0.5 * (s.range.0 + s.range.1), s.dim))
                .collect();
            if let Some(z) = at_z.filter(|z| z.len() == c.len()) {
                c = z;
            }
            for t in ts {
                match t {
                    TermSpec::Is { var, set } => {
                        if let Some(v) = c.get_mut(*var) {
                            *v = match *set {
                                SetShape::Tri(_, b, _) => b,
                                SetShape::Trap(_, b, cc, _) => 0.5 * (b + cc),
                                SetShape::Gauss(m, _) => m,
                                SetShape::Sigmoid(k, m) => m + 4.0 / k,
                            };
                        }
                    }
                    TermSpec::About { first, point, .. } => {
                        for (i, p) in point.iter().enumerate() {
                            if let Some(v) = c.get_mut(first + i) {
                                *v = *p;
                            }
                        }
                    }
                }
            }
            c
        })
        .collect()
}

/// Warns when a rule's operating point lies where its own premise does not fire.
pub(super) fn check_operating_points(
    spec: &Spec,
    layout: &PremiseLayout,
    terms: &[Vec<TermSpec>],
    diags: &mut Vec<Diagnostic>,
) {
    for (r, ts) in spec.rules.iter().zip(terms) {
        let Some((x, span)) = &r.at else { continue };
        let Ok(z) = premise_values(spec, x) else {
            continue;
        };
        if z.len() != layout.len() {
            continue;
        }
        // Nudge the point a hair towards the middle of each range, so an
        // operating point on a shoulder edge is not lost to rounding.
        let nudged: Vec<f64> = z
            .iter()
            .enumerate()
            .map(|(k, v)| {
                let slot = layout
                    .slots
                    .iter()
                    .find(|s| k >= s.first && k < s.first + s.dim);
                slot.map_or(*v, |s| {
                    v + 1e-9
                        * (0.5 * (s.range.0 + s.range.1) - v).signum()
                        * (s.range.1 - s.range.0)
                })
            })
            .collect();
        let w = rule_weight(ts, &z).max(rule_weight(ts, &nudged));
        if w <= 1e-9 {
            diags.push(
                Diagnostic::warning(
                    *span,
                    format!(
                        "the operating point of rule {} lies outside its own premise",
                        r.name
                    ),
                )
                .with_label(format!("the rule's firing strength here is {w:.2e}"))
                .with_help("a rule's local model should describe the plant where the rule fires"),
            );
        }
    }
}
