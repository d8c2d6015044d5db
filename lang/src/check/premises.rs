//! Premise variables: the expression of the state each is bound to, its range,
//! `about` width and fuzzy sets; states used with `about` in rules become
//! implicit premises.

use super::{Checker, Kind};
use crate::ast::{Expr, ExprKind, Ident, Item, ItemKind, SetDef, SetRef};
use crate::diag::Diagnostic;
use crate::eval::Mode;
use crate::spec::{FuzzySet, Premise, SetShape};
use crate::suggest::suggest;

impl Checker<'_> {
    /// The premises declared by `items`, then the implicit ones of `rules`.
    pub(super) fn premises(&mut self, items: &[&Item], rules: &[&Item]) -> Vec<Premise> {
        let mut out = Vec::new();
        for it in items {
            self.premise_item(it, &mut out);
        }
        self.implicit_premises(rules, &mut out);
        out
    }

    /// `premise names [= expr] [range lo .. hi] [sigma s] { sets }`: one premise
    /// per name. When the item fails, its names (those not declared otherwise,
    /// as states) are poisoned: the rules using them are not reported again.
    fn premise_item(&mut self, it: &Item, out: &mut Vec<Premise>) {
        let ItemKind::Premise { names, .. } = &it.kind else {
            return;
        };
        if self.checked_premise_item(it, out).is_none() {
            for n in names {
                if !self.names.contains_key(&n.node) {
                    self.poison(n.node.clone());
                }
            }
        }
    }

    fn checked_premise_item(&mut self, it: &Item, out: &mut Vec<Premise>) -> Option<()> {
        let ItemKind::Premise {
            names,
            expr,
            range,
            sigma,
            sets,
        } = &it.kind
        else {
            return Some(());
        };
        let bound = self.premise_expr(it, names, expr.as_ref())?;
        if self.poisoned(&bound) {
            return None;
        }
        let r = self.evaluate(&self.state_env(Mode::Shapes, &[], &[]), &bound);
        let v = match r {
            Ok(v) => v,
            Err(d) => {
                self.err(d);
                return None;
            }
        };
        if v.ncols() != 1 {
            self.err(
                Diagnostic::error(bound.span, "a premise must be a scalar or a vector")
                    .with_label(format!("this is {}x{}", v.nrows(), v.ncols())),
            );
            return None;
        }
        let len = v.nrows();
        if names.len() > 1 && names.len() != len {
            self.err(
                Diagnostic::error(
                    bound.span,
                    format!(
                        "{} premise names but the expression has {len} components",
                        names.len()
                    ),
                )
                .with_label(format!("a {len}-vector")),
            );
            return None;
        }
        self.check_generatable(&bound, names);
        let range = match range {
            Some((lo, hi)) => self.premise_range(lo, hi),
            None => None,
        };
        let sigma = sigma.as_ref().and_then(|s| self.positive(s, "sigma"));
        let checked_sets = self.fuzzy_sets(sets, names);
        let dim = if names.len() > 1 { 1 } else { len };
        for (k, name) in names.iter().enumerate() {
            if !self.declare_premise(name) {
                continue;
            }
            out.push(Premise {
                name: name.node.clone(),
                expr: bound.clone(),
                component: (names.len() > 1).then_some(k),
                dim,
                range,
                sigma,
                sets: checked_sets.clone(),
                span: name.span,
            });
        }
        Some(())
    }

    /// The expression the premise names are bound to: `= expr`, or the state of that name.
    fn premise_expr(&mut self, it: &Item, names: &[Ident], expr: Option<&Expr>) -> Option<Expr> {
        if let Some(e) = expr {
            return Some(e.clone());
        }
        let first = names.first()?;
        if names.len() > 1 {
            self.err(
                Diagnostic::error(it.span, "several premise names need a vector expression")
                    .with_help(format!(
                        "write `premise {} = <vector expression> ...`",
                        names
                            .iter()
                            .map(|n| n.node.as_str())
                            .collect::<Vec<_>>()
                            .join(", ")
                    )),
            );
            return None;
        }
        if !self.states.iter().any(|s| s.name == first.node) {
            if self.poisoned.contains(&first.node) {
                return None;
            }
            let mut d = Diagnostic::error(
                first.span,
                format!("premise `{}` is not a state", first.node),
            )
            .with_label("a premise without `= expr` must be a state name");
            if let Some(s) = suggest(&first.node, self.states.iter().map(|s| s.name.as_str())) {
                d = d.with_help(format!("did you mean `{s}`?"));
            } else {
                d = d.with_help(format!(
                    "bind it to an expression of the state: `premise {} = ...`",
                    first.node
                ));
            }
            self.err(d);
            return None;
        }
        Some(Expr {
            kind: ExprKind::Name(first.node.clone()),
            span: first.span,
        })
    }

    /// `range lo .. hi` with lo < hi.
    fn premise_range(&mut self, lo: &Expr, hi: &Expr) -> Option<(f64, f64)> {
        match (
            self.scalar(lo, "a range bound"),
            self.scalar(hi, "a range bound"),
        ) {
            (Some(l), Some(h)) if l < h => Some((l, h)),
            (Some(l), Some(h)) => {
                self.err(
                    Diagnostic::error(
                        lo.span.join(hi.span),
                        format!("empty premise range {l} .. {h}"),
                    )
                    .with_help("write `range lo .. hi` with lo < hi"),
                );
                None
            }
            _ => None,
        }
    }

    /// The named sets, each defined once; a failed set is poisoned for every premise name.
    fn fuzzy_sets(&mut self, sets: &[SetDef], names: &[Ident]) -> Vec<FuzzySet> {
        let mut checked_sets: Vec<FuzzySet> = Vec::new();
        for s in sets {
            if let Some(prev) = checked_sets.iter().find(|c| c.name == s.name.node) {
                let d = Diagnostic::error(
                    s.name.span,
                    format!("set `{}` is defined twice", s.name.node),
                )
                .with_secondary(prev.span, "first definition here");
                self.err(d);
                continue;
            }
            match self.set_shape(s) {
                Some(shape) => checked_sets.push(FuzzySet {
                    name: s.name.node.clone(),
                    shape,
                    span: s.span,
                }),
                None => {
                    for n in names {
                        self.poison(format!("{}.{}", n.node, s.name.node));
                    }
                }
            }
        }
        checked_sets
    }

    /// Vector states used in rules with `about` but not declared as premises: implicit premises.
    fn implicit_premises(&mut self, rules: &[&Item], out: &mut Vec<Premise>) {
        for r in rules {
            let ItemKind::Rule { clauses, .. } = &r.kind else {
                continue;
            };
            for c in clauses {
                if matches!(c.set, SetRef::About(_))
                    && !out.iter().any(|p| p.name == c.premise.node)
                {
                    if let Some(s) = self
                        .states
                        .iter()
                        .find(|s| s.name == c.premise.node)
                        .cloned()
                    {
                        out.push(Premise {
                            name: s.name.clone(),
                            expr: Expr {
                                kind: ExprKind::Name(s.name.clone()),
                                span: c.premise.span,
                            },
                            component: None,
                            dim: s.len,
                            range: None,
                            sigma: None,
                            sets: Vec::new(),
                            span: c.premise.span,
                        });
                    }
                }
            }
        }
    }

    /// Premise names share a namespace with states only when they are the same variable.
    fn declare_premise(&mut self, name: &Ident) -> bool {
        match self.names.get(&name.node) {
            Some((Kind::State, _)) => true,
            _ => self.declare(name, Kind::Premise),
        }
    }

    /// The shape of one set: a known membership function with valid parameters.
    fn set_shape(&mut self, s: &SetDef) -> Option<SetShape> {
        let want = match s.shape.node.as_str() {
            "tri" => 3,
            "trap" => 4,
            "gauss" | "sigmoid" => 2,
            other => {
                let mut d = Diagnostic::error(
                    s.shape.span,
                    format!("unknown membership function `{other}`"),
                )
                .with_label("use tri, trap, gauss or sigmoid");
                d = d.with_suggestion(other, ["tri", "trap", "gauss", "sigmoid"]);
                self.err(d);
                return None;
            }
        };
        if s.args.len() != want {
            self.err(
                Diagnostic::error(
                    s.span,
                    format!(
                        "`{}` takes {want} parameters, {} given",
                        s.shape.node,
                        s.args.len()
                    ),
                )
                .with_help(match s.shape.node.as_str() {
                    "tri" => "tri(a, b, c): feet a and c, peak b",
                    "trap" => "trap(a, b, c, d): feet a and d, plateau b..c",
                    "gauss" => "gauss(center, sigma)",
                    _ => "sigmoid(slope, center)",
                }),
            );
            return None;
        }
        let vals: Option<Vec<f64>> = s
            .args
            .iter()
            .map(|a| self.scalar(&a.value, "a membership parameter"))
            .collect();
        let v = vals?;
        let ordered = v.windows(2).all(|w| w[0] <= w[1]);
        let shape = match s.shape.node.as_str() {
            "tri" if ordered && v[0] < v[2] => SetShape::Tri(v[0], v[1], v[2]),
            "trap" if ordered && v[0] < v[3] => SetShape::Trap(v[0], v[1], v[2], v[3]),
            "gauss" if v[1] > 0.0 => SetShape::Gauss(v[0], v[1]),
            "sigmoid" if v[0] != 0.0 => SetShape::Sigmoid(v[0], v[1]),
            "tri" | "trap" => {
                self.err(
                    Diagnostic::error(
                        s.span,
                        format!("parameters of `{}` must be increasing", s.shape.node),
                    )
                    .with_label(format!("{:?}", v))
                    .with_help("the feet come first and last, e.g. tri(-1, 0, 1), with a < c"),
                );
                return None;
            }
            "gauss" => {
                self.err(
                    Diagnostic::error(s.span, "gauss width sigma must be positive")
                        .with_help("gauss(center, sigma) with sigma > 0"),
                );
                return None;
            }
            _ => {
                self.err(Diagnostic::error(s.span, "sigmoid slope must not be zero"));
                return None;
            }
        };
        Some(shape)
    }
}

