//! Rules: premise clauses (`z is set`, `z is about p`), the operating point
//! `at(...)` and matrices given directly in the rule.

use super::gains::GAIN;
use super::{Checker, Dims};
use crate::ast::{Clause, Ident, Item, ItemKind, NamedArg, SetRef};
use crate::diag::Diagnostic;
use crate::eval::Mat;
use crate::num::Num;
use crate::span::Span;
use crate::spec::{ClauseSet, Premise, RuleClause, RuleSpec};
use crate::suggest::suggest;
use std::collections::HashMap;

/// What a rule gives directly: model matrices by name, and its gain `F`.
struct RuleMatrices {
    overrides: Vec<(String, Mat, Span)>,
    gain: Option<(Mat, Span)>,
}

/// One clause of a rule's premise, comparable and hashable: the premise's
/// index and the set's index or the bits of its `about` point.
#[derive(Debug, Clone, PartialEq, Eq, Hash, PartialOrd, Ord)]
enum ClauseKey {
    Named(usize, usize),
    About(usize, Vec<u64>),
}

/// A rule's premise in canonical form (clauses sorted): two rules have the
/// same premise exactly when their keys are equal.
fn premise_key(clauses: &[RuleClause]) -> Vec<ClauseKey> {
    let mut key: Vec<ClauseKey> = clauses
        .iter()
        .map(|c| match &c.set {
            ClauseSet::Named(s) => ClauseKey::Named(c.premise, *s),
            ClauseSet::About(p) => {
                ClauseKey::About(c.premise, p.iter().map(|v| v.to_bits()).collect())
            }
        })
        .collect();
    key.sort_unstable();
    key
}

