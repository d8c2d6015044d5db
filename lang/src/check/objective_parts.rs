//! The parts of an objective item: its goal, signals, initial set and `with`
//! parameters, each checked against what the objective kind takes.

use super::objectives::ObjectiveItem;
use super::Checker;
use crate::ast::{ExprKind, Goal, Ident};
use crate::diag::Diagnostic;
use crate::spec::{InitialSet, ObjectiveKind, Output, Target};
use crate::suggest::suggest;

impl Checker<'_> {
    /// The goal: `word_ok` (optimize) or `bound_kind value` (a positive bound).
    pub(super) fn goal_target(
        &mut self,
        o: &ObjectiveItem,
        word_ok: &str,
        bound_kind: &str,
    ) -> Option<Target> {
        match o.goal {
            None => {
                self.err(
                    Diagnostic::error(o.span, format!("objective `{}` needs a goal", o.name.node))
                        .with_help(format!("write `{word_ok}` or `{bound_kind} value`")),
                );
                None
            }
            Some(Goal::Word(w)) if w.node == word_ok => Some(Target::Optimize),
            Some(Goal::AtMost(e)) if bound_kind == "<=" => {
                self.positive(e, "the bound").map(Target::Fixed)
            }
            Some(Goal::AtLeast(e)) if bound_kind == ">=" => {
                self.positive(e, "the bound").map(Target::Fixed)
            }
            Some(g) => {
                let span = match g {
                    Goal::Word(w) => w.span,
                    Goal::AtMost(e) | Goal::AtLeast(e) => e.span,
                };
                self.err(
                    Diagnostic::error(
                        span,
                        format!(
                            "objective `{}` takes `{word_ok}` or `{bound_kind} value`",
                            o.name.node
                        ),
                    )
                    .with_label("not a valid goal here"),
                );
                None
            }
        }
    }

    /// The index of disturbance `s`.
    fn disturbance_ref(&mut self, s: &Ident) -> Option<usize> {
        let found = self.disturbances.iter().position(|d| d.name == s.node);
        if found.is_none() && !self.poisoned.contains(&s.node) {
            let mut d = Diagnostic::error(s.span, format!("`{}` is not a disturbance", s.node))
                .with_label("expected a declared disturbance");
            d = d.with_suggestion(&s.node, self.disturbances.iter().map(|d| d.name.as_str()));
            self.err(d);
        }
        found
    }

    /// The index of output `s`.
    pub(super) fn output_ref(&mut self, s: &Ident, outputs: &[Output]) -> Option<usize> {
        let found = outputs.iter().position(|o| o.name == s.node);
        if found.is_none() && !self.poisoned.contains(&s.node) {
            let mut d = Diagnostic::error(s.span, format!("`{}` is not an output", s.node))
                .with_label("expected a declared output");
            if let Some(c) = suggest(&s.node, outputs.iter().map(|o| o.name.as_str())) {
                d = d.with_help(format!("did you mean `{c}`?"));
            } else {
                d = d.with_help(format!("declare it: `output {} = ...;`", s.node));
            }
            self.err(d);
        }
        found
    }

    /// `(disturbance -> output)`: their indices.
    pub(super) fn signal_pair(
        &mut self,
        o: &ObjectiveItem,
        outputs: &[Output],
    ) -> Option<(usize, usize)> {
        match o.signals {
            [from, to] => {
                let f = self.disturbance_ref(from);
                let t = self.output_ref(to, outputs);
                Some((f?, t?))
            }
            _ => {
                self.err(
                    Diagnostic::error(
                        o.span,
                        format!("`{}` needs `(disturbance -> output)`", o.name.node),
                    )
                    .with_help(format!(
                        "e.g. `objective {}(d -> z) minimize;`",
                        o.name.node
                    )),
                );
                None
            }
        }
    }

    /// The initial states: `for x0 = [...]` or `for x0 in ellipsoid(R)`.
    pub(super) fn initial_set(&mut self, o: &ObjectiveItem, n: usize) -> Option<InitialSet> {
        let Some(f) = o.for_ else {
            self.err(
                Diagnostic::error(o.span, format!("`{}` needs an initial state", o.name.node))
                    .with_help("add `for x0 = [...]` or `for x0 in ellipsoid(R)`"),
            );
            return None;
        };
        if f.name.node != "x0" {
            self.err(Diagnostic::error(f.name.span, "expected `x0`"));
            return None;
        }
        if f.is_in {
            match &f.value.kind {
                ExprKind::Call(c, args) if c.node == "ellipsoid" && args.len() == 1 => {
                    let r = self.eval_const(&args[0].value)?;
                    if r.nrows() != n || r.ncols() != n {
                        self.err(Diagnostic::error(
                            args[0].value.span,
                            format!("ellipsoid matrix must be {n}x{n}"),
                        ));
                        return None;
                    }
                    if r.clone().cholesky().is_none()
                        || (&r - r.transpose()).norm() > 1e-12 * (1.0 + r.norm())
                    {
                        self.err(Diagnostic::error(
                            args[0].value.span,
                            "ellipsoid matrix must be symmetric positive definite",
                        ));
                        return None;
                    }
                    Some(InitialSet::Ellipsoid(r))
                }
                _ => {
                    self.err(
                        Diagnostic::error(f.value.span, "expected `ellipsoid(R)`")
                            .with_help("the set {x : x' R x <= 1}"),
                    );
                    None
                }
            }
        } else {
            self.vector(&f.value, n, "x0").map(InitialSet::Point)
        }
    }

    /// The positive `with` parameter `key`, if given.
    pub(super) fn with_param(&mut self, o: &ObjectiveItem, key: &str) -> Option<f64> {
        let a = o.with.iter().find(|a| a.name.node == key)?;
        self.positive(&a.value, key)
    }

    /// Whether every `with` parameter is one the kind takes (`linf` and `finite_time`).
    pub(super) fn with_allowed(&mut self, o: &ObjectiveItem) -> bool {
        let allowed_with: &[&str] = if o.name.node == ObjectiveKind::Linf.keyword() {
            &["xi", "phi", "paper"]
        } else if o.name.node == ObjectiveKind::FiniteTime.keyword() {
            &super::finite_time::PARAMETERS
        } else {
            &[]
        };
        for a in o.with {
            if !allowed_with.contains(&a.name.node.as_str()) {
                self.err(
                    Diagnostic::error(
                        a.name.span,
                        format!(
                            "objective `{}` has no parameter `{}`",
                            o.name.node, a.name.node
                        ),
                    )
                    .with_label(if allowed_with.is_empty() {
                        "this objective takes no `with` parameters".to_string()
                    } else {
                        format!("parameters: {}", allowed_with.join(", "))
                    }),
                );
                return false;
            }
        }
        true
    }

    /// At most `k` signals.
    pub(super) fn expect_signals(&mut self, o: &ObjectiveItem, k: usize) -> bool {
        if o.signals.len() > k {
            self.err(Diagnostic::error(
                o.span,
                format!(
                    "objective `{}` takes {} signal{}",
                    o.name.node,
                    k,
                    if k == 1 { "" } else { "s" }
                ),
            ));
            false
        } else {
            true
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::check::testing::*;
    use crate::spec::{InitialSet, Objective, Target};

    const SIGNALS: &str = "disturbance d; D = 1;\noutput z = x1;\n";

    #[test]
    fn linf_takes_xi_phi_and_paper() {
        let spec = spec_with(&format!(
            "{SIGNALS}objective linf(d -> z) <= 2 with xi = 0.5, phi = 0.25, paper = 0.16;"
        ));
        assert_eq!(
            spec.objectives[0].node,
            Objective::Linf {
                from: 0,
                to: 0,
                target: Target::Fixed(2.0),
                xi: Some(0.5),
                phi: Some(0.25)
            }
        );
        assert_eq!(spec.linf_paper, Some(0.16));
        let (m, at) = only_error(&format!(
            "{SIGNALS}objective hinf(d -> z) minimize with xi = 1;"
        ));
        assert_eq!(m, "objective `hinf` has no parameter `xi`");
        assert_eq!(at, "xi");
    }

    #[test]
    fn goals_must_fit_the_kind() {
        let (m, _) = only_error(&format!("{SIGNALS}objective hinf(d -> z);"));
        assert_eq!(m, "objective `hinf` needs a goal");
        let (m, at) = only_error(&format!("{SIGNALS}objective hinf(d -> z) >= 1;"));
        assert_eq!(m, "objective `hinf` takes `minimize` or `<= value`");
        assert_eq!(at, "1");
        let (m, at) = only_error(&format!("{SIGNALS}objective hinf(d -> z) <= -1;"));
        assert_eq!(m, "the bound must be positive");
        assert_eq!(at, "-1");
    }

    #[test]
    fn signals_must_be_declared() {
        let (m, at) = only_error(&format!("{SIGNALS}objective hinf(e -> z) minimize;"));
        assert_eq!(m, "`e` is not a disturbance");
        assert_eq!(at, "e");
        let (m, at) = only_error(&format!("{SIGNALS}objective hinf(d -> y) minimize;"));
        assert_eq!(m, "`y` is not an output");
        assert_eq!(at, "y");
        let (m, _) = only_error(&format!("{SIGNALS}objective hinf minimize;"));
        assert_eq!(m, "`hinf` needs `(disturbance -> output)`");
    }

    #[test]
    fn initial_sets_are_points_or_positive_definite_ellipsoids() {
        let spec = valid(&format!(
            "{}objective saturation region for x0 in ellipsoid(2);",
            base_with("input u;", "input u saturate 1;")
        ));
        assert_eq!(
            spec.objectives[0].node,
            Objective::SaturationRegion {
                contain: Some(InitialSet::Ellipsoid(crate::eval::Mat::from_element(
                    1, 1, 2.0
                )))
            }
        );
        let (m, at) = only_error("objective input_norm <= 1 for x0 in ellipsoid(-1);");
        assert_eq!(m, "ellipsoid matrix must be symmetric positive definite");
        assert_eq!(at, "-1");
        let (m, _) = only_error("objective input_norm <= 1;");
        assert_eq!(m, "`input_norm` needs an initial state");
        let (m, at) = only_error("objective input_norm <= 1 for x0 = [1, 2];");
        assert_eq!(m, "x0 must have 1 component");
        assert_eq!(at, "[1, 2]");
    }
}