#[cfg(test)]
mod tests {
    use crate::check::testing::*;
    use crate::spec::SetShape;

    #[test]
    fn a_premise_keeps_its_expression_range_and_sets() {
        let spec = valid(&base_with(
            "premise x1 range -1 .. 1 { all = trap(-1, -1, 1, 1); }",
            "premise s = 2 * x1 range -2 .. 2 sigma 0.5 { all = trap(-2, -2, 2, 2); mid = tri(-1, 0, 1); }",
        )
        .replace("x1 is all", "s is all"));
        let p = &spec.premises[0];
        assert_eq!(
            (p.name.as_str(), p.dim, p.range),
            ("s", 1, Some((-2.0, 2.0)))
        );
        assert_eq!(p.sigma, Some(0.5));
        assert_eq!(p.sets[1].shape, SetShape::Tri(-1.0, 0.0, 1.0));
    }

    #[test]
    fn several_names_split_a_vector_premise() {
        let spec = valid(
            &base_with(
                "premise x1 range -1 .. 1 { all = trap(-1, -1, 1, 1); }",
                "premise a, b = [x1; 2 * x1] { all = trap(-9, -9, 9, 9); }",
            )
            .replace("x1 is all", "a is all and b is all"),
        );
        assert_eq!(spec.premises.len(), 2);
        assert_eq!(spec.premises[1].component, Some(1));
        let (m, at) = only_error("premise p, q = [x1; x1; x1];");
        assert_eq!(m, "2 premise names but the expression has 3 components");
        assert_eq!(at, "[x1; x1; x1]");
    }