impl Checker<'_> {
    /// The rules, each with a unique name and premise; "no rules" if there are none.
    pub(super) fn rules(
        &mut self,
        items: &[&Item],
        premises: &[Premise],
        dims: Dims,
    ) -> Vec<RuleSpec> {
        let mut out: Vec<RuleSpec> = Vec::new();
        // Each rule name and premise seen so far, with the rule's index in `out`.
        let mut by_name: HashMap<String, usize> = HashMap::new();
        let mut by_premise: HashMap<Vec<ClauseKey>, usize> = HashMap::new();
        for it in items {
            let ItemKind::Rule {
                name,
                clauses,
                at,
                matrices,
            } = &it.kind
            else {
                continue;
            };
            if let Some(prev) = by_name.get(&name.node).map(|&i| &out[i]) {
                let d =
                    Diagnostic::error(name.span, format!("rule `{}` is defined twice", name.node))
                        .with_secondary(prev.span, "first definition here")
                        .with_help("give each rule a unique name");
                self.err(d);
                continue;
            }
            let (rc, mut ok) = self.rule_clauses(name, clauses, premises);
            let at_point = at
                .as_ref()
                .and_then(|(args, aspan)| self.at_point(name, args, *aspan, dims.n));
            if at.is_some() && at_point.is_none() {
                ok = false;
            }
            let (RuleMatrices { overrides, gain }, matrices_ok) =
                self.overrides(name, matrices, dims);
            if !(ok && matrices_ok) {
                continue;
            }
            // Duplicate premise combination.
            let key = premise_key(&rc);
            if let Some(prev) = by_premise
                .get(&key)
                .filter(|_| !rc.is_empty())
                .map(|&i| &out[i])
            {
                let d = Diagnostic::error(name.span, format!("rule `{}` has the same premise as rule `{}`", name.node, prev.name))
                    .with_secondary(prev.span, "same premise here")
                    .with_help("two rules with one premise make the model ambiguous: merge them or change one premise");
                self.err(d);
                continue;
            }
            by_name.insert(name.node.clone(), out.len());
            by_premise.insert(key, out.len());
            out.push(RuleSpec {
                name: name.node.clone(),
                clauses: rc,
                at: at_point,
                overrides,
                gain,
                span: it.span,
            });
        }
        if out.is_empty() && !items.is_empty() {
            return out;
        }
        if items.is_empty() && !self.broken("rule") {
            self.err(
                Diagnostic::error(Span::new(0, 0), "no rules").with_help(
                    "add at least one rule, e.g. `rule R1: z is near => at(theta = 0);`",
                ),
            );
        }
        out
    }

    /// The clauses of rule `name`: each premise once, each set known; false if any failed.
    fn rule_clauses(
        &mut self,
        name: &Ident,
        clauses: &[Clause],
        premises: &[Premise],
    ) -> (Vec<RuleClause>, bool) {
        let mut ok = true;
        let mut rc = Vec::new();
        for c in clauses {
            let Some(pi) = premises.iter().position(|p| p.name == c.premise.node) else {
                ok = false;
                if self.poisoned.contains(&c.premise.node) {
                    continue;
                }
                let mut d = Diagnostic::error(
                    c.premise.span,
                    format!("unknown premise `{}`", c.premise.node),
                )
                .with_label("not declared as a premise");
                if let Some(s) = suggest(&c.premise.node, premises.iter().map(|p| p.name.as_str()))
                {
                    d = d.with_help(format!("did you mean `{s}`?"));
                } else {
                    d = d.with_help(format!(
                        "declare it: `premise {} range lo .. hi {{ ... }}`",
                        c.premise.node
                    ));
                }
                self.err(d);
                ok = false;
                continue;
            };
            let p = &premises[pi];
            if rc.iter().any(|x: &RuleClause| x.premise == pi) {
                self.err(Diagnostic::error(
                    c.span,
                    format!("premise `{}` appears twice in rule `{}`", p.name, name.node),
                ));
                ok = false;
                continue;
            }
            let set = match &c.set {
                SetRef::Named(s) => match p.sets.iter().position(|x| x.name == s.node) {
                    Some(i) => ClauseSet::Named(i),
                    None if self.poisoned.contains(&format!("{}.{}", p.name, s.node)) => {
                        ok = false;
                        continue;
                    }
                    None => {
                        let mut d = Diagnostic::error(
                            s.span,
                            format!("premise `{}` has no set `{}`", p.name, s.node),
                        )
                        .with_label("unknown fuzzy set")
                        .with_secondary(p.span, "premise declared here");
                        if let Some(x) = suggest(&s.node, p.sets.iter().map(|x| x.name.as_str())) {
                            d = d.with_help(format!("did you mean `{x}`?"));
                        } else if p.sets.is_empty() {
                            d = d.with_help(
                                "this premise has no named sets; use `is about <point>`",
                            );
                        } else {
                            d = d.with_help(format!(
                                "its sets are: {}",
                                p.sets
                                    .iter()
                                    .map(|x| x.name.as_str())
                                    .collect::<Vec<_>>()
                                    .join(", ")
                            ));
                        }
                        self.err(d);
                        ok = false;
                        continue;
                    }
                },
                SetRef::About(e) => match self.vector(
                    e,
                    p.dim,
                    &format!("the `about` point of premise `{}`", p.name),
                ) {
                    Some(v) => ClauseSet::About(v),
                    None => {
                        ok = false;
                        continue;
                    }
                },
            };
            rc.push(RuleClause {
                premise: pi,
                set,
                span: c.span,
            });
        }
        (rc, ok)
    }

    /// The operating point of `at(...)`: the full state vector, zero where not set.
    fn at_point(
        &mut self,
        name: &Ident,
        args: &[NamedArg],
        aspan: Span,
        n: usize,
    ) -> Option<(Vec<f64>, Span)> {
        let mut x = vec![0.0; n];
        let mut good = true;
        let mut seen: Vec<&str> = Vec::new();
        for a in args {
            let Some(s) = self.states.iter().find(|s| s.name == a.name.node).cloned() else {
                good = false;
                if self.poisoned.contains(&a.name.node) {
                    continue;
                }
                let mut d =
                    Diagnostic::error(a.name.span, format!("`{}` is not a state", a.name.node))
                        .with_label("`at(...)` sets states");
                d = d.with_suggestion(&a.name.node, self.states.iter().map(|s| s.name.as_str()));
                self.err(d);
                continue;
            };
            if seen.contains(&a.name.node.as_str()) {
                self.err(Diagnostic::error(
                    a.name.span,
                    format!("state `{}` is set twice", s.name),
                ));
                good = false;
                continue;
            }
            seen.push(&a.name.node);
            let Some(v) = self.eval_const(&a.value) else {
                good = false;
                continue;
            };
            if v.len() != s.len || (v.ncols() != 1 && v.nrows() != 1) {
                let mut d = Diagnostic::error(
                    a.value.span,
                    format!(
                        "rule {} sets {} = {} but {} has {} component{}",
                        name.node,
                        s.name,
                        if v.len() == 1 {
                            Num(v[(0, 0)]).to_string()
                        } else {
                            format!("a {}x{} value", v.nrows(), v.ncols())
                        },
                        s.name,
                        s.len,
                        if s.len == 1 { "" } else { "s" }
                    ),
                )
                .with_label(format!(
                    "expected {}",
                    if s.len == 1 {
                        "a scalar".to_string()
                    } else {
                        format!("a {}-vector", s.len)
                    }
                ));
                if v.len() == 1 && s.len > 1 {
                    d = d.with_help(format!(
                        "give every component, e.g. `{} = {} * ones({})`",
                        s.name,
                        Num(v[(0, 0)]),
                        s.len
                    ));
                }
                self.err(d);
                good = false;
                continue;
            }
            for (k, val) in v.iter().enumerate() {
                x[s.offset + k] = *val;
            }
        }
        good.then_some((x, aspan))
    }

    /// Matrices given in the rule (`A = ...`), each of the model's shape and
    /// given once, and the rule's gain `F = ...` if it gives one.
    fn overrides(
        &mut self,
        name: &Ident,
        matrices: &[NamedArg],
        dims: Dims,
    ) -> (RuleMatrices, bool) {
        let Dims { n, m, q } = dims;
        let mut ok = true;
        let mut overrides = Vec::new();
        let mut gain: Option<(Mat, Span)> = None;
        for mat in matrices {
            let (rows, cols) = match mat.name.node.as_str() {
                "A" => (n, n),
                "B" => (n, m),
                "D" => (n, q),
                GAIN if gain.is_some() => {
                    self.err(Diagnostic::error(
                        mat.name.span,
                        format!("`F` is given twice in rule {}", name.node),
                    ));
                    ok = false;
                    continue;
                }
                GAIN => {
                    match self.gain(name, mat, dims) {
                        Some(f) => gain = Some((f, mat.value.span)),
                        None => ok = false,
                    }
                    continue;
                }
                other => {
                    self.err(
                        Diagnostic::error(
                            mat.name.span,
                            format!("unknown model matrix `{other}` in rule"),
                        )
                        .with_label("a rule may give A, B, D and its gain F"),
                    );
                    ok = false;
                    continue;
                }
            };
            let Some(v) = self.eval_const(&mat.value) else {
                ok = false;
                continue;
            };
            if v.nrows() != rows || v.ncols() != cols {
                self.shape_err(
                    Diagnostic::error(
                        mat.value.span,
                        format!(
                            "`{}` of rule {} must be {rows}x{cols}, but this is {}x{}",
                            mat.name.node,
                            name.node,
                            v.nrows(),
                            v.ncols()
                        ),
                    )
                    .with_label(format!("{}x{} matrix", v.nrows(), v.ncols())),
                );
                ok = false;
                continue;
            }
            if overrides
                .iter()
                .any(|(n, _, _): &(String, Mat, Span)| *n == mat.name.node)
            {
                self.err(Diagnostic::error(
                    mat.name.span,
                    format!("`{}` is given twice in rule {}", mat.name.node, name.node),
                ));
                ok = false;
                continue;
            }
            overrides.push((mat.name.node.clone(), v, mat.value.span));
        }
        (RuleMatrices { overrides, gain }, ok)
    }
}

#[cfg(test)]
mod tests {
    use crate::check::testing::*;
    use crate::spec::ClauseSet;

    #[test]
    fn a_rule_has_clauses_an_operating_point_and_overrides() {
        let spec = valid(&base_with(
            "rule R: x1 is all => A = -2;",
            "rule R: x1 is all => at(x1 = 0.5), B = 2;",
        ));
        let r = &spec.rules[0];
        assert_eq!(r.clauses[0].set, ClauseSet::Named(0));
        assert_eq!(r.at.as_ref().map(|a| a.0.clone()), Some(vec![0.5]));
        assert_eq!(r.overrides[0].0, "B");
        assert_eq!(r.overrides[0].1[(0, 0)], 2.0);
    }

    #[test]
    fn clauses_name_known_premises_and_sets() {
        let (m, at) = only_error("rule S: zz is all => A = -3;");
        assert_eq!(m, "unknown premise `zz`");
        assert_eq!(at, "zz");
        let (m, at) = only_error("rule S: x1 is none => A = -3;");
        assert_eq!(m, "premise `x1` has no set `none`");
        assert_eq!(at, "none");
        let (m, _) = only_error("rule S: x1 is all and x1 is all => A = -3;");
        assert_eq!(m, "premise `x1` appears twice in rule `S`");
    }

    #[test]
    fn rule_names_and_premises_are_unique() {
        let (m, at) = only_error("rule R: x1 is about 0.5 => A = -3;");
        assert_eq!(m, "rule `R` is defined twice");
        assert_eq!(at, "R");
        let (m, at) = only_error("rule S: x1 is all => A = -3;");
        assert_eq!(m, "rule `S` has the same premise as rule `R`");
        assert_eq!(at, "S");
    }

    #[test]
    fn operating_points_and_overrides_have_the_model_shapes() {
        let (m, at) = only_error("rule S: x1 is about 0.5 => at(x1 = [1, 2]);");
        assert_eq!(m, "rule S sets x1 = a 1x2 value but x1 has 1 component");
        assert_eq!(at, "[1, 2]");
        let (m, at) = only_error("rule S: x1 is about 0.5 => at(y = 1);");
        assert_eq!(m, "`y` is not a state");
        assert_eq!(at, "y");
        let (m, at) = only_error("rule S: x1 is about 0.5 => A = [1, 2];");
        assert_eq!(m, "`A` of rule S must be 1x1, but this is 1x2");
        assert_eq!(at, "[1, 2]");
        let (m, _) = only_error("rule S: x1 is about 0.5 => A = 1, A = 2;");
        assert_eq!(m, "`A` is given twice in rule S");
    }
}