    #[test]
    fn a_premise_without_expression_must_be_a_state() {
        let (m, at) = only_error("premise y1 range 0 .. 1;");
        assert_eq!(m, "premise `y1` is not a state");
        assert_eq!(at, "y1");
    }

    #[test]
    fn ranges_and_sets_are_checked() {
        let (m, at) = only_error("premise p = x1 range 1 .. 0;");
        assert_eq!(m, "empty premise range 1 .. 0");
        assert_eq!(at, "1 .. 0");
        let (m, at) = only_error("premise p = x1 { a = tri(1, 0, -1); }");
        assert_eq!(m, "parameters of `tri` must be increasing");
        assert_eq!(at, "a = tri(1, 0, -1);");
        let (m, at) = only_error("premise p = x1 { a = gauss(0, 1); a = gauss(1, 1); }");
        assert_eq!(m, "set `a` is defined twice");
        assert_eq!(at, "a");
        let (m, at) = only_error("premise p = x1 { a = tria(0, 1, 2); }");
        assert_eq!(m, "unknown membership function `tria`");
        assert_eq!(at, "tria");
    }

    #[test]
    fn a_state_used_with_about_is_an_implicit_premise() {
        let spec = valid(&base_with(
            "premise x1 range -1 .. 1 { all = trap(-1, -1, 1, 1); }\nrule R: x1 is all",
            "rule R: x1 is about 0",
        ));
        let p = &spec.premises[0];
        assert_eq!((p.name.as_str(), p.dim, p.sets.len()), ("x1", 1, 0));
    }
}
